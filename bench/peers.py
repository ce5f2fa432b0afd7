#!/usr/bin/env python3
"""Pinocchio, MuJoCo and aqs side by side on the same model (make peers).

For each scene and size, build/bench/urdf_export (bench/urdf.c) writes the
C-built scene as URDF, with seeded loads and the exact accelerations of the
C-built linkage (gravity (0.5, -9.81, 0.25), 3 body forces with points and
torques, 3 joint forces). A child process, under an address-space limit
(--mem-limit-gb) and a time limit (--timeout), then loads that URDF in aqs
(aqs.load_urdf), Pinocchio (pinocchio.buildModelFromUrdf) and MuJoCo
(mujoco.MjModel.from_xml_path), sets the built configuration (q = 0: every
revolute angle 0, the floating base at its placement), zero velocity, the
same gravity, external forces and joint torques, and compares:

1. accelerations: max_j |qdd_j - qdd_j^aqs| / max_j |qdd_j^aqs| against aqs
   exact (and aqs exact against the C-built linkage);
2. time per solve, medians over repeats, in the one child process:
   Pinocchio pinocchio.aba(model, data, q, 0, tau, fext); MuJoCo
   mujoco.mj_forward (qvel = 0: qacc); aqs exact "full" (set_positions, which
   marks every assembly-tree node stale, then solve: the same work as an
   articulated-body pass from scratch); aqs exact and adaptive *steps* with
   N_f = 1 (gravity off, one 1 N force at a seeded body's origin, rel_joint
   eps = 2^-10 and 2^-19): solve, move, update only the stale nodes, as a
   quasi-static simulation runs.

Conventions bridged (all checked by the accelerations agreeing):
- Pinocchio's continuous joints have q = (cos, sin); its free flyer has
  q = (x y z qx qy qz qw) and ddq = (linear; angular) in the local frame,
  aqs's free joint (angular; linear), so the halves are swapped; external
  forces are one pinocchio.Force (linear, angular) per joint, in the joint's
  local frame about its origin.
- MuJoCo's free joint has qacc = (linear acceleration of the body origin in
  the world frame; angular acceleration in the body frame), and its
  qfrc_applied likewise (world force; local torque); xfrc_applied is
  (force; torque) in the world frame at the body's centre of mass.

Where a peer stops (a memory error, a time-out, an exception), the message
is recorded as a measured fact. One JSON line per (scene, size, engine) is
appended to --out (docs/bench/peers.jsonl) and a table printed.

  python3 bench/peers.py --exporter build/bench/urdf_export \
      [--scenes chain,molecule,millipede] [--sizes 1000,10000,50000] \
      [--engines aqs,pinocchio,mujoco] [--repeats 20] [--steps 30] \
      [--mem-limit-gb 6] [--timeout 900] [--out docs/bench/peers.jsonl]
"""

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
ENGINES = ("aqs", "pinocchio", "mujoco")
ADAPTIVE_EPS_LOG2 = (10, 19)


# ---------------------------------------------------------------------------
# The worker: one scene and size, every engine, in one process
# ---------------------------------------------------------------------------

def emit(record):
    sys.stdout.write(json.dumps(record) + "\n")
    sys.stdout.flush()


def median_time(function, repeats, budget):
    """Median seconds of function() over up to repeats calls (at least 3,
    fewer if budget seconds run out)."""
    import numpy as np
    times = []
    start = time.perf_counter()
    while len(times) < repeats and (len(times) < 3 or time.perf_counter() - start < budget):
        t0 = time.perf_counter()
        function()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), len(times)


def max_rel(a, b):
    import numpy as np
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(np.asarray(b)).max())


def peak_rss_bytes():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


class Problem:
    """The loads of urdf_export's JSON and the aqs layout of the joints."""

    def __init__(self, urdf, loads_path):
        import numpy as np
        with open(loads_path) as handle:
            self.loads = json.load(handle)
        self.urdf = urdf
        self.gravity = np.array(self.loads["gravity"])
        self.qdd_c = np.array(self.loads["qdd"])


