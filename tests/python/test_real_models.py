"""Real robot models (issue 12, item 3): the URDFs of the PyPI package
example-robot-data (69 files: arms, quadrupeds, humanoids, hands), loaded
through aqs.load_urdf, each solved by the articulated-body (ABA) and DCA exact
solvers and the adaptive solver (four measures, eps 2^-5, 2^-10, 2^-19), and
compared with the extended-precision reference of
tests/reference/hard_reference.hpp (__float128 articulated-body algorithm that
reads the model back through the public C API; build/tests/reference/
libhardref.so, passed as AQS_HARDREF by `make check-python`).

The state: gravity (0, 0, -9.81), every revolute / prismatic / continuous
joint at a seeded random position in (-1, 1), a seeded random joint force
(up to 1) on every dof, free roots as loaded.

Checked, with the thresholds of tests/reference/hardcases.cpp:
- ABA: ||qdd - ref|| / ||ref|| <= ABA_TOL;
- DCA: status OK and its error <= DCA_VS_ABA x max(ABA's error, 1e-15);
- adaptive: the true value of the measure (its formula on qdd - ref over every
  counted joint) <= error_bound (1 + 1e-9) + ADAPTIVE_ROUNDING x the ABA's
  error in that measure.
Models in KNOWN_BAD fail the DCA / adaptive checks on main at 90aa04b: they
are reported as xfail (not asserted); remove them once the DCA is fixed.
Models the loader refuses are reported as skips with the loader's reason
(test_corpus_load_outcomes checks that each refusal is a clear URDFError).
"""

import ctypes
import importlib.metadata
import os

import numpy as np
import pytest

import aqs
from aqs import urdf as aqs_urdf

ABA_TOL = 1e-9
# Constraint forces (issue 12, item 3: every output against the reference): the largest joint's
# error over the largest joint force, against the reference's (Newton-Euler from its own
# accelerations, in __float128). Measured 2026-12-04 on the 65 loaded models and regularized
# ones: the ABA's 7.4e-18 .. 9.7e-13 (median 1.6e-16; the worst the iCub with inertias
# floored at 1e-10 / 1e-16 of the mass), the exact DCA's at most 1.1x max(the ABA's, ERR_FLOOR)
# (3.4e-13 on that iCub at 1e-16, where the refinement's first step was not kept and the
# inverse dynamics' forces were taken; docs/math.md §13a). The DCA's asserted within
# DCA_VS_ABA x max(the ABA's, ERR_FLOOR), like its accelerations.
ABA_FORCE_TOL = 1e-9
DCA_VS_ABA = 10.0
ADAPTIVE_ROUNDING = 10.0
ERR_FLOOR = 1e-15
EPS = (2.0 ** -5, 2.0 ** -10, 2.0 ** -19)
METRICS = ("abs_linkage", "rel_linkage", "abs_joint", "rel_joint")

# Measured with the default (square-root) DCA form on 2026-12-02 (docs/hardcases.md, "Real
# models"): the DCA is 40-90x the ABA's error there (1.1e-14 .. 2.8e-14 against 2e-16 ..
# 6e-16), and the adaptive bound is exceeded by that rounding. (On main at 90aa04b, with the
# inverse-inertia form: alexander_v1, double_pendulum_simple, kinova, ur5_robot.)
# Since 2026-12-03 (adaptive solves that compute every joint are refined, docs/math.md 13a)
# all three pass and are asserted.
KNOWN_BAD = set()


def _find_urdfs():
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    return sorted(str(dist.locate_file(f)) for f in (dist.files or ())
                  if str(f).endswith(".urdf"))


URDFS = _find_urdfs()
pytestmark = pytest.mark.skipif(
    URDFS is None, reason="PyPI package example-robot-data not installed (tools/deps.sh installs it)")


def _model_id(path):
    parts = path.split("/")
    return parts[-1] if parts[-1] != "anymal.urdf" else parts[-3] + "/" + parts[-1]


