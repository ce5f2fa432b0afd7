"""Failed calls raise aqs.Error subclasses that carry the library's message,
and leave the linkage exactly as it was."""

import math

import numpy as np
import pytest

import aqs
from aqs_testutil import build, exact_vector_files, load_case

NAN, INF = math.nan, math.inf
EYE = np.eye(3)


def pendulum(finalize=True):
    L = aqs.Linkage()
    L.add_body(1.0, (0.5, 0, 0), np.diag([0.1, 0.1, 0.1]))
    L.add_body(1.0, (0.5, 0, 0), np.diag([0.1, 0.1, 0.1]))
    L.add_joint("revolute", aqs.WORLD, 0)
    L.add_joint("spherical", 0, 1, pos=(1, 0, 0), axis=None)
    if finalize:
        L.finalize()
    return L


def raises(cls, call, *words):
    """call() raises cls; its message (the C last error) names each of words."""
    with pytest.raises(cls) as info:
        call()
    err = info.value
    assert isinstance(err, aqs.Error)
    assert err.status == cls.status
    for word in words:
        assert word in err.message, "%r not in %r" % (word, err.message)
    return err


# -- the exception classes --------------------------------------------------------

def test_exception_hierarchy():
    pairs = [(aqs.InvalidArgument, aqs.EINVAL, ValueError),
             (aqs.RangeError, aqs.ERANGE, IndexError),
             (aqs.StateError, aqs.ESTATE, RuntimeError),
             (aqs.OutOfMemoryError, aqs.ENOMEM, MemoryError),
             (aqs.ModelError, aqs.EMODEL, ValueError),
             (aqs.NumericError, aqs.ENUMERIC, ArithmeticError),
             (aqs.SizeError, aqs.ESIZE, ValueError)]
    for cls, status, builtin in pairs:
        assert issubclass(cls, aqs.Error) and issubclass(cls, builtin)
        assert cls.status == status
        assert aqs.status_string(status) and aqs.status_string(status) != aqs.status_string(-99)
    assert aqs.status_string(aqs.OK)
    assert aqs.status_string(-99) == "unknown status"
    assert len({aqs.status_string(s) for _, s, _ in pairs}) == len(pairs)


def test_error_carries_last_error():
    with pendulum() as L:
        assert L.last_error == ""
        err = raises(aqs.RangeError, lambda: L.set_body_force(7, (1, 0, 0)), "body", "7")
        assert err.message == L.last_error
        assert err.status_name == "AQS_ERANGE"
        assert err.message in str(err) and "AQS_ERANGE" in str(err)


# -- bad indices ----------------------------------------------------------------------

@pytest.mark.parametrize("index", [2, 100, -1, -2, 2 ** 31 - 1, -2 ** 31])
def test_bad_body_index(index):
    with pendulum() as L:
        raises(aqs.RangeError, lambda: L.set_body_force(index, (1, 0, 0)), "body")
        raises(aqs.RangeError, lambda: L.clear_body_force(index), "body")
        raises(aqs.RangeError, lambda: L.body_pose(index), "body")


@pytest.mark.parametrize("index", [2, 100, -1, 2 ** 31 - 1])
def test_bad_joint_index(index):
    with pendulum() as L:
        L.solve()
        raises(aqs.RangeError, lambda: L.set_joint_force(index, 1.0), "joint")
        raises(aqs.RangeError, lambda: L.joint_layout(index), "joint")
        # each message names the function of the method called (not the layout
        # query the binding makes first to size the output)
        raises(aqs.RangeError, lambda: L.joint_position(index), "aqs_joint_get_position: joint")
        raises(aqs.RangeError, lambda: L.set_joint_position(index, [0.0]), "joint")
        raises(aqs.RangeError, lambda: L.joint_acceleration(index), "aqs_joint_get_acceleration: joint")
        raises(aqs.RangeError, lambda: L.joint_constraint_force(index), "joint")


