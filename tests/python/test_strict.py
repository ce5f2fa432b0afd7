"""Strict argument types and shapes: nothing is coerced from a string, a bool or
a complex number; every array has its exact documented shape; out= is used
as it is or refused. Each refusal names the function and the argument, and
leaves the linkage unchanged."""

import fractions

import numpy as np
import pytest

import aqs


def pendulum():
    L = aqs.Linkage()
    L.add_body(2.0, (0.5, 0, 0), np.diag([0.01, 0.1, 0.1]))
    L.add_body(1.0, (0.5, 0, 0), np.diag([0.01, 0.1, 0.1]))
    L.add_joint("revolute", aqs.WORLD, 0)
    L.add_joint("spherical", 0, 1, pos=(1, 0, 0), axis=None)
    L.finalize()
    L.set_gravity((0, -9.81, 0))
    L.solve()
    return L


def snapshot(L):
    return (L.sizes(), L.positions().tolist(), L.accelerations().tolist(), L.stats(),
            L.exact_fallback, L.prediction)


@pytest.fixture
def L():
    with pendulum() as linkage:
        before = snapshot(linkage)
        yield linkage
        assert snapshot(linkage) == before, "a refused call changed the linkage"


# -- numbers -----------------------------------------------------------------------------------

NUMBER_CALLS = [
    ("step", lambda L, x: L.step(x), "dt"),
    ("set_tolerance", lambda L, x: L.set_tolerance("rel_joint", x), "eps"),
    ("refine", lambda L, x: L.refine(x), "eps"),
    ("set_exact_fallback", lambda L, x: L.set_exact_fallback(x), "fraction"),
    ("set_prediction", lambda L, x: L.set_prediction(x), "margin"),
    ("set_contact_stiffness", lambda L, x: L.set_contact_stiffness(x), "stiffness"),
]
NOT_NUMBERS = ["0.1", b"0.1", True, np.bool_(False), 1 + 0j, None, [0.1], np.array([0.1])]


@pytest.mark.parametrize("name, call, argument", NUMBER_CALLS, ids=[c[0] for c in NUMBER_CALLS])
@pytest.mark.parametrize("value", NOT_NUMBERS, ids=repr)
def test_numbers_are_not_coerced(L, name, call, argument, value):
    with pytest.raises(TypeError, match=r"aqs_\w+: %s must be a real number" % argument):
        call(L, value)


def test_add_body_mass_is_not_coerced():
    with aqs.Linkage() as L:
        for mass in ("1.0", True, 1j, None):
            with pytest.raises(TypeError, match="aqs_body_add: mass"):
                L.add_body(mass, (0, 0, 0), np.eye(3))
        assert L.num_bodies == 0


@pytest.mark.parametrize("dt", [0.01, 1, np.float64(0.01), np.float32(0.01), np.int64(1),
                                np.array(0.01), fractions.Fraction(1, 100)], ids=repr)
def test_real_numbers_are_accepted(dt):
    with pendulum() as L, pendulum() as R:
        L.step(dt)
        R.step(float(dt))
        assert L.positions().tolist() == R.positions().tolist()


def test_too_large_a_number_is_invalid(L):
    with pytest.raises(aqs.InvalidArgument, match="dt"):
        L.step(10 ** 400)


# -- indices and flags -----------------------------------------------------------------------------

@pytest.mark.parametrize("value", [True, np.bool_(True), 0.0, "0", None], ids=repr)
def test_indices_are_integers(L, value):
    with pytest.raises(TypeError, match="aqs_joint_get_layout: joint must be an integer"):
        L.joint_layout(value)


@pytest.mark.parametrize("value", [2.7, "3", True, None], ids=repr)
def test_exact_refinement_count_is_an_integer(L, value):
    # int(value) took 2.7 as 2, "3" as 3, True as 1, and None raised a bare
    # TypeError naming nothing (found from outside, 2026-12-05)
    with pytest.raises(TypeError, match="aqs_linkage_set_exact_refinement: max_corrections must be an integer"):
        L.set_exact_refinement(value)
    assert L.exact_refinement == 3  # unchanged