def run_aqs(problem, args, state):
    import numpy as np
    import aqs
    t0 = time.perf_counter()
    L = aqs.load_urdf(problem.urdf)
    load_s = time.perf_counter() - t0
    loads = problem.loads
    L.set_gravity(loads["gravity"])
    for f in loads["body_forces"]:
        L.set_body_force(f["body"], f["force"], point=f["point"], torque=f["torque"])
    for f in loads["joint_forces"]:
        L.set_joint_force(f["joint"], f["tau"])
    q0 = L.positions().copy()
    L.solve()
    qdd = L.accelerations().copy()
    state["aqs_qdd"] = qdd
    state["layout"] = [L.joint_layout(j) for j in range(L.num_joints)]
    state["kinds"] = [L.joint_definition(j).kind for j in range(L.num_joints)]
    if state.get("quiet"):  # measured in an earlier child: only the reference is needed
        L.close()
        return

    def full():
        L.set_positions(q0)
        L.solve()
    full_s, full_n = median_time(full, args.repeats, args.budget)
    emit(dict(engine="aqs", variant="exact full", ok=True, seconds=full_s, repeats=full_n,
              load_seconds=load_s, max_rel_vs_c=max_rel(qdd, problem.qdd_c),
              peak_rss_bytes=peak_rss_bytes()))

    # N_f = 1 steps: gravity off, one 1 N force at a seeded body's origin.
    rng = np.random.default_rng(20050801)
    L.clear_forces()
    L.set_gravity((0.0, 0.0, 0.0))
    body = int(rng.integers(L.num_bodies))
    direction = rng.normal(size=3)
    L.set_body_force(body, direction / np.linalg.norm(direction))
    L.set_positions(q0)
    L.solve()
    dt = (1e-3 / np.abs(L.accelerations()).max()) ** 0.5
    for eps_log2 in (None,) + ADAPTIVE_EPS_LOG2:
        L.set_tolerance("rel_joint", 0.0 if eps_log2 is None else 2.0 ** -eps_log2)
        L.set_positions(q0)
        L.solve()
        times, computed = [], []
        for _ in range(args.steps):
            t1 = time.perf_counter()
            stats = L.step(dt)
            times.append(time.perf_counter() - t1)
            computed.append(stats.computed_joints)
        emit(dict(engine="aqs", ok=True,
                  variant="exact step" if eps_log2 is None else "adaptive step 2^-%d" % eps_log2,
                  seconds=float(np.median(times)), repeats=len(times), forces=1, dt=dt,
                  computed_joints=float(np.mean(computed)), peak_rss_bytes=peak_rss_bytes()))
    L.close()


def aqs_to_engine_tau(problem, state):
    """{aqs joint index: tau} of the JSON loads."""
    import numpy as np
    return {f["joint"]: np.array(f["tau"]) for f in problem.loads["joint_forces"]}


