#!/usr/bin/env python3
"""The optimiser table of science_connector_optimisation.md from `divcoll connector-opt` CSV files.

Usage: science_connector_optimisation_table.py PREFIX [PREFIX ...]   (prints Markdown)
"""
import csv
import sys
from collections import defaultdict


def main():
    rows = defaultdict(dict)  # (kind, label) -> {(weights, steps): (pairs, alone, not_ok, grad, fwd, s, best)}
    val0 = {}
    for p in sys.argv[1:]:
        with open(p + "_summary.csv") as f:
            for r in csv.DictReader(f):
                rows[(r["kind"], r["label"])][(r["weights"], r["steps"])] = r
        with open(p + "_curves.csv") as f:
            for r in csv.DictReader(f):
                if r["iteration"] == "0":
                    val0[(r["kind"], r["label"])] = float(r["val_bl"])
    print("| kind | optimiser | validation at iteration 0 (BL) | kept iteration | pairs, 1000 steps: kept / last | "
          "pairs, 3000 steps: kept / last | agents alone, 1000 / 3000 | episodes with gradient + forward only | wall s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (kind, label) in sorted(rows):
        d = rows[(kind, label)]

        def cell(steps):
            k = d.get(("kept", steps))
            l = d.get(("last", steps), k)
            return f"{float(k['pairs_bl']):.2f} / {float(l['pairs_bl']):.2f}"

        k1, k3 = d[("kept", "1000")], d[("kept", "3000")]
        v0 = val0.get((kind, label), float("nan"))
        print(f"| {kind} | {label} | {v0:.2f} | {k1['best_iteration']} | {cell('1000')} | {cell('3000')} | "
              f"{float(k1['alone_bl']):.2f} / {float(k3['alone_bl']):.2f} | {k1['grad_episodes']} + {k1['fwd_episodes']} | "
              f"{float(k1['seconds']):.0f} |")


if __name__ == "__main__":
    main()
