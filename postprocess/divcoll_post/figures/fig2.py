"""Fig. 2: internal diversity and loose coupling confer resilience (travel of the eight collective types).

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.fig2 RUN.h5 [--out DIR] [--dpi 150] [--strong]
        [--boot 1000] [--boot-seed 0]

Reads /deploy of a divcoll run file and writes DIR/fig2_resilience.png and .pdf (DIR defaults to
out/figures). Every number is a mean travel in body lengths (BL) over the ok episodes (status 0);
episodes that ended nan / unstable are left out and counted in the footer.

(a) Independent agents and the eight collective types: the four connector kinds (weak / strong,
    trained on uniform = orange or diverse = blue pairs), each deployed on uniform pairs (hatched,
    dashed outline) and on diverse pairs (solid). Left group: flat ground (the training environment);
    right group: the novel environments, as the mean of the per-environment means (every environment
    weighs the same). Horizontal lines: agents alone on flat (dash-dotted) and in the novel
    environments (dotted, mean of environment means), with their CI as a grey band.
(b) The "transplant" on flat: each connector kind deployed as trained and transplanted to the other
    kind of pair; the change (transplanted − as trained) is written above each pair of bars.
(c–n) One panel per novel environment: the four weak types (add --strong for all eight), agents alone
    in that environment as a dotted line.

The paper's caption defines no error bars ("visually unresolvable"); here they are 95% percentile
bootstrap confidence intervals over episodes (replicates × pairs pooled; 1000 resamples, fixed seed),
stratified by environment for the means over environments. The title names the run, its seed and the
commit that produced it.

Exit status: 0 done; 2 the file is not a divcoll run file or has no deploy stage (message on stderr).
"""

from __future__ import annotations

import os
import string
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from .. import results as R  # noqa: E402

STEM = "fig2_resilience"
KINDS = ["weak_uniform", "weak_diverse", "strong_uniform", "strong_diverse"]
KIND_TICK = {
    "weak_uniform": "weak\nuniform-trained",
    "weak_diverse": "weak\ndiverse-trained",
    "strong_uniform": "strong\nuniform-trained",
    "strong_diverse": "strong\ndiverse-trained",
}
ORANGE = "#e66101"
BLUE = "#2166ac"
AGENT_COLOR = "#404040"
YLABEL = "forward travel (body lengths, BL)"


def kind_color(kind: str) -> str:
    return ORANGE if kind.endswith("uniform") else BLUE


def bar_style(kind: str, deployed: str) -> dict:
    """solid fill for diverse deployment, light hatched fill with a dashed outline for uniform."""
    c = kind_color(kind)
    if deployed == "diverse":
        return dict(color=c, edgecolor=c, linewidth=1.0, linestyle="-")
    return dict(facecolor=matplotlib.colors.to_rgba(c, 0.22), edgecolor=c, linewidth=1.2,
                linestyle="--", hatch="///")


def compute(dep: R.Deploy, n_boot=R.BOOT_RESAMPLES, seed=R.BOOT_SEED) -> dict:
    """Every number the figure draws: {"flat": {name: Stat}, "novel": {name: Stat}, "env": {env: {name: Stat}}},
    name = "agents" or a deployment type."""
    kw = dict(n_boot=n_boot, seed=seed)
    novel = dep.novel
    out = {"flat": {}, "novel": {}, "env": {e: {} for e in novel}}
    out["flat"]["agents"] = dep.agents_stat([R.FLAT], **kw)
    if novel:
        out["novel"]["agents"] = dep.agents_stat(novel, **kw)
    for e in novel:
        out["env"][e]["agents"] = dep.agents_stat([e], **kw)
    for t in dep.types:
        out["flat"][t] = dep.collective_stat(t, [R.FLAT], **kw)
        if novel:
            out["novel"][t] = dep.collective_stat(t, novel, **kw)
        for e in novel:
            out["env"][e][t] = dep.collective_stat(t, [e], **kw)
    return out


