#!/usr/bin/python3
"""Efficiency of the paper's task-farm rounds at many ranks, from the master's cost measured by
jobs/bench-farm.sh (`divcoll bench-farm` at 8, 16, 32 ranks).

    /usr/bin/python3 postprocess/farm_model.py OUT/farm.csv [--paper configs/paper.toml] [--ranks 64 512]
                                               [--item-ms 12.5 6.25] [--pairs-per-item 1]

One round of n items of t seconds on p ranks: the master only coordinates (W = p - 1 workers; with p <= 2
it computes too, W = p). It sends every worker its first block one message after another, then answers
each result with the next block; every item costs it c_serve of CPU (taking in the result, sending the
next task, and, when the stage folds during the round, the fold); a stage that folds after the round
(unpack and add every result, as the connectors stage sums gradients) adds n c_fold of serial time:

    T(p) = max(ceil(n / W) t + W c_task, n c_serve) + n c_fold_after,     efficiency = n t / (p T(p)).

c_serve, c_task and c_fold are the rows of the largest rank count in the CSV (guided blocks). Items per
round and the result size are the paper config's connectors and specialists training rounds (one pair
episode with gradient per item; its result is the connector's gradient, 1473 doubles). Assumes a network
whose per-message CPU cost at the master is no higher than this machine's shared memory, and leaves out
what a round does besides the farm (broadcasting weights, HDF5 writes, checkpoints: see the README).
--pairs-per-item b models items of b pair episodes whose gradients the worker sums (n / b items of b t,
each still one gradient to serve and fold): a granularity the stages do not use today (it would change
the order of the gradient sums, so run files would change once).
Exit status 2 on bad input.
"""
import argparse
import csv
import math
import os
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
PAPER = os.path.join(os.path.dirname(HERE), "configs", "paper.toml")


class InputError(Exception):
    pass


def read_costs(path):
    """{fold mode: row} of the guided-block rows at the largest rank count of a bench-farm CSV."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such file (run jobs/bench-farm.sh first)")
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    need = {"ranks", "block", "fold", "master_cpu_us_per_item", "task_us_per_msg", "fold_us_per_result",
            "bytes_per_result"}
    if not rows or not need <= set(rows[0]):
        raise InputError(f"{path}: not a bench-farm CSV (columns {', '.join(sorted(need))})")
    guided = [r for r in rows if r["block"] == "0"] or rows
    top = max(int(r["ranks"]) for r in guided)
    out = {r["fold"]: r for r in guided if int(r["ranks"]) == top}
    if "after" not in out:
        raise InputError(f"{path}: no fold=after row at {top} ranks")
    return top, out


def round_time(n, t, p, c_serve, c_task, c_fold_after):
    """Seconds of one farm round (model above) and its efficiency on p ranks."""
    if n <= 0:
        return 0.0, 1.0
    w = p if p <= 2 else p - 1
    us = 1e-6
    compute = math.ceil(n / w) * t + min(w, n) * c_task * us
    T = max(compute, n * c_serve * us) + n * c_fold_after * us
    return T, n * t / (p * T)


def paper_rounds(path):
    with open(path, "rb") as fh:
        cfg = tomllib.load(fh)
    c, d, s = cfg["connectors"], cfg["deploy"], cfg["specialists"]
    novel = sum(1 for e in d["environments"] if e != "flat")
    return {"connectors": len(c["kinds"]) * c["replicates"] * c["batch_pairs"],
            "specialists": novel * s["replicates"] * c["batch_pairs"]}


def table(costs, rounds, ranks, item_ms, pairs_per_item=(1,)):
    top, rows = costs
    lines = ["| round | items | item (ms) | fold | " + " | ".join(f"{p} ranks" for p in ranks) + " |",
             "|---|---|---|---|" + "---|" * len(ranks)]
    for stage, pairs in rounds.items():
        for b, ms in [(b, b * t) for b in pairs_per_item for t in item_ms]:
            n = -(-pairs // b)
            for fold in ("after", "during"):
                if fold not in rows:
                    continue
                r = rows[fold]
                c_serve = float(r["master_cpu_us_per_item"])
                c_fold = float(r["fold_us_per_result"]) if fold == "after" else 0.0
                cells = []
                for p in ranks:
                    T, e = round_time(n, ms * 1e-3, p, c_serve, float(r["task_us_per_msg"]), c_fold)
                    cells.append(f"{e:.0%} ({T * 1e3:.0f} ms)")
                what = f"{stage} training" + (f", {b} pairs per item" if b > 1 else "")
                lines.append(f"| {what} | {n} | {ms:g} | {fold} the round | " + " | ".join(cells) + " |")
    after = rows["after"]
    caption = (f"Costs from the {top}-rank rows: c_serve = {float(after['master_cpu_us_per_item']):.2f} µs per item "
               f"(fold after)" + (f", {float(rows['during']['master_cpu_us_per_item']):.2f} µs with the fold during the "
                                  f"round" if "during" in rows else "")
               + f", c_task = {float(after['task_us_per_msg']):.2f} µs per task message, c_fold = "
               f"{float(after['fold_us_per_result']):.2f} µs per result, {float(after['bytes_per_result']):.0f} B per result.")
    return lines, caption


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", help="farm.csv of jobs/bench-farm.sh")
    ap.add_argument("--paper", default=PAPER, help="config whose round sizes to model (default configs/paper.toml)")
    ap.add_argument("--ranks", type=int, nargs="+", default=[64, 512])
    ap.add_argument("--item-ms", type=float, nargs="+", default=[12.5, 6.25],
                    help="ms of one item (pair episode with gradient): 12.5 at 80k pair-steps/s, 6.25 at twice that")
    ap.add_argument("--pairs-per-item", type=int, nargs="+", default=[1],
                    help="pair episodes per item, their gradients summed by the worker (1: today's stages)")
    a = ap.parse_args(argv)
    try:
        if any(p < 1 for p in a.ranks) or any(t <= 0 for t in a.item_ms) or any(b < 1 for b in a.pairs_per_item):
            raise InputError("--ranks, --item-ms and --pairs-per-item must be positive")
        if not os.path.isfile(a.paper):
            raise InputError(f"{a.paper}: no such config")
        lines, caption = table(read_costs(a.csv), paper_rounds(a.paper), a.ranks, a.item_ms, a.pairs_per_item)
    except (InputError, KeyError, ValueError, tomllib.TOMLDecodeError) as e:
        print(f"farm_model: {e}", file=sys.stderr)
        return 2
    print("\n".join(lines + ["", caption]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