def test_bad_joint_bodies():
    with aqs.Linkage() as L:
        L.add_body(1.0, (0, 0, 0), EYE)
        raises(aqs.RangeError, lambda: L.add_joint("revolute", aqs.WORLD, 1), "child")
        raises(aqs.RangeError, lambda: L.add_joint("revolute", aqs.WORLD, -1), "child")
        raises(aqs.RangeError, lambda: L.add_joint("revolute", 3, 0), "parent")
        raises(aqs.RangeError, lambda: L.add_joint("revolute", -2, 0), "parent")
        assert L.num_joints == 0


def test_index_outside_int32_is_a_range_error_before_c():
    with pendulum() as L:
        for index in (2 ** 31, -2 ** 31 - 1, 2 ** 40):
            with pytest.raises(aqs.RangeError, match="body"):
                L.set_body_force(index, (1, 0, 0))


def test_index_must_be_an_integer():
    with pendulum() as L:
        with pytest.raises(TypeError, match="body"):
            L.body_pose(1.0)
        assert L.body_pose(np.int64(1))[0].shape == (3,)


# -- non-finite and out-of-domain values --------------------------------------------------

@pytest.mark.parametrize("bad", [NAN, INF, -INF])
def test_non_finite_building(bad):
    with aqs.Linkage() as L:
        raises(aqs.InvalidArgument, lambda: L.add_body(bad, (0, 0, 0), EYE), "mass")
        raises(aqs.InvalidArgument, lambda: L.add_body(1.0, (0, bad, 0), EYE), "com")
        inertia = EYE.copy()
        inertia[1, 1] = bad
        raises(aqs.InvalidArgument, lambda: L.add_body(1.0, (0, 0, 0), inertia), "inertia")
        assert L.num_bodies == 0
        L.add_body(1.0, (0, 0, 0), EYE)
        raises(aqs.InvalidArgument, lambda: L.add_joint("revolute", -1, 0, pos=(bad, 0, 0)), "pos")
        raises(aqs.InvalidArgument, lambda: L.add_joint("revolute", -1, 0, quat=(bad, 0, 0, 0)),
               "quat")
        raises(aqs.InvalidArgument, lambda: L.add_joint("revolute", -1, 0, axis=(0, 0, bad)),
               "axis")
        assert L.num_joints == 0


@pytest.mark.parametrize("bad", [NAN, INF, -INF])
def test_non_finite_loads_and_state(bad):
    with pendulum() as L:
        raises(aqs.InvalidArgument, lambda: L.set_gravity((0, bad, 0)), "gravity")
        raises(aqs.InvalidArgument, lambda: L.set_body_force(0, (bad, 0, 0)), "force")
        raises(aqs.InvalidArgument, lambda: L.set_body_force(0, (1, 0, 0), point=(0, bad, 0)),
               "point")
        raises(aqs.InvalidArgument, lambda: L.set_body_force(0, (1, 0, 0), torque=(0, 0, bad)),
               "torque")
        raises(aqs.InvalidArgument, lambda: L.set_joint_force(0, bad), "tau")
        raises(aqs.InvalidArgument, lambda: L.set_joint_force(1, (0, bad, 0)), "tau")
        raises(aqs.InvalidArgument, lambda: L.set_positions([bad, 1, 0, 0, 0]), "q")
        raises(aqs.InvalidArgument, lambda: L.set_joint_position(0, bad), "q")
        raises(aqs.InvalidArgument, lambda: L.step(bad), "dt")


def test_out_of_domain_values():
    with aqs.Linkage() as L:
        raises(aqs.InvalidArgument, lambda: L.add_body(-1.0, (0, 0, 0), EYE), "mass")
        asym = EYE.copy()
        asym[0, 1] = 0.5
        raises(aqs.InvalidArgument, lambda: L.add_body(1.0, (0, 0, 0), asym), "inertia")
        raises(aqs.InvalidArgument, lambda: L.add_body(1.0, (0, 0, 0), -EYE), "inertia")
        raises(aqs.InvalidArgument, lambda: L.add_body(1.0, (0, 0, 0), np.diag([1, 1, 3])),
               "inertia")  # violates the triangle inequality
        b = L.add_body(1.0, (0, 0, 0), EYE)
        raises(aqs.InvalidArgument, lambda: L.add_joint("revolute", -1, b, quat=(2, 0, 0, 0)),
               "quat")
        raises(aqs.InvalidArgument, lambda: L.add_joint("revolute", -1, b, axis=(0, 0, 0)), "axis")
        raises(aqs.InvalidArgument, lambda: L.add_joint(99, -1, b), "type")
        raises(aqs.InvalidArgument, lambda: L.add_joint(-1, -1, b), "type")
        L.add_joint("spherical", -1, b, axis=None)
        L.finalize()
        raises(aqs.InvalidArgument, lambda: L.set_positions([2, 0, 0, 0]), "q")
        raises(aqs.InvalidArgument, lambda: L.step(0.0), "dt")
        raises(aqs.InvalidArgument, lambda: L.step(-1e-3), "dt")


