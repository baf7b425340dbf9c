"""Table and plot of a scaling benchmark (jobs/bench-scaling.sh): wall time per stage against ranks,
speed-up, each stage's busy fraction (in all, and of each rank: seconds computing items / wall seconds),
load imbalance and the master's serial seconds (its time outside the farm while the workers wait: the rounds'
inputs, items, writes and commits; runs made before the attribute existed show none), and at more than one
rank the share of their busy time the computing threads spent on a core (CPU / wall seconds inside compute():
below 100% when the serving thread, another process or the host took the core) and the serving threads' CPU as
a share of a core, and at 2 ranks the speed-up those shares imply (`implied`: 2 x busy share x on-core share /
the 1-rank busy share), read from
OUT/run_np<N>.h5. With OUT/concurrent_a.h5 and OUT/concurrent_b.h5 (bench-scaling.sh's "1+1": two independent
1-rank runs at once) and a 1-rank run, a column gives the machine's cap for 2 ranks per stage, 2 × t(1 rank) /
mean t(each of the two at once), and the 2-rank cell says what share of that cap it reached.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.fig_scaling OUT [--cores C]

Writes OUT/scaling.csv, OUT/scaling.md and OUT/scaling.png.
"""
import argparse
import glob
import os
import re
import sys

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..reader import STAGES, open_file, text as _s  # noqa: E402


def parse_serial(text):
    """'input=0.1,items=0.0,writes=0.2,commits=0.0' -> {name: seconds} ({} when absent or unreadable)"""
    out = {}
    for part in _s(text).split(","):
        name, _, value = part.partition("=")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            return {}
    return out if any(out) else {}


def read(out):
    rows = []
    for path in glob.glob(os.path.join(out, "run_np*.h5")):
        m = re.search(r"run_np(\d+)\.h5$", path)
        if not m:
            continue
        rows += _stage_rows(path, int(m.group(1)))
    return sorted(rows, key=lambda r: (r["ranks"], STAGES.index(r["stage"])))


def read_concurrent(out):
    """{stage: [wall s of concurrent_a, of concurrent_b]} for stages both runs have ({} without both files)"""
    paths = [os.path.join(out, f"concurrent_{side}.h5") for side in "ab"]
    if not all(os.path.exists(p) for p in paths):
        return {}
    walls = [{r["stage"]: r["wall_s"] for r in _stage_rows(p, 1)} for p in paths]
    return {st: [walls[0][st], walls[1][st]] for st in STAGES if st in walls[0] and st in walls[1]}


def _stage_rows(path, n):
    rows = []
    with open_file(path) as f:
        for st in STAGES:
            if st not in f or "wall_s_last_session" not in f[st].attrs:
                continue
            g = f[st]
            busy = [float(x) for x in _s(g.attrs.get("busy_s_per_rank_last_session", "")).split(",") if x]
            wall = float(g.attrs["wall_s_last_session"])
            serial = parse_serial(g.attrs.get("master_serial_s_last_session", ""))
            # CPU seconds per rank of the computing threads inside compute() and of the serving threads (runs
            # made before these attributes existed have none)
            ccpu = [float(x) for x in _s(g.attrs.get("compute_cpu_s_per_rank_last_session", "")).split(",") if x]
            scpu = [float(x) for x in _s(g.attrs.get("serve_cpu_s_per_rank_last_session", "")).split(",") if x]
            rows.append(dict(ranks=n, stage=st, wall_s=wall,
                             rank_busy=[b / wall for b in busy] if wall > 0 else [],
                             busy_fraction=sum(busy) / (n * wall) if busy and wall > 0 else float("nan"),
                             master_busy=busy[0] / wall if busy and wall > 0 else float("nan"),
                             imbalance=max(busy) / np.mean(busy) if busy and np.mean(busy) > 0 else float("nan"),
                             serial_s=sum(serial.values()) if serial else float("nan"),
                             on_cpu=sum(ccpu) / sum(busy) if ccpu and busy and sum(busy) > 0 else float("nan"),
                             serve_cpu=sum(scpu) / (n * wall) if scpu and wall > 0 else float("nan")))
    return rows


def implied(r, r1):
    """the speed-up over 1 rank that a run's busy and CPU shares imply with a core per rank and items that cost
    the CPU they cost at 1 rank: n x busy share x on-core share / busy share at 1 rank (None without them).
    On a host whose speed drifts between runs this reads the farm's own losses (idle ranks, serving threads)
    where the wall-time ratio mostly reads the drift"""
    if r1 is None or not np.isfinite(r.get("on_cpu", float("nan"))) or not r1["busy_fraction"] > 0:
        return None
    return r["ranks"] * r["busy_fraction"] * r["on_cpu"] / r1["busy_fraction"]


