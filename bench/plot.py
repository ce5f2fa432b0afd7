#!/usr/bin/env python3
"""Plots of aqs-bench results (docs/bench.md shows them).

usage: bench/plot.py [--set quick|full] [--tables] [DIR]   (DIR default docs/bench)

Reads DIR/<set>-molecule.jsonl, DIR/<set>-millipede.jsonl, DIR/<set>-chain30.jsonl,
DIR/<set>-chain30-tip.csv and DIR/scaling.jsonl (whichever exist) and writes PNGs into DIR:
  <set>-fig5-millipede.png      time per step and computed joints against eps (paper Fig. 5)
  <set>-fig7-molecule.png       the same for each N_f on the molecule (paper Fig. 7)
  <set>-fig8-displacement.png   relative displacement error against eps (paper Fig. 8)
  <set>-fig1-chain30.png        chain30 tip trajectories for several eps against exact (Fig. 1)
  scaling.png                   molecule 10k..1M joints, log-log
  world-measures.png            speedup and N_E against the final relative displacement error,
                                joint and world measures side by side (DIR/world-*.jsonl,
                                aqs-bench --metric rel_joint,rel_world; issue 16); an earlier
                                run's rel_world in the same file dashed (N_E only)
Within a file only the lines of its latest run_id are used (scaling.jsonl: the latest line
of each size). --tables prints the results as Markdown tables instead.
"""
import argparse
import csv
import json
import math
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load_jsonl(path, latest_run=True):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        rows = [json.loads(line) for line in f if line.strip()]
    rows = [r for r in rows if r.get("bench") == "aqs-bench"]
    if latest_run and rows:
        last = rows[-1]["run_id"]
        rows = [r for r in rows if r["run_id"] == last]
    return rows


def eps_index(r):
    """i of eps = 2^-i (the x axis of the paper's figures)."""
    return r["eps_log2"] if r.get("eps_log2") is not None else None


def by_forces(rows):
    groups = defaultdict(list)
    for r in rows:
        if eps_index(r) is not None:
            groups[r["forces"]].append(r)
    for g in groups.values():
        g.sort(key=eps_index)
    return dict(sorted(groups.items()))


def finish(fig, axes, out):
    """Grid and legend on each of axes, then write the figure to out."""
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return True


def time_and_joints(rows, title, out):
    """Time per step (adaptive, with the exact time dashed) and N_E against eps."""
    groups = by_forces(rows)
    if not groups:
        return False
    fig, (ax_t, ax_n) = plt.subplots(1, 2, figsize=(11, 4.2))
    for nf, g in groups.items():
        x = [eps_index(r) for r in g]
        line, = ax_t.semilogy(x, [r["ms_per_step"] for r in g], "o-", ms=3,
                              label=f"adaptive, N_f = {nf}")
        ax_t.semilogy(x, [r["exact_ms_per_step"] for r in g], "--", color=line.get_color(),
                      lw=1, label=f"exact, articulated-body (interleaved), N_f = {nf}")
        if "exact_dca_ms_per_step" in g[0]:
            ax_t.semilogy(x, [r["exact_dca_ms_per_step"] for r in g], ":",
                          color=line.get_color(), lw=1, label=f"exact, DCA, N_f = {nf}")
        ax_n.semilogy(x, [r["computed_joints"] for r in g], "o-", ms=3,
                      color=line.get_color(), label=f"N_f = {nf}")
    joints = rows[0]["joints"]
    ax_n.axhline(joints, color="gray", lw=0.8, ls=":", label=f"all {joints:,} joints")
    ax_t.set_xlabel("i  (eps = 2^-i, relative joint-acceleration error)")
    ax_t.set_ylabel("ms per step (median)")
    ax_t.set_title("time per step")
    ax_n.set_xlabel("i  (eps = 2^-i)")
    ax_n.set_ylabel("computed joints N_E (mean per step)")
    ax_n.set_title("computed joint accelerations")
    fig.suptitle(title)
    return finish(fig, (ax_t, ax_n), out)