@pytest.fixture(scope="module")
def hardref():
    path = os.environ.get("AQS_HARDREF")
    if not path or not os.path.exists(path):
        pytest.skip("AQS_HARDREF (build/tests/reference/libhardref.so) not set: run through make check-python")
    lib = ctypes.CDLL(path)
    dp = ctypes.POINTER(ctypes.c_double)
    f = lib.hardref_solve_forces
    f.restype = ctypes.c_int
    f.argtypes = [ctypes.c_void_p, dp, dp, ctypes.c_int32, ctypes.c_int32, dp, ctypes.c_int32,
                  dp, ctypes.c_int32, ctypes.c_char_p, ctypes.c_int32]

    def solve(L, gravity, tau, precision=1, forces=False):
        """The reference's accelerations (nv), and with forces=True also its constraint
        forces (joints, 6)."""
        nv = L.nv
        qdd = np.zeros(nv)
        fr = np.zeros((L.num_joints, 6))
        g = np.ascontiguousarray(gravity, dtype=np.float64)
        t = np.ascontiguousarray(tau, dtype=np.float64)
        err = ctypes.create_string_buffer(512)
        with L._lock:  # the binding's per-Linkage lock: the handle stays valid during the call
            assert L._handle is not None, "closed linkage"
            rc = f(L._handle, g.ctypes.data_as(dp), t.ctypes.data_as(dp), len(t), precision,
                   qdd.ctypes.data_as(dp), nv, fr.ctypes.data_as(dp), fr.size, err, len(err))
        assert rc == 0, err.value.decode()
        return (qdd, fr) if forces else qdd
    return solve


def _force_error(f, fref):
    """The largest joint's constraint-force error over the largest joint force (2-norms of
    the rows)."""
    return float(np.max(np.linalg.norm(f - fref, axis=1)) / max(np.max(np.linalg.norm(fref, axis=1)), 1e-300))


def _load(path):
    try:
        return aqs_urdf.load_urdf(path), None
    except aqs_urdf.URDFError as exc:
        return None, str(exc)


def test_corpus_load_outcomes():
    """Which models load; every refusal is a URDFError naming the file and what is wrong."""
    loaded, refused = [], []
    for p in URDFS:
        L, why = _load(p)
        if L is None:
            refused.append((_model_id(p), why))
            assert why.startswith(p), why
            assert ("link '" in why or "joint '" in why or "no <link>" in why or
                    "body " in why), why  # finalize names the body (its link's name)
        else:
            loaded.append(_model_id(p))
            L.close()
    # 35 of 69 loaded on main at 90aa04b; 63 with the C loader (docs/hardcases.md, docs/urdf.md).
    assert len(URDFS) >= 60
    assert len(loaded) >= 30, (loaded, refused)


def _joint_slots(L):
    slots = []
    for j in range(L.num_joints):
        lay = L.joint_layout(j)
        kind = L.joint_definition(j).kind
        slots.append((lay.v_offset, lay.nv, kind not in ("free", "fixed")))
    return slots


def _measure(metric, x, ref, slots, computed=None):
    """The measure's formula on x - ref over counted joints (computed=None), or on ref over
    the uncomputed ones."""
    e, r = [], []
    for j, (o, n, counted) in enumerate(slots):
        if not counted:
            continue
        rj = np.linalg.norm(ref[o:o + n])
        r.append(rj)
        e.append(np.linalg.norm(x[o:o + n] - ref[o:o + n]) if computed is None
                 else (0.0 if computed[j] else rj))
    e, r = np.array(e), np.array(r)
    if len(e) == 0:
        return 0.0
    if metric == "abs_linkage":
        return float(np.sqrt(np.sum(e * e)))
    if metric == "rel_linkage":
        return float(np.sqrt(np.sum(e * e)) / max(np.sqrt(np.sum(r * r)), 1e-300))
    if metric == "abs_joint":
        return float(e.max())
    return float(e.max() / max(r.max(), 1e-300))


@pytest.mark.parametrize("path", URDFS or [], ids=[_model_id(p) for p in (URDFS or [])])
def test_model_against_reference(path, hardref):
    name = _model_id(path)
    L, why = _load(path)
    if L is None:
        pytest.skip("refused by aqs.load_urdf: " + why[len(path) + 2:])
    _check_model(name, L, hardref, KNOWN_BAD)


