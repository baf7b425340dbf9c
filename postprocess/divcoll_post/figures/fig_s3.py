"""Fig. S3: graded diversity among agents — agents alone vs. pairs joined by weak diverse-trained connectors.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.fig_s3 RUN.h5 [--out DIR] [--dpi 150]
        [--boot 1000] [--boot-seed 0]

Reads /graded (the two graded populations, SPEC §7.5) and /deploy (the main population) of a divcoll
run file and writes DIR/fig_s3_graded.png and .pdf (DIR defaults to out/figures).

One panel per diversity setting, from most to least diverse:
  main                 the main evolved population (deploy/agents; pairs = weak_diverse@diverse)
  same_shape           one body shape, evolved springs (graded/same_shape)
  same_shape_springs   one body and one spring genotype, only the controllers differ
In each panel: agents alone (left, white bar with dotted outline) and connected pairs (right, blue
bar): weak diverse-trained connectors (every replicate) on the population's diverse pairs. Each bar is
the mean over the novel environments of the per-environment mean travel (body lengths, BL) over ok
episodes (status 0; nan / unstable episodes are left out and counted). The table under each panel marks
with "X" the sources of diversity the setting has (behaviour, springs, shape, pairing; stored as the
population's `diversity_sources` attribute, the main population has all four).

Error bars: bootstrapped 95% confidence intervals around the mean (the paper's caption), here
percentile bootstrap over episodes, 1000 resamples, fixed seed, resampled within each environment.

Exit status: 0 done; 2 the file is not a divcoll run file or has no (finished) graded stage. Without a
deploy stage the main population's panel is left out with a warning.
"""

from __future__ import annotations

import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from .. import results as R  # noqa: E402

STEM = "fig_s3_graded"
BLUE = "#2166ac"
TITLES = {
    "main": "main population",
    "same_shape": "same shape, evolved springs",
    "same_shape_springs": "same shape and springs",
}


def compute(pops, n_boot=R.BOOT_RESAMPLES, seed=R.BOOT_SEED):
    """[(population, novel envs, agents Stat, pairs Stat)] with bootstrap CIs."""
    out = []
    for p in pops:
        novel = [e for e in p.envs if e != R.FLAT]
        out.append((p, novel, p.agents_stat(novel, n_boot=n_boot, seed=seed),
                    p.pairs_stat(novel, n_boot=n_boot, seed=seed)))
    return out


