#!/usr/bin/env python3
"""Markdown summary of a hardcases JSON Lines file (build/hardcases-quick.jsonl from
`make check-hard`, docs/hardcases/long.jsonl from `make bench-hard`), one row per case:

  case | dofs | ABA rel | DCA rel (or status) | adaptive, per measure: worst true/bound
  over the solves that skipped joints (bound > 0) | solves whose true measure exceeds the
  bound at all (the bound is for exact arithmetic, so rounding alone does it) | solves that
  exceed it by more than the rounding allowance (the check hardcases asserts)

then one row per family for the adaptive solves' computed joints (`comp`, their own error in
the solve's measure, against 10x the ABA's error, the allowance / 10), over the solves that
skipped joints and were not answered by the rounding fallback: solves, how many are above
10x, the largest ratio (docs/hardcases.md, "The adaptive solves' computed joints refined");

then one row per family for the constraint forces (`force`: the largest joint's error over
the largest joint force, against the reference's): the ABA's worst, the exact DCA's worst and
its largest ratio to max(the ABA's, 1e-15), and the same ratio for the adaptive solves'
computed joints (docs/hardcases.md, "Constraint forces");

then one row per family for the library's articulated-body solve against the textbook pass
(`refined_rel2`, `refined_force`: refined where its balance of forces says it lost digits,
docs/math.md 5b): cases, how many it refined, the worst of each;

then, from the bound-truth sweep's records ("solver": "bound"), one row per family: solves,
how many error_bound alone put below the truth, not certified, certified bounds below the
truth (asserted 0), tightness (error_bound + rounding_bound) / true over the certified solves,
and rounding_bound / true on the exact DCA (docs/hardcases.md).

Usage: python3 tests/reference/hardcases_summary.py FILE.jsonl [> table.md]
"""
import json
import sys

METRICS = ("abs_linkage", "rel_linkage", "abs_joint", "rel_joint")


def fmt(x):
    return "-" if x is None else "%.1e" % x