def displacement(sets, out):
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    drawn = False
    for label, rows in sets:
        for nf, g in by_forces(rows).items():
            pts = [(eps_index(r), r["displacement_error"]) for r in g
                   if r["displacement_error"] > 0]
            if pts:
                ax.semilogy(*zip(*pts), "o-", ms=3,
                            label=f"{label}, N_f = {nf}, {g[0]['steps']} steps")
                drawn = True
    if not drawn:
        plt.close(fig)
        return False
    ax.set_xlabel("i  (eps = 2^-i)")
    ax.set_ylabel("max_i |d_i - d_i^exact| / max_i |d_i^exact|")
    ax.set_title("relative displacement error of the centres of mass")
    return finish(fig, (ax,), out)


def world_measures(d, out):
    """Speedup over the exact step and N_E against the final displacement error, one panel
    pair per scene and N_f, a curve per measure (the paper's Figure 8 axis). For each N_f the
    latest run of the file holding that N_f is drawn solid; the run before it with that N_f,
    its rel_world (the bound before it changed), dashed."""
    panels = []
    for scene in ("molecule", "chain30", "millipede"):
        path = os.path.join(d, f"world-{scene}.jsonl")
        allrows = load_jsonl(path, latest_run=False)
        for nf in sorted({r["forces"] for r in allrows}):
            runs = []
            for r in allrows:
                if r["forces"] == nf and r["run_id"] not in runs:
                    runs.append(r["run_id"])
            g = by_forces([r for r in allrows if r["forces"] == nf and r["run_id"] == runs[-1]]).get(nf)
            if not g:
                continue
            old = [r for r in allrows if len(runs) > 1 and r["forces"] == nf and r["run_id"] == runs[-2]
                   and r["metric"] == "rel_world"]
            panels.append((f"{scene}, N_f = {nf}, {g[0]['steps']} steps", g, old))
    if not panels:
        return False
    fig, axes = plt.subplots(2, len(panels), figsize=(3.6 * len(panels), 6.2), squeeze=False)
    for k, (title, g, old) in enumerate(panels):
        for metric, style, rows, label in (("rel_joint", "o-", g, "rel_joint"),
                                           ("rel_world", "s-", g, "rel_world"),
                                           ("rel_world", "x--", old,
                                            f"rel_world before ({old[0]['steps'] if old else 0} steps)")):
            pts = sorted((r["displacement_error"], r["speedup"], r["computed_joints"])
                         for r in rows if r["metric"] == metric and r["displacement_error"] > 0)
            if not pts:
                continue
            e, sp, ne = zip(*pts)
            if rows is old:
                axes[1][k].semilogx(e, ne, style, ms=3, alpha=0.6, label=label)  # speedups: other loads
                continue
            axes[0][k].loglog(e, sp, style, ms=3, label=label)
            axes[1][k].semilogx(e, ne, style, ms=3, label=label)
        axes[0][k].set_title(title, fontsize=9)
        axes[0][k].set_ylabel("speedup over the exact step")
        axes[1][k].set_ylabel("N_E (joints computed)")
        axes[1][k].set_xlabel("final relative displacement error")
    return finish(fig, [a for row in axes for a in row], out)


