"""aqs-bench on a tiny molecule: the JSON Lines schema and its internal consistency.

No timing value is asserted (the machine is shared); only the structure of the
output, identities between its fields, and facts that hold whatever the speed.
Run by `make check-bench` (part of `make check`) with AQS_BENCH set to the program.
"""
import csv
import json
import math
import os
import subprocess

import pytest

BENCH = os.environ.get("AQS_BENCH", "build/bench/aqs-bench")

REQUIRED = {
    "run_id": str, "time": str, "version": str, "scene": str, "joints": int, "bodies": int,
    "tree_nodes": int, "tree_height": int, "handles_mean": float, "handles_max": int,
    "forces": int, "force_seed": int, "metric": str, "eps": (int, float),
    "steps": int, "repeats": int, "ms_per_step": float, "exact_ms_per_step": float,
    "exact_us_per_joint": float, "exact_dca_ms_per_step": float, "speedup_dca": float,
    "exact_ref_ms_per_step": float, "speedup": float, "computed_joints": float,
    "nodes_updated": float, "nodes_processed": float, "displacement_error": (int, float),
    "max_error_bound": (int, float), "ratio_R": float, "peak_rss_bytes": int,
    "exact_linkage_bytes": int, "adaptive_linkage_bytes": int, "finalize_s": float,
    "exact_rss_bytes": int, "adaptive_rss_bytes": int,
    "fallback": (int, float), "fallback_steps": int,
    "prediction": (int, float), "nodes_predicted": (int, float), "factors_updated": (int, float),
    "dca_form": str,
    "ratio_R_aba": float,
    "auto": bool, "auto_exact_steps": int, "auto_cost_adaptive": (int, float),
    "auto_cost_exact": (int, float),
    "displacement_error_per_step": (int, float), "displacement_error_mean": (int, float),
    "displacement_checkpoints": int,
}


def run(*args, check=True):
    return subprocess.run([BENCH, *args], capture_output=True, text=True, check=check,
                          timeout=120)


