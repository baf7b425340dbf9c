"""Fig. S2: generalist connectors against environment specialists, per novel environment.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.fig_s2 RUN.h5 [--out DIR] [--dpi 150]

Reads /deploy and /specialists of a divcoll run file and writes DIR/fig_s2_specialists.png and .pdf
(DIR defaults to out/figures). For every novel environment:

- white bar, dotted outline: agents alone in that environment (every agent of the population);
- blue bar: the generalists — weak diverse-trained connectors (trained on flat ground only) deployed
  on diverse pairs (type weak_diverse@diverse: every replicate on the deployment's diverse pairs);
- dark horizontal line across the environment's bars: the best specialist — among the weak connectors
  trained on diverse pairs in that environment only (/specialists), the replicate with the highest
  mean travel over its ok episodes there, evaluated on the same diverse pairs; the replicate number
  and its mean are written above the line.

Every value is a mean travel in body lengths (BL) over ok episodes (status 0); nan / unstable episodes
are left out and counted in the footer. Error bars: standard error of the mean over the episodes (the
paper's caption: "standard error of the mean across all trials"); the specialist's SEM is the shaded
band around its line.

Exit status: 0 done; 2 the file is not a divcoll run file or lacks the specialists or deploy stage.
"""

from __future__ import annotations

import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from .. import results as R  # noqa: E402

STEM = "fig_s2_specialists"
BLUE = "#2166ac"
SPEC = "#08306b"
GENERALIST = "weak_diverse@diverse"


def compute(dep: R.Deploy, spec: R.Specialists):
    """[(env, agents Stat, generalist Stat, best replicate, specialist Stat)] for the novel environments
    present in both stages, in the specialists' order; error bars are SEM."""
    rows = []
    for e in spec.envs:
        if e not in dep.envs:
            continue
        a = dep.agents_stat([e], err="sem")
        g = dep.collective_stat(GENERALIST, [e], err="sem")
        r, s = spec.best_stat(e, err="sem")
        rows.append((e, a, g, r, s))
    return rows