def tip_paths(path, out):
    """Left: the tip's path per eps and exact; right: its distance from the exact tip."""
    if not os.path.exists(path):
        return False
    paths = defaultdict(list)
    with open(path) as f:
        for r in csv.DictReader(f):
            key = "exact" if r["run"] == "exact" else float(r["eps"])
            paths[key].append((int(r["step"]), float(r["x"]), float(r["y"])))
    if "exact" not in paths:
        return False
    exact = {s: (x, y) for s, x, y in paths["exact"]}
    fig, (ax, ax_d) = plt.subplots(1, 2, figsize=(11, 4.6))
    shown = sorted((k for k in paths if k != "exact"), reverse=True)
    if len(shown) > 8:  # a readable subset: 2^-0, 2^-1, 2^-3, 2^-5, 2^-7, 2^-10, 2^-15, 2^-19
        shown = [k for k in shown if round(-math.log2(k)) in (0, 1, 3, 5, 7, 10, 15, 19)]
    colors = plt.cm.viridis([i / max(1, len(shown) - 1) for i in range(len(shown))])
    for key, color in zip(shown, colors):
        _, x, y = zip(*paths[key])
        label = f"eps = 2^-{round(-math.log2(key))}"
        line, = ax.plot(x, y, lw=1, color=color, label=label)
        dist = [(s, math.hypot(px - exact[s][0], py - exact[s][1]))
                for s, px, py in paths[key] if s in exact and s > 0]
        dist = [(s, d) for s, d in dist if d > 0]
        if dist:
            ax_d.semilogy(*zip(*dist), lw=1, color=line.get_color(), label=label)
    _, x, y = zip(*paths["exact"])
    ax.plot(x, y, "k--", lw=1.5, label="exact")
    ax.plot([x[0]], [y[0]], "ko", ms=4)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("path of the tip, (0, 1, 0) N at the tip")
    ax_d.set_xlabel("step")
    ax_d.set_ylabel("|tip(eps) - tip(exact)| (m)")
    ax_d.set_title("distance from the exact tip")
    fig.suptitle("chain30 (paper Figure 1)")
    return finish(fig, (ax, ax_d), out)


def scaling(path, out):
    rows = load_jsonl(path, latest_run=False)
    latest = {}
    for r in rows:
        latest[r["joints"]] = r
    rows = [latest[n] for n in sorted(latest)]
    if len(rows) < 2:
        return False
    n = [r["joints"] for r in rows]
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax_t.loglog(n, [r["exact_ms_per_step"] for r in rows], "s-",
                label="exact step (articulated-body)")
    if all("exact_dca_ms_per_step" in r for r in rows):
        ax_t.loglog(n, [r["exact_dca_ms_per_step"] for r in rows], "d-", label="exact step (DCA)")
    ax_t.loglog(n, [r["ms_per_step"] for r in rows], "o-",
                label="adaptive step, N_f = 1, 2^-19")
    ax_t.loglog(n, [1e3 * r["finalize_s"] for r in rows], "^-", label="finalize")
    ref = rows[0]["exact_ms_per_step"]
    ax_t.loglog(n, [ref * k / n[0] for k in n], ":", color="gray", label="∝ N")
    ax_t.set_xlabel("joints N")
    ax_t.set_ylabel("ms (median)")
    ax_t.set_title("molecule: time against size")
    ax_m.semilogx(n, [r["exact_linkage_bytes"] / r["joints"] for r in rows], "s-",
                  label="exact linkage")
    ax_m.semilogx(n, [r["adaptive_linkage_bytes"] / r["joints"] for r in rows], "o-",
                  label="adaptive linkage (with total-acceleration factors)")
    ax_m.axhline(4096, color="gray", ls=":", label="target 4 KiB")
    ax_m.set_xlabel("joints N")
    ax_m.set_ylabel("resident bytes per joint")
    ax_m.set_title("memory per joint")
    ax_m.set_ylim(bottom=0)
    return finish(fig, (ax_t, ax_m), out)