def cap_for_two(wall, conc, stages, st):
    """the cap for 2 ranks of stage `st` (or "total": every stage of `stages`): 2 x t(1 rank) / mean t(two 1-rank
    runs at once), from `wall` ({(ranks, stage): row}) and `conc` (read_concurrent); None without both"""
    if st == "total":
        if not stages or not all(s in conc and (1, s) in wall for s in stages):
            return None
        return 2 * sum(wall[(1, s)]["wall_s"] for s in stages) / sum(np.mean(conc[s]) for s in stages)
    if st not in conc or (1, st) not in wall:
        return None
    return 2 * wall[(1, st)]["wall_s"] / np.mean(conc[st])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", help="folder with run_np<N>.h5")
    ap.add_argument("--cores", type=int, default=os.cpu_count(), help="cores of the machine (marks oversubscription)")
    a = ap.parse_args(argv)
    rows = read(a.out)
    if not rows:
        print(f"fig_scaling: no run_np<N>.h5 with stage timings in {a.out}", file=sys.stderr)
        return 2
    with open(os.path.join(a.out, "scaling.csv"), "w") as fh:
        fh.write("ranks,stage,wall_s,busy_fraction,master_busy,imbalance,master_serial_s,busy_per_rank\n")
        for r in rows:
            fh.write(f"{r['ranks']},{r['stage']},{r['wall_s']:.3f},{r['busy_fraction']:.3f},{r['master_busy']:.3f},"
                     f"{r['imbalance']:.3f},{r['serial_s']:.3f},{' '.join(f'{b:.3f}' for b in r['rank_busy'])}\n")
    ranks = sorted({r["ranks"] for r in rows})
    stages = [s for s in STAGES if any(r["stage"] == s for r in rows)]
    wall = {(r["ranks"], r["stage"]): r for r in rows}
    conc = read_concurrent(a.out) if 1 in ranks else {}

    def cap(st):
        return cap_for_two(wall, conc, stages, st)

    md = ["| stage | " + " | ".join(f"{n} rank{'s' if n > 1 else ''}{' (oversubscribed)' if n > a.cores else ''}"
                                     for n in ranks) +
          (" | two 1-rank runs at once: each, and the cap for 2 ranks" if conc else "") + " |",
          "|---|" + "---|" * (len(ranks) + (1 if conc else 0))]
    for st in stages + ["total"]:
        cells = []
        for n in ranks:
            def of_cap(ratio):  # ", X% of the cap" after the 2-rank ratio over 1 rank, where there is a cap
                c = cap(st) if n == 2 and ranks[0] == 1 else None
                return f", {ratio / c:.0%} of the cap" if c is not None else ""
            if st == "total":
                w = sum(wall[(n, s)]["wall_s"] for s in stages if (n, s) in wall)
                base = sum(wall[(ranks[0], s)]["wall_s"] for s in stages if (ranks[0], s) in wall)
                cells.append(f"**{w:.1f} s** (×{base / w:.2f}{of_cap(base / w)})")
            elif (n, st) in wall:
                r = wall[(n, st)]
                ratio = wall[(ranks[0], st)]["wall_s"] / r["wall_s"] if (ranks[0], st) in wall else None
                speed = f" (×{ratio:.2f}{of_cap(ratio)})" if ratio is not None and n != ranks[0] else ""
                serial = f", serial {r['serial_s']:.2f} s" if np.isfinite(r["serial_s"]) else ""
                if n > 1 and np.isfinite(r["on_cpu"]):
                    serial += f", computing on a core {r['on_cpu']:.0%} of busy"
                if n > 1 and np.isfinite(r["serve_cpu"]):
                    serial += f", serving {r['serve_cpu']:.1%} of a core"
                imp = implied(r, wall.get((1, st)))
                if n == 2 and imp is not None:
                    serial += f"; implied ×{imp:.2f}"
                cells.append(f"{r['wall_s']:.1f} s{speed}, busy {r['busy_fraction']:.0%} (per rank "
                             f"{'/'.join(f'{b:.0%}' for b in r['rank_busy'])}), imbalance {r['imbalance']:.2f}{serial}")
            else:
                cells.append("—")
        if conc:
            c = cap(st)
            if st == "total":
                each = [sum(conc[s][k] for s in stages if s in conc) for k in (0, 1)]
                cells.append(f"{each[0]:.1f} s, {each[1]:.1f} s: **cap ×{c:.2f}**" if c is not None else "—")
            elif st in conc:
                cells.append(f"{conc[st][0]:.1f} s, {conc[st][1]:.1f} s" + (f": cap ×{c:.2f}" if c is not None else ""))
            else:
                cells.append("—")
        md.append(f"| {st} | " + " | ".join(cells) + " |")
    with open(os.path.join(a.out, "scaling.md"), "w") as fh:
        fh.write("\n".join(md) + "\n")
    print("\n".join(md))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4), dpi=100)
    for st in stages:
        ns = [n for n in ranks if (n, st) in wall]
        w = [wall[(n, st)]["wall_s"] for n in ns]
        ax1.plot(ns, w, "o-", label=st)
        ax2.plot(ns, [w[0] / x for x in w], "o-", label=st)
    ax2.plot(ranks, [min(n, a.cores) / ranks[0] for n in ranks], "k--", lw=0.8, label=f"ideal ({a.cores} cores)")
    for ax in (ax1, ax2):
        ax.set_xlabel("MPI ranks")
        ax.set_xticks(ranks)
        if ranks[-1] > a.cores:
            ax.axvspan(a.cores + 0.5, ranks[-1] + 0.5, color="0.9", zorder=0)
            if ax is ax2:
                ax.text(a.cores + 0.6, ax.get_ylim()[1] * 0.95, "oversubscribed", fontsize=8, va="top")
    ax1.set_ylabel("wall time per stage (s)")
    ax1.set_yscale("log")
    ax2.set_ylabel(f"speed-up over {ranks[0]} rank(s)")
    ax1.legend(fontsize=8)
    ax1.set_title("time per stage")
    ax2.set_title("speed-up")
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "scaling.png"))
    print(f"fig_scaling: wrote {os.path.join(a.out, 'scaling.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
