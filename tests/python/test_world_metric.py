"""The world-space measures (aqs.h AQS_METRIC_ABS_WORLD / _REL_WORLD,
docs/math.md section 10b) through the bindings.

The reference is independent of the library's kinematics: the body motion an
acceleration vector d causes is taken by central differences of the bodies'
world poses at q +- h d (revolute and prismatic joints only, so q and qdd
share their coordinates), and the true error of an adaptive solve is that of
d = exact - adaptive accelerations. e_b = |delta a_b| + ell_b |delta alpha_b|
with ell_b = sqrt(tr(I_b) / (2 m_b)).
"""

import math

import numpy as np
import pytest

import aqs

H = 1e-6


def quat_matrix(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def build(seed, n, chain=False):
    rng = np.random.default_rng(seed)
    L = aqs.Linkage()
    L.set_exact_solver("dca")  # the twin back-substitutes the same coefficients
    coms, ells = [], []
    for i in range(n):
        m = math.exp(rng.uniform(-1, 1))
        com = rng.uniform(-0.3, 0.3, 3)
        inertia = np.diag(0.1 * m * rng.uniform(0.6, 1.0, 3))
        L.add_body(m, com, inertia)
        coms.append(com)
        ells.append(math.sqrt(np.trace(inertia) / (2 * m)))
    for i in range(n):
        parent = aqs.WORLD if i == 0 else (i - 1 if chain else int(rng.integers(max(0, i - 4), i)))
        kind = "prismatic" if i % 5 == 3 else "revolute"
        L.add_joint(kind, parent, i, pos=rng.uniform(-0.8, 0.8, 3), axis=rng.uniform(-1, 1, 3))
    L.finalize()
    L.set_positions(rng.uniform(-1.5, 1.5, L.nq))
    L.set_gravity((0.0, -9.81, 0.0))
    for b in rng.choice(n, size=3, replace=False):
        L.set_body_force(int(b), rng.uniform(-5, 5, 3))
    return L, np.array(coms), np.array(ells)


def body_state(L, coms):
    poses = L.body_poses()
    R = np.array([quat_matrix(p[3:7]) for p in poses])
    return poses[:, :3] + np.einsum("bij,bj->bi", R, coms), R


def world_measure(L, coms, ells, d):
    """max_b |a_b| + ell_b |alpha_b| of the motion of d, by central differences."""
    q = L.positions()
    L.set_positions(q + H * d)
    cp, Rp = body_state(L, coms)
    L.set_positions(q - H * d)
    cm, Rm = body_state(L, coms)
    L.set_positions(q)
    lin = (cp - cm) / (2 * H)
    M = np.einsum("bij,bkj->bik", Rp, Rm)  # exp(2h skew(alpha))
    ang = np.stack([M[:, 2, 1] - M[:, 1, 2], M[:, 0, 2] - M[:, 2, 0], M[:, 1, 0] - M[:, 0, 1]], 1) / (4 * H)
    return float(np.max(np.linalg.norm(lin, axis=1) + ells * np.linalg.norm(ang, axis=1)))


def test_names_and_constants():
    assert aqs.METRICS["abs_world"] == aqs.METRIC_ABS_WORLD == 4
    assert aqs.METRICS["rel_world"] == aqs.METRIC_REL_WORLD == 5
    L, _, _ = build(1, 10)
    with pytest.raises(aqs.InvalidArgument, match="metric"):
        L.set_tolerance("world", 0.1)
    with pytest.raises(aqs.InvalidArgument, match="metric = 6"):
        L.set_tolerance(6, 0.1)
    L.set_tolerance(aqs.METRIC_REL_WORLD, 0.25)
    assert L.solve().metric == "rel_world"
    L.close()


@pytest.mark.parametrize("metric", ["abs_world", "rel_world"])
@pytest.mark.parametrize("seed,n,chain", [(3, 40, False), (4, 60, True), (5, 80, False)])
def test_bound_holds(metric, seed, n, chain):
    L, coms, ells = build(seed, n, chain)
    L.set_tolerance(metric, 0.0)
    exact = L.solve() and L.accelerations()
    scale = world_measure(L, coms, ells, exact)
    assert scale > 0
    skipped = 0
    for k in (0, 2, 4, 6, 8, 10, 14, 20):
        L.set_tolerance(metric, 2.0 ** -k)
        stats = L.solve()
        assert stats.error_bound <= 2.0 ** -k
        skipped += stats.computed_joints < stats.counted_joints
        err = world_measure(L, coms, ells, exact - L.accelerations())
        if metric == "rel_world":
            err /= scale
        # central differences: relative 1e-6 of the motion's scale
        slack = 1e-6 * (1.0 if metric == "rel_world" else scale)
        assert err <= stats.error_bound * (1 + 1e-9) + slack, (k, err, stats)
    assert skipped > 0  # the tolerances left joints out
    L.close()


@pytest.mark.parametrize("metric", ["abs_world", "rel_world"])
def test_world_measures_rounding_estimate(metric):
    """The rounding estimate covers the world measures (docs/math.md 10b,
    "Rounding"): on a benign random tree the solve is certified, with a finite
    rounding_bound <= eps, and error_bound + rounding_bound bounds the error
    measured by finite differences against the exact DCA; at an eps below
    the estimate (2^-50) it is not certified."""
    L, coms, ells = build(3, 40)
    with L:
        L.set_auto(False)
        L.set_tolerance(metric, 0.0)
        exact = L.solve() and L.accelerations()
        scale = world_measure(L, coms, ells, exact)
        L.set_tolerance(metric, 2.0 ** -10)
        s = L.solve()
        assert s.metric == metric
        assert s.certified is True and math.isfinite(s.rounding_bound) and 0 < s.rounding_bound <= 2.0 ** -10
        err = world_measure(L, coms, ells, exact - L.accelerations())
        if metric == "rel_world":
            err /= scale
        slack = 1e-6 * (1.0 if metric == "rel_world" else scale)  # central differences
        assert err <= (s.error_bound + s.rounding_bound) * (1 + 1e-9) + slack
        L.set_tolerance(metric, 2.0 ** -50)
        s = L.solve()
        assert s.certified is False and s.rounding_bound > 2.0 ** -50
