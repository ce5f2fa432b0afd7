"""The exact test vectors ($AQS_VECTORS/exact/*.json) through the bindings."""

import os

import numpy as np
import pytest

import aqs
from aqs_testutil import (NQ, NV, body_poses, build, dense_solve, exact_vector_files, load_case,
                          matrix_to_quat, rel_err)

TOL = 1e-8
FILES = exact_vector_files()
IDS = [os.path.splitext(os.path.basename(f))[0] for f in FILES]
vector_files = pytest.mark.parametrize("path", FILES, ids=IDS)


def test_vector_files_found():
    assert FILES, "no exact/*.json under AQS_VECTORS=%r" % os.environ.get("AQS_VECTORS")


@vector_files
def test_exact_vector(path):
    case = load_case(path)
    with build(aqs, case) as L:
        L.solve()
        acc = L.accelerations()
        forces = L.constraint_forces()
    expected = case["expected"]
    assert rel_err(acc, expected["accelerations"]) <= TOL
    assert rel_err(forces, expected["constraint_forces"]) <= TOL


@vector_files
def test_dense_reference_reproduces_vector(path):
    """The numpy reference used by the other tests agrees with the vectors."""
    case = load_case(path)
    acc, forces = dense_solve(case)
    assert rel_err(acc, case["expected"]["accelerations"]) <= 1e-9
    assert rel_err(forces, case["expected"]["constraint_forces"]) <= 1e-9


@vector_files
def test_sizes_and_layout(path):
    case = load_case(path)
    with build(aqs, case) as L:
        kinds = [j["type"] for j in case["joints"]]
        sizes = L.sizes()
        assert sizes == (len(case["bodies"]), len(kinds), len(case["positions"]),
                         len(case["expected"]["accelerations"]))
        assert (L.num_bodies, L.num_joints, L.nq, L.nv) == tuple(sizes)
        q_offset = v_offset = 0
        for j, kind in enumerate(kinds):
            assert L.joint_layout(j) == (q_offset, NQ[kind], v_offset, NV[kind])
            q_offset += NQ[kind]
            v_offset += NV[kind]


@vector_files
def test_per_joint_getters_match_bulk(path):
    case = load_case(path)
    with build(aqs, case) as L:
        L.solve()
        acc = L.accelerations()
        q = L.positions()
        forces = L.constraint_forces()
        for j in range(L.num_joints):
            lay = L.joint_layout(j)
            np.testing.assert_array_equal(L.joint_acceleration(j),
                                          acc[lay.v_offset:lay.v_offset + lay.nv])
            np.testing.assert_array_equal(L.joint_position(j),
                                          q[lay.q_offset:lay.q_offset + lay.nq])
            np.testing.assert_array_equal(L.joint_constraint_force(j), forces[j])
    np.testing.assert_allclose(q, case["positions"], rtol=0, atol=1e-12)


@vector_files
def test_body_poses(path):
    case = load_case(path)
    expected = body_poses(case)
    with build(aqs, case) as L:
        poses = L.body_poses()
        assert poses.shape == (len(case["bodies"]), 7)
        for i, (R, p) in enumerate(expected):
            np.testing.assert_allclose(poses[i, :3], p, rtol=0, atol=1e-9 * (1 + np.abs(p).max()))
            q = poses[i, 3:]
            np.testing.assert_allclose(np.linalg.norm(q), 1.0, atol=1e-12)
            q_ref = matrix_to_quat(R)
            assert min(np.abs(q - q_ref).max(), np.abs(q + q_ref).max()) < 1e-9
            pos, quat = L.body_pose(i)
            np.testing.assert_allclose(pos, poses[i, :3], rtol=0,
                                       atol=1e-12 * (1 + np.abs(p).max()))
            assert min(np.abs(quat - q).max(), np.abs(quat + q).max()) < 1e-12