# Regularized variants of the refused models, as a user would make them load: <mimic>
# removed (the coupled joints become independent), and every inertia of a link with mass
# made positive definite and physical: its symmetric part's principal moments raised to at
# least floor x mass (kg m^2 per kg: near-point masses; floor 1e-10 m^2 is a radius of
# gyration of 10 um, 1e-16 m^2 one of 10 nm) and to the triangle inequality. Near-point
# masses on real robots: the "regularized humanoid" row.
REG_FLOORS = (1e-10, 1e-16)
# Square-root form, 2026-12-02: icub 1.4e-11 / 1.5e-5, icub_reduced 4.9e-9 / 2.7e-3 (floors
# 1e-10 / 1e-16; the ABA 1e-12 / 4e-16). With the inverse-inertia form (90aa04b) also b1,
# panda and talos_left_arm failed.
# Since 2026-12-03 the 1e-10 floors pass (asserted); at 1e-16 the exact DCA (GMRES-refined)
# is within the ABA's error (2.6e-13, 4.0e-16), but 1 and 3 of the 12 adaptive solves that
# skip joints exceeded their bound by more than 10x the ABA's error (not certified there).
# Since the rounding fallback (2026-12-03) those solves are the ABA's: 0 problems, asserted.
KNOWN_BAD_REGULARIZED = set()


def _regularize(path, out, floor):
    import xml.etree.ElementTree as ET
    tree = ET.parse(path)
    robot = tree.getroot()
    for joint in robot.findall("joint"):
        for mimic in joint.findall("mimic"):
            joint.remove(mimic)
    changed = 0
    for link in robot.findall("link"):
        inertial = link.find("inertial")
        if inertial is None or inertial.find("mass") is None or inertial.find("inertia") is None:
            continue
        mass = float(inertial.find("mass").get("value", "0"))
        if mass <= 0:
            continue
        el = inertial.find("inertia")
        v = {k: float(el.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        inertia = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]],
                            [v["ixz"], v["iyz"], v["izz"]]])
        w, V = np.linalg.eigh(inertia)
        w2 = np.maximum(w, floor * mass)
        w2[2] = min(w2[2], w2[0] + w2[1])  # triangle inequality (sorted ascending)
        if np.allclose(w, w2, rtol=1e-9, atol=0):
            continue
        changed += 1
        r = V @ np.diag(w2) @ V.T
        for k, (i, j) in {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1),
                          "iyz": (1, 2), "izz": (2, 2)}.items():
            el.set(k, repr(float(r[i, j])))
    tree.write(out)
    return changed


REFUSED = []
for _p in URDFS or []:
    _L, _why = _load(_p)
    if _L is None:
        REFUSED.append(_p)
    else:
        _L.close()


@pytest.mark.parametrize("floor", REG_FLOORS, ids=["reg%g" % f for f in REG_FLOORS])
@pytest.mark.parametrize("path", REFUSED, ids=[_model_id(p) for p in REFUSED])
def test_regularized_model_against_reference(path, floor, hardref, tmp_path):
    name = _model_id(path) + "+reg%g" % floor
    out = str(tmp_path / "model.urdf")
    _regularize(path, out, floor)
    L, why = _load(out)
    if L is None:
        pytest.skip("refused even regularized: " + why[len(out) + 2:])
    _check_model(name, L, hardref, KNOWN_BAD_REGULARIZED)


