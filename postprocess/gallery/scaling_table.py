#!/usr/bin/python3
"""One table over several measurements of `bash jobs/bench-scaling.sh CONFIG OUT "1 1+1 2"` (or "1 2"): per stage
and measurement, the 2-rank wall ratio, the cap (two 1-rank runs at once; only in measurements that ran `1+1`) and
the share of the cap reached, and where the runs have the CPU counters the speed-up their busy and on-core shares
imply (divcoll_post.figures.fig_scaling's `implied`).

    /usr/bin/python3 postprocess/gallery/scaling_table.py [--factors] OUT1 OUT2 ...

--factors: instead, the two factors of `implied` per stage and measurement: the busy share at 2 ranks (and
2 × busy₂ / busy₁, the farm's idle time alone) and the share of the computing threads' busy time they were on a core.
"""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from divcoll_post.figures import fig_scaling as F  # noqa: E402


def factors(dirs):
    print("| stage | " + " | ".join(os.path.basename(os.path.normpath(d)) for d in dirs) + " |")
    print("|---|" + "---|" * len(dirs))
    data = [{(r["ranks"], r["stage"]): r for r in F.read(d)} for d in dirs]
    for st in F.STAGES:
        cells = []
        for rows in data:
            if (1, st) not in rows or (2, st) not in rows or not math.isfinite(rows[(2, st)].get("on_cpu", math.nan)):
                cells.append("—")
                continue
            r1, r2 = rows[(1, st)], rows[(2, st)]
            cells.append(f"{100 * r2['busy_fraction']:.0f}% (×{2 * r2['busy_fraction'] / r1['busy_fraction']:.2f}), "
                         f"on core {100 * r2['on_cpu']:.0f}%")
        print(f"| {st} | " + " | ".join(cells) + " |")
    return 0


def main(dirs):
    if dirs and dirs[0] == "--factors":
        return factors(dirs[1:]) if dirs[1:] else main([])
    if not dirs:
        print(__doc__, file=sys.stderr)
        return 2
    print("| stage | " + " | ".join(os.path.basename(os.path.normpath(d)) for d in dirs) + " |")
    print("|---|" + "---|" * len(dirs))
    data = []
    for d in dirs:
        rows = {(r["ranks"], r["stage"]): r for r in F.read(d)}
        conc = F.read_concurrent(d)
        if not conc:  # no 1+1 run: the stages both rank counts ran, no cap
            conc = {s: None for s in F.STAGES if (1, s) in rows and (2, s) in rows}
        if not conc or not all((n, s) in rows for n in (1, 2) for s in conc):
            print(f"scaling_table: {d} lacks a 1-rank or a 2-rank run", file=sys.stderr)
            return 2
        data.append((rows, conc))
    for st in F.STAGES + ["total"]:
        cells = []
        for rows, conc in data:
            stages = [s for s in F.STAGES if s in conc]
            if st != "total" and st not in conc:
                cells.append("—")
                continue
            w1, w2 = (sum(rows[(n, s)]["wall_s"] for s in ([st] if st != "total" else stages)) for n in (1, 2))
            imp = F.implied(rows[(2, st)], rows[(1, st)]) if st != "total" else None
            if all(v is None for v in conc.values()):
                cell = f"×{w1 / w2:.2f}"
            else:
                cap = F.cap_for_two(rows, conc, stages, st)
                cell = f"×{w1 / w2:.2f} of cap ×{cap:.2f} ({w1 / w2 / cap:.0%})"
            cells.append(cell + (f", implied ×{imp:.2f}" if imp is not None else ""))
        print(f"| {st} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