def _bar(ax, x, st: R.Stat, kind, deployed, width, label_values=True, fontsize=6.5):
    if not np.isfinite(st.mean):
        ax.text(x, 0, "no ok\nepisode", ha="center", va="bottom", fontsize=fontsize, color="#c00000")
        return
    ax.bar(x, st.mean, width, **bar_style(kind, deployed), zorder=2)
    lo, hi = st.yerr
    ax.errorbar(x, st.mean, yerr=[[lo], [hi]], fmt="none", ecolor="black", elinewidth=0.9, capsize=2.5,
                zorder=3)
    if label_values:
        top = st.mean + hi if st.mean >= 0 else st.mean - lo
        ax.annotate(f"{st.mean:.2f}", (x, top), xytext=(0, 2 if st.mean >= 0 else -2),
                    textcoords="offset points", ha="center", va="bottom" if st.mean >= 0 else "top",
                    fontsize=fontsize, zorder=4,
                    bbox=dict(boxstyle="square,pad=0.05", facecolor="white", edgecolor="none", alpha=0.75))


def _agent_line(ax, st: R.Stat, style: str, xmin=0, xmax=1, band=True):
    if not np.isfinite(st.mean):
        return
    ax.axhline(st.mean, color=AGENT_COLOR, ls=style, lw=1.4, zorder=1.5, xmin=xmin, xmax=xmax)
    if band and np.isfinite(st.lo) and np.isfinite(st.hi):
        ax.axhspan(st.lo, st.hi, xmin=xmin, xmax=xmax, color="#bbbbbb", alpha=0.35, lw=0, zorder=0.5)


def _kinds_present(dep):
    return [k for k in KINDS if f"{k}@uniform" in dep.types or f"{k}@diverse" in dep.types]


def _ylim(ax, values, pad=0.18):
    v = [x for x in values if np.isfinite(x)]
    if not v:
        return
    lo, hi = min(0.0, min(v)), max(0.0, max(v))
    span = hi - lo if hi > lo else 1.0
    ax.set_ylim(lo - (0.08 * span if lo < 0 else 0), hi + pad * span)


def panel_a(ax, dep, S):
    kinds = _kinds_present(dep)
    groups = [("flat", "flat ground (training)")]
    if dep.novel:
        groups.append(("novel", f"{len(dep.novel)} novel environments\n(mean of environment means)"))
    w = 0.38
    gap = len(kinds) + 0.8
    tops = []
    xt, xl = [], []
    for gi, (g, glabel) in enumerate(groups):
        x0 = gi * gap
        for ki, k in enumerate(kinds):
            for di, d in enumerate(("uniform", "diverse")):
                t = f"{k}@{d}"
                if t not in S[g]:
                    continue
                st = S[g][t]
                _bar(ax, x0 + ki + (di - 0.5) * w, st, k, d, w)
                tops += [st.hi, st.lo, st.mean]
            xt.append(x0 + ki)
            xl.append(KIND_TICK[k])
        ax.annotate(glabel, (x0 + (len(kinds) - 1) / 2, 0), xycoords=ax.get_xaxis_transform(),
                    xytext=(0, -30), textcoords="offset points", ha="center", va="top", fontsize=9,
                    fontweight="bold")
    if len(groups) == 2:
        ax.axvline(gap - 0.9, color="#999999", lw=0.8)
    _agent_line(ax, S["flat"]["agents"], "-.")
    tops += [S["flat"]["agents"].hi]
    if "agents" in S["novel"]:
        _agent_line(ax, S["novel"]["agents"], ":")
        tops += [S["novel"]["agents"].hi]
    ax.set_xticks(xt)
    ax.set_xticklabels(xl, fontsize=7.5)
    ax.set_xlim(-0.7, (len(groups) - 1) * gap + len(kinds) - 0.3)
    _ylim(ax, tops, pad=0.22)
    ax.set_ylabel(YLABEL)
    ax.set_title("(a) agents alone and the eight collective types", loc="left", fontsize=10)
    ax.grid(axis="y", color="#e5e5e5", lw=0.6, zorder=0)


