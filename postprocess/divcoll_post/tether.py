"""What the tether does to each agent of a pair: the `tether.csv` files that `divcoll tether RUN.h5` writes (one row per
episode: a pair, a connector, its environment; gzipped or not) summarised into one page and one picture, for one
population (`divcoll tether` runs this module on its own table) or over several.

Per environment and connector, over the pairs of each population and then over populations (mean, and the range of
the population means): the pair's travel against the free tether on the same pairs (no springs: each agent as it walks
alone from its place in the pair), the slower and the faster agent's (slower: less travel under the free tether), the
tether's net horizontal push on the slower agent as a share of the force it exerted (∫|f|dt over its five springs),
and the work its springs did on both agents.

    /usr/bin/python3 -m divcoll_post.tether postprocess/gallery/tether/besteffort_seed*/tether.csv.gz \
        --out postprocess/gallery/tether
"""

from __future__ import annotations

import argparse
import csv
import gzip
import os
import re
from typing import Dict, List, Sequence, Tuple

import numpy as np

from . import results as R

CONNECTORS = ("passive", "follower", "trained")
COLUMNS = ("travel", "pair", "slower", "faster", "push", "work")


def read(path: str) -> Dict[Tuple[str, str, str], Dict[str, float]]:
    """{(environment, deployment, connector): {column: mean over the pairs}} of one tether.csv, each against the free
    tether of the same pair; pairs whose episode (or free episode) did not end ok are left out"""
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    free = {(r["environment"], r["deployment"], r["pair"]): r for r in rows if r["connector"] == "free"}
    acc: Dict[Tuple[str, str, str], List[List[float]]] = {}
    for r in rows:
        f = free.get((r["environment"], r["deployment"], r["pair"]))
        if r["connector"] == "free" or f is None or r["status"] != "ok" or f["status"] != "ok":
            continue
        fp, fa = float(f["posterior_travel_bl"]), float(f["anterior_travel_bl"])
        slow = "posterior" if fp <= fa else "anterior"
        fast = "anterior" if slow == "posterior" else "posterior"
        ft = float(r["force_time"])
        acc.setdefault((r["environment"], r["deployment"], r["connector"]), []).append([
            float(r["pair_travel_bl"]), float(r["pair_travel_bl"]) - float(f["pair_travel_bl"]),
            float(r[f"{slow}_travel_bl"]) - float(f[f"{slow}_travel_bl"]),
            float(r[f"{fast}_travel_bl"]) - float(f[f"{fast}_travel_bl"]),
            float(r[f"{slow}_impulse_x"]) / ft if ft > 0 else 0.0,
            float(r["posterior_work"]) + float(r["anterior_work"])])
    return {k: dict(zip(COLUMNS, np.mean(np.array(v), axis=0))) for k, v in acc.items()}


def population_of(path: str) -> str:
    """the population a table belongs to: the last `seed<k>` in its path (a file or the folder that holds it)"""
    m = re.findall(r"seed(\d+)", path)
    return m[-1] if m else os.path.basename(path)


def summarise(paths: Sequence[str]):
    """(populations, {(environment, deployment, connector): {column: (P,) population means}}, environments in file
    order)"""
    per = [read(p) for p in paths]
    keys = [k for k in per[0] if all(k in q for q in per)]
    envs = list(dict.fromkeys(k[0] for k in keys))
    table = {k: {c: np.array([q[k][c] for q in per]) for c in COLUMNS} for k in keys}
    return [population_of(p) for p in paths], table, envs


def cell(x: np.ndarray, fmt: str) -> str:
    return f"{np.mean(x):{fmt}}" + (f" [{np.min(x):{fmt}}, {np.max(x):{fmt}}]" if len(x) > 1 else "")


