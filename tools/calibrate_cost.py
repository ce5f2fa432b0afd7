#!/usr/bin/env python3
"""Calibrate src/solve/cost.h: the per-node instruction costs of the automatic path.

Runs build/bench/aqs-bench under callgrind (instruction counts: the same on
every machine and at any load) on the 5,000-joint molecule, once per DCA form,
and build/bench/autocount_main for the work meter's passes (the exact
refinements: the articulated-body one on the molecule with heavy atoms,
bench_build_molecule_heavy at 1e3, and the exact DCA's on the plain molecule),
and prints the #define lines of src/solve/cost.h: each constant is the
inclusive instruction count per call of the kernel it prices (per joint for
the articulated-body solve, the exact step's frame refresh and the
refinements' passes).

    python3 tools/calibrate_cost.py [--bench build/bench/aqs-bench]
        [--autocount build/bench/autocount_main] [--joints 5000]

Needs valgrind. About two minutes.
"""
import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile


def parse(path):
    """Inclusive cost (Ir) and call count per function name, from the calls
    recorded in a callgrind output file (the callee's inclusive cost of each
    call site, summed over the sites)."""
    names = {}
    incl = collections.Counter()
    calls = collections.Counter()
    cfn = None
    pending = 0
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            m = re.match(r"^(c?fn)=\((\d+)\)(?: (.*))?$", line)
            if m:
                kind, ident, name = m.groups()
                if name:
                    names[ident] = name
                if kind == "cfn":
                    cfn = names.get(ident, ident)
                continue
            m = re.match(r"^calls=(\d+)", line)
            if m:
                pending = int(m.group(1))
                continue
            if pending and line and (line[0].isdigit() or line[0] in "+-*"):
                parts = line.split()
                if len(parts) >= 2:
                    incl[cfn] += int(parts[1])
                    calls[cfn] += pending
                pending = 0
    return incl, calls


def run(bench, joints, form, steps):
    out = tempfile.NamedTemporaryFile(prefix="aqs-cost-", suffix=".out", delete=False).name
    cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out,
           bench, "--joints", str(joints), "--forces", "10", "--steps", str(steps),
           "--exact-every", "100", "--auto", "off", "--dca-form", form, "--quiet", "--out", os.devnull]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        return parse(out)
    finally:
        os.unlink(out)


def run_autocount(autocount, joints, mode, heavy):
    out = tempfile.NamedTemporaryFile(prefix="aqs-cost-", suffix=".out", delete=False).name
    cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out, "--toggle-collect=bench_counted_steps",
           autocount, mode, str(joints), "10", "4", "sqrt", str(heavy)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        return parse(out)
    finally:
        os.unlink(out)


def per_call(incl, calls, name):
    if calls[name] == 0:
        sys.exit("calibrate_cost: %s was never called" % name)
    return incl[name] / calls[name]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", default="build/bench/aqs-bench")
    ap.add_argument("--autocount", default="build/bench/autocount_main")
    ap.add_argument("--joints", type=int, default=5000)
    ap.add_argument("--steps", type=int, default=12)
    a = ap.parse_args()
    res = {}
    for form in ("sqrt", "phi"):
        res[form] = run(a.bench, a.joints, form, a.steps)
    incl, calls = res["sqrt"]
    ne = a.joints  # every joint of the molecule is revolute: one effective joint each
    c = collections.OrderedDict()
    c["COST_DCA_NODE_SQRT"] = per_call(incl, calls, "dca_node_update")
    c["COST_DCA_NODE_PHI"] = per_call(*res["phi"], "dca_node_update")
    c["COST_FACTOR"] = per_call(incl, calls, "totalacc_node_update")
    # a processed node: its back-substitution, one evaluation of A, one heap
    # push and pop
    # (dca_node_backsub_sums: the adaptive solve's back-substitution in the
    # square-root form, its products shared with the rounding estimate)
    c["COST_PROCESS"] = (per_call(incl, calls, "dca_node_backsub_sums") + per_call(incl, calls, "totalacc_eval") +
                         per_call(incl, calls, "heap_push") + per_call(incl, calls, "heap_pop"))
    # a moved node: its joint integrated, its frames
    c["COST_MOVE"] = per_call(incl, calls, "joint_integrate") + per_call(incl, calls, "frames_node")
    # the exact step as the model prices it (the work meter counts
    # COST_ABA_JOINT a joint for the pass; autopath.c adds COST_ABA_MOVE a
    # joint for a step): the whole solve of an exact step on the plain
    # molecule (the loads' update, the pass, its checks) and the rest of the
    # step (the move, the positions' update); in aqs-bench's run above the
    # exact solves are a few reference ones among adaptive steps
    xi, xc = run_autocount(a.autocount, a.joints, "exact", 1)
    c["COST_ABA_JOINT"] = per_call(xi, xc, "solve_body") / ne
    c["COST_ABA_MOVE"] = (per_call(xi, xc, "step_body") - per_call(xi, xc, "solve_body")) / ne
    # the work meter's passes (cost.h): the articulated-body refinement on the
    # molecule with heavy atoms (every solve refines), the exact DCA's on the
    # plain molecule (every solve refined by GMRES)
    hi, hc = run_autocount(a.autocount, a.joints, "exact", 1e3)
    di, dc = run_autocount(a.autocount, a.joints, "exactdca", 1)
    # abarefine.c's correction, with what aba_refine does besides its
    # double-double passes (the state's copies, the forces' loop)
    c["COST_ABA_CORRECTION"] = (hi["aba_refine"] - hi["residual_dd_eval"] - hi["residual_dd_accelerations"] -
                                hi["residual_dd_acc_add"]) / hc["correction"] / ne
    c["COST_DD_RESIDUAL"] = per_call(hi, hc, "residual_dd_eval") / ne
    c["COST_DD_ACCEL"] = per_call(hi, hc, "residual_dd_accelerations") / ne
    c["COST_RESIDUAL"] = per_call(di, dc, "residual_eval") / ne
    c["COST_BACKSUB"] = per_call(di, dc, "dca_node_backsub")  # the refinement's passes (refine.c)
    c["COST_NODE_LOADS"] = per_call(di, dc, "dca_node_loads")
    print("/* tools/calibrate_cost.py --joints %d --steps %d */" % (a.joints, a.steps))
    for k, v in c.items():
        print("#define %s %.1f" % (k, round(v, -1)))


if __name__ == "__main__":
    main()