def main(path):
    rows, order, bound = {}, [], {}
    for line in open(path):
        r = json.loads(line)
        if r.get("solver") == "bound":
            bound.setdefault(r["family"], []).append(r)
            continue
        if r.get("solver") == "world":  # the world-measure sweep (printed by hardcases itself)
            continue
        name = r["case"]
        if name not in rows:
            rows[name] = {"adaptive": {m: [] for m in METRICS}}
            order.append(name)
        row = rows[name]
        if "refused" in r:
            row["refused"] = r["refused"]
        elif r["solver"] in ("aba", "dca"):
            row[r["solver"]] = r
            row["dofs"] = r["dofs"]
        else:
            row["adaptive"][r["metric"]].append(r)
    print("| case | dofs | ABA rel | DCA rel | " + " | ".join(METRICS) +
          " | true > bound | true > bound + allowance |")
    print("|---|---:|---:|---:|" + "---:|" * len(METRICS) + "---:|---:|")
    for name in order:
        row = rows[name]
        if "refused" in row:
            print("| %s | | refused: %s | | | | | | | |" % (name, row["refused"]))
            continue
        aba, dca = row["aba"], row["dca"]
        dcs = fmt(dca["rel2"]) if dca["status"] == 0 else "ENUMERIC" if dca["status"] == -6 else str(dca["status"])
        cols, exceeded, beyond, total = [], 0, 0, 0
        for m in METRICS:
            rs = row["adaptive"][m]
            ratios = [r["true"] / r["error_bound"] for r in rs
                      if r["status"] == 0 and r["error_bound"] and r["true"] is not None]
            if rs and all(r["status"] != 0 for r in rs):
                cols.append("ENUMERIC")
            else:
                cols.append(fmt(max(ratios)) if ratios else "-")
            total += len(rs)
            exceeded += sum(1 for r in rs if not r["holds"])
            beyond += sum(1 for r in rs if not r.get("ok", r["holds"]))
        print("| %s | %d | %s | %s | %s | %s | %s |" % (
            name, row["dofs"], fmt(aba["rel2"]), dcs, " | ".join(cols),
            "%d / %d" % (exceeded, total) if total else "-",
            "%d / %d" % (beyond, total) if total else "-"))
    comp = {}
    for name in order:
        for m in METRICS:
            for r in rows[name].get("adaptive", {}).get(m, []):
                if (r["status"] != 0 or r.get("path", 0) != 0 or r.get("comp") is None
                        or r["computed"] >= r["counted"] or not r.get("allowance")):
                    continue
                comp.setdefault(r["family"], []).append(r["comp"] / (r["allowance"] / 10.0))
    if comp:
        print()
        print("| family | adaptive solves that skipped joints | computed joints above 10x the ABA's error | largest ratio |")
        print("|---|---:|---:|---:|")
        for fam, v in comp.items():
            print("| %s | %d | %d | %s |" % (fam, len(v), sum(1 for x in v if x > 10.0), fmt(max(v))))
    forces = {}
    for name in order:
        aba, dca = rows[name].get("aba"), rows[name].get("dca")
        if not aba or aba.get("force") is None:
            continue
        floor = max(aba["force"], 1e-15)
        f = forces.setdefault(aba["family"], {"aba": 0.0, "dca": 0.0, "dca_ratio": 0.0, "adaptive": 0.0})
        f["aba"] = max(f["aba"], aba["force"])
        if dca and dca.get("force") is not None:
            f["dca"] = max(f["dca"], dca["force"])
            f["dca_ratio"] = max(f["dca_ratio"], dca["force"] / floor)
        for m in METRICS:
            for r in rows[name].get("adaptive", {}).get(m, []):
                if r["status"] == 0 and r.get("force") is not None:
                    f["adaptive"] = max(f["adaptive"], r["force"] / floor)
    if forces:
        print()
        print("| family | ABA forces (worst) | exact DCA forces (worst) | DCA / max(ABA, 1e-15) | "
              "adaptive computed joints / max(ABA, 1e-15) |")
        print("|---|---:|---:|---:|---:|")
        for fam, f in forces.items():
            print("| %s | %s | %s | %s | %s |" % (fam, fmt(f["aba"]), fmt(f["dca"]), fmt(f["dca_ratio"]),
                                                 fmt(f["adaptive"])))
    # The library's ABA (refined where its balance of forces says it lost digits, docs/math.md
    # 5b) against the textbook pass the rows above use as the yardstick.
    refined = {}
    for name in order:
        aba = rows[name].get("aba")
        if not aba or aba.get("refined_rel2") is None:
            continue
        r = refined.setdefault(aba["family"], {"cases": 0, "changed": 0, "rel2": 0.0, "now": 0.0,
                                               "force": 0.0, "force_now": 0.0})
        r["cases"] += 1
        r["changed"] += aba["rel2"] != aba["refined_rel2"] or aba["force"] != aba["refined_force"]
        r["rel2"] = max(r["rel2"], aba["rel2"])
        r["now"] = max(r["now"], aba["refined_rel2"])
        r["force"] = max(r["force"], aba["force"])
        r["force_now"] = max(r["force_now"], aba["refined_force"])
    if refined:
        print()
        print("| family | cases | refined | textbook ABA (worst) | ABA (worst) | textbook forces | forces |")
        print("|---|---:|---:|---:|---:|---:|---:|")
        for fam, r in refined.items():
            print("| %s | %d | %d | %s | %s | %s | %s |" % (fam, r["cases"], r["changed"], fmt(r["rel2"]),
                                                         fmt(r["now"]), fmt(r["force"]), fmt(r["force_now"])))
    if bound:
        print()
        print("| family | solves | error_bound alone below the truth | not certified | "
              "certified bound below the truth | tightness min / median / max | "
              "rounding_bound / true, exact DCA: min / median / max |")
        print("|---|---:|---:|---:|---:|---:|---:|")
        for fam, rs in bound.items():
            n = len(rs)
            old = sum(1 for r in rs if r["true"] > r["error_bound"] * (1 + 1e-9))
            unc = sum(1 for r in rs if not r["certified"])
            cert = [r for r in rs if r["certified"]]
            false = sum(1 for r in cert if r["true"] > (r["error_bound"] + r["rounding_bound"]) * (1 + 1e-9))
            tight = sorted((r["error_bound"] + r["rounding_bound"]) / r["true"] for r in cert if r["true"] > 0)
            exact = sorted(r["rounding_bound"] / r["true"] for r in cert if r["eps"] == 0 and r["true"] > 0)

            def mmm(v):
                return "%s / %s / %s" % (fmt(v[0]), fmt(v[len(v) // 2]), fmt(v[-1])) if v else "-"
            print("| %s | %d | %d (%.0f%%) | %d (%.0f%%) | %d | %s | %s |" % (
                fam, n, old, 100.0 * old / n, unc, 100.0 * unc / n, false, mmm(tight), mmm(exact)))


if __name__ == "__main__":
    main(sys.argv[1])