def run_pinocchio(problem, args, state):
    import numpy as np
    import pinocchio as pin
    t0 = time.perf_counter()
    model = pin.buildModelFromUrdf(problem.urdf)
    load_s = time.perf_counter() - t0
    data = pin.Data(model)  # dense nv x nv members: where large models stop
    q = pin.neutral(model)
    v = np.zeros(model.nv)
    model.gravity.linear = problem.gravity
    layout, kinds = state["layout"], state["kinds"]
    joint_id = [model.getJointId("joint_%d" % j) for j in range(len(layout))]
    tau = np.zeros(model.nv)
    for j, t in aqs_to_engine_tau(problem, state).items():
        jm = model.joints[joint_id[j]]
        if kinds[j] == "free":
            t = np.concatenate([t[3:], t[:3]])  # aqs [n; f] -> Pinocchio [f; n]
        tau[jm.idx_v:jm.idx_v + jm.nv] = t
    pin.forwardKinematics(model, data, q)
    fext = pin.StdVec_Force()
    for _ in range(model.njoints):
        fext.append(pin.Force.Zero())
    for f in problem.loads["body_forces"]:
        frame = model.frames[model.getFrameId("link_%d" % f["body"])]
        parent = frame.parentJoint
        rotation = data.oMi[parent].rotation
        point = frame.placement.act(np.array(f["point"]))  # in the joint frame
        force = rotation.T @ np.array(f["force"])
        torque = rotation.T @ np.array(f["torque"]) + np.cross(point, force)
        fext[parent] = fext[parent] + pin.Force(force, torque)
    ddq = pin.aba(model, data, q, v, tau, fext).copy()
    qdd = np.zeros_like(state["aqs_qdd"])
    for j, (lay, kind) in enumerate(zip(layout, kinds)):
        jm = model.joints[joint_id[j]]
        part = ddq[jm.idx_v:jm.idx_v + jm.nv]
        if kind == "free":
            part = np.concatenate([part[3:], part[:3]])
        qdd[lay.v_offset:lay.v_offset + lay.nv] = part
    seconds, n = median_time(lambda: pin.aba(model, data, q, v, tau, fext), args.repeats,
                             args.budget)
    emit(dict(engine="pinocchio", variant="aba", ok=True, seconds=seconds, repeats=n,
              load_seconds=load_s, max_rel_vs_aqs=max_rel(qdd, state["aqs_qdd"]),
              peak_rss_bytes=peak_rss_bytes(), version=pin.__version__))


def run_mujoco(problem, args, state):
    import numpy as np
    import mujoco
    t0 = time.perf_counter()
    model = mujoco.MjModel.from_xml_path(problem.urdf)
    load_s = time.perf_counter() - t0
    data = mujoco.MjData(model)
    model.opt.gravity[:] = problem.gravity
    layout, kinds = state["layout"], state["kinds"]
    joint = [model.joint("joint_%d" % j) for j in range(len(layout))]
    mujoco.mj_kinematics(model, data)
    for j, t in aqs_to_engine_tau(problem, state).items():
        adr = int(joint[j].dofadr[0])
        if kinds[j] == "free":
            body = int(joint[j].bodyid[0])
            rotation = data.xmat[body].reshape(3, 3)
            t = np.concatenate([rotation @ t[3:], t[:3]])  # world force; local torque
        data.qfrc_applied[adr:adr + len(t)] = t
    for f in problem.loads["body_forces"]:
        body = model.body("link_%d" % f["body"]).id
        rotation = data.xmat[body].reshape(3, 3)
        point = data.xpos[body] + rotation @ np.array(f["point"])
        force = np.array(f["force"])
        torque = np.array(f["torque"]) + np.cross(point - data.xipos[body], force)
        data.xfrc_applied[body] = np.concatenate([force, torque])
    mujoco.mj_forward(model, data)
    qdd = np.zeros_like(state["aqs_qdd"])
    for j, (lay, kind) in enumerate(zip(layout, kinds)):
        adr = int(joint[j].dofadr[0])
        part = data.qacc[adr:adr + lay.nv].copy()
        if kind == "free":
            rotation = data.xmat[int(joint[j].bodyid[0])].reshape(3, 3)
            part = np.concatenate([part[3:], rotation.T @ part[:3]])
        qdd[lay.v_offset:lay.v_offset + lay.nv] = part
    seconds, n = median_time(lambda: mujoco.mj_forward(model, data), args.repeats,
                             args.budget)
    emit(dict(engine="mujoco", variant="mj_forward", ok=True, seconds=seconds, repeats=n,
              load_seconds=load_s, max_rel_vs_aqs=max_rel(qdd, state["aqs_qdd"]),
              peak_rss_bytes=peak_rss_bytes(), version=mujoco.__version__,
              sparse=bool(mujoco.mj_isSparse(model))))


RUNNERS = {"aqs": run_aqs, "pinocchio": run_pinocchio, "mujoco": run_mujoco}