def panel_b(ax, dep, S):
    kinds = _kinds_present(dep)
    w = 0.38
    tops = []
    for ki, k in enumerate(kinds):
        trained = "diverse" if k.endswith("diverse") else "uniform"
        other = "uniform" if trained == "diverse" else "diverse"
        pair = []
        for di, d in enumerate((trained, other)):
            t = f"{k}@{d}"
            if t not in S["flat"]:
                continue
            st = S["flat"][t]
            _bar(ax, ki + (di - 0.5) * w, st, k, d, w)
            pair.append(st)
            tops += [st.hi, st.lo, st.mean]
        if len(pair) == 2 and np.isfinite(pair[0].mean) and np.isfinite(pair[1].mean):
            dlt = pair[1].mean - pair[0].mean
            top = max(pair[0].hi, pair[1].hi, pair[0].mean, pair[1].mean)
            ax.annotate(f"Δ {dlt:+.2f}", (ki, top), xytext=(0, 11), textcoords="offset points",
                        ha="center", va="bottom", fontsize=7.5, color="#333333")
    _agent_line(ax, S["flat"]["agents"], "-.")
    tops += [S["flat"]["agents"].hi]
    ax.set_xticks(range(len(kinds)))
    ax.set_xticklabels([KIND_TICK[k] for k in kinds], fontsize=7.5)
    ax.set_xlim(-0.6, len(kinds) - 0.4)
    _ylim(ax, tops, pad=0.3)
    ax.set_ylabel(YLABEL)
    ax.set_title("(b) transplant on flat: as trained (left) | transplanted (right)", loc="left",
                 fontsize=10)
    ax.grid(axis="y", color="#e5e5e5", lw=0.6, zorder=0)


def panel_env(ax, env, letter, dep, S, kinds):
    w = 0.8
    x = 0
    xs, tops = [], []
    for k in kinds:
        for d in ("uniform", "diverse"):
            t = f"{k}@{d}"
            if t not in S["env"][env]:
                continue
            st = S["env"][env][t]
            _bar(ax, x, st, k, d, w, label_values=len(kinds) <= 2, fontsize=6)
            tops += [st.hi, st.lo, st.mean]
            xs.append(x)
            x += 1
        x += 0.4
    _agent_line(ax, S["env"][env]["agents"], ":")
    a = S["env"][env]["agents"]
    tops += [a.hi, a.mean]
    ax.set_xticks([])
    ax.set_xlim(-0.7, x - 0.7)
    _ylim(ax, tops, pad=0.25)
    ax.set_title(f"({letter}) {env.replace('_', ' ')}", loc="left", fontsize=9)
    ax.tick_params(labelsize=7)
    ax.grid(axis="y", color="#e5e5e5", lw=0.6, zorder=0)


def legend_handles(n_boot, seed):
    return [
        Patch(facecolor=ORANGE, edgecolor=ORANGE, label="connector trained on uniform pairs"),
        Patch(facecolor=BLUE, edgecolor=BLUE, label="connector trained on diverse pairs"),
        Patch(facecolor="white", edgecolor="#555555", hatch="///", linestyle="--",
              label="deployed on uniform pairs (clones)"),
        Patch(facecolor="#777777", edgecolor="#777777", label="deployed on diverse pairs"),
        Line2D([], [], color=AGENT_COLOR, ls="-.", lw=1.4, label="agents alone, flat"),
        Line2D([], [], color=AGENT_COLOR, ls=":", lw=1.4, label="agents alone, novel environment(s)"),
        Patch(facecolor="#bbbbbb", alpha=0.5, label="agents alone: 95% CI"),
        Line2D([], [], color="black", marker="_", ls="", markersize=8,
               label=f"error bars: 95% bootstrap CI over episodes ({n_boot} resamples, seed {seed})"),
    ]


