"""Efficiency of the paper's task-farm rounds at many ranks, from the master's cost measured by
jobs/bench-farm.sh (`divcoll bench-farm` at 8, 16, 32 ranks).

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.farm_model OUT/farm.csv [--paper configs/paper.toml]
        [--ranks 64 512] [--item-ms 6.25] [--pairs-per-item 1] [--cost fit|top]

One round of n items of t seconds on p ranks: the master only coordinates (W = p - 1 workers; with p <= 2
it computes too, W = p). It sends every worker its first block one message after another, then answers
each result with the next block; every item costs it c_serve of CPU (taking in the result, sending the
next task, and, when the stage folds during the round, the fold); a stage that folds after the round
(unpack and add every result, as the connectors stage sums gradients) adds n c_fold of serial time:

    T(p) = max(ceil(n / W) t + W c_task, n c_serve) + n c_fold_after,     efficiency = n t / (p T(p)).

c_task and c_fold are the rows of the largest rank count in the CSV (guided blocks). c_serve (--cost fit, the
default) comes from every guided row of a fold mode: the master's CPU per round is fitted as a w + b n (w the
round's wall time, n its items; least squares over the rank counts). a is the share of a core the master spends
between messages while it waits (waking from its sleeps, polling MPI), which does not grow with the ranks; b is
its CPU per item. At small rank counts the waiting dominates the CPU per item (26 µs at 8 ranks, 13 at 32 in one
sweep), so the largest rank count's row (--cost top, the model before) still counts some of it. A master that
waits a share a of a round serves n items in n b / (1 - a), the c_serve the model uses. Items per
round and the result size are the paper config's connectors and specialists training rounds (one pair
episode with gradient per item; its result is the connector's gradient, 1473 doubles). Assumes a network
whose per-message CPU cost at the master is no higher than this machine's shared memory, and leaves out
what a round does besides the farm (broadcasting weights, HDF5 writes, checkpoints: see mpi/README.md).
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
PAPER = os.path.join(os.path.dirname(os.path.dirname(HERE)), "configs", "paper.toml")  # the repository's


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
    out = {r["fold"]: dict(r) for r in guided if int(r["ranks"]) == top}
    if "after" not in out:
        raise InputError(f"{path}: no fold=after row at {top} ranks")
    for fold, r in out.items():
        r["fit"] = fit_serve([g for g in guided if g["fold"] == fold])
    return top, out


def fit_serve(rows):
    """(a, b µs, c_serve µs) of the master's CPU per round = a * wall + b * items over the rows (several rank
    counts), or None with fewer than two rank counts or a fit outside 0 <= a < 1, b > 0."""
    pts = []
    for r in rows:
        n = float(r["items"])
        pts.append((float(r["round_s"]), n, float(r["master_cpu_us_per_item"]) * 1e-6 * n))
    if len({(w, n) for w, n, _ in pts}) < 2:
        return None
    sww = sum(w * w for w, _, _ in pts)
    swn = sum(w * n for w, n, _ in pts)
    snn = sum(n * n for _, n, _ in pts)
    swy = sum(w * y for w, _, y in pts)
    sny = sum(n * y for _, n, y in pts)
    det = sww * snn - swn * swn
    if abs(det) <= 1e-12 * sww * snn:
        return None
    a = (swy * snn - sny * swn) / det
    b = (sww * sny - swn * swy) / det
    if not (0 <= a < 1 and b > 0):
        return None
    return a, b * 1e6, b * 1e6 / (1 - a)


def serve_cost(row, cost):
    """c_serve (µs per item) of one fold mode's row: the fit's, or the row's own CPU per item."""
    if cost == "fit" and row.get("fit"):
        return row["fit"][2]
    return float(row["master_cpu_us_per_item"])


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


def table(costs, rounds, ranks, item_ms, pairs_per_item=(1,), cost="fit"):
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
                c_serve = serve_cost(r, cost)
                c_fold = float(r["fold_us_per_result"]) if fold == "after" else 0.0
                cells = []
                for p in ranks:
                    T, e = round_time(n, ms * 1e-3, p, c_serve, float(r["task_us_per_msg"]), c_fold)
                    cells.append(f"{e:.0%} ({T * 1e3:.0f} ms)")
                what = f"{stage} training" + (f", {b} pairs per item" if b > 1 else "")
                lines.append(f"| {what} | {n} | {ms:g} | {fold} the round | " + " | ".join(cells) + " |")
    after = rows["after"]
    parts = []
    for fold in ("after", "during"):
        if fold not in rows:
            continue
        r, label = rows[fold], "fold after" if fold == "after" else "with the fold during the round"
        if cost == "fit" and r.get("fit"):
            a, b, c = r["fit"]
            parts.append(f"c_serve = {c:.2f} µs per item {label} (fit over the rank counts: {b:.2f} µs per item, "
                         f"waiting {a:.1%} of a core; the {top}-rank row alone: "
                         f"{float(r['master_cpu_us_per_item']):.2f} µs)")
        else:
            parts.append(f"c_serve = {float(r['master_cpu_us_per_item']):.2f} µs per item {label} ({top}-rank row)")
    caption = ("Costs: " + "; ".join(parts) + f"; c_task = {float(after['task_us_per_msg']):.2f} µs per task message, "
               f"c_fold = {float(after['fold_us_per_result']):.2f} µs per result, {float(after['bytes_per_result']):.0f} "
               f"B per result ({top}-rank rows).")
    return lines, caption


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", help="farm.csv of jobs/bench-farm.sh")
    ap.add_argument("--paper", default=PAPER, help="config whose round sizes to model (default configs/paper.toml)")
    ap.add_argument("--ranks", type=int, nargs="+", default=[64, 512])
    ap.add_argument("--item-ms", type=float, nargs="+", default=[6.25],
                    help="ms of one item (pair episode with gradient): 6.25 at 160k pair-steps/s (the current "
                         "engine), 12.5 at dea5a14's 80k")
    ap.add_argument("--cost", choices=["fit", "top"], default="fit",
                    help="c_serve from a fit over every rank count (default) or the largest rank count's row")
    ap.add_argument("--pairs-per-item", type=int, nargs="+", default=[1],
                    help="pair episodes per item, their gradients summed by the worker (1: today's stages)")
    a = ap.parse_args(argv)
    try:
        if any(p < 1 for p in a.ranks) or any(t <= 0 for t in a.item_ms) or any(b < 1 for b in a.pairs_per_item):
            raise InputError("--ranks, --item-ms and --pairs-per-item must be positive")
        if not os.path.isfile(a.paper):
            raise InputError(f"{a.paper}: no such config")
        lines, caption = table(read_costs(a.csv), paper_rounds(a.paper), a.ranks, a.item_ms, a.pairs_per_item,
                               a.cost)
    except (InputError, KeyError, ValueError, tomllib.TOMLDecodeError) as e:
        print(f"farm_model: {e}", file=sys.stderr)
        return 2
    print("\n".join(lines + ["", caption]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
