"""Random linkages built through the bindings against the numpy dense solver
of aqs_testutil (M qdd = tau in world coordinates; Newton-Euler on subtrees),
which shares no code with the C library."""

import numpy as np
import pytest

import aqs
from aqs_testutil import (ONE_DOF_OR_MORE, apply_state, build, dense_solve, random_case,
                          random_position, rel_err)

TOL = 1e-8


def check(L, case, tol=TOL):
    L.solve()
    acc, forces = dense_solve(case)
    # Scale of the loads: gravity forces and applied forces, for answers that are ~0.
    weight = sum(b["mass"] for b in case["bodies"]) * (1 + np.linalg.norm(case["gravity"]))
    assert rel_err(L.accelerations(), acc, floor=1e-6) <= tol
    assert rel_err(L.constraint_forces(), forces, floor=1e-6 * weight) <= tol


@pytest.mark.parametrize("kind", ONE_DOF_OR_MORE)
@pytest.mark.parametrize("floating", [False, True], ids=["fixed-base", "floating"])
def test_chain_of_one_kind(kind, floating):
    rng = np.random.default_rng(2 * ONE_DOF_OR_MORE.index(kind) + floating)
    case = random_case(rng, [kind] * 6, floating=floating)
    with build(aqs, case) as L:
        check(L, case)


@pytest.mark.parametrize("seed", range(3))
def test_chain_with_fixed_joints(seed):
    rng = np.random.default_rng(seed)
    kinds = ["revolute", "fixed", "prismatic", "fixed", "fixed", "spherical", "revolute", "fixed"]
    case = random_case(rng, kinds)
    with build(aqs, case) as L:
        check(L, case)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("floating", [False, True], ids=["fixed-base", "floating"])
def test_tree_of_mixed_kinds(seed, floating):
    rng = np.random.default_rng(1000 + seed)
    kinds = list(rng.choice(ONE_DOF_OR_MORE + ["fixed"], size=40))
    case = random_case(rng, kinds, tree=True, floating=floating)
    with build(aqs, case) as L:
        check(L, case)


def test_long_revolute_chain():
    rng = np.random.default_rng(7)
    case = random_case(rng, ["revolute"] * 200)
    with build(aqs, case) as L:
        check(L, case)


def test_masses_over_four_decades():
    rng = np.random.default_rng(8)
    case = random_case(rng, ["revolute", "prismatic", "spherical"] * 10, tree=True,
                       mass_range=(1e-2, 1e2))
    with build(aqs, case) as L:
        check(L, case, tol=1e-7)


def test_free_joint_force():
    """Q on a free joint is a body-frame spatial force [n; f] about the body origin,
    as its acceleration's layout; the joint then exerts exactly Q on its child."""
    rng = np.random.default_rng(9)
    case = random_case(rng, ["revolute"] * 4, floating=True)
    case["joint_forces"].append({"joint": 0, "tau": list(rng.normal(size=6))})
    with build(aqs, case) as L:
        check(L, case)
        np.testing.assert_allclose(L.joint_constraint_force(0), case["joint_forces"][-1]["tau"],
                                   atol=1e-10)


@pytest.mark.parametrize("floating", [False, True], ids=["fixed-base", "floating"])
def test_changing_state_between_solves(floating):
    """Positions and loads changed between solves (the library's incremental
    update) give the same answers as a fresh dense solve each time."""
    rng = np.random.default_rng(11 + floating)
    kinds = list(rng.choice(ONE_DOF_OR_MORE, size=30))
    case = random_case(rng, kinds, tree=True, floating=floating)
    with build(aqs, case) as L:
        check(L, case)
        for round_ in range(6):
            if round_ % 3 == 0:  # every position
                fresh = random_case(np.random.default_rng(round_), kinds, tree=True,
                                    floating=floating)
                case["positions"] = fresh["positions"]
                L.set_positions(case["positions"])
            elif round_ % 3 == 1:  # one joint
                k = int(rng.integers(1, len(kinds)))
                lay = L.joint_layout(k)
                q = random_position(case["joints"][k]["type"], rng)
                case["positions"][lay.q_offset:lay.q_offset + lay.nq] = q
                L.set_joint_position(k, q)
            else:  # loads
                body = int(rng.integers(0, len(kinds)))
                case["body_forces"] = [f for f in case["body_forces"] if f["body"] != body]
                L.clear_body_force(body)
                load = {"body": int(rng.integers(0, len(kinds))), "force": list(rng.normal(size=3)),
                        "point": list(rng.normal(size=3)), "torque": list(rng.normal(size=3))}
                case["body_forces"] = [f for f in case["body_forces"] if f["body"] != load["body"]]
                case["body_forces"].append(load)
                L.set_body_force(load["body"], load["force"], load["point"], load["torque"])
                case["gravity"] = list(rng.normal(size=3))
                L.set_gravity(case["gravity"])
            check(L, case)
        L.clear_forces()
        case["body_forces"], case["joint_forces"] = [], []
        check(L, case)


def test_two_linkages_are_independent():
    rng = np.random.default_rng(12)
    a = random_case(rng, ["revolute"] * 5)
    b = random_case(rng, ["prismatic", "spherical"] * 3, floating=True)
    with build(aqs, a) as La, build(aqs, b) as Lb:
        check(La, a)
        check(Lb, b)
        La.set_gravity((0, 0, 0))
        check(Lb, b)
        apply_state(La, a)
        check(La, a)