def worker(args):
    problem = Problem(args.urdf, args.loads)
    engines = args.engines.split(",")
    state = {"quiet": "aqs" not in engines}
    if state["quiet"]:
        run_aqs(problem, args, state)
    for engine in engines:
        emit(dict(engine=engine, started=True))
        try:
            RUNNERS[engine](problem, args, state)
        except Exception as exc:  # MemoryError, RuntimeError, ValueError, ...
            emit(dict(engine=engine, ok=False, error="%s: %s" % (type(exc).__name__, exc),
                      peak_rss_bytes=peak_rss_bytes()))
            emit(dict(engine=engine, done=True))
            if engine == "aqs":
                for other in args.engines.split(","):
                    if other != "aqs":
                        emit(dict(engine=other, ok=False, error="not run: aqs failed"))
                        emit(dict(engine=other, done=True))
                return  # the others need aqs's layout and answer
            continue
        emit(dict(engine=engine, done=True))


# ---------------------------------------------------------------------------
# The driver
# ---------------------------------------------------------------------------

def limit_memory(gigabytes):
    def apply():
        limit = int(gigabytes * 2 ** 30)
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    return apply


def run_case(args, scene, size, engines, tmp):
    urdf = os.path.join(tmp, "%s_%s.urdf" % (scene, size))
    loads = os.path.join(tmp, "%s_%s.json" % (scene, size))
    command = [args.exporter, scene] + ([] if scene == "millipede" else [str(size)])
    t0 = time.perf_counter()
    subprocess.run(command + [urdf, loads], check=True)
    export_s = time.perf_counter() - t0
    results = []
    remaining = list(engines)
    while remaining:
        child = [sys.executable, os.path.abspath(__file__), "--worker", "--urdf", urdf,
                 "--loads", loads, "--engines", ",".join(remaining),
                 "--repeats", str(args.repeats), "--steps", str(args.steps),
                 "--budget", str(args.budget)]
        process = subprocess.Popen(child, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True, preexec_fn=limit_memory(args.mem_limit_gb))
        try:
            out, err = process.communicate(timeout=args.timeout)
            timed_out = False
        except subprocess.TimeoutExpired:
            process.kill()
            out, err = process.communicate()
            timed_out = True
        running, progress = None, False
        for line in out.splitlines():
            record = json.loads(line)
            if record.get("started"):
                running, progress = record["engine"], True
            elif record.get("done"):
                remaining.remove(record["engine"])
                running = None
            else:
                record.update(scene=scene, size=size, export_seconds=export_s)
                results.append(record)
        if running is not None:  # the child died or was killed inside this engine
            if timed_out:
                reason = "killed after the %g s time limit" % args.timeout
            else:
                code = process.returncode
                reason = "process died (%s): %s" % (
                    "signal %s" % signal.Signals(-code).name if code < 0 else "exit %d" % code,
                    " | ".join(err.strip().splitlines()[-3:]))
            results.append(dict(engine=running, ok=False, error=reason, scene=scene,
                                size=size, export_seconds=export_s))
            remaining.remove(running)
            if running == "aqs":
                break
        if not progress:
            break
    for path in (urdf, loads):
        os.remove(path)
    return results


def format_table(results):
    rows = ["| scene | joints | engine | variant | ms per solve | max rel. diff vs aqs | notes |",
            "|---|---|---|---|---|---|---|"]
    for r in results:
        if r.get("ok"):
            diff = r.get("max_rel_vs_aqs", r.get("max_rel_vs_c"))
            note = []
            if "computed_joints" in r:
                note.append("N_E = %.0f" % r["computed_joints"])
            if "load_seconds" in r:
                note.append("load %.1f s" % r["load_seconds"])
            note.append("peak RSS %.0f MiB" % (r["peak_rss_bytes"] / 2 ** 20))
            rows.append("| %s | %s | %s | %s | %.3f | %s | %s |" % (
                r["scene"], r["size"], r["engine"], r["variant"], 1e3 * r["seconds"],
                "%.1e" % diff if diff is not None else "", ", ".join(note)))
        else:
            rows.append("| %s | %s | %s | — | — | — | **stopped**: %s |" % (
                r["scene"], r["size"], r["engine"], r["error"].replace("|", "/")))
    return "\n".join(rows)


