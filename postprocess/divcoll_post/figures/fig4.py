"""Fig. 4: travel of uniform and diverse collectives against collective size, per environment.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.fig4 RUN.h5 [--out DIR] [--dpi 150] [--no-pair]
        [--no-agents] [--boot 1000] [--boot-seed 0]

Reads /scaling (travel_bl, status: E × S × 2 × R × draws; sizes) and, for the reference points,
/deploy; writes DIR/fig4_scaling.png and .pdf (DIR defaults to out/figures).

One panel per environment of the scaling stage (flat, the training environment, is marked as such),
preceded by a panel with the mean over the novel environments (mean of per-environment means). In each:

- orange dashed: chains of N clones joined by weak uniform-trained connectors (variant "uniform");
- blue solid: chains of N distinct agents joined by weak diverse-trained connectors ("diverse");
- at size 2 (open markers, from the deploy stage): the pairs the connectors were trained as —
  weak_uniform@uniform on the orange line and weak_diverse@diverse on the blue one (--no-pair drops
  them; the paper's insets show chains from two agents up);
- at size 1 (grey diamond, not joined to the lines; --no-agents drops it): agents alone. The paper's
  caption does not mention this point; it is drawn as a reference only.

Each point is the mean travel in body lengths (BL) over ok episodes (status 0) of every chain of that
size (replicates × draws pooled). Vertical error bars: 95% confidence intervals (the paper's caption),
computed as percentile bootstrap over episodes, 1000 resamples, fixed seed; stratified by environment
in the novel-mean panel. Episodes that ended nan / unstable are left out and counted in the footer.

Exit status: 0 done; 2 the file is not a divcoll run file or has no scaling stage (message on stderr).
"""

from __future__ import annotations

import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import FixedLocator, NullLocator  # noqa: E402

from .. import results as R  # noqa: E402

STEM = "fig4_scaling"
ORANGE = "#e66101"
BLUE = "#2166ac"
GREY = "#555555"
NOVEL = "novel (mean)"
STYLE = {
    "uniform": dict(color=ORANGE, ls="--", marker="s", label="uniform chains, weak uniform-trained connectors"),
    "diverse": dict(color=BLUE, ls="-", marker="o", label="diverse chains, weak diverse-trained connectors"),
}
PAIR_TYPE = {"uniform": "weak_uniform@uniform", "diverse": "weak_diverse@diverse"}


def compute(sc: R.Scaling, dep, pair=True, agents=True, n_boot=R.BOOT_RESAMPLES, seed=R.BOOT_SEED):
    """{panel: {"uniform": [(size, Stat, source)], "diverse": [...], "agents": Stat or None}} for the
    panels NOVEL and every scaling environment; source is "scaling" or "deploy"."""
    kw = dict(n_boot=n_boot, seed=seed)
    novel = [e for e in sc.envs if e != R.FLAT]
    panels = ([NOVEL] if novel else []) + list(sc.envs)
    out = {}
    for p in panels:
        envs = novel if p == NOVEL else [p]
        d = {"agents": None}
        dep_ok = dep is not None and all(e in dep.envs for e in envs)
        for v in ("uniform", "diverse"):
            pts = []
            if pair and dep_ok and PAIR_TYPE[v] in dep.types and 2 not in sc.sizes:
                pts.append((2, dep.collective_stat(PAIR_TYPE[v], envs, **kw), "deploy"))
            for n in sc.sizes:
                pts.append((n, sc.stat(envs, n, v, **kw), "scaling"))
            d[v] = sorted(pts, key=lambda t: t[0])
        if agents and dep_ok:
            d["agents"] = dep.agents_stat(envs, **kw)
        out[p] = d
    return out


def _errbar(ax, x, st, **kw):
    if not np.isfinite(st.mean):
        return
    lo, hi = st.yerr
    ax.errorbar([x], [st.mean], yerr=[[lo], [hi]], capsize=3, elinewidth=1.0, **kw)


def draw_panel(ax, title, d, sizes_all):
    off = {"uniform": 0.965, "diverse": 1.035}  # multiplicative x offsets (log axis) so bars do not overlap
    vals = []
    for v in ("uniform", "diverse"):
        st = STYLE[v]
        pts = d[v]
        xs = [n * off[v] for n, s, _ in pts if np.isfinite(s.mean)]
        ys = [s.mean for n, s, _ in pts if np.isfinite(s.mean)]
        ax.plot(xs, ys, color=st["color"], ls=st["ls"], lw=1.6, zorder=2)
        for n, s, src in pts:
            face = "white" if src == "deploy" else st["color"]
            _errbar(ax, n * off[v], s, fmt=st["marker"], color=st["color"], markerfacecolor=face,
                    markeredgecolor=st["color"], markersize=5, zorder=3)
            vals += [s.lo, s.hi, s.mean]
    a = d.get("agents")
    if a is not None and np.isfinite(a.mean):
        _errbar(ax, 1, a, fmt="D", color=GREY, markerfacecolor="white", markeredgecolor=GREY, markersize=5,
                zorder=3)
        vals += [a.lo, a.hi, a.mean]
    ax.set_xscale("log")
    ax.xaxis.set_major_locator(FixedLocator(sizes_all))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xticklabels([str(s) for s in sizes_all])
    ax.set_xlim(min(sizes_all) / 1.25, max(sizes_all) * 1.25)
    v = [x for x in vals if np.isfinite(x)]
    if v:
        lo, hi = min(v), max(v)
        span = hi - lo if hi > lo else max(abs(hi), 0.1)
        ax.set_ylim(lo - 0.1 * span, hi + 0.1 * span)
        if lo < 0 < hi:
            ax.axhline(0, color="#999999", lw=0.7, zorder=0)
    ax.set_title(title, loc="left", fontsize=9)
    ax.grid(axis="y", color="#e5e5e5", lw=0.6, zorder=0)
    ax.tick_params(labelsize=7)


