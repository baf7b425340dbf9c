#!/usr/bin/python3
"""The claims tables of two report pages side by side: each claim's number and verdict in run A and run B, and
whether the verdict is the same. Reads the `report.md` that `divcoll report` writes (the table under "The paper's
claims beside this run"), so it needs no run file.

    /usr/bin/python3 postprocess/gallery/claims_side_by_side.py A/report.md B/report.md [--names A B]

Prints a Markdown table and a last line "N of M claims keep their verdict"; exits 1 when a claim is in one page
only (the pages come from different versions of the claims).
"""
import argparse
import sys


def claims(path):
    """[(claim, number, verdict)] in the page's order"""
    rows, inside = [], False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("## "):
                inside = line.startswith("## The paper's claims beside this run")
                continue
            if not inside or not line.startswith("| ") or line.startswith("| claim |"):
                continue
            cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
            if len(cells) < 3:
                continue
            rows.append((cells[0], cells[1], cells[2].strip("*")))
    if not rows:
        sys.exit(f"{path}: no claims table (a report.md of `divcoll report`?)")
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--names", nargs=2, default=["A", "B"])
    args = ap.parse_args()
    a, b = claims(args.a), claims(args.b)
    bmap = {c: (n, v) for c, n, v in b}
    na, nb = args.names
    print(f"| claim | {na}: this run | {na} | {nb}: this run | {nb} | same verdict |")
    print("|---|---|---|---|---|---|")
    same = 0
    missing = [c for c, _, _ in a if c not in bmap] + [c for c, _, _ in b if c not in {x for x, _, _ in a}]
    for c, n, v in a:
        if c not in bmap:
            continue
        n2, v2 = bmap[c]
        same += v == v2
        print(f"| {c} | {n} | {v} | {n2} | {v2} | {'yes' if v == v2 else '**no**'} |")
    print()
    print(f"{same} of {len(a) - len([c for c, _, _ in a if c not in bmap])} claims keep their verdict")
    if missing:
        print("in one page only: " + "; ".join(missing), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