def _check_model(name, L, hardref, known_bad):
    with L:
        if L.nv == 0:
            pytest.skip("no degrees of freedom")
        rng = np.random.default_rng(sum(map(ord, name)))  # seeded by the model's name
        q = L.positions()
        for j in range(L.num_joints):
            lay = L.joint_layout(j)
            if L.joint_definition(j).kind in ("revolute", "prismatic"):
                q[lay.q_offset] = rng.uniform(-1, 1)
        L.set_positions(q)
        gravity = np.array([0.0, 0.0, -9.81])
        L.set_gravity(gravity)
        tau = rng.uniform(-1, 1, L.nv)
        for j in range(L.num_joints):
            lay = L.joint_layout(j)
            if lay.nv:
                L.set_joint_force(j, tau[lay.v_offset:lay.v_offset + lay.nv])
        ref, fref = hardref(L, gravity, tau, 1, forces=True)
        ref_ld = hardref(L, gravity, tau, 0)
        nref = np.linalg.norm(ref)
        assert np.linalg.norm(ref_ld - ref) <= 1e-12 * nref, "reference: long double vs quad"
        slots = _joint_slots(L)

        L.set_exact_solver("aba")
        L.solve()
        aba = L.accelerations().copy()
        e_aba = np.linalg.norm(aba - ref) / nref
        assert e_aba <= ABA_TOL, "%s: ABA error %.2e" % (name, e_aba)
        f_aba = _force_error(L.constraint_forces(), fref)
        assert f_aba <= ABA_FORCE_TOL, "%s: ABA constraint forces %.2e" % (name, f_aba)

        problems = []
        false_bounds = []  # certified solves whose error_bound + rounding_bound is below the truth

        def bound_holds(what, metric, st, acc):
            true = _measure(metric, acc, ref, slots)
            if st.certified and not true <= (st.error_bound + st.rounding_bound) * (1 + 1e-9):
                false_bounds.append("%s %s: true %.2e > error_bound %.2e + rounding_bound %.2e" %
                                    (what, metric, true, st.error_bound, st.rounding_bound))

        e_dca_report = [None]
        f_dca_report = [None]
        L.set_exact_solver("dca")
        try:
            for metric in METRICS:  # the exact DCA's rounding estimate, in each measure
                L.set_tolerance(metric, 0.0)
                bound_holds("exact DCA", metric, L.solve(), L.accelerations())
            e_dca = np.linalg.norm(L.accelerations() - ref) / nref
            e_dca_report[0] = float(e_dca)
            if e_dca > DCA_VS_ABA * max(e_aba, ERR_FLOOR):
                problems.append("DCA error %.2e vs ABA %.2e" % (e_dca, e_aba))
            f_dca = _force_error(L.constraint_forces(), fref)
            f_dca_report[0] = f_dca
            if not f_dca <= DCA_VS_ABA * max(f_aba, ERR_FLOOR):
                problems.append("DCA constraint forces %.2e vs ABA %.2e" % (f_dca, f_aba))
        except aqs.Error as exc:
            problems.append("DCA: %s" % exc)
        L.set_exact_solver("aba")
        for metric in METRICS:
            allowance = ADAPTIVE_ROUNDING * max(_measure(metric, aba, ref, slots),
                                                ERR_FLOOR * (1.0 if metric.startswith("rel")
                                                             else np.linalg.norm(ref)))
            for eps in EPS:
                try:
                    L.set_tolerance(metric, eps)
                    st = L.solve()
                except aqs.Error as exc:
                    problems.append("adaptive %s eps %g: %s" % (metric, eps, exc))
                    continue
                true = _measure(metric, L.accelerations(), ref, slots)
                bound_holds("adaptive eps %g" % eps, metric, st, L.accelerations())
                if not true <= st.error_bound * (1 + 1e-9) + allowance:
                    problems.append("adaptive %s eps %g: true %.2e > bound %.2e" %
                                    (metric, eps, true, st.error_bound))
            # the bound alone, eps = 2^-1 .. 2^-28, with the rounding fallback off: this
            # validates the adaptive solver's own estimate, which the fallback would
            # replace by exact solves (uncertified, so never a false bound)
            L.set_rounding_fallback(0.0)
            for k in range(1, 31, 3):
                L.set_tolerance(metric, 2.0 ** -k)
                try:
                    st = L.solve()
                except aqs.Error:
                    continue  # reported above
                bound_holds("adaptive eps 2^-%d" % k, metric, st, L.accelerations())
            L.set_rounding_fallback(aqs.ROUNDING_FALLBACK_LEVEL)
            L.set_tolerance(metric, 0.0)
        report = os.environ.get("AQS_REAL_MODELS_REPORT")
        if report:  # one JSON line per model, for docs/hardcases.md
            import json
            with open(report, "a") as fh:
                fh.write(json.dumps(dict(model=name, nv=L.nv, aba=e_aba, dca=e_dca_report[0],
                                         aba_force=f_aba, dca_force=f_dca_report[0],
                                         problems=len(problems), first=problems[:1])) + "\n")
        # Issue 12, item 2: a certified bound holds against the quad reference on every model,
        # known bad or not.
        assert not false_bounds, "%s: %d certified bounds below the truth, first: %s" % (
            name, len(false_bounds), false_bounds[0])
        if problems:
            msg = "%s (ABA %.1e): %d problems, first: %s" % (name, e_aba, len(problems), problems[0])
            if name in known_bad:
                pytest.xfail("known bad on main: " + msg)
            pytest.fail(msg)