def test_unknown_joint_kind_name():
    with aqs.Linkage() as L:
        L.add_body(1.0, (0, 0, 0), EYE)
        with pytest.raises(aqs.InvalidArgument, match="hinge"):
            L.add_joint("hinge", aqs.WORLD, 0)
        assert L.add_joint("ReVoLuTe", aqs.WORLD, 0) == 0


# -- wrong phase ------------------------------------------------------------------------------

def test_building_after_finalize():
    with pendulum() as L:
        raises(aqs.StateError, lambda: L.add_body(1.0, (0, 0, 0), EYE), "body_add")
        raises(aqs.StateError, lambda: L.add_joint("revolute", 1, 0), "joint_add")
        raises(aqs.StateError, L.finalize, "finalize")
        assert L.sizes() == (2, 2, 5, 4)


def test_solving_before_finalize():
    with pendulum(finalize=False) as L:
        raises(aqs.StateError, L.solve, "solve")
        raises(aqs.StateError, lambda: L.step(1e-3), "step")
        raises(aqs.StateError, L.tree_stats, "tree_stats")
        raises(aqs.StateError, lambda: L.body_pose(0), "pose")
        raises(aqs.StateError, L.body_poses, "poses")
        raises(aqs.StateError, L.accelerations, "accelerations")
        raises(aqs.StateError, L.constraint_forces, "constraint_forces")
        # Loads, sizes and positions work in any phase.
        L.set_gravity((0, -9.81, 0))
        L.set_body_force(1, (1, 2, 3))
        L.set_joint_force(0, 0.5)
        L.set_positions([0.1, 1, 0, 0, 0])
        assert L.joint_layout(1) == (1, 4, 1, 3)
        L.finalize()
        L.solve()


def test_reading_before_solve():
    with pendulum() as L:
        raises(aqs.StateError, L.accelerations, "accelerations")
        raises(aqs.StateError, lambda: L.joint_acceleration(0), "acceleration")
        raises(aqs.StateError, L.constraint_forces, "constraint_forces")
        raises(aqs.StateError, lambda: L.joint_constraint_force(0), "constraint_force")
        L.solve()
        L.accelerations()


# -- model errors at finalize -----------------------------------------------------------------

def test_model_errors_keep_the_linkage_editable():
    with aqs.Linkage() as L:
        raises(aqs.ModelError, L.finalize)  # no body
        L.add_body(1.0, (0, 0, 0), EYE)
        L.add_body(1.0, (0, 0, 0), EYE)
        L.add_joint("revolute", aqs.WORLD, 0)
        raises(aqs.ModelError, L.finalize, "1")  # body 1 has no joint
        L.add_joint("revolute", 0, 1)
        L.finalize()
        L.solve()


@pytest.mark.parametrize("problem", ["two-parents", "cycle", "free-from-body", "massless",
                                     "massless-welded-to-massless"])