@pytest.fixture(scope="module")
def lines(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench") / "tiny.jsonl"
    res = run("--scene", "molecule", "--joints", "500", "--steps", "3", "--eps", "0,2^-10",
              "--forces", "1,10", "--repeats", "2", "--out", str(out))
    assert "assembly tree:" in res.stdout and "handles per node" in res.stdout
    with open(out) as f:
        return [json.loads(line) for line in f]


def test_one_object_per_configuration(lines):
    assert [(d["forces"], d["eps"]) for d in lines] == [
        (1, 0), (1, 2.0 ** -10), (10, 0), (10, 2.0 ** -10)]
    assert len({d["run_id"] for d in lines}) == 1


def test_schema(lines):
    for d in lines:
        for key, typ in REQUIRED.items():
            assert key in d, key
            assert isinstance(d[key], typ), (key, d[key])
        assert d["scene"] == "molecule" and d["metric"] == "rel_joint"
        assert d["joints"] == 500 and d["bodies"] == 500
        assert d["steps"] == 3 and d["repeats"] == 2
        assert d["tree_nodes"] == 2 * d["joints"] + 1
        assert d["tree_height"] >= math.log2(d["joints"])
        assert 1 <= d["handles_mean"] <= d["handles_max"]
        assert d["eps_log2"] == (10 if d["eps"] > 0 else None)


def test_consistency(lines):
    for d in lines:
        assert d["ms_per_step"] > 0 and d["exact_ms_per_step"] > 0
        assert d["exact_dca_ms_per_step"] > 0
        assert d["speedup"] == pytest.approx(d["exact_ms_per_step"] / d["ms_per_step"],
                                             rel=1e-6)
        assert d["speedup_dca"] == pytest.approx(d["exact_dca_ms_per_step"] / d["ms_per_step"],
                                                 rel=1e-6)
        assert d["exact_us_per_joint"] == pytest.approx(
            1e3 * d["exact_ms_per_step"] / d["joints"], rel=1e-6)
        # R's time per tree node is the exact DCA step's
        assert d["exact_us_per_node"] == pytest.approx(
            1e3 * d["exact_dca_ms_per_step"] / d["tree_nodes"], rel=1e-6)
        log2n = math.log2(d["joints"])
        t_node = d["exact_dca_ms_per_step"] / d["tree_nodes"]
        assert d["ratio_R"] == pytest.approx(
            d["ms_per_step"] / ((d["computed_joints"] + d["forces"] * log2n) * t_node), rel=1e-6)
        # the same against the articulated-body step's time per joint
        t_joint = d["exact_ms_per_step"] / d["joints"]
        assert d["ratio_R_aba"] == pytest.approx(
            d["ms_per_step"] / ((d["computed_joints"] + d["forces"] * log2n) * t_joint), rel=1e-6)
        assert 0 < d["computed_joints"] <= d["max_computed_joints"] <= d["joints"]
        assert d["nodes_processed"] <= d["tree_nodes"]
        assert d["peak_rss_bytes"] > 0
        # held by each linkage (aqs_linkage_get_memory): the tolerance adds the DCA's storage
        assert 0 < d["exact_linkage_bytes"] < d["adaptive_linkage_bytes"]
        assert d["displacement_error"] >= 0 and d["max_displacement"] > 0


def test_exact_configuration(lines):
    for d in (d for d in lines if d["eps"] == 0):
        # eps = 0: every joint computed, the same trajectory as the exact run.
        assert d["displacement_error"] == 0
        assert d["computed_joints"] == d["joints"]
        assert d["max_error_bound"] == 0


def test_adaptive_configuration(lines):
    for d in (d for d in lines if d["eps"] > 0):
        # the certified bound of every step is within eps, and fewer joints are
        # computed than in the exact run
        assert d["max_error_bound"] <= d["eps"]
        assert d["computed_joints"] < d["joints"]


def test_displacement_error_recomputed(tmp_path):
    """displacement_error recomputed independently through the Python bindings:
    chain30 exported as URDF, the same tip force, dt and steps, exact and
    adaptive from the straight start; max_i |d_i - d_i^exact| / max_i |d_i^exact|
    over the links' centres of mass. Both runs are deterministic, so the two
    computations agree to the 9 significant digits the JSON carries (1e-8)."""
    aqs = pytest.importorskip("aqs")
    np = pytest.importorskip("numpy")
    out, urdf = tmp_path / "c.jsonl", tmp_path / "chain30.urdf"
    run("--scene", "chain30", "--steps", "40", "--eps", "2^-4", "--quiet", "--out", str(out))
    run("--scene", "chain30", "--export-urdf", str(urdf))
    with open(out) as f:
        d = json.loads(f.readline())
    assert d["eps"] == 2.0 ** -4 and d["computed_joints"] < 30

    def com_positions(eps):
        with aqs.load_urdf(str(urdf)) as L:
            L.set_auto(False)  # the adaptive solver, as aqs-bench measures it by default
            L.set_body_force(29, (0, 1, 0), point=(1, 0, 0))
            L.set_tolerance("rel_joint", eps)
            track = []
            for k in range(41):
                poses = [L.body_pose(b) for b in range(30)]
                track.append(np.array([p + aqs_rotate(q, (0.5, 0, 0)) for p, q in poses]))
                if k < 40:
                    L.step(d["dt"])
            return np.array(track) - track[0]  # displacements after 0 .. 40 steps

    def aqs_rotate(q, v):
        w, x, y, z = q
        R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        return R @ np.asarray(v, dtype=float)

    exact, approx = com_positions(0.0), com_positions(2.0 ** -4)
    errs = [np.max(np.linalg.norm(approx[k] - exact[k], axis=1)) / np.max(np.linalg.norm(exact[k], axis=1))
            for k in range(1, 41)]
    err = errs[-1]
    assert err > 0
    assert d["displacement_error"] == pytest.approx(err, rel=1e-8)
    # the two readings of the paper's "per time step": final / steps, and the
    # mean over the steps of the error after each (every step a checkpoint)
    assert d["displacement_checkpoints"] == 40
    assert d["displacement_error_per_step"] == pytest.approx(err / 40, rel=1e-8)
    assert d["displacement_error_mean"] == pytest.approx(np.mean(errs), rel=1e-7)


def test_fallback(tmp_path):
    """--fallback: steps after one that computed more than the fraction of the
    joints are exact (fallback_steps counts them; every 16th is adaptive)."""
    out = tmp_path / "fb.jsonl"
    run("--joints", "300", "--steps", "20", "--eps", "1e-13", "--forces", "10", "--quiet",
        "--fallback", "0.5", "--out", str(out))
    run("--joints", "300", "--steps", "20", "--eps", "1e-13", "--forces", "10", "--quiet",
        "--append", "--out", str(out))
    on, off = [json.loads(line) for line in out.read_text().splitlines()]
    assert on["fallback"] == 0.5 and off["fallback"] == 0
    assert on["fallback_steps"] >= 15 and off["fallback_steps"] == 0
    assert on["computed_joints"] > off["computed_joints"] / 2


def test_prediction(tmp_path):
    """--prediction: on by default (1024), nodes predicted and factors skipped
    after the first step; --prediction 0 predicts nothing and updates every
    factor; the same joints are computed either way (the loads do not change
    during a run, so the prediction is right)."""
    out = tmp_path / "pred.jsonl"
    args = ("--joints", "2000", "--steps", "10", "--eps", "2^-19", "--forces", "10", "--quiet")
    run(*args, "--out", str(out))
    run(*args, "--prediction", "0", "--append", "--out", str(out))
    on, off = [json.loads(line) for line in out.read_text().splitlines()]
    assert on["prediction"] == 1024 and off["prediction"] == 0
    assert on["nodes_predicted"] > 0 and off["nodes_predicted"] == 0
    assert on["factors_updated"] < on["nodes_updated"]
    assert off["factors_updated"] == off["nodes_updated"]
    assert on["computed_joints"] == off["computed_joints"]


def test_tip_path(tmp_path):
    tip = tmp_path / "tip.csv"
    run("--scene", "chain30", "--steps", "4", "--eps", "2^-5", "--tip-path", str(tip),
        "--quiet")
    with open(tip) as f:
        rows = list(csv.DictReader(f))
    assert [r["run"] for r in rows] == ["exact"] * 5 + ["adaptive"] * 5
    assert [int(r["step"]) for r in rows] == list(range(5)) * 2
    # chain30 starts straight along +x: its tip at (30, 0, 0), and the tip force
    # is along +y, so the tip moves towards +y
    x0, y0 = float(rows[0]["x"]), float(rows[0]["y"])
    assert x0 == pytest.approx(30.0, abs=1e-12) and y0 == pytest.approx(0.0, abs=1e-12)
    assert float(rows[4]["y"]) > 0


@pytest.mark.parametrize("args,message", [
    (["--bogus"], "unknown option"),
    (["--steps", "x"], "--steps"),
    (["--steps", "0"], "--steps"),
    (["--eps", "-1"], "--eps"),
    (["--eps", "2^-5..3"], "--eps"),
    (["--scene", "teapot"], "unknown scene"),
    (["--metric", "worst"], "unknown measure"),
    (["--forces", "1,,"], "--forces"),
    (["--forces", "31", "--scene", "chain30"], "forces"),
    (["--steps"], "needs a value"),
    (["--fallback", "1.5"], "--fallback"),
    (["--prediction", "0.5"], "--prediction"),
    (["--dca-form", "cholesky"], "--dca-form"),
    (["--auto", "maybe"], "--auto"),
])
def test_bad_input(args, message):
    res = run("--joints", "200", "--quiet", *args, check=False)
    assert res.returncode != 0
    assert message in res.stderr


def test_dca_form(tmp_path):
    """--dca-form phi and sqrt (the default): the same scene and loads, the
    same joints computed to within the rounding of the two forms, and the
    form recorded in the JSON."""
    out = tmp_path / "forms.jsonl"
    args = ("--scene", "molecule", "--joints", "400", "--steps", "3", "--exact-every", "3",
            "--quiet", "--eps", "2^-10")
    run(*args, "--out", str(out))
    run(*args, "--dca-form", "phi", "--append", "--out", str(out))
    sq, ph = [json.loads(x) for x in out.read_text().splitlines()]
    assert sq["dca_form"] == "sqrt" and ph["dca_form"] == "phi"
    assert abs(sq["computed_joints"] - ph["computed_joints"]) <= 0.02 * max(1.0, ph["computed_joints"])


def test_auto(tmp_path):
    """--auto on: with 100 forces on a 2,000-joint molecule the exact step is
    cheaper and every step after the first solve is exact (auto_exact_steps,
    its predicted costs in the JSON, bound 0); --auto off (the default): the
    adaptive solver alone, as before."""
    out = tmp_path / "auto.jsonl"
    args = ("--joints", "2000", "--steps", "6", "--forces", "100", "--quiet", "--eps", "2^-19")
    run(*args, "--auto", "on", "--out", str(out))
    run(*args, "--append", "--out", str(out))
    on, off = [json.loads(x) for x in out.read_text().splitlines()]
    assert on["auto"] is True and off["auto"] is False
    assert on["auto_exact_steps"] == 6 and off["auto_exact_steps"] == 0
    assert on["auto_cost_adaptive"] > on["auto_cost_exact"] > 0
    assert off["auto_cost_adaptive"] == 0 == off["auto_cost_exact"]
    assert on["max_error_bound"] == 0 and on["computed_joints"] == on["joints"]
    assert off["max_error_bound"] <= 2.0 ** -19


def test_export_urdf(tmp_path):
    """--export-urdf writes the scene as URDF and benchmarks nothing. The file
    loads back (aqs.load_urdf) as chain30's 30 bodies and joints; pulled
    sideways at its tip, the straight chain's accelerations are finite and
    largest at the tip joint. (The exporter's round-trip accuracy against the
    C-built scenes is tested in tests/python/test_urdf_bench.py.)"""
    aqs = pytest.importorskip("aqs")
    np = pytest.importorskip("numpy")
    path = tmp_path / "chain30.urdf"
    res = run("--scene", "chain30", "--export-urdf", str(path))
    assert "wrote" in res.stdout and "ms/step" not in res.stdout
    with aqs.load_urdf(str(path)) as L:
        nb, nj, nq, nv = L.sizes()
        assert (nb, nj, nq, nv) == (30, 30, 30, 30)
        L.set_body_force(29, (0, 1, 0), point=(1, 0, 0))
        L.solve()
        qdd = L.accelerations()
        assert np.all(np.isfinite(qdd)) and abs(qdd[-1]) == np.max(np.abs(qdd))
    bad = run("--scene", "chain30", "--export-urdf", str(tmp_path / "no" / "x.urdf"), check=False)
    assert bad.returncode != 0 and "cannot open" in bad.stderr
