"""Arrays in and out: float64, C-contiguous, the right shapes; no copies of
inputs that already are float64 C-contiguous; other inputs converted."""

import numpy as np
import pytest

import aqs
from aqs_testutil import build, exact_vector_files, load_case


@pytest.fixture
def case():
    files = exact_vector_files()
    return load_case([f for f in files if "floating" in f][0])


def assert_fresh_output(array, shape):
    assert isinstance(array, np.ndarray)
    assert array.dtype == np.float64
    assert array.shape == shape
    assert array.flags.c_contiguous and array.flags.writeable and array.flags.owndata


def test_output_shapes(case):
    with build(aqs, case) as L:
        nb, nj, nq, nv = L.sizes()
        L.solve()
        assert_fresh_output(L.positions(), (nq,))
        assert_fresh_output(L.accelerations(), (nv,))
        assert_fresh_output(L.constraint_forces(), (nj, 6))
        assert_fresh_output(L.body_poses(), (nb, 7))
        pos, quat = L.body_pose(0)
        assert_fresh_output(pos, (3,))
        assert_fresh_output(quat, (4,))
        for j in range(nj):
            lay = L.joint_layout(j)
            assert_fresh_output(L.joint_position(j), (lay.nq,))
            assert_fresh_output(L.joint_acceleration(j), (lay.nv,))
            assert_fresh_output(L.joint_constraint_force(j), (6,))
        # Each call returns a new array: the caller may keep it.
        first = L.accelerations()
        assert L.accelerations() is not first


def test_out_arrays_are_filled_in_place(case):
    with build(aqs, case) as L:
        nb, nj, nq, nv = L.sizes()
        L.solve()
        buffers = {"positions": np.full(nq, np.nan), "accelerations": np.full(nv, np.nan),
                   "constraint_forces": np.full((nj, 6), np.nan),
                   "body_poses": np.full((nb, 7), np.nan)}
        for name, buffer in buffers.items():
            got = getattr(L, name)(out=buffer)
            assert got is buffer
            np.testing.assert_array_equal(buffer, getattr(L, name)())


def test_float64_contiguous_inputs_are_not_copied():
    values = np.array([1.0, 2.0, 3.0])
    assert aqs._array(values, "f", "x", 3) is values
    matrix = np.eye(3)
    assert aqs._array(matrix, "f", "x", ((3, 3), (9,))) is matrix
    assert aqs._array(values[::-1], "f", "x", 3) is not values  # not contiguous: one copy
    assert aqs._array([1, 2, 3], "f", "x", 3).dtype == np.float64


def solve_pendulum_variants(convert):
    """The same two-link linkage built from inputs passed through convert."""
    with aqs.Linkage() as L:
        L.add_body(convert([2])[0], convert([1, 0, 0]), convert([[1, 0, 0], [0, 2, 0], [0, 0, 2]]))
        L.add_body(convert([1])[0], convert([0, 1, 0]), convert([1, 0, 0, 0, 1, 0, 0, 0, 1]))
        L.add_joint(aqs.JOINT_REVOLUTE, aqs.WORLD, 0, convert([0, 0, 0]), convert([1, 0, 0, 0]),
                    convert([0, 0, 1]))
        L.add_joint("prismatic", 0, 1, convert([2, 0, 0]), convert([1, 0, 0, 0]),
                    convert([1, 1, 0]))
        L.finalize()
        L.set_gravity(convert([0, -10, 0]))
        L.set_positions(convert([1, 2]))
        L.set_joint_position(1, convert([3])[0])
        L.set_body_force(1, convert([1, 2, 3]), convert([0, 0, 1]), convert([0, 0, -1]))
        L.set_joint_force(0, convert([3])[0])
        L.set_joint_force(1, convert([-1]))
        L.solve()
        return L.accelerations(), L.constraint_forces(), L.positions()


@pytest.mark.parametrize("name, convert", [
    ("int-lists", lambda v: v),
    ("tuples", lambda v: tuple(map(tuple, v)) if isinstance(v[0], list) else tuple(v)),
    ("int64", lambda v: np.array(v, dtype=np.int64)),
    ("float32", lambda v: np.array(v, dtype=np.float32)),
    ("fortran", lambda v: np.asfortranarray(np.array(v, dtype=np.float64))),
    ("strided", lambda v: np.repeat(np.array(v, dtype=np.float64), 2, axis=0)[::2]),
])
def test_other_input_types_give_the_same_answer(name, convert):
    reference = solve_pendulum_variants(lambda v: np.array(v, dtype=np.float64))
    for got, expected in zip(solve_pendulum_variants(convert), reference):
        np.testing.assert_array_equal(got, expected)


def test_scalar_and_sequence_joint_force():
    def run(tau):
        with aqs.Linkage() as L:
            L.add_body(1.0, (1, 0, 0), np.eye(3))
            L.add_joint("revolute", aqs.WORLD, 0)
            L.finalize()
            L.set_joint_force(0, tau)
            L.solve()
            return L.accelerations()[0]

    values = {run(2.5), run([2.5]), run(np.array([2.5])), run(np.float32(2.5)), run(5 // 2 + 0.5)}
    assert len(values) == 1 and values.pop() == pytest.approx(2.5 / 2.0)


def test_fixed_joint_has_empty_slices():
    with aqs.Linkage() as L:
        L.add_body(1.0, (0, 0, 0), np.eye(3))
        L.add_body(1.0, (0, 0, 0), np.eye(3))
        L.add_joint("revolute", aqs.WORLD, 0)
        L.add_joint("fixed", 0, 1, pos=(1, 0, 0), axis=None)
        L.finalize()
        L.set_joint_force(1, ())
        L.set_joint_position(1, [])
        L.solve()
        assert L.joint_layout(1) == (1, 0, 1, 0)
        assert L.joint_position(1).shape == (0,)
        assert L.joint_acceleration(1).shape == (0,)
        assert L.joint_constraint_force(1).shape == (6,)


def test_joint_kind_constants():
    assert aqs.JOINT_KINDS == {"revolute": 0, "prismatic": 1, "spherical": 2, "free": 3,
                               "fixed": 4, "universal": 5, "cylindrical": 6, "planar": 7}
    assert aqs.WORLD == -1
    assert (aqs.OK, aqs.EINVAL, aqs.ERANGE, aqs.ESTATE, aqs.ENOMEM, aqs.EMODEL, aqs.ENUMERIC,
            aqs.ESIZE) == (0, -1, -2, -3, -4, -5, -6, -7)


def test_all_fixed_linkage_has_empty_state():
    """A linkage of fixed joints only has nq = nv = 0: empty arrays in and out."""
    with aqs.Linkage() as L:
        b = L.add_body(2.0, (0, 0, 0.1), np.eye(3) * 0.01)
        L.add_joint("fixed", aqs.WORLD, b, (0, 0, 1), (1, 0, 0, 0), (0, 0, 1))
        L.finalize()
        L.set_gravity((0, 0, -9.81))
        L.set_positions(np.zeros(0))
        L.solve()
        assert L.positions().shape == (0,)
        assert L.accelerations().shape == (0,)
        # the weld carries the body's weight: force m g up in the child frame
        f = L.constraint_forces()
        np.testing.assert_allclose(f[0, 3:], (0, 0, 2.0 * 9.81), rtol=1e-14)
        with pytest.raises(aqs.SizeError):
            L.set_positions(np.zeros(1))