def draw(args) -> list:
    meta = R.load_meta(args.run)
    spec = R.load_specialists(args.run)
    try:
        dep = R.load_deploy(args.run)
    except R.StageMissing as e:
        raise R.StageMissing(f"{e}; Fig. S2 compares the specialists with the deployed generalists") from None
    if GENERALIST not in dep.types:
        raise R.StageMissing(f"{args.run}: the deploy stage has no {GENERALIST} collectives "
                             f"(types: {', '.join(dep.types)}; train and deploy the weak_diverse connectors)")
    rows = compute(dep, spec)
    if not rows:
        raise R.StageMissing(f"{args.run}: no novel environment is done in both the deploy and the specialists "
                             f"stage (run the deploy stage to the end first)")
    missing = [e for e in spec.envs if e not in dep.envs]

    n = len(rows)
    fig_w = max(8.0, 1.05 * n + 1.6)
    fig_h = 5.4
    fig, ax = plt.subplots(figsize=(fig_w, fig_h))
    fig.subplots_adjust(left=0.85 / fig_w, right=1 - 0.2 / fig_w, top=1 - 1.25 / fig_h, bottom=1.35 / fig_h)
    w = 0.36
    vals = []
    for i, (e, a, g, r, s) in enumerate(rows):
        for x, st, style in ((i - w / 2, a, dict(facecolor="white", edgecolor="#333333", linestyle=":", linewidth=1.4)),
                             (i + w / 2, g, dict(color=BLUE, edgecolor=BLUE))):
            if not np.isfinite(st.mean):
                ax.text(x, 0, "no ok\nepisode", ha="center", va="bottom", fontsize=6.5, color="#c00000")
                continue
            ax.bar(x, st.mean, w, zorder=2, **style)
            lo, hi = st.yerr
            ax.errorbar(x, st.mean, yerr=[[lo], [hi]], fmt="none", ecolor="black", elinewidth=0.9, capsize=2.5,
                        zorder=3)
            vals += [st.lo, st.hi]
        if np.isfinite(s.mean):
            x0, x1 = i - w - 0.06, i + w + 0.06
            ax.fill_between([x0, x1], [s.lo] * 2, [s.hi] * 2, color=SPEC, alpha=0.15, lw=0, zorder=1)
            ax.plot([x0, x1], [s.mean] * 2, color=SPEC, lw=2.4, zorder=4, solid_capstyle="butt")
            ax.annotate(f"best #{r}: {s.mean:.2f}", (i, 0), xycoords=ax.get_xaxis_transform(), xytext=(0, -19),
                        textcoords="offset points", ha="center", va="top", fontsize=7.5, color=SPEC)
            vals += [s.lo, s.hi]
        else:
            ax.annotate("no ok specialist", (i, 0), xycoords=ax.get_xaxis_transform(), xytext=(0, -19),
                        textcoords="offset points", ha="center", va="top", fontsize=7.5, color="#c00000")
    ax.set_xticks(range(n))
    ax.set_xticklabels([e.replace("_", " ") for e, *_ in rows], fontsize=8.5)
    ax.set_xlim(-0.6, n - 0.4)
    v = [x for x in vals if np.isfinite(x)]
    if v:
        lo, hi = min(0.0, min(v)), max(0.0, max(v))
        span = hi - lo if hi > lo else 1.0
        ax.set_ylim(lo - (0.05 * span if lo < 0 else 0), hi + 0.12 * span)
    ax.axhline(0, color="#999999", lw=0.7, zorder=1)
    ax.set_ylabel("forward travel (body lengths, BL)")
    ax.set_xlabel("novel environment (below each: the best specialist's replicate, counted from 0, and its mean, BL)",
                  labelpad=20)
    ax.grid(axis="y", color="#e5e5e5", lw=0.6, zorder=0)

    title = f"Fig. S2 — generalists vs. environment specialists, {R.run_title(meta)}"
    if spec.stage_status != "complete":
        title += f"  [specialists stage {spec.stage_status}]"
    fig.suptitle(title, fontsize=12, y=1 - 0.1 / fig_h, va="top")
    R_s = spec.travel.shape[1]
    handles = [
        Patch(facecolor="white", edgecolor="#333333", linestyle=":", linewidth=1.4, label="agents alone"),
        Patch(facecolor=BLUE, edgecolor=BLUE,
              label=f"generalists: weak diverse-trained connectors on diverse pairs ({dep.replicates} replicates)"),
        Line2D([], [], color=SPEC, lw=2.4,
               label=f"best of {R_s} specialist(s) trained in that environment only"),
        Line2D([], [], color="black", marker="|", ls="", markersize=8, label="error bars / band: ± SEM over episodes"),
    ]
    fig.legend(handles=handles, loc="upper center", ncol=2, fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 1 - 0.45 / fig_h))
    bad_a = sum(R.n_not_ok(*dep.agents(e)) for e, *_ in rows)
    bad_g = sum(R.n_not_ok(*dep.collective(GENERALIST, e)) for e, *_ in rows)
    bad_s = R.n_not_ok(spec.travel, spec.status)
    foot = (f"Per environment: {dep.agents_alone} agents alone; generalists {dep.replicates} × {dep.pairs} "
            f"pair episodes; each specialist {spec.travel.shape[2]} pair episodes. Means over ok episodes; not ok "
            f"(left out): agents {bad_a}, generalists {bad_g}, specialists {bad_s}.")
    if missing:
        foot += f" Not drawn (deploy stage not done there): {', '.join(missing)}."
    fig.text(0.5, 0.1 / fig_h, foot, ha="center", va="bottom", fontsize=7.5, color="#333333")
    paths = R.save(fig, args.out, STEM, dpi=args.dpi, software="divcoll fig_s2")
    plt.close(fig)
    return paths


def main(argv=None) -> int:
    args = R.parse_args(__doc__, argv)
    return R.run_script("fig_s2", draw, args)


if __name__ == "__main__":
    sys.exit(main())
