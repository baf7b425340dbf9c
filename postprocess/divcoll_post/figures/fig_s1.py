"""Fig. S1: the morphologies of the final evolved population, one panel per agent.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.fig_s1 RUN.h5 [--out DIR] [--dpi 150]

Reads /agents/final of a divcoll run file (rest positions, springs, amplitudes, fitness, status) and
writes DIR/fig_s1_morphologies.png and .pdf. Panels are sorted by fitness, best first, and titled
"#rank  fitness BL"; every body is drawn at the same scale, standing on its lowest mass. Active springs
(amplitude > 0) are dark and thick, passive springs light and thin, masses are circles. An agent whose
final evaluation was not ok (status nan / unstable) keeps its rank at the end and is titled in red.

Exit status: 0 done, 2 the input is not a divcoll run file or has no final population (message on
stderr), 1 anything else.
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from ..results import run_script  # noqa: E402
from ..runfile import STATUS_NAMES, RunFileError, read_final, read_meta  # noqa: E402

ACTIVE_COLOR = "#b2182b"  # dark red
PASSIVE_COLOR = "#bdbdbd"  # light grey
MASS_FACE = "white"
MASS_EDGE = "#252525"
ACTIVE_LW = 2.0
PASSIVE_LW = 1.2
STEM = "fig_s1_morphologies"


def fitness_order(fitness: np.ndarray, status: np.ndarray) -> np.ndarray:
    """Agent indices sorted best first: ok agents with finite fitness by fitness descending (ties by
    index), then the rest (not ok or non-finite fitness) in index order."""
    fitness = np.asarray(fitness, dtype=float)
    good = np.isfinite(fitness) & (np.asarray(status) == 0)
    idx = np.arange(fitness.size)
    ranked = idx[good][np.lexsort((idx[good], -fitness[good]))]
    return np.concatenate([ranked, idx[~good]]).astype(int)


def grid_shape(m: int):
    """(rows, cols): 10 x 10 for 100, near square, wider than tall."""
    cols = max(1, math.ceil(math.sqrt(m)))
    rows = max(1, math.ceil(m / cols))
    return rows, cols


def panel_title(rank: int, fitness: float, status: int) -> str:
    if status != 0:
        return f"#{rank}  {STATUS_NAMES.get(int(status), f'status {int(status)}')}"
    if not np.isfinite(fitness):
        return f"#{rank}  {fitness} BL"
    return f"#{rank}  {fitness:.1f} BL"


def fitness_summary(fitness: np.ndarray, status: np.ndarray) -> str:
    ok = np.isfinite(fitness) & (status == 0)
    n_bad = int((~ok).sum())
    if ok.sum() == 0:
        s = "fitness: none finite"
    else:
        f = fitness[ok]
        sd = f.std(ddof=1) if f.size > 1 else 0.0
        s = f"fitness {f.mean():.2f} ± {sd:.2f} BL (mean ± sd), best {f.max():.2f}"
    if n_bad:
        s += f", {n_bad} not ok"
    return s


def draw(pop, meta, out_dir: str, dpi: int = 150):
    m = len(pop)
    if m == 0:
        raise RunFileError(f"{meta.path}: /agents/final holds no agents")
    pos = pop.rest_pos - pop.rest_pos.min(axis=1, keepdims=True)  # min x = min y = 0 per body
    widths = pos[:, :, 0].max(axis=1)
    heights = pos[:, :, 1].max(axis=1)
    finite = np.isfinite(widths) & np.isfinite(heights)
    box_w = float(widths[finite].max()) if finite.any() else 0.35
    box_h = float(heights[finite].max()) if finite.any() else 0.15
    pad = 0.02  # u, room for the mass markers
    box_w = max(box_w, 0.05) + 2 * pad
    box_h = max(box_h, 0.05) + 2 * pad

    rows, cols = grid_shape(m)
    panel_w = 1.5  # inches
    panel_h = panel_w * box_h / box_w
    title_h = 0.22  # inches above each panel for its title
    top_h = 0.95  # two-line figure title + legend
    fig_w = max(cols * panel_w + 0.3, 6.5)  # wide enough for the title
    side = (fig_w - cols * panel_w) / 2
    fig_h = rows * (panel_h + title_h) + top_h + 0.1
    fig = plt.figure(figsize=(fig_w, fig_h))
    fig.subplots_adjust(
        left=side / fig_w,
        right=1 - side / fig_w,
        bottom=0.1 / fig_h,
        top=1 - (top_h + title_h) / fig_h,
        wspace=0.0,
        hspace=title_h / panel_h,
    )
    axes = fig.subplots(rows, cols, squeeze=False)
    order = fitness_order(pop.fitness, pop.status)
    mass_size = 9.0  # points^2 at 1.5 in panels

    for k, ax in enumerate(axes.flat):
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_aspect("equal")
        ax.set_xlim(0, box_w)
        ax.set_ylim(0, box_h)
        for s in ax.spines.values():
            s.set_visible(False)
        if k >= m:
            ax.set_visible(False)
            continue
        a = order[k]
        p = pos[a].copy()
        p[:, 0] += (box_w - widths[a]) / 2  # centred horizontally
        p[:, 1] += pad  # standing on the bottom of the box
        act = pop.amplitude[a] > 0
        segs = np.stack([p[pop.spring_i[a]], p[pop.spring_j[a]]], axis=1)  # (21, 2, 2)
        ax.add_collection(LineCollection(segs[~act], colors=PASSIVE_COLOR, linewidths=PASSIVE_LW,
                                         capstyle="round", zorder=1))
        ax.add_collection(LineCollection(segs[act], colors=ACTIVE_COLOR, linewidths=ACTIVE_LW,
                                         capstyle="round", zorder=2))
        ax.scatter(p[:, 0], p[:, 1], s=mass_size, facecolors=MASS_FACE, edgecolors=MASS_EDGE,
                   linewidths=0.7, zorder=3)
        st = int(pop.status[a])
        ax.set_title(panel_title(k + 1, float(pop.fitness[a]), st), fontsize=8, pad=2,
                     color="#c00000" if st != 0 or not np.isfinite(pop.fitness[a]) else "black")
        # thin ground line under each body
        ax.axhline(pad, color="#e0e0e0", lw=0.6, zorder=0)

    head = f"Run \"{meta.name}\" (seed {meta.seed if meta.seed is not None else '?'}): final population, {m} agents"
    if meta.agents_status not in (None, "complete"):
        head += f" [agents stage {meta.agents_status}]"
    head += "\n" + fitness_summary(pop.fitness, pop.status) + ", panels sorted by fitness"
    fig.suptitle(head, fontsize=11, y=1 - 0.1 / fig_h, va="top", linespacing=1.4)
    amps = np.unique(np.round(pop.amplitude[pop.amplitude > 0], 6))
    act_label = f"active spring (amplitude {amps[0]:g})" if amps.size == 1 else "active spring (amplitude > 0)"
    handles = [
        Line2D([], [], color=ACTIVE_COLOR, lw=ACTIVE_LW, label=act_label),
        Line2D([], [], color=PASSIVE_COLOR, lw=PASSIVE_LW, label="passive spring"),
        Line2D([], [], ls="", marker="o", markersize=4, markerfacecolor=MASS_FACE,
               markeredgecolor=MASS_EDGE, label="point mass"),
    ]
    fig.legend(handles=handles, loc="upper center", ncol=3, fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 1 - 0.58 / fig_h))

    os.makedirs(out_dir, exist_ok=True)
    paths = []
    for ext in ("png", "pdf"):
        path = os.path.join(out_dir, f"{STEM}.{ext}")
        fig.savefig(path, dpi=dpi, metadata=None if ext == "pdf" else {"Software": "divcoll fig_s1"})
        paths.append(path)
    plt.close(fig)
    return paths


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", help="divcoll run file (HDF5) with a finished agents stage")
    ap.add_argument("--out", default=None, help="output directory (default: the run file's directory)")
    ap.add_argument("--dpi", type=int, default=150, help="PNG resolution (default 150)")
    args = ap.parse_args(argv)
    out_dir = args.out if args.out is not None else (os.path.dirname(os.path.abspath(args.run)))

    def draw_run(args):
        meta = read_meta(args.run)
        pop = read_final(args.run, params=False)
        if meta.agents_status not in (None, "complete"):
            print(f"fig_s1: warning: {args.run}: agents stage status is \"{meta.agents_status}\"",
                  file=sys.stderr)
        return draw(pop, meta, out_dir, dpi=args.dpi)

    return run_script("fig_s1", draw_run, args)


if __name__ == "__main__":
    sys.exit(main())
