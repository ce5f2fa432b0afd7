#!/usr/bin/env python3
"""Markdown summary of a hardcases JSON Lines file (build/hardcases-quick.jsonl from
`make check-hard`, docs/hardcases/long.jsonl from `make bench-hard`), one row per case:

  case | dofs | ABA rel | DCA rel (or status) | adaptive, per measure: worst true/bound
  over the solves that skipped joints (bound > 0) | solves whose true measure exceeds the
  bound at all (the bound is for exact arithmetic, so rounding alone does it) | solves that
  exceed it by more than the rounding allowance (the check hardcases asserts)

Usage: python3 tests/reference/hardcases_summary.py FILE.jsonl [> table.md]
"""
import json
import sys

METRICS = ("abs_linkage", "rel_linkage", "abs_joint", "rel_joint")


def fmt(x):
    return "-" if x is None else "%.1e" % x


def main(path):
    rows, order = {}, []
    for line in open(path):
        r = json.loads(line)
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


if __name__ == "__main__":
    main(sys.argv[1])
