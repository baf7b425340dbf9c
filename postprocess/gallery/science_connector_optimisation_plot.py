#!/usr/bin/env python3
"""Travel against iteration per connector optimiser: the validation batch's mean pair travel (BL,
1000 steps) of each optimiser's current weights, mean over replicates, one panel per connector kind, with the
agents alone on the evaluation pairs. Reads the CSV files `divcoll connector-opt` writes.

Usage: science_connector_optimisation_plot.py OUT.png PREFIX [PREFIX ...]
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    out, prefixes = sys.argv[1], sys.argv[2:]
    curves = defaultdict(lambda: defaultdict(list))  # kind -> label -> [(rep, it, val)]
    alone = {}
    for p in prefixes:
        with open(p + "_curves.csv") as f:
            for r in csv.DictReader(f):
                curves[r["kind"]][r["label"]].append((int(r["replicate"]), int(r["iteration"]), float(r["val_bl"])))
        with open(p + "_summary.csv") as f:
            for r in csv.DictReader(f):
                if r["steps"] == "1000":
                    alone[r["kind"]] = float(r["alone_bl"])
    kinds = sorted(curves)
    fig, axes = plt.subplots(1, len(kinds), figsize=(6 * len(kinds), 4.2), squeeze=False)
    for ax, kind in zip(axes[0], kinds):
        for label, rows in sorted(curves[kind].items()):
            by_it = defaultdict(list)
            for _, it, v in rows:
                by_it[it].append(v)
            its = sorted(by_it)
            ax.plot(its, [sum(by_it[i]) / len(by_it[i]) for i in its], label=label, lw=1.4)
        if kind in alone:
            ax.axhline(alone[kind], color="k", ls="--", lw=1, label="agents alone")
        ax.set_title(kind)
        ax.set_xlabel("iteration")
        ax.set_ylabel("validation pair travel, 1000 steps (BL)")
        ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
