"""Fig. 3: internal adversity (DTW, a) and external adversity (familiarity of the connector's states, b-c).

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.fig3 RUN.h5 [--out DIR] [--dpi 150] [--env wind]
        [--replicate 0] [--boot 1000] [--boot-seed 0]

Reads /analysis of a divcoll run file (src/stages/analysis.hpp) and writes DIR/fig3_adversity_familiarity.png
and .pdf (DIR defaults to out/figures). Two connector types, both weak and deployed as trained: uniform-trained
on clones (orange, hatched, dashed outline, as in fig2.py) and diverse-trained on diverse pairs (blue, solid).

(a) How much a tethered agent's behaviour differs from the same agent's independent behaviour in the same
    environment: DTW distance per step (masses relative to the centre of mass, u), pooled over the flat and
    the novel environments and every pair of a connector replicate, then averaged over replicates. Worse /
    better agent = the one that travelled less / more alone. The worse and better bars, their error bars
    (95% percentile bootstrap CI over the replicate means) and the stars (Welch's t-test, uniform vs
    diverse: *** p < 0.001, ** < 0.01, * < 0.05, n.s.) are the numbers the C++ analysis stage stored
    (adversity/summary, adversity/welch). The "all agents" bars (the paper's large bars) are computed here
    from adversity/<type>/dtw, both slots pooled, with the same kind of CI (--boot resamples, --boot-seed)
    and Welch test. Grey dots: the replicate means.
(b, c) One PaCMAP fit of the connector's hidden states in flat (training) and in one novel environment (--env,
    default wind; the first novel environment done when it is absent), replicate --replicate, for the
    uniform-trained (b) and the diverse-trained (c) connector. Coordinates are rounded half to even
    (numpy.round) into unit cells; each state falls in a cell holding both training and novel states, only
    training or only novel states. Each fit is drawn as three panels, one per class, with the class's count
    of states and cells in the title: every state in light grey, the class's states on top in colour
    (training circles, novel crosses), so the few training-only and novel-only states (tens among
    thousands) are visible. The classification is recomputed here from the embedding and n_states and
    checked against the stored counts (a mismatch is printed and written on the panel).

Exit status: 0 done; 2 the file is not a divcoll run file, has no analysis stage, or lacks the datasets the
figure needs (message on stderr). An analysis stage that is not complete is drawn from what is there, with a
warning.
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

from .. import analysis as A  # noqa: E402
from .. import results as R  # noqa: E402
from .fig2 import BLUE, ORANGE, bar_style  # noqa: E402

STEM = "fig3_adversity_familiarity"
YLABEL = "DTW distance per step (u)"
CLASS_COLOR = {0: "#6a3d9a", 1: "#1a9850", 2: "#e31a1c"}  # both, train-only, novel-only
TYPE_STYLE = {A.UNIFORM: ("weak_uniform", "uniform"), A.DIVERSE: ("weak_diverse", "diverse")}


def warn(msg):
    print(f"fig3: warning: {msg}", file=sys.stderr)


def adversity_bars(adv: A.Adversity, n_boot=R.BOOT_RESAMPLES, seed=R.BOOT_SEED) -> dict:
    """{group: {type: (mean, lo, hi, replicate means)}, group + "_p": p} for the groups all / worse / better."""
    out = {"all": {}, "worse": {}, "better": {}}
    for t in A.TYPES:
        m = adv.all_replicate_means(t)
        v = m[np.isfinite(m)]
        lo, hi = R.bootstrap_ci(v, n_boot=n_boot, seed=seed)
        out["all"][t] = (float(v.mean()) if v.size else float("nan"), lo, hi, m)
        ti = adv.types.index(t)
        for g, k in (("worse", A.WORSE), ("better", A.BETTER)):
            s = adv.summary[ti, k]
            out[g][t] = (float(s[0]), float(s[1]), float(s[2]), adv.replicate_means[ti, k])
    out["all_p"] = A.welch(out["all"][A.UNIFORM][3], out["all"][A.DIVERSE][3])[2]
    out["worse_p"] = adv.p(A.WORSE)
    out["better_p"] = adv.p(A.BETTER)
    return out


def check_replicate_means(adv: A.Adversity) -> list:
    """messages for stored replicate means that differ from the ones recomputed from dtw and worse_slot"""
    msgs = []
    for t in A.TYPES:
        got = adv.replicate_means[adv.types.index(t)]
        want = adv.recomputed_replicate_means(t)
        if not np.allclose(got, want, rtol=1e-9, atol=1e-12, equal_nan=True):
            msgs.append(f"{t}: adversity/replicate_means differ from the means recomputed from dtw and worse_slot "
                        f"(largest difference {np.nanmax(np.abs(got - want)):.3g})")
    return msgs


def panel_a(ax, adv, B):
    groups = [("all", "all agents\n(computed here)"), ("worse", "worse-performing\nagent"),
              ("better", "better-performing\nagent")]
    w = 0.36
    tops = []
    rng = np.random.default_rng(0)
    for gi, (g, label) in enumerate(groups):
        for di, t in enumerate(A.TYPES):
            mean, lo, hi, reps = B[g][t]
            x = gi + (di - 0.5) * w
            kind, dep = TYPE_STYLE[t]
            if not np.isfinite(mean):
                ax.text(x, 0, "no ok\nepisode", ha="center", va="bottom", fontsize=7, color="#c00000")
                continue
            ax.bar(x, mean, w, **bar_style(kind, dep), zorder=2)
            if np.isfinite(lo) and np.isfinite(hi):
                ax.errorbar(x, mean, yerr=[[max(mean - lo, 0)], [max(hi - mean, 0)]], fmt="none", ecolor="black",
                            elinewidth=1.0, capsize=3, zorder=4)
            r = np.asarray(reps, float)
            r = r[np.isfinite(r)]
            ax.scatter(x + rng.uniform(-0.25, 0.25, r.size) * w, r, s=7, color="#505050", alpha=0.7, zorder=3, lw=0)
            ax.annotate(f"{mean:.3g}", (x, max(hi if np.isfinite(hi) else mean, mean)), xytext=(0, 2),
                        textcoords="offset points", ha="center", va="bottom", fontsize=7, zorder=5)
            tops += [mean, hi] + list(r)
    top = max([v for v in tops if np.isfinite(v)], default=1.0)
    for gi, (g, _) in enumerate(groups):
        p = B[g + "_p"]
        y = 1.12 * top
        x0, x1 = gi - w / 2, gi + w / 2
        ax.plot([x0, x0, x1, x1], [y * 0.98, y, y, y * 0.98], color="black", lw=0.9)
        ax.text(gi, y, f"{A.stars(p)}\n", ha="center", va="bottom", fontsize=9, linespacing=0.9)
        ax.text(gi, y * 1.075, f"p = {p:.2g}" if np.isfinite(p) else "p = —", ha="center", va="bottom",
                fontsize=6.5, color="#444444")
    ax.axvline(0.5, color="#999999", lw=0.8)
    ax.set_xticks(range(len(groups)))
    ax.set_xticklabels([lab for _, lab in groups], fontsize=8.5)
    ax.set_xlim(-0.6, len(groups) - 0.4)
    ax.set_ylim(0, 1.32 * top if top > 0 else 1)
    ax.set_ylabel(YLABEL)
    ax.set_title("(a) internal adversity: tethered vs independent behaviour", loc="left", fontsize=10)
    ax.grid(axis="y", color="#e5e5e5", lw=0.6, zorder=0)
    ax.legend(handles=[Patch(**bar_style("weak_uniform", "uniform"), label="uniform-trained, on clones"),
                       Patch(facecolor=BLUE, edgecolor=BLUE, label="diverse-trained, on diverse pairs"),
                       Line2D([], [], color="#505050", marker="o", ls="", markersize=3, label="replicate means"),
                       Line2D([], [], color="black", marker="_", ls="", markersize=8, label="95% bootstrap CI")],
              fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=2, frameon=False)


CLASS_SHORT = {0: "cells with training and novel states", 1: "cells with training states only",
               2: "cells with novel states only"}


def familiarity_row(axes, an: A.Analysis, t, env, rep, letter):
    """one fit drawn as three panels, one per cell class: every state of the fit in light grey for context, the
    states of the panel's class on top in its colour (so the rare classes are not buried); the counts in the
    titles. Returns a mismatch message or None"""
    e = an.familiarity.envs.index(env)
    tr, nv = an.embedding(t, env, rep)
    label, counts = A.classify_cells(tr, nv)
    stored = an.familiarity.counts[t][e, rep]
    msg = None
    if not np.array_equal(counts, stored):
        msg = (f"{t}, {env}, replicate {rep}: cells recomputed from the embedding give states/cells "
               f"{counts.astype(int).tolist()}, the run file's counts are {stored.tolist()}")
    xy = np.concatenate([tr, nv])
    n = xy.shape[0]
    is_novel = np.r_[np.zeros(len(tr), bool), np.ones(len(nv), bool)]
    c = counts.astype(int)
    kind, _ = TYPE_STYLE[t]
    color = ORANGE if kind.endswith("uniform") else BLUE
    short = "uniform-trained connector on clones" if t == A.UNIFORM else "diverse-trained connector on diverse pairs"
    pad = 1.0
    lim = ((xy[:, 0].min() - pad, xy[:, 0].max() + pad), (xy[:, 1].min() - pad, xy[:, 1].max() + pad)) if n else None
    for k, ax in enumerate(axes):
        if n:
            ax.scatter(xy[:, 0], xy[:, 1], s=2, color="#d0d0d0", lw=0, zorder=1, rasterized=True)
            sel = label == k
            # within the class, training states as circles and novel ones as crosses
            for nov, marker in ((False, "o"), (True, "x")):
                m = sel & (is_novel == nov)
                if m.any():
                    ax.scatter(xy[m, 0], xy[m, 1], s=9 if k else 3, marker=marker, color=CLASS_COLOR[k],
                               alpha=0.35 if k == 0 else 0.9, lw=0.8 if marker == "x" else 0, zorder=2 + k,
                               rasterized=True)
            ax.set_xlim(*lim[0])
            ax.set_ylim(*lim[1])
        else:
            ax.text(0.5, 0.5, "no states", transform=ax.transAxes, ha="center", va="center", color="#c00000")
        ax.set_aspect("equal", adjustable="box")
        ax.set_xticks([])
        ax.set_yticks([])
        share = 100.0 * c[k] / max(c[0] + c[1] + c[2], 1)
        ax.set_title(f"{CLASS_SHORT[k]}\n{c[k]} states ({share:.1f}%), {c[3 + k]} cells", fontsize=8.5,
                     color=CLASS_COLOR[k])
        for sp in ax.spines.values():
            sp.set_edgecolor(color)
            sp.set_linewidth(1.4)
        if msg:
            ax.text(0.02, 0.02, "counts differ from the run file's!", transform=ax.transAxes, color="#c00000",
                    fontsize=7, va="bottom")
    axes[0].set_ylabel("PaCMAP dimension 2", fontsize=8)
    axes[0].text(-0.02, 1.32, f"({letter}) {short}: flat + {env.replace('_', ' ')}, replicate {rep}, "
                 f"{len(tr)} training + {len(nv)} novel states", transform=axes[0].transAxes, fontsize=10,
                 fontweight="bold", va="bottom", color=color)
    for ax in axes:
        ax.set_xlabel("PaCMAP dimension 1", fontsize=8)
    return msg


def choose_env(fam: A.Familiarity, want: str):
    """(environment of panels b-c, note or None): `want` when its fit is there, else the first one done"""
    if want in fam.envs:
        return want, None
    return fam.envs[0], f"{want} has no familiarity fit in this run file; showing {fam.envs[0]}"


def draw(args) -> list:
    meta = R.load_meta(args.run)
    an = A.load_analysis(args.run)
    adv, fam = an.adversity, an.familiarity
    if not an.complete:
        warn(f"the analysis stage is not complete ({an.progress()}); drawing what is there")
    for m in check_replicate_means(adv):
        warn(m)
    env, note = choose_env(fam, args.env)
    if note:
        warn(note)
    if not 0 <= args.replicate < fam.replicates:
        raise R.RunFileError(f"{args.run}: --replicate {args.replicate} out of range 0..{fam.replicates - 1}")
    B = adversity_bars(adv, n_boot=args.boot, seed=args.boot_seed)

    fig = plt.figure(figsize=(17.0, 10.0))
    gs = fig.add_gridspec(2, 4, width_ratios=[1.5, 1, 1, 1], left=0.05, right=0.99, top=0.83, bottom=0.21,
                          wspace=0.12, hspace=0.55)
    ax_a = fig.add_subplot(gs[:, 0])
    panel_a(ax_a, adv, B)
    msgs = []
    for i, (t, letter) in enumerate(((A.UNIFORM, "b"), (A.DIVERSE, "c"))):
        axes = [fig.add_subplot(gs[i, 1 + k]) for k in range(3)]
        m = familiarity_row(axes, an, t, env, args.replicate, letter)
        if m:
            msgs.append(m)
            warn(m)
    fig.text(0.70, 0.155, "grey: every state of the fit · in colour: the states of the panel's class "
             "(circles: training, crosses: novel)", ha="center", fontsize=8.5, color="#333333")

    title = f"Fig. 3 — internal adversity (a) and familiarity of a novel environment (b, c), {R.run_title(meta)}"
    if not an.complete:
        title += f"  [analysis {an.status}]"
    fig.suptitle(title, fontsize=12, y=0.975)
    steps = R.config_value(meta, "analysis", "dtw_every")
    band = R.config_value(meta, "analysis", "dtw_band")
    nboot = R.config_value(meta, "analysis", "bootstrap_resamples")
    ties = ", ".join(f"{t} {n}" for t, n in adv.ties.items() if n)
    foot = [
        f"(a) {adv.replicates} connector replicates × {adv.pairs} pairs × {len(adv.envs)} environments "
        f"({', '.join(adv.envs[:3])}{', …' if len(adv.envs) > 3 else ''}); per replicate the mean over ok episodes, "
        f"then the mean over replicates. Worse / better agent: travelled less / more alone"
        + (f" (ties, clones: the posterior agent is the worse; {ties})" if ties else "") + ".",
        "Behaviour: masses relative to the centre of mass" + (f" every {steps} steps" if steps else "")
        + (f", Sakoe–Chiba band {band:g}" if band is not None else "") + "; DTW divided by the warping path length. "
        "Worse/better error bars and p: the analysis stage's (bootstrap over replicate means"
        + (f", {nboot} resamples" if nboot else "") + f"; Welch); all agents: computed here ({args.boot} resamples, "
        f"seed {args.boot_seed}; Welch).",
        f"(b, c) PaCMAP of the 32-D connector hidden states, flat (training) + {env}, one panel per cell class; "
        f"coordinates rounded half to even into unit cells, classes recomputed from the embedding"
        + (" and equal to the run file's counts." if not msgs else " — DIFFERENT from the run file's counts (see stderr).")
        + (f" [{note}]" if note else ""),
    ]
    if adv.deploy_mismatches:
        foot.append(f"Warning: {adv.deploy_mismatches} re-simulated episodes did not match deploy's travel.")
    fig.text(0.5, 0.015, "\n".join(foot), ha="center", va="bottom", fontsize=7.5, color="#333333")
    paths = R.save(fig, args.out, STEM, dpi=args.dpi, software="divcoll fig3")
    plt.close(fig)
    return paths


def main(argv=None) -> int:
    def extra(ap):
        ap.add_argument("--env", default=A.WIND, help="novel environment of panels b-c (default wind)")
        ap.add_argument("--replicate", type=int, default=0, help="connector replicate of panels b-c (default 0)")

    args = R.parse_args(__doc__, argv, extra=extra)
    return R.run_script("fig3", draw, args)


if __name__ == "__main__":
    sys.exit(main())
