#!/usr/bin/env python3
"""Wall-clock time per adaptive step of the 5,000-joint molecule, several builds
side by side (docs/bench.md, "The articulated-inertia route's ceiling, measured").

Each build is an autocount_main-like program (bench/autocount_main.c's command
line: MODE JOINTS FORCES STEPS [FORM]); a build is given as NAME=PROGRAM[:FORM].
For each number of forces the program runs with S0 and then S1 steps; the time
per step is the difference of the two runs' wall clocks over S1 - S0 (the set-up,
the molecule and its first solve, cancels). The builds alternate within each
round; the medians over the rounds are printed, with each build's ratio to the
first one and the spread.

    python3 tools/time_steps.py [--rounds 9] \\
        90aa04b=/tmp/autocount_base sqrt=build/bench/autocount_main:sqrt \\
        phi=build/bench/autocount_main:phi
"""
import argparse
import statistics
import subprocess
import time

# forces -> (S0, S1): about 0.1-0.3 s of steps beyond the set-up at each
PLAN = {1: (10, 1010), 10: (10, 210), 100: (5, 45)}


def run(cmd, forces, steps, form):
    t = time.perf_counter()
    subprocess.run(cmd + ["adaptive", "5000", str(forces), str(steps)] + form, check=True,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("builds", nargs="+", help="NAME=PROGRAM[:FORM]")
    a = ap.parse_args()
    builds = []
    for b in a.builds:
        name, _, prog = b.partition("=")
        prog, _, form = prog.partition(":")
        builds.append((name, [prog], [form] if form else []))
    per = {}
    for forces, (s0, s1) in PLAN.items():
        for _ in range(a.rounds):
            for name, cmd, form in builds:
                t0 = run(cmd, forces, s0, form)
                t1 = run(cmd, forces, s1, form)
                per.setdefault((forces, name), []).append((t1 - t0) / (s1 - s0) * 1e3)
    for forces in PLAN:
        base = statistics.median(per[(forces, builds[0][0])])
        cells = []
        for name, _, _ in builds:
            v = per[(forces, name)]
            m = statistics.median(v)
            cells.append("%s %.3f ms (%.2fx; %.3f-%.3f)" % (name, m, m / base, min(v), max(v)))
        print("N_f = %d: %s" % (forces, ", ".join(cells)))


if __name__ == "__main__":
    main()
