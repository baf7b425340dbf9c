#!/usr/bin/env python3
"""A/B of two engines measured together (jobs/BENCHMARKS.md): the same fixed work through two builds of
jobs/engine_ab_driver.cpp, run in turn (A B, then B A, ...), each timed by its thread's CPU time; prints the
markdown table of medians and the ratio A/B pair by pair (min, median, max). A benchmark, not a test.

    jobs/engine_ab.py NEW_DRIVER BASE_DRIVER [ROUNDS=7] [ONLY]

ONLY keeps the rows whose name contains it. The base driver is built without -DHAS_AGRAD for a tree older than
RunOptions::agent_param_grad (it then computes every gradient block, as such a tree must)."""
import statistics
import subprocess
import sys

CASES = [("pair b100 fwd+bwd (training)", "pair 100 1000 1 0 1"), ("pair b100 fwd", "pair 100 1000 0 0 2"),
         ("chain20 b100 fwd", "chain20 100 200 0 0 1")]


def steps_per_cpu_second(exe, args):
    out = subprocess.run([exe] + args.split(), capture_output=True, text=True, check=True).stdout.split()
    return float(out[0])


def main():
    new, base = sys.argv[1], sys.argv[2]
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 7
    cases = [c for c in CASES if len(sys.argv) <= 4 or sys.argv[4] in c[0]]
    res = {name: ([], [], []) for name, _ in cases}
    for r in range(rounds):
        for name, args in cases:
            a, b, ratio = res[name]
            runs = [(new, a), (base, b)] if r % 2 == 0 else [(base, b), (new, a)]
            for exe, into in runs:
                into.append(steps_per_cpu_second(exe, args))
            ratio.append(a[-1] / b[-1])
    print("| work (one thread, CPU time) | B steps/CPU-s (median) | A steps/CPU-s (median) | A/B min | median | max |")
    print("|---|---|---|---|---|---|")
    for name, _ in cases:
        a, b, ratio = res[name]
        print(f"| {name} | {statistics.median(b):.0f} | {statistics.median(a):.0f} | {min(ratio):.2f} | "
              f"{statistics.median(ratio):.2f} | {max(ratio):.2f} |")


if __name__ == "__main__":
    main()
