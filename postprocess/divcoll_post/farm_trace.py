"""Where a multi-rank run's time goes, from the task farm's trace (mpi/scheduler.hpp, DIVCOLL_FARM_TRACE).

    DIVCOLL_FARM_TRACE=/tmp/tr mpirun -x DIVCOLL_FARM_TRACE -np 2 build/divcoll run CONFIG --out RUN.h5
    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.farm_trace /tmp/tr [--ranks 2]

Every rank appends its events to PREFIX.RANK, one per line, "KIND T A B" with T on the machine's monotonic
clock (seconds; the ranks of one machine share it): F farm() entered (A = items of the round), C an item
computed (T its end, A its start), E farm() left; the master's G (a block handed to a worker, A its first
item) and R (a worker's result taken in); a worker's S (its result sent, A its first item) and T (a block
received). Several runs appended to one prefix are told apart by their farm() calls only: use a new prefix.

Prints, for each rank, the share of the traced time (first farm entered to last farm left, over all ranks)
spent computing items and where the rest went: outside farm() (the master's work between rounds, which the
workers wait for), from farm() entered to its first item, from its last item to farm() left (the round's
tail: waiting for the other ranks' last items), and between items inside a round; then, for the worker
ranks, each wait between two items of one round taken apart (its result sent, the master taking it in,
the master handing out the next block, the worker receiving it, its computing thread starting it).
Exit status 2 on bad input.
"""
import argparse
import bisect
import statistics
import sys


def load(path):
    events = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            parts = line.split()
            if len(parts) != 4 or parts[0] not in "FCEGRST" or len(parts[0]) != 1:
                raise ValueError(f"{path}:{n}: not a farm trace line: {line.strip()!r}")
            events.append((parts[0], float(parts[1]), float(parts[2])))
    return events


def farm_calls(events):
    """the rank's farm() calls in order: dict(F=entered, E=left, n=items, C=[(start, end)])"""
    calls, cur = [], None
    for kind, t, a in events:
        if kind == "F":
            cur = {"F": t, "n": int(a), "C": []}
        elif kind == "C" and cur is not None:
            cur["C"].append((a, t))
        elif kind == "E" and cur is not None:
            cur["E"] = t
            calls.append(cur)
            cur = None
    return calls


def decompose(ranks):
    """per rank: dict of seconds (busy, outside, start, tail, gaps) and the traced wall time"""
    calls = [farm_calls(ev) for ev in ranks]
    if not calls[0] or any(len(c) != len(calls[0]) for c in calls):
        raise ValueError(f"the ranks' traces hold different numbers of farm() calls: {[len(c) for c in calls]}")
    t0 = min(c[0]["F"] for c in calls)
    t1 = max(c[-1]["E"] for c in calls)
    out = []
    for rc in calls:
        d = dict(busy=0.0, outside=0.0, start=0.0, tail=0.0, gaps=0.0, items=0)
        prev = t0
        for c in rc:
            d["outside"] += c["F"] - prev
            prev = c["E"]
            items = c["C"]
            d["items"] += len(items)
            d["busy"] += sum(b - a for a, b in items)
            if items:
                d["start"] += items[0][0] - c["F"]
                d["tail"] += c["E"] - items[-1][1]
                d["gaps"] += sum(a1 - b0 for (_, b0), (a1, _) in zip(items, items[1:]))
            else:
                d["start"] += c["E"] - c["F"]
        d["outside"] += t1 - prev
        out.append(d)
    return out, t1 - t0, len(calls[0])


def handoffs(master, worker):
    """a worker's waits between two items of one round, each taken apart (seconds)"""
    def times(ev, kind):
        return sorted(t for k, t, _ in ev if k == kind)

    sent, got, taken, given, entered = (times(worker, "S"), times(worker, "T"), times(master, "R"),
                                        times(master, "G"), times(worker, "F"))
    items = [(a, t) for k, t, a in worker if k == "C"]

    def after(seq, t):
        i = bisect.bisect_left(seq, t)
        return seq[i] if i < len(seq) else None

    parts = []
    for (_, end), (start, _) in zip(items, items[1:]):
        f = after(entered, end)
        if f is not None and f < start:  # the next item is in the next round
            continue
        s = after(sent, end)
        r = after(taken, s) if s is not None else None
        g = after(given, r) if r is not None else None
        t = after(got, g) if g is not None else None
        if None in (s, r, g, t) or t > start:  # the next item was already queued
            continue
        parts.append((s - end, r - s, g - r, t - g, start - t, start - end))
    return parts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("prefix", help="DIVCOLL_FARM_TRACE's prefix (files PREFIX.0, PREFIX.1, ...)")
    ap.add_argument("--ranks", type=int, default=2, help="ranks of the run (default 2)")
    a = ap.parse_args(argv)
    try:
        ranks = [load(f"{a.prefix}.{r}") for r in range(a.ranks)]
        per_rank, wall, rounds = decompose(ranks)
    except (OSError, ValueError) as e:
        print(f"farm_trace: {e}", file=sys.stderr)
        return 2
    print(f"{rounds} farm() calls, {wall:.3f} s from the first farm() entered to the last one left")
    print()
    print("| rank | items | computing | outside farm() | first item's wait | round tails | between items |")
    print("|---|---|---|---|---|---|---|")
    for r, d in enumerate(per_rank):
        cells = [f"{d[k]:.3f} s ({100 * d[k] / wall:.1f}%)" for k in ("busy", "outside", "start", "tail", "gaps")]
        print(f"| {r} | {d['items']} | " + " | ".join(cells) + " |")
    names = ["result sent", "master took it in", "next block handed out", "worker received it", "item started"]
    for w in range(1, a.ranks):
        parts = handoffs(ranks[0], ranks[w])
        if not parts:
            continue
        print()
        print(f"rank {w}: {len(parts)} waits between two items of a round, {sum(p[5] for p in parts):.3f} s in all;"
              " each, in µs (median, mean):")
        print()
        print("| step | median | mean |")
        print("|---|---|---|")
        for i, name in enumerate(names + ["whole wait"]):
            v = [p[i] * 1e6 for p in parts]
            print(f"| {name} | {statistics.median(v):.0f} | {statistics.mean(v):.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