def draw(args) -> list:
    meta = R.load_meta(args.run)
    graded = R.load_graded(args.run)
    notes = []
    pops = []
    try:
        pops.append(R.main_population(R.load_deploy(args.run)))
    except R.StageMissing as e:
        notes.append("main population not drawn (no deploy stage or no weak_diverse@diverse collectives)")
        print(f"fig_s3: warning: {e}", file=sys.stderr)
    pops += graded
    rows = compute(pops, n_boot=args.boot, seed=args.boot_seed)
    if pops and pops[0].name == "main" and graded:
        mn = [e for e in pops[0].envs if e != R.FLAT]
        gn = [e for e in graded[0].envs if e != R.FLAT]
        if mn != gn:
            notes.append(f"the main population's mean is over {len(mn)} novel environments, the graded ones' over {len(gn)}")

    n = len(rows)
    fig_w = max(7.5, 3.1 * n + 1.3)
    fig_h = 6.4
    fig, axes = plt.subplots(1, n, figsize=(fig_w, fig_h), sharey=True, squeeze=False)
    axes = axes[0]
    fig.subplots_adjust(left=0.9 / fig_w, right=1 - 0.2 / fig_w, top=1 - 1.25 / fig_h, bottom=2.25 / fig_h,
                        wspace=0.12)
    vals = []
    for ax, (p, novel, a, q) in zip(axes, rows):
        for x, st, style in ((0, a, dict(facecolor="white", edgecolor="#333333", linestyle=":", linewidth=1.5)),
                             (1, q, dict(color=BLUE, edgecolor=BLUE, linewidth=1.5))):
            if not np.isfinite(st.mean):
                ax.text(x, 0, "no ok\nepisode", ha="center", va="bottom", fontsize=7, color="#c00000")
                continue
            ax.bar(x, st.mean, 0.62, zorder=2, **style)
            lo, hi = st.yerr
            ax.errorbar(x, st.mean, yerr=[[lo], [hi]], fmt="none", ecolor="black", elinewidth=1.0, capsize=4,
                        zorder=3)
            ax.annotate(f"{st.mean:.2f}", (x, st.hi), xytext=(0, 3), textcoords="offset points", ha="center",
                        va="bottom", fontsize=8)
            vals += [st.lo, st.hi]
        ax.set_xticks([0, 1])
        ax.set_xticklabels([f"agents alone\n(n = {p.agents_travel.shape[1]})",
                            f"pairs\n({p.pairs_travel.shape[1]} connectors × {p.pairs_travel.shape[2]} pairs)"],
                           fontsize=8)
        ax.set_xlim(-0.6, 1.6)
        ax.set_title(f"{TITLES.get(p.name, p.name)}\n({len(novel)} novel environments)", fontsize=9.5)
        ax.grid(axis="y", color="#e5e5e5", lw=0.6, zorder=0)
        # the diversity table under the panel
        src = set(p.diversity_sources)
        for j, name in enumerate(R.DIVERSITY_SOURCES):
            y = -0.25 - 0.085 * j
            ax.text(0.12, y, name, transform=ax.transAxes, ha="left", va="center", fontsize=8.5)
            ax.text(0.78, y, "X" if name in src else "–", transform=ax.transAxes, ha="center", va="center",
                    fontsize=9, fontweight="bold" if name in src else "normal",
                    color="black" if name in src else "#aaaaaa")
        ax.plot([0.05, 0.95], [-0.205, -0.205], transform=ax.transAxes, color="#888888", lw=0.7, clip_on=False)
        ax.text(0.12, -0.185, "diversity in", transform=ax.transAxes, ha="left", va="bottom", fontsize=8,
                style="italic", color="#444444")
        other = sorted(src - set(R.DIVERSITY_SOURCES))
        if other:
            ax.text(0.5, -0.25 - 0.085 * len(R.DIVERSITY_SOURCES), "also: " + ", ".join(other),
                    transform=ax.transAxes, ha="center", va="center", fontsize=7.5)
    v = [x for x in vals if np.isfinite(x)]
    if v:
        lo, hi = min(0.0, min(v)), max(0.0, max(v))
        span = hi - lo if hi > lo else 1.0
        axes[0].set_ylim(lo - (0.05 * span if lo < 0 else 0), hi + 0.14 * span)
    axes[0].set_ylabel("forward travel (body lengths, BL),\nmean of novel-environment means")

    fig.suptitle(f"Fig. S3 — graded diversity among agents, {R.run_title(meta)}", fontsize=12,
                 y=1 - 0.1 / fig_h, va="top")
    handles = [
        Patch(facecolor="white", edgecolor="#333333", linestyle=":", linewidth=1.5, label="agents alone (unpaired)"),
        Patch(facecolor=BLUE, edgecolor=BLUE, label="pairs joined by weak diverse-trained connectors"),
        Line2D([], [], color="black", marker="|", ls="", markersize=8,
               label=f"95% CI: percentile bootstrap over episodes ({args.boot} resamples, seed {args.boot_seed})"),
    ]
    fig.legend(handles=handles, loc="upper center", ncol=2, fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 1 - 0.42 / fig_h))
    bad = []
    for p, novel, a, q in rows:
        if a.n_bad or q.n_bad:
            bad.append(f"{p.name}: agents {a.n_bad}, pairs {q.n_bad}")
    foot = "Episodes not ok (nan/unstable, left out) in the novel environments: " + ("; ".join(bad) if bad else "none") + "."
    if notes:
        foot += " Note: " + "; ".join(notes) + "."
    fig.text(0.5, 0.1 / fig_h, foot, ha="center", va="bottom", fontsize=7.5, color="#333333")
    paths = R.save(fig, args.out, STEM, dpi=args.dpi, software="divcoll fig_s3")
    plt.close(fig)
    return paths


def main(argv=None) -> int:
    args = R.parse_args(__doc__, argv)
    return R.run_script("fig_s3", draw, args)


if __name__ == "__main__":
    sys.exit(main())