def tables(sets, scaling_path):
    """Markdown tables of the results (for docs/bench.md) on stdout."""
    for label, rows in sets:
        if not rows:
            continue
        r0 = rows[0]
        print(f"\n{label}: {r0['joints']:,} joints, run {r0['run_id']}, {r0['steps']} steps, "
              f"load average {min(r['loadavg1'] for r in rows):.2f}-"
              f"{max(r['loadavg1'] for r in rows):.2f}\n")
        dca = "exact_dca_ms_per_step" in r0
        print("| N_f | eps | ms/step | exact ms/step | speedup |"
              + (" DCA ms/step | speedup vs DCA |" if dca else "")
              + " N_E | nodes updated | R | R vs ABA/joint | displ. error | max bound |")
        print("|---:|---:|---:|---:|---:|" + ("---:|---:|" if dca else "")
              + "---:|---:|---:|---:|---:|---:|")
        for nf, g in by_forces(rows).items():
            for r in g:
                extra = (f"{r['exact_dca_ms_per_step']:.4g} | {r['speedup_dca']:.3g} | "
                         if dca else "")
                print(f"| {nf} | 2^-{r['eps_log2']} | {r['ms_per_step']:.3g} | "
                      f"{r['exact_ms_per_step']:.4g} | {r['speedup']:.3g} | {extra}"
                      f"{r['computed_joints']:,.1f} | {r['nodes_updated']:,.1f} | "
                      f"{r['ratio_R']:.2f} | {r.get('ratio_R_aba', float('nan')):.2f} | "
                      f"{r['displacement_error']:.2g} | {r['max_error_bound']:.2g} |")
    rows = load_jsonl(scaling_path, latest_run=False)
    latest = {r["joints"]: r for r in rows}
    if latest:
        print("\nscaling\n")
        print("| joints | tree height | finalize s | exact ms/step (interleaved / ref. run) "
              "| exact µs/joint | DCA ms/step | adaptive ms/step | N_E | R | exact B/joint "
              "| adaptive B/joint | peak RSS B/joint | load |")
        print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for n in sorted(latest):
            r = latest[n]
            print(f"| {n:,} | {r['tree_height']} | {r['finalize_s']:.2f} | "
                  f"{r['exact_ms_per_step']:.4g} / {r['exact_ref_ms_per_step']:.4g} | "
                  f"{1e3 * r['exact_ms_per_step'] / n:.3g} | "
                  f"{r.get('exact_dca_ms_per_step', float('nan')):.4g} | "
                  f"{r['ms_per_step']:.3g} | {r['computed_joints']:.1f} | "
                  f"{r['ratio_R']:.2f} | {r['exact_linkage_bytes'] / n:,.0f} | "
                  f"{r['adaptive_linkage_bytes'] / n:,.0f} | {r['peak_rss_bytes'] / n:,.0f} | "
                  f"{r['loadavg1']:.2f} |")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", default="quick", choices=["quick", "full"])
    ap.add_argument("--tables", action="store_true",
                    help="print Markdown tables of the results instead of plotting")
    ap.add_argument("dir", nargs="?", default="docs/bench")
    a = ap.parse_args(argv)
    d, s = a.dir, a.set
    molecule = load_jsonl(os.path.join(d, f"{s}-molecule.jsonl"))
    millipede = load_jsonl(os.path.join(d, f"{s}-millipede.jsonl"))
    chain30 = load_jsonl(os.path.join(d, f"{s}-chain30.jsonl"))
    if a.tables:
        tables([("chain30", chain30), ("millipede", millipede), ("molecule", molecule)],
               os.path.join(d, "scaling.jsonl"))
        return 0
    made = []
    jobs = [
        (f"{s}-fig5-millipede.png", lambda o: time_and_joints(
            millipede, "millipede (13,000 links), one force on a leg", o)),
        (f"{s}-fig7-molecule.png", lambda o: time_and_joints(
            molecule, f"molecule ({molecule[0]['joints']:,} joints)" if molecule else "", o)),
        (f"{s}-fig8-displacement.png", lambda o: displacement(
            [("molecule", molecule), ("millipede", millipede), ("chain30", chain30)], o)),
        (f"{s}-fig1-chain30.png", lambda o: tip_paths(
            os.path.join(d, f"{s}-chain30-tip.csv"), o)),
        ("scaling.png", lambda o: scaling(os.path.join(d, "scaling.jsonl"), o)),
        ("world-measures.png", lambda o: world_measures(d, o)),
    ]
    for name, job in jobs:
        out = os.path.join(d, name)
        if job(out):
            made.append(out)
    print("plot.py: wrote " + (", ".join(made) if made else "nothing (no results found)"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