def short_error(text):
    text = text.replace("\n", " ").replace("|", "/")
    return text if len(text) < 110 else text[:107] + "..."


def summary_table(results):
    """One row per scene and size: every engine's time per solve (ms) and
    difference from aqs exact, or where it stopped."""
    cases = {}
    for r in results:
        cases.setdefault((r["scene"], int(r["size"])), {})[(r["engine"], r.get("variant"))] = r
    order = {"chain": 0, "molecule": 1, "millipede": 2}
    rows = ["| scene | joints | aqs exact, full (ms) | Pinocchio ABA (ms) | MuJoCo mj_forward (ms) "
            "| aqs exact step, N_f = 1 (ms) | aqs 2^-10 step (ms, N_E) | aqs 2^-19 step (ms, N_E) |",
            "|---|---|---|---|---|---|---|---|"]
    stops = []
    for (scene, size) in sorted(cases, key=lambda k: (order.get(k[0], 9), k[1])):
        c = cases[(scene, size)]

        def cell(engine, variant, with_diff=False, with_ne=False):
            r = c.get((engine, variant))
            if r is None:
                failed = [x for (e, v), x in c.items() if e == engine and not x.get("ok")]
                if failed:
                    stops.append("%s %d, %s: %s" % (scene, size, engine, failed[0]["error"]))
                    return "stopped (%d)" % len(stops)
                return ""
            text = "%.3f" % (1e3 * r["seconds"])
            if with_diff:
                text += " (diff %.1e)" % r["max_rel_vs_aqs"]
            if with_ne:
                text += ", %.0f" % r["computed_joints"]
            return text

        rows.append("| %s | %d | %s | %s | %s | %s | %s | %s |" % (
            scene, size, cell("aqs", "exact full"), cell("pinocchio", "aba", True),
            cell("mujoco", "mj_forward", True), cell("aqs", "exact step"),
            cell("aqs", "adaptive step 2^-10", with_ne=True),
            cell("aqs", "adaptive step 2^-19", with_ne=True)))
    notes = ["(%d) %s" % (i + 1, short_error(t)) for i, t in enumerate(stops)]
    return "\n".join(rows) + "\n\n" + "\n".join("- " + n for n in notes)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--urdf", help=argparse.SUPPRESS)
    parser.add_argument("--loads", help=argparse.SUPPRESS)
    parser.add_argument("--exporter", default=os.path.join(REPO, "build", "bench",
                                                           "urdf_export"))
    parser.add_argument("--scenes", default="chain,molecule,millipede")
    parser.add_argument("--sizes", default="1000,10000,50000")
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--budget", type=float, default=20.0,
                        help="seconds of timed calls per measurement (at least 3 calls)")
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--mem-limit-gb", type=float, default=6.0)
    parser.add_argument("--timeout", type=float, default=900.0)
    parser.add_argument("--out", default=os.path.join(REPO, "docs", "bench", "peers.jsonl"))
    parser.add_argument("--summary", metavar="JSONL",
                        help="only print the summary table of an earlier run's JSON lines")
    args = parser.parse_args()
    if args.summary:
        with open(args.summary) as handle:
            print(summary_table([json.loads(line) for line in handle if line.strip()]))
        return 0
    if args.worker:
        worker(args)
        return 0
    engines = args.engines.split(",")
    stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    results = []
    with tempfile.TemporaryDirectory(prefix="aqs-peers-") as tmp:
        for scene in args.scenes.split(","):
            sizes = ["13000"] if scene == "millipede" else args.sizes.split(",")
            for size in sizes:
                print("peers: %s %s ..." % (scene, size), file=sys.stderr, flush=True)
                case = run_case(args, scene, int(size), engines, tmp)
                for r in case:
                    r["utc"] = stamp
                    print("  %s" % json.dumps(r), file=sys.stderr, flush=True)
                results += case
    if args.out != "-":
        os.makedirs(os.path.dirname(args.out), exist_ok=True)
        with open(args.out, "a") as handle:
            for r in results:
                handle.write(json.dumps(r) + "\n")
    print(format_table(results))
    print()
    print(summary_table(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