def draw(args) -> list:
    meta = R.load_meta(args.run)
    sc = R.load_scaling(args.run)
    dep = None
    note = []
    if not (args.no_pair and args.no_agents):
        try:
            dep = R.load_deploy(args.run)
        except R.StageMissing as e:
            note.append("no deploy stage: the size-1 and size-2 reference points are not drawn")
            print(f"fig4: warning: {e}", file=sys.stderr)
    S = compute(sc, dep, pair=not args.no_pair, agents=not args.no_agents, n_boot=args.boot, seed=args.boot_seed)
    sizes_all = sorted({n for d in S.values() for v in ("uniform", "diverse") for n, _, _ in d[v]}
                       | ({1} if any(d["agents"] is not None for d in S.values()) else set()))
    panels = list(S)
    ncols = min(7, len(panels))
    nrows = int(np.ceil(len(panels) / ncols))
    fig_w = max(2.3 * ncols + 0.6, 9.0)
    fig_h = 2.45 * nrows + 1.75
    fig, axes = plt.subplots(nrows, ncols, figsize=(fig_w, fig_h), squeeze=False)
    fig.subplots_adjust(left=0.6 / fig_w, right=1 - 0.15 / fig_w, top=1 - 1.15 / fig_h, bottom=0.95 / fig_h,
                        wspace=0.32, hspace=0.45)
    for i, ax in enumerate(axes.flat):
        if i >= len(panels):
            ax.set_visible(False)
            continue
        p = panels[i]
        if p == NOVEL:
            title = f"mean of {len([e for e in sc.envs if e != R.FLAT])} novel environments"
        elif p == R.FLAT:
            title = "flat (training environment)"
        else:
            title = p.replace("_", " ")
        draw_panel(ax, title, S[p], sizes_all)
        if i % ncols == 0:
            ax.set_ylabel("travel (BL)", fontsize=8)
        if i // ncols == nrows - 1 or i + ncols >= len(panels):
            ax.set_xlabel("collective size (agents)", fontsize=8)
        if p == NOVEL:
            for s in ax.spines.values():
                s.set_linewidth(1.6)

    title = f"Fig. 4 — travel against collective size, {R.run_title(meta)}"
    if sc.stage_status != "complete" or len(sc.envs) < sc.envs_total:
        title += f"  [scaling stage {sc.stage_status}: {len(sc.envs)} of {sc.envs_total} environments]"
    fig.suptitle(title, fontsize=12, y=1 - 0.1 / fig_h, va="top")
    handles = [Line2D([], [], color=STYLE[v]["color"], ls=STYLE[v]["ls"], marker=STYLE[v]["marker"],
                      lw=1.6, markersize=5, label=STYLE[v]["label"]) for v in ("uniform", "diverse")]
    if any(src == "deploy" for d in S.values() for v in ("uniform", "diverse") for _, _, src in d[v]):
        handles.append(Line2D([], [], color=GREY, ls="", marker="o", markerfacecolor="white", markersize=5,
                              label="size 2: the trained pairs (deploy stage; weak_uniform@uniform, weak_diverse@diverse)"))
    if any(d["agents"] is not None for d in S.values()):
        handles.append(Line2D([], [], color=GREY, ls="", marker="D", markerfacecolor="white", markersize=5,
                              label="size 1: agents alone (deploy stage; reference, not in the paper's caption)"))
    handles.append(Line2D([], [], color="black", marker="|", ls="", markersize=8,
                          label=f"95% CI: percentile bootstrap over episodes ({args.boot} resamples, seed {args.boot_seed})"))
    fig.legend(handles=handles, loc="upper center", ncol=3, fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 1 - 0.42 / fig_h))
    R_, D_ = sc.travel.shape[3], sc.travel.shape[4]
    bad = R.n_not_ok(sc.travel, sc.status)
    foot = (f"Each chain point: {R_} connector replicates × {D_} draws = {R_ * D_} chains per size, variant and "
            f"environment; means over ok episodes; episodes not ok (nan/unstable, left out): {bad}.")
    st_steps = R.config_value(meta, "scaling", "episode_steps")
    dp_steps = R.config_value(meta, "deploy", "episode_steps")
    if dep is not None and st_steps is not None and dp_steps is not None and st_steps != dp_steps:
        w = (f"deploy episodes ({dp_steps} steps) and scaling episodes ({st_steps} steps) differ in length: "
             f"the size-1/2 points are not directly comparable")
        note.append(w)
        print(f"fig4: warning: {w}", file=sys.stderr)
    elif st_steps is not None:
        foot += f" Episodes of {st_steps} steps."
    if note:
        foot += " Note: " + "; ".join(note) + "."
    fig.text(0.5, 0.12 / fig_h, foot, ha="center", va="bottom", fontsize=8, color="#333333", wrap=True)
    paths = R.save(fig, args.out, STEM, dpi=args.dpi, software="divcoll fig4")
    plt.close(fig)
    return paths


def main(argv=None) -> int:
    def extra(ap):
        ap.add_argument("--no-pair", action="store_true", help="leave out the size-2 pairs from the deploy stage")
        ap.add_argument("--no-agents", action="store_true", help="leave out agents alone (size 1)")

    args = R.parse_args(__doc__, argv, extra=extra)
    return R.run_script("fig4", draw, args)


if __name__ == "__main__":
    sys.exit(main())