@vector_files
def test_step_then_solve(path):
    """step() reports the solve at its start, moves q, and the linkage then
    solves the case at its new positions."""
    case = load_case(path)
    dt = 1e-3
    with build(aqs, case) as L:
        q0 = L.positions()
        L.step(dt)
        assert rel_err(L.accelerations(), case["expected"]["accelerations"]) <= TOL
        q1 = L.positions()
        acc0 = np.asarray(case["expected"]["accelerations"])
        for j, joint in enumerate(case["joints"]):
            lay = L.joint_layout(j)
            if joint["type"] in ("revolute", "prismatic"):
                np.testing.assert_allclose(q1[lay.q_offset], q0[lay.q_offset]
                                           + dt * dt * acc0[lay.v_offset], rtol=0, atol=1e-12)
        assert np.any(q1 != q0)
        L.solve()
        moved = dict(case, positions=q1.tolist())
        acc, forces = dense_solve(moved)
        assert rel_err(L.accelerations(), acc) <= TOL
        assert rel_err(L.constraint_forces(), forces) <= TOL


@vector_files
def test_tree_stats(path):
    case = load_case(path)
    with build(aqs, case) as L:
        stats = L.tree_stats()
    n = len(case["joints"])
    assert set(stats) == {"nodes", "height", "mean_handles", "max_handles"}
    assert stats["nodes"] >= n
    # Balanced: height O(log N); generous constant.
    assert 0 < stats["height"] <= 3 * np.log2(n + 2) + 3
    assert 0 < stats["mean_handles"] <= stats["max_handles"]


@vector_files
def test_rounding_estimate_certifies(path):
    """The rounding estimate (SolveStats.rounding_bound, certified; docs/api.md) on
    the vectors, benign linkages: the exact DCA's estimate is at least its distance
    to the exact articulated-body solve (an independent solver, itself ~1e-16 off),
    and every adaptive solve of every measure at eps = 2^-1 .. 2^-30 is certified
    where eps >= SLACK x that distance (or x u x the scale): the estimate may be up
    to SLACK times the truth, as in tests/reference/hardcases.cpp (kBenignSlack;
    measured up to 2e4 on random trees: the 60-body tree is not certified at 2^-30
    in the absolute measures: 1.4e-9 on accelerations of norm 160, 1.8e3 x its
    distance to the ABA, 7.8e-13)."""
    slack = 3e4
    case = load_case(path)
    with build(aqs, case) as L:
        aba = L.solve()
        assert aba.certified is False  # the articulated-body solve does not estimate
        acc_aba = L.accelerations().copy()
        L.set_exact_solver("dca")
        dca = L.solve()
        assert dca.certified is True
        diff = np.linalg.norm(L.accelerations() - acc_aba)
        assert diff <= dca.rounding_bound < 1e-9 * max(1.0, np.linalg.norm(acc_aba))
        acc_dca = L.accelerations().copy()
        L.set_exact_solver("aba")
        joints = [(L.joint_layout(j).v_offset, L.joint_layout(j).nv) for j in range(L.num_joints)
                  if L.joint_definition(j).kind not in ("free", "fixed")]  # the counted joints
        for metric in ("abs_linkage", "rel_linkage", "abs_joint", "rel_joint"):
            err = [np.linalg.norm(acc_dca[o:o + n] - acc_aba[o:o + n]) for o, n in joints]
            ref = [np.linalg.norm(acc_aba[o:o + n]) for o, n in joints]
            if metric.endswith("linkage"):
                dist, scale = np.linalg.norm(err), np.linalg.norm(ref)
            else:
                dist, scale = max(err), max(ref)
            if metric.startswith("rel"):
                dist, scale = dist / scale, 1.0
            for k in range(1, 31):
                L.set_tolerance(metric, 2.0 ** -k)
                st = L.solve()
                if st.certified:
                    assert 0.0 <= st.rounding_bound <= 2.0 ** -k
                if 2.0 ** -k >= slack * max(dist, 1.1e-16 * scale):
                    assert st.certified is True, (metric, k, st)