def draw(args) -> list:
    meta = R.load_meta(args.run)
    dep = R.load_deploy(args.run)
    S = compute(dep, n_boot=args.boot, seed=args.boot_seed)
    novel = dep.novel
    env_kinds = [k for k in _kinds_present(dep) if args.strong or k.startswith("weak")]

    ncols = 6
    nrows_env = max(1, int(np.ceil(len(novel) / ncols))) if novel else 0
    fig_w = 16.0
    fig_h = 6.05 + 2.35 * nrows_env + 0.9
    fig = plt.figure(figsize=(fig_w, fig_h))
    top_h = 4.0 / fig_h
    head = 1.15 / fig_h
    gs_top = fig.add_gridspec(1, 2, width_ratios=[2.1, 1.0], left=0.055, right=0.99,
                              top=1 - head, bottom=1 - head - top_h, wspace=0.17)
    ax_a = fig.add_subplot(gs_top[0, 0])
    ax_b = fig.add_subplot(gs_top[0, 1])
    panel_a(ax_a, dep, S)
    panel_b(ax_b, dep, S)

    if novel:
        bottom_top = 1 - head - top_h - 1.4 / fig_h
        gs_env = fig.add_gridspec(nrows_env, ncols, left=0.055, right=0.99, top=bottom_top,
                                  bottom=0.75 / fig_h, hspace=0.42, wspace=0.32)
        letters = string.ascii_lowercase[2:]
        for i, env in enumerate(novel):
            ax = fig.add_subplot(gs_env[i // ncols, i % ncols])
            panel_env(ax, env, letters[i] if i < len(letters) else str(i + 3), dep, S, env_kinds)
            if i % ncols == 0:
                ax.set_ylabel("travel (BL)", fontsize=8)
        fig.text(0.055, bottom_top + 0.42 / fig_h,
                 "(c–" + (letters[len(novel) - 1] if len(novel) <= len(letters) else "…") + ") per novel environment, "
                 + ("all eight collective types" if args.strong else "the four weak-connector types")
                 + " in the order of (a); dotted line = agents alone in that environment",
                 fontsize=9, fontweight="bold", va="bottom")

    title = f"Fig. 2 — travel of agents alone and of collectives, {R.run_title(meta)}"
    if dep.status != "complete" or len(dep.envs) < dep.envs_total:
        title += f"  [deploy stage {dep.status}: {len(dep.envs)} of {dep.envs_total} environments]"
    fig.suptitle(title, fontsize=12, y=1 - 0.12 / fig_h, va="top")
    fig.legend(handles=legend_handles(args.boot, args.boot_seed), loc="upper center", ncol=4, fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, 1 - 0.42 / fig_h))
    # footer: counts behind each bar and the episodes left out
    bad = {}
    for t in dep.types:
        n = R.n_not_ok(dep.coll_travel.sel(type=t), dep.coll_status.sel(type=t))
        if n:
            bad[t] = n
    nb_agents = R.n_not_ok(dep.agents_travel, dep.agents_status)
    foot = (f"Means over ok episodes; per bar and environment {dep.replicates} replicates × {dep.pairs} pairs = "
            f"{dep.replicates * dep.pairs} episodes; agents alone: {dep.agents_alone} agents per environment. "
            f"Episodes not ok (nan/unstable, left out): "
            + (", ".join(f"{k} {v}" for k, v in bad.items()) + (f", agents {nb_agents}" if nb_agents else "")
               if bad or nb_agents else "none") + ".")
    steps = R.config_value(meta, "deploy", "episode_steps")
    if steps is not None:
        foot += f" Deployment episodes of {steps} steps."
    # wrapped, so a long list of episodes left out stays inside the figure
    foot = "\n".join(textwrap.wrap(foot, width=200))
    fig.text(0.5, 0.08 / fig_h, foot, ha="center", va="bottom", fontsize=8, color="#333333")
    paths = R.save(fig, args.out, STEM, dpi=args.dpi, software="divcoll fig2")
    plt.close(fig)
    return paths


def main(argv=None) -> int:
    args = R.parse_args(__doc__, argv, extra=lambda ap: ap.add_argument(
        "--strong", action="store_true", help="also draw the four strong types in the per-environment panels"))
    return R.run_script("fig2", draw, args)


if __name__ == "__main__":
    sys.exit(main())