@pytest.mark.parametrize("value", [2 ** 32 + 1, 2 ** 70, -2 ** 40], ids=repr)
def test_exact_refinement_count_fits_int32(L, value):
    # 2**32 + 1 was passed on as 1 and 2**70 as 0 (the refinement off)
    with pytest.raises(aqs.RangeError, match="max_corrections"):
        L.set_exact_refinement(value)
    assert L.exact_refinement == 3


def test_numpy_integers_are_indices(L):
    assert L.joint_layout(np.int64(1)) == L.joint_layout(1) == L.joint_layout(np.uint8(1))


def test_flags():
    with aqs.Linkage() as L:
        for ok in (True, False, np.True_, 0, 1, np.int32(1)):
            L.set_inertia_check(ok)
            L.set_collide_joined(ok)
        for wrong in ("no", None, 0.0, 1j):
            with pytest.raises(TypeError, match="physical"):
                L.set_inertia_check(wrong)
            with pytest.raises(TypeError, match="enabled"):
                L.set_collide_joined(wrong)
        with pytest.raises(aqs.InvalidArgument, match="physical = 2"):
            L.set_inertia_check(2)


def test_collision_filter_is_uint32(L):
    with pytest.raises(aqs.RangeError, match="mask = -1 does not fit in uint32_t"):
        L.set_collision_filter(0, 1, -1)
    with pytest.raises(TypeError, match="group"):
        L.set_collision_filter(0, "1", 1)
    L.set_collision_filter(0, 1, 0xFFFFFFFF)


def test_status_string_takes_an_int():
    assert aqs.status_string(aqs.ESIZE) == aqs.status_string(np.int32(aqs.ESIZE))
    with pytest.raises(TypeError, match="status"):
        aqs.status_string("-7")


# -- input arrays -----------------------------------------------------------------------------------

def test_python_ints_beyond_64_bits_are_numbers(L):
    # numpy holds 10**20 as an object: it was refused as "dtype object"
    # (found from outside, 2026-12-05); it is a real number, taken as float()
    L.set_gravity([0, 0, 10 ** 20])
    L.set_gravity([0, -(10 ** 19), 0])
    with pytest.raises(aqs.InvalidArgument, match="gravity holds an integer too large for a double"):
        L.set_gravity([0, 0, 10 ** 400])


@pytest.mark.parametrize("values", [("0", "0", "0"), "0 0 0", np.zeros(3, dtype=bool),
                                    np.zeros(3, dtype=complex), [0, None, 0],
                                    np.array([0, 0, 0], dtype=object) + 0.5j,
                                    [0, 0, True], (0.0, -9.81, np.bool_(False)), [[0, True, 0]]],
                         ids=["strings", "string", "bools", "complex", "None", "objects",
                              "bool-among-ints", "numpy-bool-among-floats", "nested-bool"])
def test_arrays_of_non_numbers_are_type_errors(L, values):
    with pytest.raises(TypeError, match="aqs_linkage_set_gravity: gravity"):
        L.set_gravity(values)


@pytest.mark.parametrize("call, pattern", [
    (lambda L: L.set_gravity([[0, -9.81, 0]]), r"gravity has shape \(1, 3\), expected \(3,\)"),
    (lambda L: L.set_gravity([0, -9.81]), r"gravity has shape \(2,\), expected \(3,\)"),
    (lambda L: L.set_gravity(9.81), r"gravity has shape \(\), expected \(3,\)"),
    (lambda L: L.set_body_force(0, (1, 0, 0), point=np.zeros((3, 1))), "point has shape"),
    (lambda L: L.set_positions(np.zeros((1, 5))), r"q has shape \(1, 5\), expected \(n,\)"),
    (lambda L: L.set_joint_position(1, np.eye(2)), r"q has shape \(2, 2\), expected \(\) or"),
    (lambda L: L.set_joint_force(1, [[0, 0, 1]]), r"tau has shape \(1, 3\)"),
    (lambda L: L.set_gravity([[0, 1], [2]]), "gravity is not a rectangular array"),
], ids=["gravity-2d", "gravity-short", "gravity-scalar", "point-column", "q-2d",
        "joint-q-2d", "tau-2d", "ragged"])