def page(paths: Sequence[str], out: str, provenance: str = "") -> str:
    """OUT/tether.md and OUT/tether.png from the tether.csv files `paths`; `provenance` (what `divcoll tether` passes:
    the run file, command, commit and machine) replaces the line naming the tables; returns the page's path"""
    pops, table, envs = summarise(paths)
    os.makedirs(out, exist_ok=True)
    rel = [os.path.relpath(p) for p in paths]
    source = provenance or (
        f"`/usr/bin/python3 -m divcoll_post.tether {' '.join(rel)} --out {os.path.relpath(out)}`, from the "
        f"`divcoll tether` tables of populations {', '.join(pops)} (each population's page names its run file, "
        "command, commit and machine).")
    over = ("Mean over populations of the per-population means over pairs, with the range of the population means in "
            "brackets." if len(paths) > 1 else "Means over the pairs.")
    lines = ["# What the tether does to each agent of a pair", "", source, "",
             "*Pair*: the pair's travel, BL over the episode. Against the free tether on the same pairs (no springs: "
             "each agent walks as alone from its place in the pair), in BL: the pair, its slower agent (less travel "
             "under the free tether) and its faster one. *Push*: the tether's net horizontal impulse on the slower "
             "agent as a share of the force its springs exerted (∫|f|dt); the faster agent gets the opposite push. "
             "*Work*: what the tether's springs "
             "did on both agents, mass·u²/s² (negative: energy taken from the agents' gaits). " + over, "",
             "![each agent's travel against the free tether](tether.png)", ""]
    for dep, label in (("uniform", "clones (the weak uniform kind trained)"),
                       ("diverse", "diverse pairs (the weak diverse kind trained)")):
        lines += [f"## {label.capitalize()}", "",
                  "| environment | connector | pair (BL) | pair − free (BL) | slower agent − free (BL) | "
                  "faster agent − free (BL) | push on the slower agent | work on the pair |",
                  "|---|---|---|---|---|---|---|---|"]
        for e in envs:
            for c in CONNECTORS:
                v = table.get((e, dep, c))
                if v is None:
                    continue
                lines.append(f"| {e} | {c} | {cell(v['travel'], '.2f')} | {cell(v['pair'], '+.2f')} | "
                             f"{cell(v['slower'], '+.2f')} | {cell(v['faster'], '+.2f')} | "
                             f"{cell(100 * v['push'], '+.1f')}% | {cell(v['work'], '+.0f')} |")
        lines.append("")
    figure(table, envs, os.path.join(out, "tether.png"))
    path = os.path.join(out, "tether.md")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines))
    return path


def figure(table, envs, path: str) -> None:
    """per deployment, environment by environment: the slower and the faster agent against the free tether under the
    trained connector (bars: mean over populations; dots: populations), and the pair"""
    plt = R.pyplot()
    deps = [d for d in ("uniform", "diverse") if all((e, d, "trained") in table for e in envs)]
    fig, axes = plt.subplots(len(deps), 1, figsize=(11, 1 + 2.75 * len(deps)), sharex=True, squeeze=False)
    axes = axes[:, 0]
    x = np.arange(len(envs))
    for ax, dep in zip(axes, deps):
        for k, (col, colour, label) in enumerate((("slower", "tab:green", "slower agent"),
                                                  ("faster", "tab:red", "faster agent"),
                                                  ("pair", "tab:blue", "pair"))):
            vals = [table[(e, dep, "trained")][col] for e in envs]
            ax.bar(x + (k - 1) * 0.27, [np.mean(v) for v in vals], 0.27, color=colour, alpha=0.6, label=label)
            for i, v in enumerate(vals):
                ax.plot(np.full(len(v), x[i] + (k - 1) * 0.27), v, ".", color=colour, ms=3)
        ax.axhline(0, color="black", lw=0.6)
        ax.set_ylabel("travel − free tether (BL)")
        ax.set_title(f"trained weak connector on {'clones' if dep == 'uniform' else 'diverse pairs'}", fontsize=10)
        ax.legend(fontsize=8, loc="lower right")
    axes[-1].set_xticks(x, envs, rotation=30, ha="right")
    R.save_figure(plt, fig, path)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", nargs="+", help="tether.csv files of `divcoll tether` (one per population)")
    ap.add_argument("--out", required=True, help="folder for tether.md and tether.png")
    ap.add_argument("--provenance", default="", help="the page's source line (divcoll tether passes its own)")
    ap.add_argument("--divcoll", help="accepted for `divcoll tether`; unused")
    a = ap.parse_args(argv)
    missing = [p for p in a.csv if not os.path.isfile(p)]
    if missing:
        print(f"tether: no such file: {', '.join(missing)}")
        return 2
    print(f"tether: wrote {page(a.csv, a.out, a.provenance)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