def test_model_errors(problem):
    with aqs.Linkage() as L:
        for mass in (1.0, 0.0 if problem.startswith("massless") else 1.0, 1.0):
            L.add_body(mass, (0, 0, 0), EYE * (mass > 0))
        L.add_joint("revolute", aqs.WORLD, 0)
        if problem == "two-parents":
            L.add_joint("revolute", 0, 1)
            L.add_joint("revolute", aqs.WORLD, 1)
            L.add_joint("revolute", 1, 2)
        elif problem == "cycle":
            L.add_joint("revolute", 2, 1)
            L.add_joint("revolute", 1, 2)
        elif problem == "free-from-body":
            # aqs.h says finalize checks this; the library may refuse it earlier.
            try:
                L.add_joint("free", 0, 1, axis=None)
            except aqs.InvalidArgument as exc:
                assert "free" in exc.message and "parent" in exc.message
                assert L.num_joints == 1
                return
            L.add_joint("revolute", 1, 2)
        elif problem == "massless":
            L.add_joint("revolute", 0, 1)
            L.add_joint("revolute", 1, 2)
        else:  # bodies 1 and 3 welded together, both massless
            L.add_joint("revolute", 0, 1)
            L.add_joint("revolute", 1, 2)
            L.add_body(0.0, (0, 0, 0), np.zeros((3, 3)))
            L.add_joint("fixed", 1, 3, axis=None)
        raises(aqs.ModelError, L.finalize)
        raises(aqs.StateError, L.solve)


# -- wrong sizes ---------------------------------------------------------------------------------

def test_fixed_size_arrays_checked_before_c():
    """C cannot see the length of com[3] etc.: the bindings check it (SizeError)."""
    with aqs.Linkage() as L:
        with pytest.raises(aqs.SizeError, match="com"):
            L.add_body(1.0, (0, 0), EYE)
        with pytest.raises(aqs.SizeError, match="inertia"):
            L.add_body(1.0, (0, 0, 0), np.eye(2))
        with pytest.raises(aqs.SizeError, match="inertia"):
            L.add_body(1.0, (0, 0, 0), np.eye(4))
        L.add_body(1.0, (0, 0, 0), EYE)
        with pytest.raises(aqs.SizeError, match="pos"):
            L.add_joint("revolute", -1, 0, pos=(0, 0, 0, 0))
        with pytest.raises(aqs.SizeError, match="quat"):
            L.add_joint("revolute", -1, 0, quat=(1, 0, 0))
        with pytest.raises(aqs.SizeError, match="axis"):
            L.add_joint("revolute", -1, 0, axis=(0, 1))
        with pytest.raises(aqs.SizeError, match="gravity"):
            L.set_gravity((0, -9.81))
        with pytest.raises(aqs.SizeError, match="force"):
            L.set_body_force(0, (1, 0, 0, 0))
        with pytest.raises(aqs.SizeError, match="point"):
            L.set_body_force(0, (1, 0, 0), point=[1])
        with pytest.raises(aqs.SizeError, match="torque"):
            L.set_body_force(0, (1, 0, 0), torque=np.zeros(6))
        with pytest.raises(TypeError, match="com"):
            L.add_body(1.0, ("a", 0, 0), EYE)
        assert (L.num_bodies, L.num_joints) == (1, 0)


def test_variable_size_arrays_checked_by_c():
    with pendulum() as L:
        for call in (lambda: L.set_positions([0.0] * 4), lambda: L.set_positions([0.0] * 6),
                     lambda: L.set_positions([])):
            with pytest.raises((aqs.SizeError, aqs.InvalidArgument)) as info:
                call()
            assert "positions" in info.value.message
        for call in (lambda: L.set_joint_force(0, (1.0, 2.0)), lambda: L.set_joint_force(1, 1.0),
                     lambda: L.set_joint_force(0, ())):
            with pytest.raises((aqs.SizeError, aqs.InvalidArgument)) as info:
                call()
            assert "tau" in info.value.message or "n" in info.value.message
        with pytest.raises((aqs.SizeError, aqs.InvalidArgument)):
            L.set_joint_position(0, (0.0, 0.0))
        with pytest.raises((aqs.SizeError, aqs.InvalidArgument)):
            L.set_joint_position(1, (1.0, 0.0, 0.0))
        L.solve()
        with pytest.raises(aqs.SizeError, match="accelerations"):
            L.accelerations(out=np.empty(3))
        with pytest.raises(aqs.SizeError, match="positions"):
            L.positions(out=np.empty(4))
        with pytest.raises(aqs.SizeError, match="constraint_forces"):
            L.constraint_forces(out=np.empty((1, 6)))
        with pytest.raises(aqs.SizeError, match="poses"):
            L.body_poses(out=np.empty(13))