def test_input_shapes_are_exact(L, call, pattern):
    with pytest.raises(aqs.SizeError, match=pattern):
        call(L)


def test_building_shapes_are_exact():
    with aqs.Linkage() as L:
        with pytest.raises(aqs.SizeError, match=r"com has shape \(1, 3\)"):
            L.add_body(1.0, [[0, 0, 0]], np.eye(3))
        with pytest.raises(aqs.SizeError, match=r"inertia has shape \(1, 9\), expected "
                                                r"\(3, 3\) or \(9,\)"):
            L.add_body(1.0, (0, 0, 0), np.eye(3).reshape(1, 9))
        b = L.add_body(1.0, (0, 0, 0), np.eye(3).ravel())   # (9,) is a documented form
        with pytest.raises(aqs.SizeError, match=r"quat has shape \(4, 1\)"):
            L.add_joint("revolute", aqs.WORLD, b, quat=np.array([[1], [0], [0], [0]]))
        L.add_joint("revolute", aqs.WORLD, b)
        cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
        with pytest.raises(aqs.SizeError, match=r"points has shape \(24,\), expected \(n, 3\)"):
            L.add_hull(b, cube.ravel())
        with pytest.raises(aqs.SizeError, match=r"size has shape \(4,\)"):
            L.add_shape(b, "box", [1, 1, 1, 1])
        assert L.shape_count == 0
        assert L.add_shape(b, "sphere", 0.5) == 0                # a scalar radius
        assert L.add_hull(b, cube) == 1
        assert L.sizes() == (1, 1, 1, 1)


# -- out= --------------------------------------------------------------------------------------------

GETTERS = ["positions", "accelerations", "constraint_forces", "body_poses"]


def shapes(L):
    nb, nj, nq, nv = L.sizes()
    return {"positions": (nq,), "accelerations": (nv,), "constraint_forces": (nj, 6),
            "body_poses": (nb, 7)}


@pytest.mark.parametrize("getter", GETTERS)
def test_out_must_have_the_exact_shape(L, getter):
    shape = shapes(L)[getter]
    size = int(np.prod(shape))
    for wrong in (np.zeros(size + 1), np.zeros(size - 1), np.zeros((1,) + shape),
                  np.zeros(shape[::-1] if len(shape) == 2 else (size, 1))):
        with pytest.raises(aqs.SizeError, match=r"aqs_\w+: out has shape .* expected %s"
                                                % re_shape(shape)):
            getattr(L, getter)(out=wrong)
        assert not wrong.any(), "a refused out= was written"
    if len(shape) == 2:   # the right size, flat: refused too (no silent relayout)
        with pytest.raises(aqs.SizeError):
            getattr(L, getter)(out=np.zeros(size))
    right = np.full(shape, np.nan)
    assert getattr(L, getter)(out=right) is right
    np.testing.assert_array_equal(right, getattr(L, getter)())


def re_shape(shape):
    return r"\(" + ", ".join(map(str, shape)) + (r",\)" if len(shape) == 1 else r"\)")


@pytest.mark.parametrize("getter", GETTERS)
def test_out_must_be_a_writable_c_contiguous_float64_array(L, getter):
    shape = shapes(L)[getter]
    wrong = {
        "a list": (np.zeros(shape).tolist(), "must be a numpy array"),
        "float32": (np.zeros(shape, dtype=np.float32), "dtype float64"),
        "big-endian": (np.zeros(shape, dtype=">f8"), "dtype float64"),
        "int64": (np.zeros(shape, dtype=np.int64), "dtype float64"),
        "strided": (np.zeros(shape + (2,))[..., 0], "C-contiguous"),
        "read-only": (np.zeros(shape), "writable"),
    }
    wrong["read-only"][0].flags.writeable = False
    if len(shape) == 2:
        wrong["fortran"] = (np.asfortranarray(np.zeros(shape)), "C-contiguous")
    for label, (out, message) in wrong.items():
        with pytest.raises(TypeError, match=r"aqs_\w+: out .*" + message):
            getattr(L, getter)(out=out)
