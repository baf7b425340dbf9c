#!/usr/bin/python3
"""One table over several sittings of `bash jobs/bench-scaling.sh CONFIG OUT "1 1+1 2"`: per stage and sitting, the
2-rank wall ratio, the cap (two 1-rank runs at once) and the share of the cap reached, and where the runs have the
CPU counters the speed-up their busy and on-core shares imply (postprocess/fig_scaling.py's `implied`).

    /usr/bin/python3 postprocess/gallery/scaling_sittings_table.py OUT1 OUT2 ...
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import fig_scaling as F  # noqa: E402


def main(dirs):
    if not dirs:
        print(__doc__, file=sys.stderr)
        return 2
    print("| stage | " + " | ".join(os.path.basename(os.path.normpath(d)) for d in dirs) + " |")
    print("|---|" + "---|" * len(dirs))
    data = []
    for d in dirs:
        rows = {(r["ranks"], r["stage"]): r for r in F.read(d)}
        conc = F.read_concurrent(d)
        if not conc or not all((n, s) in rows for n in (1, 2) for s in conc):
            print(f"scaling_sittings_table: {d} lacks a 1-rank, 2-rank or 1+1 run", file=sys.stderr)
            return 2
        data.append((rows, conc))
    for st in F.STAGES + ["total"]:
        cells = []
        for rows, conc in data:
            stages = [s for s in F.STAGES if s in conc]
            if st != "total" and st not in conc:
                cells.append("—")
                continue
            cap = F.cap_for_two(rows, conc, stages, st)
            w1, w2 = (sum(rows[(n, s)]["wall_s"] for s in ([st] if st != "total" else stages)) for n in (1, 2))
            imp = F.implied(rows[(2, st)], rows[(1, st)]) if st != "total" else None
            cells.append(f"×{w1 / w2:.2f} of cap ×{cap:.2f} ({w1 / w2 / cap:.0%})" +
                         (f", implied ×{imp:.2f}" if imp is not None else ""))
        print(f"| {st} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