def test_output_arrays_are_float64_c_contiguous():
    with pendulum() as L:
        L.solve()
        with pytest.raises(TypeError, match="out"):
            L.accelerations(out=np.empty(4, dtype=np.float32))
        with pytest.raises(TypeError, match="out"):
            L.accelerations(out=np.empty(8)[::2])
        with pytest.raises(TypeError, match="out"):
            L.accelerations(out=[0.0] * 4)
        readonly = np.empty(4)
        readonly.flags.writeable = False
        with pytest.raises(TypeError, match="out"):
            L.accelerations(out=readonly)


# -- a failed call changes nothing ---------------------------------------------------------------

def test_failed_calls_change_nothing():
    files = exact_vector_files()
    case = load_case(files[len(files) // 2])
    with build(aqs, case) as L:
        L.solve()
        acc, forces = L.accelerations(), L.constraint_forces()
        q, poses = L.positions(), L.body_poses()
        loaded = case["body_forces"][0]["body"]
        nb, nj = L.num_bodies, L.num_joints
        failures = [
            lambda: L.set_body_force(nb, (1, 0, 0)),
            lambda: L.set_body_force(loaded, (NAN, 0, 0)),
            lambda: L.set_body_force(loaded, (1, 0, 0), torque=(INF, 0, 0)),
            lambda: L.clear_body_force(-1),
            lambda: L.set_gravity((0, NAN, 0)),
            lambda: L.set_joint_force(nj, 1.0),
            lambda: L.set_joint_force(1, [1.0] * 9),
            lambda: L.set_joint_force(1, [NAN] * L.joint_layout(1).nv),
            lambda: L.set_positions(np.zeros(L.nq + 1)),
            lambda: L.set_positions(np.full(L.nq, NAN)),
            lambda: L.set_joint_position(1, [NAN] * L.joint_layout(1).nq),
            lambda: L.set_joint_position(nj, [0.0]),
            lambda: L.step(-1.0),
            lambda: L.step(NAN),
            lambda: L.add_body(1.0, (0, 0, 0), EYE),
            lambda: L.add_joint("revolute", 0, 1),
            L.finalize,
            lambda: L.accelerations(out=np.empty(L.nv - 1)),
        ]
        for call in failures:
            with pytest.raises(aqs.Error):
                call()
            assert L.last_error
        np.testing.assert_array_equal(L.accelerations(), acc)  # the last solve still readable
        L.solve()
        np.testing.assert_array_equal(L.accelerations(), acc)
        np.testing.assert_array_equal(L.constraint_forces(), forces)
        np.testing.assert_array_equal(L.positions(), q)
        np.testing.assert_array_equal(L.body_poses(), poses)
        assert L.sizes() == (nb, nj, len(case["positions"]), len(acc))


def test_inertia_check():
    """Physically unrealizable inertias (I1 + I2 < I3) are refused unless the
    check is turned off; the switch belongs to the building phase."""
    unphysical = np.diag([1.0, 1.0, 3.0])
    with aqs.Linkage() as L:
        raises(aqs.InvalidArgument, lambda: L.add_body(1.0, (0, 0, 0), unphysical), "inertia")
        L.set_inertia_check(False)
        b = L.add_body(1.0, (0, 0, 0), unphysical)
        L.set_inertia_check(True)
        raises(aqs.InvalidArgument, lambda: L.add_body(1.0, (0, 0, 0), unphysical), "inertia")
        # Not positive semi-definite: refused with the check on (with it off,
        # any symmetric inertia is accepted and finalize judges the rigid group).
        raises(aqs.InvalidArgument, lambda: L.add_body(1.0, (0, 0, 0), -EYE), "semi-definite")
        L.add_joint("revolute", aqs.WORLD, b, axis=(0, 0, 1))
        L.finalize()
        raises(aqs.StateError, lambda: L.set_inertia_check(False), "inertia_check")
        L.set_joint_force(0, 3.0)
        L.solve()
        assert L.accelerations()[0] == pytest.approx(1.0)
