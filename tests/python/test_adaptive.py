"""Error-bounded adaptive solving (aqs.h "Error-bounded adaptive solving";
MATH.md sections 4-6) through the bindings: set_tolerance, set_max_computed,
refine, stats, joint_computed, and the SolveStats of solve() and step().

Every adaptive solve is compared with an exact solve (eps = 0) of the same
linkage, itself checked once against the independent numpy dense solver.
The true error under a measure follows aqs.h: a joint's error is the 2-norm
of its exact acceleration vector when the solve did not compute it (it then
reads 0) and nothing otherwise; free joints are not part of the measure; the
relative measures divide by the exact solution's corresponding norm over all
counted joints.
"""

import ctypes
import dataclasses
import functools
import math

import numpy as np
import pytest

import aqs
from aqs import _lib
from aqs_testutil import NV, ONE_DOF_OR_MORE, build, dense_solve, random_case, rel_err

NAN, INF = math.nan, math.inf
METRICS = ["abs_linkage", "rel_linkage", "abs_joint", "rel_joint"]
EPS_EXPONENTS = [0, 5, 10, 20]  # eps = 2^-k
SAME = 1e-12  # computed values against the exact solve, relative


# -- the linkages -----------------------------------------------------------------------------

def _mixed_tree(seed, n, floating):
    rng = np.random.default_rng(seed)
    kinds = list(rng.choice(ONE_DOF_OR_MORE + ["fixed"], size=n))
    return random_case(rng, kinds, tree=True, floating=floating)


def _local_load(case, body):
    """No gravity, one body force: the accelerations concentrate near body,
    so small tolerances skip many joints."""
    case["gravity"] = [0.0, 0.0, 0.0]
    case["body_forces"] = [{"body": body, "force": [0.0, 1.0, 0.0], "point": [0.1, 0.0, 0.0],
                            "torque": [0.0, 0.0, 0.2]}]
    case["joint_forces"] = []
    return case


def _tip_chain(seed, n):
    rng = np.random.default_rng(seed)
    return _local_load(random_case(rng, ["revolute"] * n, loads=False), n - 1)


def _local_tree(seed, n):
    rng = np.random.default_rng(seed)
    case = random_case(rng, list(rng.choice(ONE_DOF_OR_MORE, size=n)), tree=True, floating=True,
                       loads=False)
    return _local_load(case, (3 * n) // 4)


CASES = {
    "tree-60-mixed": lambda: _mixed_tree(100, 60, floating=False),  # fixed joints too
    "tree-60-floating": lambda: _mixed_tree(101, 60, floating=True),
    "chain-300-tip-load": lambda: _tip_chain(102, 300),
    "tree-200-floating-local-load": lambda: _local_tree(103, 200),
}
FIXED_BASE = ["tree-60-mixed", "chain-300-tip-load"]


@functools.lru_cache(maxsize=None)
def exact(name):
    """(case, exact accelerations, exact constraint forces) of a named case."""
    case = CASES[name]()
    with build(aqs, case) as L:
        stats = L.solve()
        acc, forces = L.accelerations().copy(), L.constraint_forces().copy()
        assert stats.error_bound == 0.0 and stats.computed_joints == stats.counted_joints
    dense_acc, dense_forces = dense_solve(case)
    assert rel_err(acc, dense_acc) <= 1e-8
    weight = sum(b["mass"] for b in case["bodies"]) * (1 + np.linalg.norm(case["gravity"]))
    assert rel_err(forces, dense_forces, floor=1e-6 * weight) <= 1e-8
    return case, acc, forces


def joint_slices(case):
    """(kind, slice into the acceleration array) of each joint."""
    out, offset = [], 0
    for j in case["joints"]:
        out.append((j["type"], slice(offset, offset + NV[j["type"]])))
        offset += NV[j["type"]]
    return out


def counted(case):
    """Indices of the joints the measures count: those with an acceleration
    (nv > 0) that are not free joints."""
    return [k for k, (kind, s) in enumerate(joint_slices(case))
            if kind != "free" and s.stop > s.start]


def true_error(metric, case, acc, uncomputed):
    """The measure of aqs.h for a solve that left `uncomputed` (a set of joint
    indices) at 0, from the exact accelerations acc."""
    slices = joint_slices(case)
    norms = {k: np.linalg.norm(acc[slices[k][1]]) for k in counted(case)}
    zeroed = [norms[k] for k in norms if k in uncomputed]
    every = list(norms.values())
    if metric in ("abs_linkage", "rel_linkage"):
        error = math.sqrt(sum(z * z for z in zeroed))
        if metric == "rel_linkage":
            error /= math.sqrt(sum(z * z for z in every))
    else:
        error = max(zeroed, default=0.0)
        if metric == "rel_joint":
            error /= max(every)
    return error


def check_solution(L, name, stats, metric):
    """The last solve of L against the exact one; returns its computed joints."""
    case, acc, forces = exact(name)
    got_acc, got_forces = L.accelerations(), L.constraint_forces()
    acc_scale = max(np.linalg.norm(acc[s]) for _, s in joint_slices(case))
    force_scale = np.abs(forces).max()
    computed = set()
    for k, (kind, s) in enumerate(joint_slices(case)):
        flag = L.joint_computed(k)
        assert isinstance(flag, bool)
        if kind == "free":
            assert flag, "free joint %d must always be computed" % k
        if flag:
            computed.add(k)
            assert np.linalg.norm(got_acc[s] - acc[s]) <= SAME * acc_scale, k
            assert np.array_equal(L.joint_acceleration(k), got_acc[s])
            assert np.abs(got_forces[k] - forces[k]).max() <= SAME * force_scale, k
        else:
            assert np.all(got_acc[s] == 0.0), k
            assert np.all(L.joint_acceleration(k) == 0.0), k
            assert np.all(np.isnan(got_forces[k])), k
            assert np.all(np.isnan(L.joint_constraint_force(k))), k
    assert stats.counted_joints == len(counted(case))
    assert stats.computed_joints == len(computed & set(counted(case)))
    uncomputed = set(range(len(case["joints"]))) - computed
    error = true_error(metric, case, acc, uncomputed)
    assert error <= stats.error_bound * (1 + 1e-9) + 1e-300, (error, stats)
    return computed


# -- error bounds, per measure and tolerance ---------------------------------------------------

@pytest.mark.parametrize("k", EPS_EXPONENTS, ids=["eps=2^-%d" % k for k in EPS_EXPONENTS])
@pytest.mark.parametrize("metric", METRICS)
@pytest.mark.parametrize("name", list(CASES))
def test_error_is_bounded(name, metric, k):
    case, _, _ = exact(name)
    eps = 2.0 ** -k
    with build(aqs, case) as L:
        L.set_tolerance(metric, eps)
        stats = L.solve()
        assert stats == L.stats()
        assert stats.metric == metric and stats.eps == eps
        assert not stats.capped
        assert 0.0 <= stats.error_bound <= eps
        assert stats.nodes_processed >= stats.computed_joints
        check_solution(L, name, stats, metric)


def same_solve(a, b):
    """Two SolveStats equal but for what the prediction changes."""
    skip = {"nodes_predicted": 0, "factors_updated": 0}
    return dataclasses.replace(a, **skip) == dataclasses.replace(b, **skip)


@pytest.mark.parametrize("metric", ["abs_joint", "rel_joint"])
@pytest.mark.parametrize("name", list(CASES))
def test_joint_bound_sum(name, metric):
    """The paper's sum bound is certified too and computes at least the joints
    of the (default) heap-top bound; the linkage-wise measures ignore it."""
    case, _, _ = exact(name)
    with build(aqs, case) as top, build(aqs, case) as total:
        total.set_joint_bound("sum")
        for k in EPS_EXPONENTS:
            top.set_tolerance(metric, 2.0 ** -k)
            total.set_tolerance(metric, 2.0 ** -k)
            by_top, by_sum = top.solve(), total.solve()
            assert by_sum.error_bound <= 2.0 ** -k
            check_solution(total, name, by_sum, metric)
            assert by_sum.computed_joints >= by_top.computed_joints
        total.set_joint_bound(aqs.JOINT_BOUND_HEAP_TOP)
        # top solves the same state again: it predicts, total starts over
        assert same_solve(total.solve(), top.solve())
        for other in ("abs_linkage", "rel_linkage"):
            top.set_tolerance(other, 2.0 ** -5)
            total.set_tolerance(other, 2.0 ** -5)
            total.set_joint_bound("SUM")
            assert total.solve() == top.solve()


@pytest.mark.parametrize("metric", METRICS)
@pytest.mark.parametrize("name", list(CASES))
def test_smaller_eps_computes_a_superset(name, metric):
    """The solve follows one priority order: a smaller eps computes every joint
    a larger one did, and its bound is no larger."""
    case, _, _ = exact(name)
    with build(aqs, case) as L:
        previous, previous_bound = set(), INF
        for k in EPS_EXPONENTS + [40]:
            L.set_tolerance(metric, 2.0 ** -k)
            stats = L.solve()
            computed = check_solution(L, name, stats, metric)
            assert previous <= computed
            assert stats.error_bound <= previous_bound
            previous, previous_bound = computed, stats.error_bound


def test_adaptivity_skips_joints():
    """On a local load the tolerances leave most joints out (a solve that
    always computed everything would pass the bound tests trivially)."""
    for name in ("chain-300-tip-load", "tree-200-floating-local-load"):
        case, _, _ = exact(name)
        with build(aqs, case) as L:
            for metric in METRICS:
                L.set_tolerance(metric, 2.0 ** -5)
                stats = L.solve()
                assert stats.computed_joints < stats.counted_joints, (name, stats)
                if name.startswith("chain"):
                    assert stats.computed_joints < stats.counted_joints / 4, (name, stats)


@pytest.mark.parametrize("metric", METRICS)
def test_metric_constant_or_name(metric):
    case, _, _ = exact("tree-60-floating")
    constant = getattr(aqs, "METRIC_" + metric.upper())
    assert aqs.METRICS[metric] == constant
    with build(aqs, case) as A, build(aqs, case) as B:
        A.set_tolerance(metric, 2.0 ** -5)
        B.set_tolerance(constant, 2.0 ** -5)
        assert A.solve() == B.solve()
        assert np.array_equal(A.accelerations(), B.accelerations())
        B.set_tolerance(metric.upper(), 2.0 ** -5)  # names are case-insensitive
        assert B.solve().metric == metric


def test_exact_by_default_and_with_eps_zero():
    name = "tree-60-mixed"
    case, acc, forces = exact(name)
    with build(aqs, case) as L:
        stats = L.solve()
        assert stats.metric == "abs_linkage" and stats.eps == 0.0 and stats.error_bound == 0.0
        assert stats.computed_joints == stats.counted_joints == len(counted(case))
        # the default exact solver, the articulated-body algorithm, touches no tree node
        assert L.exact_solver == "aba"
        assert not stats.capped and stats.nodes_updated == 0 and stats.nodes_processed == 0
        assert np.array_equal(L.accelerations(), acc)
        L.set_exact_solver("dca")  # the full DCA back-substitution over the tree
        stats = L.solve()
        assert L.exact_solver == "dca" and stats.nodes_processed > 0 and stats.error_bound == 0.0
        assert rel_err(L.accelerations(), acc) <= SAME
        L.set_exact_solver(aqs.EXACT_ABA)
        assert all(L.joint_computed(k) for k in range(len(case["joints"])))
        L.set_tolerance("rel_joint", 2.0 ** -5)
        assert L.solve().computed_joints < len(counted(case))
        L.set_tolerance("rel_joint", 0.0)
        stats = L.solve()
        assert stats.eps == 0.0 and stats.error_bound == 0.0
        assert stats.computed_joints == stats.counted_joints
        assert rel_err(L.accelerations(), acc) <= SAME
        assert not np.isnan(L.constraint_forces()).any()
        stats_again = L.solve()  # nothing changed: no node recomputed
        assert stats_again.nodes_updated == 0


def test_dca_forms():
    """set_dca_form: "sqrt" by default, "phi" (or aqs.DCA_FORM_PHI) before finalize;
    both forms' exact DCA and adaptive solves agree with the exact vector (SAME);
    a bad name, a bool or a string number, and a call after finalize are refused
    with the linkage unchanged."""
    name = "tree-60-mixed"
    case, acc, forces = exact(name)
    for form in ("sqrt", "phi", aqs.DCA_FORM_PHI):
        L = aqs.Linkage()
        assert L.dca_form == "sqrt"
        with pytest.raises(aqs.InvalidArgument, match="form"):
            L.set_dca_form("cholesky")
        with pytest.raises(TypeError):
            L.set_dca_form(True)
        assert L.dca_form == "sqrt"
        L.set_dca_form(form)
        with build(aqs, case, linkage=L):
            assert L.dca_form == ("phi" if form == aqs.DCA_FORM_PHI else form)
            with pytest.raises(aqs.StateError, match="finalized"):
                L.set_dca_form("sqrt")
            assert L.dca_form == ("phi" if form == aqs.DCA_FORM_PHI else form)
            L.set_exact_solver("dca")
            L.solve()
            assert rel_err(L.accelerations(), acc) <= SAME
            L.set_tolerance("rel_joint", 2.0 ** -5)
            stats = L.solve()
            assert stats.computed_joints < stats.counted_joints and stats.error_bound <= 2.0 ** -5


def test_exact_fallback():
    """set_exact_fallback: after an adaptive solve that computed more than the
    fraction of the joints, FALLBACK_RUN exact solves (the exact accelerations
    of the dense reference), then an adaptive probe; bad fractions raise and
    change nothing."""
    name = "tree-60-mixed"
    case, acc, forces = exact(name)
    with build(aqs, case) as L:
        assert L.exact_fallback == 0.0
        for bad in (float("nan"), -0.5, 2.0):
            with pytest.raises(aqs.InvalidArgument, match="fraction"):
                L.set_exact_fallback(bad)
        assert L.exact_fallback == 0.0
        L.set_exact_fallback(0.5)
        assert L.exact_fallback == 0.5
        L.set_tolerance("rel_joint", 1e-13)
        first = L.solve()
        assert not first.fallback and first.computed_joints > first.counted_joints / 2
        for _ in range(aqs.FALLBACK_RUN):
            stats = L.solve()
            assert stats.fallback and stats.error_bound == 0.0
            assert stats.computed_joints == stats.counted_joints
            assert rel_err(L.accelerations(), acc) <= SAME
        assert not L.solve().fallback  # the probe
        L.set_exact_fallback(0.0)
        assert not any(L.solve().fallback for _ in range(2 * aqs.FALLBACK_RUN))


def _altmass_chain(n, ratio):
    """n revolute links hanging under gravity, masses alternating 1 and ratio
    (the hard-case suite's altmass family), at fixed angles."""
    L = aqs.Linkage()
    parent = aqs.WORLD
    for i in range(n):
        m = ratio if i % 2 else 1.0
        b = L.add_body(m, (0.5, 0, 0), np.diag([0.01 * m, 0.1 * m, 0.1 * m]))
        L.add_joint("revolute", parent, b, pos=(1.0 if i else 0.0, 0, 0),
                    axis=(0, 1, 0) if i % 2 else (0, 0, 1))
        parent = b
    L.finalize()
    L.set_positions(0.4 * np.sin(np.arange(n) * 1.7))
    L.set_gravity((9.81, 0, 0))
    return L


def test_rounding_fallback():
    """set_rounding_fallback (on by default): at mass ratio 1e9 an adaptive
    solve that skips joints estimates its rounding far above the level, so
    the solve is exact by the articulated-body algorithm (the same
    accelerations as an exact solve); with the level 0 the adaptive solver
    answers and its estimate is above the default level; bad levels raise and
    change nothing."""
    with _altmass_chain(60, 1e9) as L:
        L.set_auto(False)
        L.solve()
        acc = L.accelerations()
        assert L.rounding_fallback == aqs.ROUNDING_FALLBACK_LEVEL == 1e-8
        for bad in (float("nan"), float("inf"), -1.0):
            with pytest.raises(aqs.InvalidArgument, match="level"):
                L.set_rounding_fallback(bad)
        assert L.rounding_fallback == 1e-8
        L.set_tolerance("rel_joint", 0.5)
        stats = L.solve()
        assert stats.rounding_fallback and stats.path == "exact_aba" and stats.error_bound == 0.0
        assert stats.computed_joints == stats.counted_joints
        assert np.array_equal(L.accelerations(), acc)
        L.set_rounding_fallback(0.0)
        assert L.rounding_fallback == 0.0
        stats = L.solve()
        assert not stats.rounding_fallback and stats.path == "adaptive"
        assert stats.computed_joints < stats.counted_joints
        assert stats.rounding_bound > 1e3 * aqs.ROUNDING_FALLBACK_LEVEL


def test_adaptive_refinement():
    """set_adaptive_refinement (on by default at 1e-10): on the mass-ratio-1e6
    chain an adaptive solve's computed joints agree with the articulated-body
    solve within 1e-14 of the largest acceleration, and more than 1e-12 away
    with the level 0 (the unrefined back-substitution); bad levels raise and
    change nothing."""
    with _altmass_chain(60, 1e6) as L:
        L.set_auto(False)
        L.solve()
        acc = L.accelerations()
        scale = np.max(np.abs(acc))
        assert L.adaptive_refinement == aqs.ADAPTIVE_REFINEMENT_LEVEL == 1e-10
        for bad in (float("nan"), float("inf"), -1.0):
            with pytest.raises(aqs.InvalidArgument, match="level"):
                L.set_adaptive_refinement(bad)
        assert L.adaptive_refinement == 1e-10
        L.set_rounding_fallback(0.0)  # else the ABA answers at this ratio
        L.set_tolerance("rel_joint", 2.0 ** -4)
        errors = []
        for level in (aqs.ADAPTIVE_REFINEMENT_LEVEL, 0.0):
            L.set_adaptive_refinement(level)
            stats = L.solve()
            assert stats.path == "adaptive" and stats.computed_joints < stats.counted_joints
            computed = np.array([L.joint_computed(j) for j in range(60)])
            errors.append(np.max(np.abs(L.accelerations() - acc)[computed]) / scale)
        assert errors[0] <= 1e-14 < 1e-12 < errors[1]


@pytest.mark.parametrize("metric", METRICS)
@pytest.mark.parametrize("name", ["chain-300-tip-load", "tree-200-floating-local-load"])
def test_prediction(name, metric):
    """set_prediction (on by default): a second solve at the same state
    computes the joints the first one needed by far without evaluating
    theirs; its joints equal the exact ones, its bound holds and it computes
    the same joints as the first; bad margins raise and change nothing;
    margin 0 predicts nothing; steps skip factors."""
    case, _, _ = exact(name)
    with build(aqs, case) as L:
        assert L.prediction == aqs.PREDICTION_MARGIN
        for bad in (NAN, INF, -1.0, 0.5):
            with pytest.raises(aqs.InvalidArgument, match="margin"):
                L.set_prediction(bad)
        assert L.prediction == aqs.PREDICTION_MARGIN
        L.set_auto(False)  # the adaptive solver's own prediction
        L.set_tolerance(metric, 2.0 ** -20)
        first = L.solve()
        assert first.nodes_predicted == 0
        first_computed = check_solution(L, name, first, metric)
        second = L.solve()
        assert second.nodes_predicted > 0
        assert check_solution(L, name, second, metric) == first_computed
        L.set_prediction(0.0)
        assert L.prediction == 0.0
        assert L.solve().nodes_predicted == 0
        L.set_prediction(64.0)
        L.step(1e-3)
        stats = L.step(1e-3)
        assert stats.nodes_predicted > 0
        assert stats.factors_updated < stats.nodes_updated


def test_nothing_moves():
    """Every joint fixed: nothing is counted, a tolerance changes nothing."""
    with aqs.Linkage() as L:
        L.add_body(1.0, (0.5, 0, 0), np.eye(3) * 0.1)
        L.add_body(1.0, (0.5, 0, 0), np.eye(3) * 0.1)
        L.add_joint("fixed", aqs.WORLD, 0)
        L.add_joint("fixed", 0, 1, pos=(1, 0, 0))
        L.finalize()
        L.set_gravity((0, -9.81, 0))
        L.set_tolerance("abs_joint", 0.5)
        stats = L.solve()
        assert stats.counted_joints == stats.computed_joints == 0
        assert stats.error_bound == 0.0
        assert L.joint_computed(0) and L.joint_computed(1)
        np.testing.assert_allclose(L.joint_constraint_force(1)[3:], (0, 9.81, 0), rtol=1e-12)


def test_refine_after_solving_a_linkage_that_cannot_move():
    with aqs.Linkage() as L:
        L.add_body(1.0, (0.5, 0, 0), np.eye(3) * 0.1)
        L.add_joint("fixed", aqs.WORLD, 0)
        L.finalize()
        L.set_tolerance("abs_joint", 0.5)
        stats = L.solve()
        assert L.refine(0.0) == stats


# -- the cap and refining ----------------------------------------------------------------------

def fresh_solve(name, metric, eps):
    """(stats, computed joints, accelerations) of a new linkage solved at eps."""
    case, _, _ = exact(name)
    with build(aqs, case) as L:
        L.set_tolerance(metric, eps)
        stats = L.solve()
        computed = {k for k in range(len(case["joints"])) if L.joint_computed(k)}
        return stats, computed, L.accelerations().copy()


@pytest.mark.parametrize("metric", METRICS)
@pytest.mark.parametrize("name", FIXED_BASE)
def test_cap_then_refine(name, metric):
    case, _, _ = exact(name)
    eps = 2.0 ** -20
    with build(aqs, case) as L:
        L.set_tolerance(metric, eps)
        for cap in (1, 5, 20):
            L.set_max_computed(cap)
            stats = L.solve()
            assert stats.capped and stats.computed_joints == cap
            assert stats.error_bound > eps
            check_solution(L, name, stats, metric)
        # The cap still applies to refine: nothing more is computed.
        again = L.refine(eps)
        assert again.capped and again.computed_joints == 20
        assert again.error_bound == stats.error_bound
        # Without the cap, refining continues the capped solve and ends where a
        # fresh solve at the same eps ends.
        L.set_max_computed(0)
        for target in (2.0 ** -5, 2.0 ** -10, eps):
            previous = stats
            stats = L.refine(target)
            if previous.error_bound <= target:
                assert stats == previous  # a target already met does nothing
            else:
                assert stats.eps == target and not stats.capped
                assert stats.error_bound <= target, (target, stats)
                assert stats.computed_joints > previous.computed_joints
            computed = check_solution(L, name, stats, metric)
        fresh_stats, fresh_computed, fresh_acc = fresh_solve(name, metric, eps)
        assert computed == fresh_computed
        assert stats.computed_joints == fresh_stats.computed_joints
        np.testing.assert_allclose(L.accelerations(), fresh_acc, rtol=0,
                                   atol=SAME * np.abs(fresh_acc).max())


def test_cap_with_a_floating_base():
    """Joints on the path to a floating base are computed whatever the cap;
    the bound reached still holds."""
    name = "tree-200-floating-local-load"
    case, _, _ = exact(name)
    with build(aqs, case) as L:
        L.set_tolerance("abs_linkage", 2.0 ** -20)
        L.set_max_computed(1)
        forced = L.solve()
        assert forced.capped and forced.computed_joints >= 1
        check_solution(L, name, forced, "abs_linkage")
        L.set_max_computed(forced.computed_joints + 10)
        stats = L.solve()
        assert stats.capped and stats.computed_joints == forced.computed_joints + 10
        check_solution(L, name, stats, "abs_linkage")


def test_cap_with_eps_zero_then_refine_to_exact():
    """A cap with eps = 0 uses the adaptive solver; refine(0) without the cap
    completes it to the exact solution."""
    name = "chain-300-tip-load"
    case, acc, forces = exact(name)
    with build(aqs, case) as L:
        L.set_max_computed(7)
        stats = L.solve()
        assert stats.eps == 0.0 and stats.capped and stats.computed_joints == 7
        assert stats.error_bound > 0.0
        check_solution(L, name, stats, stats.metric)
        L.set_max_computed(0)
        stats = L.refine(0.0)
        assert not stats.capped and stats.error_bound == 0.0
        assert stats.computed_joints == stats.counted_joints
        check_solution(L, name, stats, stats.metric)
        assert rel_err(L.accelerations(), acc) <= SAME
        assert rel_err(L.constraint_forces(), forces) <= SAME


def test_refine_to_a_larger_eps_does_nothing():
    name = "chain-300-tip-load"
    case, _, _ = exact(name)
    with build(aqs, case) as L:
        L.set_tolerance("abs_joint", 2.0 ** -10)
        stats = L.solve()
        acc = L.accelerations().copy()
        assert L.refine(2.0 ** -5) == stats
        assert L.refine(stats.error_bound) == stats
        assert np.array_equal(L.accelerations(), acc)
        L.set_tolerance("abs_joint", 0.0)  # exact: refine has nothing to add
        stats = L.solve()
        assert L.refine(0.0) == stats


CHANGES = {
    "set_body_force": lambda L: L.set_body_force(0, (1.0, 0, 0)),
    "clear_body_force": lambda L: L.clear_body_force(299),
    "clear_forces": lambda L: L.clear_forces(),
    "set_gravity": lambda L: L.set_gravity((0, 0, -1.0)),
    "set_joint_force": lambda L: L.set_joint_force(3, 0.5),
    "set_positions": lambda L: L.set_positions(L.positions()),
    "set_joint_position": lambda L: L.set_joint_position(5, 0.25),
    "set_tolerance": lambda L: L.set_tolerance("abs_joint", 2.0 ** -10),
    "set_joint_bound": lambda L: L.set_joint_bound("sum"),
    "step": lambda L: L.step(1e-3),
}


@pytest.mark.parametrize("change", list(CHANGES))
def test_refine_after_a_change_is_a_state_error(change):
    name = "chain-300-tip-load"
    case, _, _ = exact(name)
    with build(aqs, case) as L:
        L.set_tolerance("abs_joint", 2.0 ** -5)
        L.solve()
        CHANGES[change](L)
        with pytest.raises(aqs.StateError) as info:
            L.refine(2.0 ** -10)
        assert "aqs_linkage_refine" in info.value.message
        # The failed refine changed nothing: solving again works, and refines.
        L.solve()
        assert L.refine(2.0 ** -10).error_bound <= 2.0 ** -10


def test_refine_before_any_solve_is_a_state_error():
    case, _, _ = exact("tree-60-mixed")
    with build(aqs, case) as L:
        L.set_tolerance("abs_linkage", 0.5)
        with pytest.raises(aqs.StateError, match="aqs_linkage_refine"):
            L.refine(0.1)


# -- stepping ------------------------------------------------------------------------------------

def test_step_returns_the_stats_of_its_solve():
    name = "tree-60-floating"
    case, acc, _ = exact(name)
    with build(aqs, case) as L:
        stats = L.step(1e-3)
        assert isinstance(stats, aqs.SolveStats) and stats == L.stats()
        # the articulated-body algorithm leaves the tree alone
        assert stats.nodes_updated == 0 and stats.error_bound == 0.0
        assert stats.computed_joints == stats.counted_joints
        assert np.array_equal(L.accelerations(), acc)  # the solve at the start of the step
        L.set_exact_solver("dca")
        nodes = L.tree_stats()["nodes"]
        # the DCA brings the stale tree up to date before solving, and recomputes it after the move
        assert L.step(1e-3).nodes_updated == 2 * nodes
        assert L.step(1e-3).nodes_updated == nodes


def test_adaptive_step_moves_only_computed_joints():
    name = "chain-300-tip-load"
    case, _, _ = exact(name)
    with build(aqs, case) as L:
        layouts = [L.joint_layout(k) for k in range(len(case["joints"]))]
        L.set_auto(False)  # an adaptive step as such (on 300 joints the exact one is cheaper)
        L.set_tolerance("rel_linkage", 2.0 ** -5)
        L.solve()  # builds every node's factors: the step's own solve updates nothing
        before = L.positions().copy()
        stats = L.step(0.1)
        assert stats.nodes_updated > 0 and stats.error_bound <= 2.0 ** -5
        check_solution(L, name, stats, "rel_linkage")  # the solve at the start of the step
        after, qdd = L.positions(), L.accelerations()
        # A revolute chain: q and qdd share one layout; q <- q + dt^2 qdd,
        # with qdd = 0 (no move at all) for the joints not computed.
        for k, lay in enumerate(layouts):
            q = slice(lay.q_offset, lay.q_offset + lay.nq)
            if L.joint_computed(k):
                np.testing.assert_allclose(after[q], before[q] + 0.01 * qdd[q], rtol=1e-15,
                                           atol=1e-300)
            else:
                assert np.array_equal(after[q], before[q]), k
        assert 0 < np.count_nonzero(after != before) <= stats.computed_joints
        # The update after the move touched only what moved: fewer nodes than
        # the whole tree (the solve before the step built every node).
        assert stats.computed_joints <= stats.nodes_updated < L.tree_stats()["nodes"]


# -- SolveStats ----------------------------------------------------------------------------------

def test_solve_stats_fields_and_types():
    names = ["metric", "eps", "error_bound", "computed_joints", "counted_joints",
             "nodes_updated", "nodes_processed", "capped", "fallback", "nodes_predicted",
             "factors_updated", "path", "auto_chosen", "cost_adaptive", "cost_exact",
             "rounding_bound", "certified", "rounding_fallback"]
    types = [str, float, float, int, int, int, int, bool, bool, int, int, str, bool, float, float, float, bool,
             bool]
    fields = dataclasses.fields(aqs.SolveStats)
    assert [f.name for f in fields] == names
    assert [f.type for f in fields] in (types, [t.__name__ for t in types])
    case, _, _ = exact("tree-60-mixed")
    with build(aqs, case) as L:
        L.set_tolerance(aqs.METRIC_REL_LINKAGE, 0.25)
        L.set_max_computed(2)
        stats = L.solve()
        for name, kind in zip(names, types):
            assert type(getattr(stats, name)) is kind, name
        assert stats.metric == "rel_linkage" and stats.eps == 0.25 and stats.capped is True
        with pytest.raises(dataclasses.FrozenInstanceError):
            stats.eps = 1.0
        assert "SolveStats(" in repr(stats)


def test_stats_struct_size_is_honoured():
    """The library fills only what aqs_solve_stats.size covers."""
    with aqs.Linkage() as L:
        L.add_body(1.0, (0.5, 0, 0), np.eye(3) * 0.1)
        L.add_joint("revolute", aqs.WORLD, 0)
        L.finalize()
        L.set_gravity((0, -9.81, 0))
        L.set_tolerance("abs_joint", 0.5)
        L.solve()
        handle = L._handle
        full = _lib.aqs_solve_stats(size=ctypes.sizeof(_lib.aqs_solve_stats))
        assert _lib.lib.aqs_linkage_get_stats(handle, full) == aqs.OK
        assert full.metric == aqs.METRIC_ABS_JOINT and full.eps == 0.5 and full.fallback == 0
        for size, filled in ((8, ["metric"]), (16, ["metric", "eps"])):
            partial = _lib.aqs_solve_stats(size=size, metric=-7, eps=-7.0, error_bound=-7.0,
                                           computed_joints=-7, counted_joints=-7,
                                           nodes_updated=-7, nodes_processed=-7, capped=-7,
                                           fallback=-7, nodes_predicted=-7, factors_updated=-7,
                                           path=-7, auto_chosen=-7, cost_adaptive=-7.0,
                                           cost_exact=-7.0, rounding_bound=-7.0,
                                           certified=-7, rounding_fallback=-7)
            assert _lib.lib.aqs_linkage_get_stats(handle, partial) == aqs.OK
            assert partial.size == size
            for name, _ in _lib.aqs_solve_stats._fields_[1:]:
                expected = getattr(full, name) if name in filled else -7
                assert getattr(partial, name) == expected, (size, name)
        small = _lib.aqs_solve_stats(size=4)
        assert _lib.lib.aqs_linkage_get_stats(handle, small) == aqs.EINVAL
        assert "size" in L.last_error


# -- errors --------------------------------------------------------------------------------------

def pendulum(finalize=True):
    L = aqs.Linkage()
    L.add_body(1.0, (0.5, 0, 0), np.diag([0.1, 0.1, 0.1]))
    L.add_body(1.0, (0.5, 0, 0), np.diag([0.1, 0.1, 0.1]))
    L.add_joint("revolute", aqs.WORLD, 0)
    L.add_joint("spherical", 0, 1, pos=(1, 0, 0), axis=None)
    if finalize:
        L.finalize()
        L.set_gravity((0, -9.81, 0))
    return L


def raises(cls, call, *words):
    with pytest.raises(cls) as info:
        call()
    for word in words:
        assert word in info.value.message, (word, info.value.message)
    return info.value


def test_bad_metric():
    with pendulum() as L:
        err = raises(aqs.InvalidArgument, lambda: L.set_tolerance("abs", 0.1),
                     "aqs_linkage_set_tolerance", "metric", "'abs'", "rel_joint")
        assert isinstance(err, ValueError)
        for bad in (6, -1, 99):
            raises(aqs.InvalidArgument, lambda: L.set_tolerance(bad, 0.1),
                   "aqs_linkage_set_tolerance", "metric", str(bad))
            assert "metric" in L.last_error
        raises(aqs.RangeError, lambda: L.set_tolerance(2 ** 31, 0.1), "metric")
        for wrong in (1.0, None, b"abs_joint"):
            with pytest.raises(TypeError):
                L.set_tolerance(wrong, 0.1)


def test_bad_eps():
    with pendulum() as L:
        for bad in (-1e-3, -INF, INF, NAN):
            raises(aqs.InvalidArgument, lambda: L.set_tolerance("abs_joint", bad),
                   "aqs_linkage_set_tolerance", "eps")
        L.set_tolerance("abs_joint", 1e-3)
        L.solve()
        for bad in (-1.0, NAN, INF):
            raises(aqs.InvalidArgument, lambda: L.refine(bad), "aqs_linkage_refine", "eps")
        with pytest.raises((TypeError, ValueError)):
            L.set_tolerance("abs_joint", "small")


def test_bad_joint_bound():
    with pendulum() as L:
        raises(aqs.InvalidArgument, lambda: L.set_joint_bound("max"),
               "aqs_linkage_set_joint_bound", "kind", "'max'", "heap_top")
        for bad in (2, -1):
            raises(aqs.InvalidArgument, lambda: L.set_joint_bound(bad),
                   "aqs_linkage_set_joint_bound", "kind", str(bad))
        with pytest.raises(TypeError):
            L.set_joint_bound(None)
    with pendulum(finalize=False) as L:
        raises(aqs.StateError, lambda: L.set_joint_bound("sum"), "aqs_linkage_set_joint_bound")


def test_failed_calls_change_nothing():
    with pendulum() as L:
        L.set_tolerance("rel_joint", 0.125)
        L.set_max_computed(1)
        for call in (lambda: L.set_tolerance("nope", 0.5), lambda: L.set_tolerance(7, 0.5),
                     lambda: L.set_tolerance("abs_joint", NAN),
                     lambda: L.set_tolerance("abs_joint", -2.0),
                     lambda: L.set_max_computed(-1)):
            with pytest.raises(aqs.Error):
                call()
        stats = L.solve()
        assert stats.metric == "rel_joint" and stats.eps == 0.125
        assert stats.computed_joints <= 1


def test_before_finalize_is_a_state_error():
    with pendulum(finalize=False) as L:
        raises(aqs.StateError, lambda: L.set_tolerance("abs_joint", 0.1),
               "aqs_linkage_set_tolerance")
        raises(aqs.StateError, lambda: L.set_max_computed(3), "aqs_linkage_set_max_computed")
        raises(aqs.StateError, lambda: L.refine(0.1), "aqs_linkage_refine")
        raises(aqs.StateError, L.stats, "aqs_linkage_get_stats")
        raises(aqs.StateError, lambda: L.joint_computed(0), "aqs_joint_get_computed")


def test_before_any_solve_and_bad_indices():
    with pendulum() as L:
        raises(aqs.StateError, L.stats, "aqs_linkage_get_stats")
        raises(aqs.StateError, lambda: L.joint_computed(0), "aqs_joint_get_computed")
        L.solve()
        for bad in (2, -1, 1000):
            raises(aqs.RangeError, lambda: L.joint_computed(bad), "aqs_joint_get_computed")
        with pytest.raises(TypeError):
            L.joint_computed(0.5)
        raises(aqs.InvalidArgument, lambda: L.set_max_computed(-1),
               "aqs_linkage_set_max_computed", "max_joints")
        with pytest.raises(TypeError):
            L.set_max_computed(2.5)


def test_solve_and_step_keep_other_behaviour():
    """solve()/step() failures still raise, and leave the last stats alone."""
    with pendulum() as L:
        first = L.solve()
        raises(aqs.InvalidArgument, lambda: L.step(-1.0), "dt")
        assert L.stats() == first


def test_tree_builders_agree():
    """Bisection and contraction trees give the same exact answer (1e-10:
    two rounding histories on a well-conditioned chain)."""
    results = []
    for builder in ("contraction", "bisection"):
        with aqs.Linkage() as L:
            L.set_tree_builder(builder)
            L.set_exact_solver("dca")  # the exact solve that goes through the tree
            prev = aqs.WORLD
            for i in range(50):
                b = L.add_body(1.0, (0.5, 0, 0), np.diag([0.01, 0.1, 0.1]))
                L.add_joint("revolute", prev, b, pos=(1.0 if i else 0.0, 0, 0),
                            axis=(0, i % 2, (i + 1) % 2))
                prev = b
            L.finalize()
            L.set_gravity((0, -9.81, 0))
            L.set_body_force(49, (0.3, 0.2, 1.0))
            L.solve()
            results.append(L.accelerations())
            with pytest.raises(aqs.StateError):
                L.set_tree_builder("contraction")
    np.testing.assert_allclose(results[1], results[0], rtol=1e-10, atol=1e-12)
    with aqs.Linkage() as L:
        with pytest.raises(aqs.InvalidArgument):
            L.set_tree_builder("random")


@pytest.mark.parametrize("name", sorted(CASES))
def test_exact_solvers_agree(name):
    """The articulated-body algorithm (default) and the DCA back-substitution
    give the same accelerations and constraint forces (1e-10 relative: two
    rounding histories; constraint forces with the floor of exact()), and the
    same trajectory over 20 exact steps (1e-10)."""
    case, _, _ = exact(name)
    out = {}
    for solver in ("aba", "dca"):
        with build(aqs, case) as L:
            L.set_exact_solver(solver)
            L.solve()
            acc, forces = L.accelerations().copy(), L.constraint_forces().copy()
            for _ in range(20):
                stats = L.step(0.05)
                assert stats.error_bound == 0.0
                assert (stats.nodes_updated == 0) == (solver == "aba")
            out[solver] = acc, forces, L.positions().copy()
    weight = sum(b["mass"] for b in case["bodies"]) * (1 + np.linalg.norm(case["gravity"]))
    assert rel_err(out["aba"][0], out["dca"][0]) <= 1e-10
    assert rel_err(out["aba"][1], out["dca"][1], floor=1e-9 * weight) <= 1e-10
    assert rel_err(out["aba"][2], out["dca"][2]) <= 1e-10


def test_exact_solver_switching_keeps_the_tree_right():
    """Exact steps by the articulated-body algorithm leave the tree stale; an
    adaptive solve afterwards recomputes it and agrees with a linkage that
    took the same steps with the DCA."""
    case, _, _ = exact("chain-300-tip-load")
    result = []
    for solver in ("aba", "dca"):
        with build(aqs, case) as L:
            L.set_exact_solver(solver)
            for _ in range(5):
                L.step(0.1)
            L.set_tolerance("rel_joint", 2.0 ** -10)
            stats = L.solve()
            result.append((L.accelerations().copy(), stats.computed_joints, stats.error_bound))
    assert result[0][1] == result[1][1]
    assert rel_err(result[0][0], result[1][0]) <= 1e-10
    assert abs(result[0][2] - result[1][2]) <= 1e-10 * result[1][2]


def test_exact_solver_errors():
    with aqs.Linkage() as L:
        assert L.exact_solver == "aba"
        with pytest.raises(aqs.InvalidArgument, match="solver"):
            L.set_exact_solver("lu")
        with pytest.raises(aqs.InvalidArgument, match="solver = 7"):
            L.set_exact_solver(7)
        assert L.exact_solver == "aba"
        L.set_exact_solver(aqs.EXACT_DCA)  # before finalize too
        assert L.exact_solver == "dca"


@pytest.mark.parametrize("name", ["chain-300-tip-load", "tree-200-floating-local-load"])
def test_auto(name):
    """set_auto / auto (on by default): bad values raise and change nothing;
    the first solve after the tolerance is set is adaptive, the next ones
    are chosen by the cost model (SolveStats.path, auto_chosen, the two
    predicted costs, the cheaper one taken); a step on the exact path
    reports bound 0 and equals an exact linkage's solve at the same state
    (both the articulated-body algorithm); off: adaptive throughout."""
    case, _, _ = exact(name)
    with build(aqs, case) as L, build(aqs, case) as X:
        assert L.auto is True
        for bad in (2, -1, 0.5, "yes"):
            with pytest.raises((aqs.InvalidArgument, TypeError)):
                L.set_auto(bad)
        assert L.auto is True
        L.set_tolerance("rel_joint", 2.0 ** -20)
        first = L.solve()
        assert first.path == "adaptive" and not first.auto_chosen
        assert first.cost_adaptive == 0.0 == first.cost_exact
        paths = set()
        for _ in range(4):
            X.set_positions(L.positions())  # the exact twin at the state the step starts from
            X.solve()
            stats = L.step(1e-4)
            assert stats.auto_chosen
            assert stats.cost_adaptive > 0.0 and stats.cost_exact > 0.0
            if stats.path == "exact_aba":  # never when the adaptive path is predicted cheaper
                assert stats.cost_adaptive >= stats.cost_exact
            paths.add(stats.path)
            if stats.path == "exact_aba":
                assert stats.error_bound == 0.0 and not stats.fallback
                assert stats.computed_joints == stats.counted_joints
                # the same algorithm on the same state (set_positions renormalizes
                # a quaternion: last bits)
                assert rel_err(L.accelerations(), X.accelerations()) <= 1e-12
            else:
                assert stats.error_bound <= 2.0 ** -20
        # a few hundred joints: the articulated-body step is cheaper than an
        # adaptive one (each node costs ~10x an ABA joint), so the model goes exact
        assert paths == {"exact_aba"}
        L.set_auto(False)
        assert L.auto is False
        for _ in range(2):
            stats = L.step(1e-4)
            assert stats.path == "adaptive" and not stats.auto_chosen
            assert stats.error_bound <= 2.0 ** -20
        L.set_auto(1)
        assert L.auto is True
def _measure_diff(metric, case, a, b):
    """The measure of aqs.h applied to the difference a - b over every counted joint."""
    slices = joint_slices(case)
    err = [np.linalg.norm(a[slices[k][1]] - b[slices[k][1]]) for k in counted(case)]
    ref = [np.linalg.norm(b[slices[k][1]]) for k in counted(case)]
    if metric in ("abs_linkage", "rel_linkage"):
        e = math.sqrt(sum(x * x for x in err))
        return e / math.sqrt(sum(x * x for x in ref)) if metric == "rel_linkage" else e
    return max(err) / max(ref) if metric == "rel_joint" else max(err)


@pytest.mark.parametrize("metric", METRICS)
def test_rounding_bound_and_certified(metric):
    """SolveStats.rounding_bound and certified (aqs.h, docs/api.md "What the bound
    covers"): the exact ABA does not estimate its rounding (inf, not certified);
    the exact DCA's estimate covers its distance to the ABA (an independent solver,
    ~1e-15 off on this benign tree, far below the estimate); adaptive solves are
    certified with 0 < rounding_bound <= eps, and not certified when eps is below
    the rounding; the "phi" form is never certified."""
    case, acc_aba, _ = exact("tree-60-mixed")
    with build(aqs, case) as L:
        st = L.solve()  # exact, articulated-body algorithm
        assert st.certified is False and st.rounding_bound == INF
        L.set_exact_solver("dca")
        L.set_tolerance(metric, 0.0)
        st = L.solve()
        assert st.certified is True and 0.0 < st.rounding_bound < 1e-9
        assert _measure_diff(metric, case, L.accelerations(), acc_aba) <= st.rounding_bound
        L.set_exact_solver("aba")
        for k in (1, 10, 20, 30):
            st = L.set_tolerance(metric, 2.0 ** -k) or L.solve()
            assert st.certified is True, (k, st)
            assert 0.0 < st.rounding_bound <= 2.0 ** -k
            assert math.isfinite(st.error_bound + st.rounding_bound)
        L.set_tolerance(metric, 1e-300)  # below any rounding: computed, but not certified
        st = L.solve()
        assert st.error_bound == 0.0 and st.certified is False and st.rounding_bound > 1e-300
        refined = L.refine(1e-301)
        assert refined.certified is False
    phi = aqs.Linkage()
    phi.set_dca_form("phi")
    with build(aqs, case, linkage=phi) as L:
        L.set_tolerance(metric, 2.0 ** -10)
        st = L.solve()
        assert st.certified is False and st.rounding_bound == INF
