"""The verdict page of a study judged by the protocol (configs/studies/verdicts_protocol.md): per claim the paper's
number, the effect over populations with its hierarchical-bootstrap interval, the verdict after Holm, the power
when inconclusive; a forest plot; Fig. 2A under both comparison protocols and Figs 3A, 4, S2, S3 with intervals
over populations. Every number comes from the `*.arrays.json` kept beside the study's run summaries.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.verdict_page STUDY_DIR [--out DIR] [--resamples B]
        [--readings | --states | --dev | --budget [--compare DEV_DIR]] [--readme README.md]
    (postprocess/verdicts.py STUDY_DIR ... is the same)

STUDY_DIR is a study folder (`divcoll study --out`) or its kept copy (postprocess/gallery/studies/NAME): the page
reads the `*.arrays.json` beside the run summaries, which `divcoll report STUDY_DIR` writes from the run files.
Writes DIR/verdicts.md (default STUDY_DIR/verdicts) with its figures; with --readings, DIR/readings.md (default
STUDY_DIR/readings): each variant of the study judged as its own family beside its baseline on the same populations
(configs/studies/verdicts_readings.toml); with --states, DIR/states.md (default STUDY_DIR/states): the analysis
claims of one population at each variant's state count (configs/studies/verdicts_states.toml); with --dev,
DIR/connector_dev.md (default STUDY_DIR/connector_dev): the development grid of connector training and the
candidate amendment A5 chooses (configs/studies/connector_dev.toml, divcoll_post.connector_dev); with --budget,
DIR/budget.md: the same trainings to 1000 iterations (configs/studies/connector_budget.toml)."""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import tomllib
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import results as R, verdicts as V

MIN_POPULATIONS = 3
# the earlier paper-scale seeds (10 connectors per kind, central stages), kept as run summaries only: shown as a check
PAPER_SEEDS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "gallery", "studies",
                           "paper_seeds", "baseline")
MAIN_VARIANTS = ["baseline"]
SUPPLEMENT_VARIANTS = ["baseline", "supplement"]
READINGS = [("training_length", "agents alone at 1000 steps (travel at deploy.early_step)"),
            ("training_rate", "agents alone's 3000-step travel × 1000/3000 (a second estimator of the 1000-step "
                              "reading, not independent evidence)")]
COLORS = {"supported": "#1a9641", "equivalent": "#1a9641", "contradicted": "#d7191c",
          "contradicted (negligible)": "#f4a582", "inconclusive": "#777777", "too few populations": "#bbbbbb",
          "not measured": "#bbbbbb"}


def num(x, d=3):
    return "—" if x is None or not np.isfinite(x) else f"{x:+.{d}g}" if abs(x) < 1e-2 and x != 0 else f"{x:+.{d}f}"


def judge_family(pops, family, protocol="same_length", claims=None, B=V.B_DEFAULT):
    cl = [c for c in (claims or V.CLAIMS) if c.family == family]
    res = V.judge(pops, cl, protocol, B=B)
    for r in res:
        if np.isfinite(r.estimate) and r.n < MIN_POPULATIONS:
            r.verdict, r.reason = "too few populations", f"{r.n} population(s); a verdict needs {MIN_POPULATIONS}"
    return res


def margin_text(c):
    if c.form == "band":
        return f"[{c.band[0]:g}, {c.band[1]:g}] {c.unit}".strip()
    m = f"{c.margin:.3g}" if c.margin != 1 / 12 else "1/12"
    return f"{'±' if c.form == 'equivalent' else ''}{m} {c.unit}".strip()


def cell(r):
    if not np.isfinite(r.estimate):
        return r.verdict + (f" ({r.reason})" if r.reason else "")
    if not np.isfinite(r.lo):
        return f"{num(r.estimate)} {r.claim.unit} · {r.verdict} ({r.reason})"
    v = f"**{r.verdict}**"
    if r.verdict == "inconclusive" and np.isfinite(r.power):
        v += f" (power {r.power:.2f}; " + (f"80% at n ≈ {int(r.n80)})" if np.isfinite(r.n80) else
                                            "80% beyond 10,000 populations)")
    return f"{num(r.estimate)} [{num(r.lo)}, {num(r.hi)}] {r.claim.unit} · {v}"


_pyplot, _save = R.pyplot, R.save_figure


def forest(results: Sequence[V.Result], path, title):
    """every claim's estimate and interval in units of its margin: 0 and the margin(s) drawn"""
    plt = _pyplot()
    rs = [r for r in results if np.isfinite(r.lo)]
    if not rs:
        return False
    fig, ax = plt.subplots(figsize=(10, 0.32 * len(rs) + 1.6))
    for i, r in enumerate(rs):
        c = r.claim
        if c.form == "band":
            mid, half = (c.band[0] + c.band[1]) / 2, (c.band[1] - c.band[0]) / 2
            f = lambda x: (x - mid) / half  # noqa: E731
        else:
            f = lambda x: x / c.margin  # noqa: E731
        y = len(rs) - i
        col = COLORS.get(r.verdict, "#777777")
        ax.plot([f(r.lo), f(r.hi)], [y, y], color=col, lw=2)
        ax.plot([f(r.estimate)], [y], "o", color=col, ms=4)
    ax.set_yticks([len(rs) - i for i in range(len(rs))])
    ax.set_yticklabels([f"{r.claim.id} {r.claim.text[:60]}" for r in rs], fontsize=6)
    for x, ls in [(0, "-"), (1, "--"), (-1, ":")]:
        ax.axvline(x, color="k", lw=0.6, ls=ls)
    ax.set_xscale("symlog", linthresh=2)
    ax.set_xlabel("effect / margin (band claims: (θ − centre) / half-width)\n0 solid, +margin dashed, −margin dotted; "
                  "green supported, red contradicted, grey inconclusive", fontsize=8)
    ax.set_title(title, fontsize=8, wrap=True)
    _save(plt, fig, path)
    return True


def _mean_ci(pops, fn, protocol="same_length", B=4000):
    point, th = V.bootstrap(pops, fn, protocol, B=B)
    lo, hi = np.quantile(th, [0.025, 0.975])
    return float(np.mean(point)), float(lo), float(hi), point


def fig2a(pops, path):
    """flat and novel travel of agents alone (two protocols) and the 8 collective types: mean over populations,
    hierarchical bootstrap 95% interval, each population a dot"""
    plt = _pyplot()
    p0 = pops[0]
    rows = []
    for label, proto in [("alone, 3000 steps", "same_length"), ("alone, 1000 steps", "training_length")]:
        for where in ("flat", "novel"):
            def fn(p, d, pr, where=where, proto=proto):
                a = p.alone(proto)
                return np.array([a[p.flat] if where == "flat" else a[p.novel].mean()])
            try:
                rows.append((label, where, *_mean_ci(pops, fn)))
            except KeyError:
                pass
    refs = [n for n in p0.references() if all(n in p.references() for p in pops)]
    for n in refs:
        for where in ("flat", "novel"):
            def fn(p, d, pr, n=n, where=where):
                x = p.references()[n]
                return np.array([x[p.flat] if where == "flat" else x[p.novel].mean()])
            rows.append((f"reference {n}", where, *_mean_ci(pops, fn)))
    for t in p0.types:
        for where in ("flat", "novel"):
            def fn(p, d, pr, t=t, where=where):
                T = p.T(d)[:, :, p.types.index(t)]
                return T[:, p.flat] if where == "flat" else T[:, p.novel].mean(axis=1)
            rows.append((t, where, *_mean_ci(pops, fn)))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=False)
    for ax, where in zip(axes, ("flat", "novel")):
        rr = [r for r in rows if r[1] == where]
        for i, (lab, _, m, lo, hi, pts) in enumerate(rr):
            col = ("#b2abd2" if lab.startswith("reference") else "#2c7bb6" if "diverse@" in lab
                   else "#fdae61" if "@" in lab else "#999999")
            ax.bar(i, m, color=col, alpha=0.6 if "strong" in lab else 1.0)
            ax.errorbar(i, m, yerr=[[m - lo], [hi - m]], color="k", capsize=2, lw=1)
            ax.plot(np.full(len(pts), i), pts, "k.", ms=2)
        ax.set_xticks(range(len(rr)))
        ax.set_xticklabels([r[0] for r in rr], rotation=60, ha="right", fontsize=7)
        ax.set_title(f"{where} ({'mean of the 12 novel environments' if where == 'novel' else 'training'})", fontsize=8)
        ax.set_ylabel("travel, BL")
    fig.suptitle(f"Fig. 2A over {len(pops)} populations: mean, hierarchical bootstrap 95% interval, dots = populations",
                 fontsize=8)
    _save(plt, fig, path)
    return rows


def fig3a(pops, path):
    plt = _pyplot()
    rows = []
    for t in (V.WU, V.WD):
        for which in ("all", "worse", "better"):
            fn = lambda p, d, pr, t=t, which=which: p.dtw(t, which, d)  # noqa: E731
            rows.append((t, which, *_mean_ci(pops, fn)))
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for i, (t, which, m, lo, hi, pts) in enumerate(rows):
        ax.bar(i, m, color="#2c7bb6" if t == V.WD else "#fdae61", hatch="" if which == "all" else "//" if which ==
               "worse" else "..")
        ax.errorbar(i, m, yerr=[[m - lo], [hi - m]], color="k", capsize=2, lw=1)
        ax.plot(np.full(len(pts), i), pts, "k.", ms=2)
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels([f"{t.split('@')[0]}\n{w}" for t, w, *_ in rows], fontsize=7)
    ax.set_ylabel("mean DTW per step, u")
    ax.set_title(f"Fig. 3A over {len(pops)} populations (hierarchical bootstrap 95% interval)", fontsize=8)
    _save(plt, fig, path)
    return rows


def supplement_figs(pops, out_dir):
    """Figs 4, S2, S3 over the populations with those stages; returns [(name, png, rows)]"""
    plt = _pyplot()
    made = []
    sp = [p for p in pops if p.has("scaling")]
    if len(sp) >= 2:
        sizes = sp[0].a["scaling"]["sizes"]
        rows = []
        fig, ax = plt.subplots(figsize=(5, 3.5))
        for v, (lab, col) in enumerate([("uniform", "#fdae61"), ("diverse", "#2c7bb6")]):
            ms, los, his = [], [], []
            for si, n in enumerate(sizes):
                fn = lambda p, d, pr, si=si, v=v: p.scaling(d)[:, si, v]  # noqa: E731
                m, lo, hi, _ = _mean_ci(sp, fn)
                ms.append(m), los.append(lo), his.append(hi)
                rows.append((f"{lab} chains, N={n}", m, lo, hi))
            ax.errorbar(sizes, ms, yerr=[np.subtract(ms, los), np.subtract(his, ms)], color=col, capsize=3,
                        ls="--" if lab == "uniform" else "-", label=lab)
        ax.set_xlabel("agents in the chain")
        ax.set_ylabel("travel, BL (mean of the 12 novel environments)")
        ax.legend(fontsize=7)
        ax.set_title(f"Fig. 4 over {len(sp)} populations", fontsize=8)
        png = os.path.join(out_dir, "fig4.png")
        _save(plt, fig, png)
        made.append(("Fig. 4", png, rows))
    sp = [p for p in pops if p.has("specialists")]
    if len(sp) >= 2:
        envs = sp[0].a["specialists"]["environments"]
        rows = []
        for i, e in enumerate(envs):
            fs = lambda p, d, pr, i=i: p.specialists_best(d)[:, i]  # noqa: E731
            fg = lambda p, d, pr, e=e: p.T(d)[:, p.envs.index(e), p.types.index(V.WD)]  # noqa: E731
            rows.append((e, *_mean_ci(sp, fg)[:3], *_mean_ci(sp, fs)[:3]))
        fig, ax = plt.subplots(figsize=(8, 3.5))
        x = np.arange(len(envs))
        g = np.array([r[1:4] for r in rows])
        s = np.array([r[4:7] for r in rows])
        ax.bar(x, g[:, 0], color="#2c7bb6", label="generalist (weak diverse@diverse)")
        ax.errorbar(x, g[:, 0], yerr=[g[:, 0] - g[:, 1], g[:, 2] - g[:, 0]], fmt="none", color="k", capsize=2)
        ax.errorbar(x, s[:, 0], yerr=[s[:, 0] - s[:, 1], s[:, 2] - s[:, 0]], fmt="_", color="navy", ms=14,
                    label="best specialist")
        ax.set_xticks(x)
        ax.set_xticklabels(envs, rotation=45, ha="right", fontsize=7)
        ax.set_ylabel("travel, BL")
        ax.legend(fontsize=7)
        ax.set_title(f"Fig. S2 over {len(sp)} populations", fontsize=8)
        png = os.path.join(out_dir, "fig_s2.png")
        _save(plt, fig, png)
        made.append(("Fig. S2", png, [(f"{r[0]}: generalist", *r[1:4]) for r in rows]
                     + [(f"{r[0]}: best specialist", *r[4:7]) for r in rows]))
    sp = [p for p in pops if p.has("graded")]
    if len(sp) >= 2:
        rows = []

        def main_gain(p, d, pr):
            return p.T(d)[:, p.novel, p.types.index(V.WD)].mean(axis=1) - p.alone(pr)[p.novel].mean()
        rows.append(("all sources (main)", *_mean_ci(sp, main_gain)[:3]))
        for pop in ("same_shape", "same_shape_springs"):
            fn = lambda p, d, pr, pop=pop: p.graded_gain(pop, d)  # noqa: E731
            rows.append((pop, *_mean_ci(sp, fn)[:3]))
        fig, ax = plt.subplots(figsize=(5, 3.5))
        for i, (lab, m, lo, hi) in enumerate(rows):
            ax.bar(i, m, color="#2c7bb6")
            ax.errorbar(i, m, yerr=[[m - lo], [hi - m]], color="k", capsize=3)
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xticks(range(len(rows)))
        ax.set_xticklabels([r[0] for r in rows], fontsize=7)
        ax.set_ylabel("pairs − agents alone, BL (novel mean)")
        ax.set_title(f"Fig. S3 over {len(sp)} populations", fontsize=8)
        png = os.path.join(out_dir, "fig_s3.png")
        _save(plt, fig, png)
        made.append(("Fig. S3", png, rows))
    return made


def variance_components(pops):
    """per type on flat: (between-population variance of the connector means, mean within-population variance of
    one connector, R) in BL²"""
    out = []
    for t in pops[0].types:
        ti = pops[0].types.index(t)
        means = [np.nanmean(p.coll[p.flat, ti, :]) for p in pops]
        within = [np.nanvar(p.coll[p.flat, ti, :], ddof=1) for p in pops if p.coll.shape[2] > 1]
        R = pops[0].coll.shape[2]
        w = float(np.mean(within)) if within else float("nan")
        b = float(np.var(means, ddof=1) - w / R) if len(means) > 1 else float("nan")
        out.append((t, max(b, 0.0) if np.isfinite(b) else b, w, R))
    return out


def provenance(folder, pops):
    commits = sorted({p.a.get("git_commit", "") for p in pops} - {""})
    return commits, R.code_version()


def check_paper_seeds(B):
    """markdown: the deploy claims on the earlier paper-scale seeds' summaries (10 connectors per kind)"""
    import glob
    files = sorted(glob.glob(os.path.join(PAPER_SEEDS, "seed*.summary.json")))
    if len(files) < 2:
        return []
    pops = [V.population_from_summary(f) for f in files]
    claims = [c for c in V.CLAIMS if c.needs == ("deploy",)]
    res = judge_family(pops, "M", claims=claims, B=B)
    lines = ["", "## Check: the earlier paper-scale seeds", "",
             f"Seeds {', '.join(str(p.seed) for p in pops)} of `configs/studies/paper_seeds.toml` (10 connectors per "
             "kind, the central stages, kept as run summaries in `postprocess/gallery/studies/paper_seeds/`): the "
             "claims that read deploy's travel, judged by the same rules as their own family. Their summaries keep "
             "each type's mean over its 10 connectors, so the interval has no connector level; these populations "
             "are not pooled with the study's (same seeds, other connector draws).", "",
             "| id | claim | effect [95% interval] · verdict | per population |", "|---|---|---|---|"]
    for r in res:
        pp = ", ".join(f"{s}: {v:.3g}" for s, v in r.per_population.items())
        lines.append(f"| {r.claim.id} | {r.claim.text} | {cell(r)} | {pp} |")
    return lines


@dataclasses.dataclass
class Judged:
    """a verdicts study judged once: its manifest, its main-text and supplement populations, every claim's result"""
    man: dict
    main: List[V.Population]
    supp: List[V.Population]
    res: List[V.Result]

    @property
    def planned(self) -> List[int]:
        return planned_seeds(self.man)


def planned_seeds(man: dict) -> List[int]:
    """the seeds a study's manifest plans runs for"""
    return sorted({r["seed"] for r in man["run"]})


def judge_study(folder: str, B: int = V.B_DEFAULT) -> Judged:
    with open(os.path.join(folder, "study.toml"), "rb") as fh:
        man = tomllib.load(fh)
    main = V.load_study(folder, MAIN_VARIANTS)
    supp = [p for p in V.load_study(folder, SUPPLEMENT_VARIANTS)
            if any(p.has(s) for s in ("specialists", "scaling", "graded"))]
    if not main:
        raise ValueError(f"{folder}: no run with kept arrays (`*.arrays.json`; `divcoll report {folder}` writes them)")
    attach_references(main, references_folder(folder))
    return Judged(man, main, supp, judge_family(main, "M", B=B) + judge_family(supp, "S", B=B)
                  + judge_family(main, "A6", B=B))


def besteffort_folder(folder: str) -> str:
    """the kept confirmation study of best-effort connector training (verdicts_besteffort.toml, amendment A5),
    beside the paper-faithful one: <folder>_besteffort"""
    return os.path.normpath(folder) + "_besteffort"


def judge_besteffort(folder: str, B: int = V.B_DEFAULT) -> Optional[Judged]:
    """the best-effort confirmation beside a verdicts study, judged by the same rules (families M′, S′ and A6′ are
    the claims of M, S and A6 on its own populations, each its own Holm family); None when it has no kept run"""
    be = besteffort_folder(folder)
    if not os.path.exists(os.path.join(be, "study.toml")):
        return None
    with open(os.path.join(be, "study.toml"), "rb") as fh:
        man = tomllib.load(fh)
    main = V.load_study(be, MAIN_VARIANTS)
    if not main:
        return None
    supp = [p for p in V.load_study(be, SUPPLEMENT_VARIANTS) if any(p.has(s) for s in ("specialists", "scaling",
                                                                                        "graded"))]
    return Judged(man, main, supp, judge_family(main, "M", B=B) + judge_family(supp, "S", B=B)
                  + judge_family(main, "A6", B=B))


def references_folder(folder: str) -> str:
    """the kept study of the reference connectors of a verdicts study's populations (verdicts_references.toml),
    beside it: <folder>_references"""
    return os.path.normpath(folder) + "_references"


def attach_references(pops: Sequence[V.Population], ref_folder: str) -> List[int]:
    """adds the reference connectors of `ref_folder`'s runs to the populations of the same seed that lack them, after
    checking that the two runs deployed the same agents (every environment's agents-alone travel equal to the last
    digit); returns the seeds attached. A population whose agents differ is refused with a message"""
    if not os.path.exists(os.path.join(ref_folder, "study.toml")):
        return []
    done = []
    by_seed = {p.seed: p for p in V.load_study(ref_folder, ["references"])}
    for p in pops:
        r = by_seed.get(p.seed)
        if r is None or p.references() or "deploy" not in p.a:
            continue
        mine, theirs = p.a["deploy"], r.a["deploy"]
        if mine["environments"] != theirs["environments"] or mine["alone_bl"] != theirs["alone_bl"]:
            raise ValueError(f"{ref_folder}: seed {p.seed}'s agents alone differ from the study's: not the same agents")
        for k in ("references", "references_bl", "references_ok", "references_bl_early"):
            if k in theirs:
                p.a["deploy"][k] = theirs[k]
        done.append(p.seed)
    return done


def on_threshold(res: Sequence[V.Result], rel: float = 0.2) -> List[V.Result]:
    """the claims whose Holm-adjusted p of either hypothesis lies within `rel` of α on either side: their verdict
    turns on the last digits of the test"""
    out = []
    for r in res:
        for p in (r.p_support_holm, r.p_contra_holm):
            if np.isfinite(p) and abs(p - V.ALPHA) <= rel * V.ALPHA:
                out.append(r)
                break
    return out


def amendment_sections(j: Judged, B: int, jb: Optional[Judged] = None) -> List[str]:
    """markdown: the claims on Holm's threshold, the verdicts that an amendment changes (A4's spread rule), and
    amendment A6's statistics (C24b; C24c where the runs counted at the calibrated cell scale), for the best-effort
    confirmation too when there is one"""
    lines = []
    mine = [r for r in j.res if r.claim.family in ("M", "S")]
    near = on_threshold(mine)
    if near:
        lines += ["", "**On Holm's threshold.** " + "; ".join(
            f"{r.claim.id} ({r.verdict}): Holm p {r.p_support_holm:.4g} (supports) / {r.p_contra_holm:.4g} "
            f"(contradicts) against α = {V.ALPHA}" for r in near)
            + ". These verdicts turn on the last digits of the test: read them with the spread rule below and the "
              "interval, not as settled."]
    other = {r.claim.id: r for fam, pops in (("M", j.main), ("S", j.supp))
             for r in V.judge(pops, [c for c in V.CLAIMS if c.family == fam], B=B, spread="sd")}
    changed = [(r, other[r.claim.id]) for r in mine if r.claim.id in other and other[r.claim.id].verdict != r.verdict
               and r.verdict != "too few populations"]
    lines += ["", "## Where an amendment changes a verdict", "",
              "Amendment A4 set the bootstrap's spread to the interquartile range / 1.349 after 3 of 10 populations; "
              "under the rule it replaced (the resamples' standard deviation) these claims get another verdict "
              "(every other claim keeps its verdict under both):", ""]
    if changed:
        lines += ["| id | claim | registered (A4: IQR) | before A4 (sd) |", "|---|---|---|---|"]
        for r, o in changed:
            lines.append(f"| {r.claim.id} | {r.claim.text} | {cell(r)} | {cell(o)} |")
    else:
        lines.append("none.")
    a6 = [r for r in j.res if r.claim.family == "A6"]
    if a6:
        lines += ["", "## Amendment A6: wind's familiarity without the cell size", "",
                  "C24's share of wind's fit in shared cells is 0.995-0.999 for every type at this program's cell size, "
                  "so its margin of 0.02 cannot be reached whatever the connectors do. C24b compares the states that "
                  "lie in cells of one source only, as a ratio (its own Holm family; the paper's ratio is "
                  "(200,000 − 131,303) / (200,000 − 158,118) ≈ 1.64, ln 1.64 = 0.49). C24c is C24 at the cell scale "
                  "calibrated on development population 101 to the paper's exclusive shares (4.7; "
                  "configs/studies/verdicts_cells.toml); only runs that counted their familiarity there "
                  "(analysis.calibrated_cell_scale: the best-effort confirmation) measure it.",
                  "", "| id | training | claim | paper | effect [95% interval] · verdict | per population |",
                  "|---|---|---|---|---|---|"]
        for name, judged in (("paper-faithful", j), ("best-effort", jb)):
            for r in ([r for r in judged.res if r.claim.family == "A6"] if judged else []):
                pp = ", ".join(f"{s}: {v:.3g}" for s, v in r.per_population.items())
                lines.append(f"| {r.claim.id} | {name} | {r.claim.text} | {r.claim.paper} | {cell(r)} | "
                             f"{pp or '—'} |")
    return lines


def besteffort_lines(j: Judged, jb: Optional[Judged], B: int) -> List[str]:
    """markdown: the best-effort confirmation (amendment A5) beside the paper-faithful study: its populations, the
    claims whose verdict the training changes, and its reference connectors per population"""
    lines = ["", "## Best-effort connector training (amendment A5)", ""]
    if jb is None:
        return lines + ["No kept run of the confirmation yet (configs/studies/verdicts_besteffort.toml, kept in "
                        "postprocess/gallery/studies/verdicts_besteffort)."]
    planned = jb.planned
    lines += [f"Study `{jb.man['name']}` ([configs/studies/verdicts_besteffort.toml]"
              "(../../../configs/studies/verdicts_besteffort.toml)): the training the development grid chose (the "
              "follower start, cosine rate, keep-best; postprocess/gallery/connector_dev/connector_dev.md) on fresh "
              f"populations, judged by the same rules as families M′, S′ and A6′. Main text {len(jb.main)} of "
              f"{len(planned)} planned (seeds {', '.join(str(p.seed) for p in jb.main)}); supplement {len(jb.supp)} "
              f"of 5 (seeds {', '.join(str(p.seed) for p in jb.supp) or 'none yet'}). Run files made by divcoll "
              f"{', '.join(provenance(None, jb.main + jb.supp)[0]) or '—'}.", ""]
    if len(jb.main) < len(planned) or len(jb.supp) < 5:
        lines += [f"**Interim**: {len(jb.main)} of {len(planned)} main-text and {len(jb.supp)} of 5 supplement "
                  "populations are in; the protocol's verdicts are those at the planned counts.", ""]
    counts: Dict[str, int] = {}
    for r in jb.res:
        counts[r.verdict] = counts.get(r.verdict, 0) + 1
    lines += ["Verdicts: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) + ".", ""]
    pf = {r.claim.id: r for r in j.res}
    moved = [(pf[r.claim.id], r) for r in jb.res if r.claim.id in pf and r.verdict != pf[r.claim.id].verdict
             and r.verdict not in ("too few populations", "not measured")]
    lines += ["Claims whose verdict differs between the trainings:", ""]
    if moved:
        lines += ["| id | claim | paper-faithful | best-effort |", "|---|---|---|---|"]
        lines += [f"| {a.claim.id} | {a.claim.text} | {cell(a)} | {cell(b)} |" for a, b in moved]
    else:
        lines.append("none.")
    return lines + reference_lines(jb.main)


def reference_lines(pops: Sequence[V.Population]) -> List[str]:
    """markdown: per population on flat, agents alone, the reference connectors and the weak connectors as trained,
    in BL and as shares of agents alone (3000 steps)"""
    have = [p for p in pops if p.references()]
    if not have:
        return ["", "No reference connectors for these populations (deploy.references; "
                    "configs/studies/verdicts_references.toml computes them for the study's populations)."]
    names = list(have[0].references())
    cols = ["free@uniform", "passive@uniform", "follower@uniform", V.WU, "free@diverse", "passive@diverse",
            "follower@diverse", V.WD]
    lines = ["", "### Reference connectors, per population (flat, 3000 steps)", "",
             "Beside agents alone and the weak connectors as trained, the connectors that need no training "
             "(src/collective/references.hpp): *free* (no tether: the two agents side by side), *passive* (fixed rest "
             "lengths), *follower* (each spring's target length follows its length). BL, and in brackets the share "
             f"of agents alone. {len(have)} of {len(pops)} populations"
             + (" (the others' runs did not deploy them)." if len(have) < len(pops) else "."), "",
             "| population | agents alone | " + " | ".join(cols) + " |", "|---" * (len(cols) + 2) + "|"]
    share = {c: [] for c in cols}
    for p in have:
        a = p.alone()[p.flat]
        ref = p.references()
        T = p.T(None)[0]
        cells = []
        for c in cols:
            x = ref[c][p.flat] if c in ref else T[p.flat, p.types.index(c)] if c in p.types else float("nan")
            share[c].append(x / a)
            cells.append(f"{x:.2f} ({x / a:.0%})")
        lines.append(f"| {p.seed} | {a:.2f} | " + " | ".join(cells) + " |")
    lines.append("| mean share | | " + " | ".join(f"{np.nanmean(share[c]):.0%}" for c in cols) + " |")
    fo = {c: np.array(share[c]) for c in cols}
    lines += ["", f"Weak uniform as trained reaches {np.nanmean(fo[V.WU] / fo['follower@uniform']):.0%} of the "
              f"follower's travel on clones, weak diverse {np.nanmean(fo[V.WD] / fo['follower@diverse']):.0%} on "
              "diverse pairs (means over populations of the per-population ratios)."]
    del names
    return lines


FREE = {V.WU: "free@uniform", V.WD: "free@diverse"}  # the free reference on the same pairs as each weak kind


def _pair_difference_rows(have, envs, base, B):
    """rows of (environment, cells): per training and weak kind, the matched pairs' travel minus base(p, ei, t) over
    populations, a hierarchical-bootstrap 95% interval from 3 populations on, and the count where the pair went
    further"""
    rows = []
    for e in envs:
        cells = []
        for _, pops in have:
            ei = pops[0].envs.index(e)
            for t in (V.WU, V.WD):
                ti = pops[0].types.index(t)

                def fn(p, d, protocol, ei=ei, ti=ti, t=t):
                    return p.T(d)[:, ei, ti] - base(p, ei, t, protocol)

                if len(pops) >= 3:
                    m, lo, hi, point = _mean_ci(pops, fn, B=B)
                    ci = f" [{lo:+.2f}, {hi:+.2f}]"
                else:
                    point = np.array([float(fn(p, None, "same_length")[0]) for p in pops])
                    m, ci = float(np.mean(point)), ""
                cells.append(f"{m:+.2f}{ci} ({int(np.sum(point > 0))}/{len(pops)})")
        rows.append((e, cells))
    return rows


def pairs_vs_alone_lines(trainings: Sequence[Tuple[str, Sequence[V.Population]]], B: int = 4000) -> List[str]:
    """markdown: environment by environment, the weak matched pairs' travel minus that of their agents alone, and
    minus that of the free pair on the same pairs (no tether: each agent as alone, but placed as in the pair), 3000
    steps, mean over populations with a hierarchical-bootstrap 95% interval and the populations in which the pair went
    further; one pair of columns per training. Exploratory: no registered claim, no multiplicity control."""
    have = [(name, pops) for name, pops in trainings if pops]
    if not have:
        return []
    p0 = have[0][1][0]
    labels = [(V.WU, "weak uniform on clones"), (V.WD, "weak diverse on diverse pairs")]
    alone = {e: float(np.mean([p.alone()[i] for p in have[0][1]])) for i, e in enumerate(p0.envs)}
    envs = sorted(p0.envs, key=lambda e: -alone[e])
    head = " | ".join(f"{name}: {label}" for name, _ in have for _, label in labels)
    rule = "|---" * (2 + len(have) * len(labels)) + "|"
    lines = ["", "## Pairs against their agents alone, environment by environment (exploratory)", "",
             "The registered claims compare collectives with agents alone on flat (C07, C08) and over the novel "
             "environments (C11, C16). Environment by environment: travel of the pair minus that "
             "of its agents alone, BL over 3000 steps: mean over populations [hierarchical-bootstrap 95% interval] "
             "(populations in which the pair went further / populations). Not a registered claim: read it as a "
             "pattern, not as 26 tests. Environments in order of the agents' travel alone (paper-faithful "
             "populations). The second table separates the tether's part from where the terrain features start.", "",
             f"| environment | agents alone | {head} |", rule]
    lines += [f"| {e} | {alone[e]:.2f} | " + " | ".join(c) + " |"
              for e, c in _pair_difference_rows(have, envs, lambda p, ei, t, pr: p.alone(pr)[ei], B)]
    with_free = [(name, [p for p in pops if all(f in p.references() for f in FREE.values())]) for name, pops in have]
    with_free = [(name, pops) for name, pops in with_free if pops]
    if not with_free:
        return lines
    pf = with_free[0][1]
    gap = {e: [float(np.mean([p.references()[FREE[t]][i] - p.alone()[i] for p in pf])) for t in (V.WU, V.WD)]
           for i, e in enumerate(pf[0].envs)}
    head = " | ".join(f"{name}: {label}" for name, _ in with_free for _, label in labels)
    lines += ["", "The agents of a pair do not start where an agent alone does: terrain features (a gap, an obstacle, "
              "a step) begin 0.05 u ahead of the collective's front (deploy.feature_placement = front), so the "
              "posterior walks its body length and more before it meets them. The *free* pair (no tether: each agent "
              "walks as alone, from its place in the pair) separates that placement from the tether. Below, the "
              "same pairs' travel minus the free pair's on the same pairs, and in the second column the free pair "
              "minus agents alone (mean over the first training's populations, clones / diverse pairs): where that "
              "column is positive, the table above credits the tether with what the placement did. Populations whose "
              "runs deployed the references: " + ", ".join(f"{name} {len(pops)}" for name, pops in with_free) + ". What "
              "the tether does to each agent of a pair (its impulse, its work, each agent's travel against the free "
              "pair): `divcoll tether RUN.h5`, over populations in [../tether/tether.md](../tether/tether.md).",
              "", f"| environment | free pair − agents alone | {head} |",
              "|---" * (2 + len(with_free) * len(labels)) + "|"]
    lines += [f"| {e} | {gap[e][0]:+.2f} / {gap[e][1]:+.2f} | " + " | ".join(c) + " |"
              for e, c in _pair_difference_rows(with_free, envs,
                                                lambda p, ei, t, pr: p.references(pr)[FREE[t]][ei], B)]
    return lines


def write(folder: str, out: str, B: int = V.B_DEFAULT, readme: str = "", html: bool = False) -> str:
    """the page DIR/verdicts.md with its figures; with readme, also that README's results table (readme_lines),
    from the same judging; with html, also DIR/verdicts.html (write_html)"""
    os.makedirs(out, exist_ok=True)
    j = judge_study(folder, B)
    jb = judge_besteffort(folder, B)
    man, main, supp, res = j.man, j.main, j.supp, j.res
    if readme:
        write_readme_table(readme, readme_lines(j, B, jb))
    alone_claims = [c for c in V.CLAIMS if c.reads_alone]
    readings = {}
    for proto, _ in READINGS:
        readings[proto] = {r.claim.id: r for fam, pops in (("M", main), ("S", supp))
                           for r in judge_family(pops, fam, proto, alone_claims, B=B)}
    commits, here = provenance(folder, main + supp)
    seeds_m = ", ".join(str(p.seed) for p in main)
    seeds_s = ", ".join(str(p.seed) for p in supp) or "none yet"
    planned = j.planned
    lines = ["# The paper's claims, judged", "",
             f"Study `{man['name']}` ([configs/studies/verdicts.toml](../../../configs/studies/verdicts.toml)), judged by "
             "the pre-registered protocol [configs/studies/verdicts_protocol.md]"
             "(../../../configs/studies/verdicts_protocol.md): unit of replication the agent population, hierarchical "
             "bootstrap (population → connector) 95% intervals, Holm over each family's hypotheses at familywise "
             f"α = {V.ALPHA} (one-sided), margins fixed in advance. Populations: main text {len(main)} of "
             f"{len(planned)} planned (seeds {seeds_m}); supplement and Fig. 4 {len(supp)} of 5 planned (seeds "
             f"{seeds_s}). Run files made by divcoll {', '.join(commits) or '—'}; page by postprocess/ at {here}; "
             f"{B} bootstrap resamples (seed {V.BOOT_SEED}).", ""]
    if len(main) < len(planned):
        lines += [f"**Interim**: {len(main)} of the {len(planned)} planned populations are in; verdicts can still move "
                  "as the rest arrive (the protocol's verdicts are those at the planned count).", ""]
    counts: Dict[str, int] = {}
    for r in res:
        counts[r.verdict] = counts.get(r.verdict, 0) + 1
    lines += ["Verdicts: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) + ".", ""]
    if forest(res, os.path.join(out, "forest.png"), f"every claim: estimate and 95% interval over populations\nin "
              f"units of its margin (main text n = {len(main)}, supplement n = {len(supp)})"):
        lines += ["![forest plot](forest.png)", ""]
    be = {r.claim.id: r for r in jb.res} if jb else {}
    be_head = (f" best-effort training (M′ n = {len(jb.main)}, S′ n = {len(jb.supp)}) |" if jb else "")
    lines += ["| id | claim | paper | effect [95% interval] · verdict (same episode length) | training length | "
              "training rate | Holm p: supports / contradicts | t interval | per population |" + be_head,
              "|---|---|---|---|---|---|---|---|---|" + ("---|" if jb else "")]
    for r in [r for r in res if r.claim.family in ("M", "S")]:
        c = r.claim
        extra = []
        for proto, _ in READINGS:
            rr = readings[proto].get(c.id)
            extra.append(cell(rr) if rr is not None else "as same length")
        pp = ", ".join(f"{s}: {v:.3g}" for s, v in r.per_population.items())
        tci = f"[{num(r.t_lo)}, {num(r.t_hi)}]" if np.isfinite(r.t_lo) else "—"
        hp = f"{r.p_support_holm:.3g} / {r.p_contra_holm:.3g}" if np.isfinite(r.p_support_holm) else "—"
        lines.append(f"| {c.id} | {c.text} ({c.where}) | {c.paper} | {cell(r)} | {extra[0]} | {extra[1]} | {hp} | "
                     f"{tci} | {pp or '—'} |" + (f" {cell(be[c.id])} |" if jb else ""))
    lines += amendment_sections(j, B, jb)
    lines += besteffort_lines(j, jb, B)
    lines += ["", "## Effects and margins", "", "| id | family | effect θ (positive = the paper's direction) | form | "
              "margin |", "|---|---|---|---|---|"]
    for c in V.CLAIMS:
        lines.append(f"| {c.id} | {c.family} | {c.effect_text} | {c.form} | {margin_text(c)} |")
    fig_dir = os.path.join(out, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    rows = fig2a(main, os.path.join(fig_dir, "fig2a.png"))
    lines += ["", "## Fig. 2A under both comparison protocols", "", "![Fig. 2A](figures/fig2a.png)", "",
              "| | flat: mean [95% interval] | ratio to agents alone (3000 / 1000 steps) | novel: mean [95% interval] "
              "| ratio to agents alone (3000 / 1000 steps) |", "|---|---|---|---|---|"]
    get = {(r[0], r[1]): r for r in rows}
    for lab in [r[0] for r in rows if r[1] == "flat"]:
        cells = []
        for where in ("flat", "novel"):
            _, _, m, lo, hi, _ = get[(lab, where)]
            a3 = get.get(("alone, 3000 steps", where))
            a1 = get.get(("alone, 1000 steps", where))
            ratio = "—" if "alone" in lab else f"{m / a3[2]:.2f} / " + (f"{m / a1[2]:.2f}" if a1 else "—")
            cells += [f"{m:.2f} [{lo:.2f}, {hi:.2f}]", ratio]
        lines.append(f"| {lab} | " + " | ".join(cells) + " |")
    lines += reference_lines(main)
    lines += pairs_vs_alone_lines([("paper-faithful", main)] + ([("best-effort", jb.main)] if jb else []))
    rows3 = fig3a(main, os.path.join(fig_dir, "fig3a.png"))
    lines += ["", "## Fig. 3A", "", "![Fig. 3A](figures/fig3a.png)", "",
              "| type | agents | mean DTW per step, u [95% interval] |", "|---|---|---|"]
    for t, which, m, lo, hi, _ in rows3:
        lines.append(f"| {t} | {which} | {m:.4f} [{lo:.4f}, {hi:.4f}] |")
    for name, png, frows in supplement_figs(supp, fig_dir):
        rel = os.path.relpath(png, out)
        lines += ["", f"## {name}", "", f"![{name}]({rel})", "", "| | mean [95% interval], BL |", "|---|---|"]
        for lab, m, lo, hi in frows:
            lines.append(f"| {lab} | {m:.2f} [{lo:.2f}, {hi:.2f}] |")
    if not supp:
        lines += ["", "## Figs 4, S2, S3", "", "No population with the supplement stages yet."]
    lines += ["", "## Variance components (flat travel, BL²)", "",
              "Between populations (of a population's connector mean, less its connector part) and within a population "
              "(one connector), the inputs of the protocol's choice of connectors per kind.", "",
              "| type | between populations | within (one connector) | connectors per kind |", "|---|---|---|---|"]
    for t, b, w, R in variance_components(main):
        lines.append(f"| {t} | {b:.3f} | {w:.3f} | {R} |")
    lines += check_paper_seeds(B)
    path = os.path.join(out, "verdicts.md")
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    if html:
        write_html(out, man["name"])
    return path


def write_html(out: str, study: str) -> str:
    """out/verdicts.html: the verdict page out/verdicts.md as one self-contained HTML page (report_html's writer:
    the same tables, the forest plot and the figures embedded)"""
    from . import report_html
    with open(os.path.join(out, "verdicts.md")) as fh:
        md = fh.read()
    return report_html.write(study, out, md, name="verdicts.html", title=f"divcoll verdicts: study {study}",
                             css=report_html.CSS + report_html.VERDICT_CSS)


class Paired:
    """a population under a reading beside the same population under the baseline: effects are differences"""

    def __init__(self, reading: V.Population, base: V.Population):
        self.r, self.b, self.seed = reading, base, reading.seed

    def draws(self, rng, b):
        return (self.r.draws(rng, b), self.b.draws(rng, b))

    def has(self, stage):
        return self.r.has(stage) and self.b.has(stage)


def paired_effect(fn):
    def g(pp, d, pr):
        dr, db = (None, None) if d is None else d
        return np.asarray(fn(pp.r, dr, pr), float) - np.asarray(fn(pp.b, db, pr), float)
    return g


def readings_page(folder: str, out: str, baseline: str = "baseline", B: int = V.B_DEFAULT) -> str:
    """the readings page: per claim the baseline's verdict and each reading's (each its own Holm family), and the
    paired difference reading − baseline over the same populations (descriptive: an interval, no verdict)"""
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(folder, "study.toml"), "rb") as fh:
        man = tomllib.load(fh)
    names = [v["name"] for v in man["variant"]]
    docs = {v["name"]: v.get("doc", "") for v in man["variant"]}
    pops = {v: V.load_study(folder, [v]) for v in names}
    if not pops.get(baseline):
        raise ValueError(f"{folder}: no run of variant {baseline} with kept arrays")
    claims = [c for c in V.CLAIMS if c.family == "M"]
    res = {v: {r.claim.id: r for r in judge_family(p, "M", claims=claims, B=B)} for v, p in pops.items() if p}
    base_by_seed = {p.seed: p for p in pops[baseline]}
    diffs = {}
    for v, ps in pops.items():
        if v == baseline or not ps:
            continue
        pairs = [Paired(p, base_by_seed[p.seed]) for p in ps if p.seed in base_by_seed]
        for c in claims:
            if len(pairs) < 2 or not all(pp.has(s) for pp in pairs for s in c.needs):
                continue
            try:
                point, th = V.bootstrap(pairs, paired_effect(c.effect), B=B)
            except (KeyError, ValueError, IndexError):
                continue
            m, _, lo, hi = V.interval(point, th)
            diffs[(v, c.id)] = (m, lo, hi)
    cols = [v for v in names if v in res]
    lines = ["# The paper's claims under each reading", "",
             f"Study `{man['name']}` ([configs/studies/{man['name']}.toml](../../../configs/studies/{man['name']}.toml)), "
             "judged by the protocol [configs/studies/verdicts_protocol.md](../../../configs/studies/verdicts_protocol.md) "
             "§7: each reading is its own family (Holm within it); the baseline is the same populations under the "
             "defaults. Per cell: the effect [95% interval] and verdict; under it, the paired difference reading − "
             "baseline over the same populations [95% interval] (what the reading moves; no verdict).", "",
             "| reading | populations | what it stands for |", "|---|---|---|"]
    for v in cols:
        lines.append(f"| {v} | {', '.join(str(p.seed) for p in pops[v])} | {docs[v]} |")
    planned = planned_seeds(man)
    short = [v for v in cols if len(pops[v]) < len(planned)]
    if short:
        lines += ["", f"**Interim**: {len(planned)} populations are planned per reading (seeds "
                  f"{', '.join(map(str, planned))}); {', '.join(short)} have fewer so far, and their verdicts and "
                  "differences can still move as the rest arrive."]
    lines += ["", "| id | claim | " + " | ".join(cols) + " |", "|---|---|" + "---|" * len(cols)]
    for c in claims:
        row = [c.id, c.text]
        for v in cols:
            r = res[v][c.id]
            txt = cell(r)
            if (v, c.id) in diffs:
                m, lo, hi = diffs[(v, c.id)]
                txt += f"<br>Δ {num(m)} [{num(lo)}, {num(hi)}]"
            row.append(txt)
        lines.append("| " + " | ".join(row) + " |")
    counts = {v: {} for v in cols}
    for v in cols:
        for r in res[v].values():
            counts[v][r.verdict] = counts[v].get(r.verdict, 0) + 1
    lines += ["", "| verdicts | " + " | ".join(cols) + " |", "|---|" + "---|" * len(cols)]
    for vd in ["supported", "equivalent", "contradicted", "contradicted (negligible)", "inconclusive",
               "too few populations", "not measured"]:
        lines.append(f"| {vd} | " + " | ".join(str(counts[v].get(vd, 0)) for v in cols) + " |")
    path = os.path.join(out, "readings.md")
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return path


README_BEGIN, README_END = "<!-- verdict table -->", "<!-- /verdict table -->"


def _at1000(j: Judged, B: int) -> Dict[str, V.Result]:
    """the claims that compare with agents alone, judged with agents alone at their training length (1000 steps)"""
    alone_claims = [c for c in V.CLAIMS if c.reads_alone]
    return {r.claim.id: r for fam, pops in (("M", j.main), ("S", j.supp))
            for r in judge_family(pops, fam, "training_length", alone_claims, B=B)}


def _effect_text(r: V.Result) -> str:
    c = r.claim
    if np.isfinite(r.lo):
        return f"{num(r.estimate)} [{num(r.lo)}, {num(r.hi)}] {c.unit}".rstrip()
    if np.isfinite(r.estimate):
        return f"{num(r.estimate)} {c.unit}".rstrip()
    return "—"


def _verdict_text(r: V.Result) -> str:
    return r.verdict + (f" ({r.reason})" if r.verdict == "not measured" and r.reason else "")


def _alone_text(o: Optional[V.Result]) -> str:
    return (f"{num(o.estimate)} [{num(o.lo)}, {num(o.hi)}] {o.claim.unit}: {o.verdict}".replace(" :", ":")
            if o is not None and np.isfinite(o.lo) else "")


def readme_lines(j: Judged, B: int = V.B_DEFAULT, jb: Optional[Judged] = None) -> List[str]:
    """the README's results: one row per claim (effect, interval, verdict), and for the claims that compare with
    agents alone also the verdict with agents alone at their training length (1000 steps); with jb, the same for
    the best-effort confirmation beside them"""
    planned = len(j.planned)
    main, supp, res = j.main, j.supp, j.res
    at1000 = _at1000(j, B)
    be = {r.claim.id: r for r in jb.res} if jb else {}
    be1000 = _at1000(jb, B) if jb else {}
    lines = [f"Paper-faithful training: main text {len(main)} of {planned} populations; supplement and Fig. 4: "
             f"{len(supp)} of 5" + (" (interim: the study is still running, and verdicts can move as populations "
                                    "arrive)." if len(main) < planned or len(supp) < 5 else ".")]
    if jb:
        interim = len(jb.main) < len(jb.planned) or len(jb.supp) < 5
        lines.append(f"Best-effort training (amendment A5): main text {len(jb.main)} of {len(jb.planned)} fresh "
                     f"populations; supplement {len(jb.supp)} of 5"
                     + (" (interim: verdicts can move as populations arrive)." if interim else "."))
    lines += ["Claims that compare with agents alone are judged at the same episode length (3000 steps, the registered "
              "primary) and with agents alone at their training length (1000 steps): the paper's agent numbers "
              "(\"almost four\", \"just over two\" BL) are this program's 1000-step values, so that is the "
              "comparison the paper's figure most plausibly made.", ""]
    head = "| | claim | paper | effect [95% interval] | verdict | agents alone at 1000 steps |"
    rule = "|---|---|---|---|---|---|"
    if jb:
        head += " best-effort: effect [95% interval] | verdict | agents alone at 1000 steps |"
        rule += "---|---|---|"
    lines += [head, rule]
    for r in res:
        c = r.claim
        row = f"| {c.id} | {c.text} | {c.paper} | {_effect_text(r)} | {_verdict_text(r)} | {_alone_text(at1000.get(c.id))} |"
        if jb:
            b = be.get(c.id)
            row += (f" {_effect_text(b)} | {_verdict_text(b)} | {_alone_text(be1000.get(c.id))} |" if b is not None
                    else " | | |")
        lines.append(row)
    return lines


def readme_table(folder: str, B: int = V.B_DEFAULT) -> List[str]:
    """readme_lines of a kept verdicts study, with its best-effort confirmation when there is one"""
    return readme_lines(judge_study(folder, B), B, judge_besteffort(folder, B))


def write_readme_table(readme: str, lines: List[str]) -> None:
    """replaces the README's block between the verdict-table markers with `lines`"""
    with open(readme) as fh:
        s = fh.read()
    if README_BEGIN not in s or README_END not in s:
        raise ValueError(f"{readme} has no block between {README_BEGIN} and {README_END}")
    a, b = s.index(README_BEGIN) + len(README_BEGIN), s.index(README_END)
    s = s[:a] + "\n" + "\n".join(lines) + "\n" + s[b:]
    with open(readme, "w") as fh:
        fh.write(s)


def states_page(folder: str, out: str) -> str:
    """the state-count page (configs/studies/verdicts_states.toml): one population deployed and analysed at several
    state counts per environment; per claim that reads the analysis stage, its effect on that population at each
    count with the single-run rule (one population: an effect and where it lies, no interval). The DTW claims do not
    read the hidden states, so their equal values across the counts check that nothing else moved"""
    from . import single_run
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(folder, "study.toml"), "rb") as fh:
        man = tomllib.load(fh)
    loaded = {v["name"]: V.load_study(folder, [v["name"]]) for v in man["variant"]}
    variants = [v for v in man["variant"] if loaded[v["name"]]]
    if not variants:
        raise ValueError(f"{folder}: no run with kept arrays")
    pops = {v["name"]: loaded[v["name"]][0] for v in variants}
    seeds = sorted({p.seed for p in pops.values()})
    commits = sorted({p.a.get("git_commit", "") for p in pops.values()} - {""})
    claims = [c for c in V.CLAIMS if "analysis" in c.needs]
    name = man["name"]
    lines = ["# The familiarity claims at the paper's state count", "",
             f"Study `{name}` ([configs/studies/{name}.toml](../../../configs/studies/{name}.toml)), population "
             f"{', '.join(map(str, seeds))}: the same agents and connectors deployed and analysed with each number of "
             "hidden states per environment and PaCMAP fit. One population, so each cell is that population's effect "
             "and the single-run rule (held when the effect lies in the claim's region), not a verdict of the "
             f"protocol. Run files made by divcoll {', '.join(commits) or '—'}; page by postprocess/ at "
             f"{R.code_version()}.", "",
             "| variant | overrides | what it stands for |", "|---|---|---|"]
    for v in variants:
        lines.append(f"| {v['name']} | {', '.join('`' + s + '`' for s in v.get('set', [])) or '—'} | {v.get('doc', '')} |")
    cols = [v["name"] for v in variants]
    lines += ["", "| id | claim | " + " | ".join(cols) + " |", "|---|---|" + "---|" * len(cols)]
    for c in claims:
        row = [c.id, c.text]
        for v in cols:
            _, e, verdict = single_run.evaluate(c, pops[v], "same_length")
            row.append("—" if e is None else f"{num(e)} {c.unit}".rstrip() + f" · {verdict}")
        lines.append("| " + " | ".join(row) + " |")
    path = os.path.join(out, "states.md")
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(description="The verdict page of a study judged by the pre-registered protocol "
                                             "(configs/studies/verdicts_protocol.md)")
    ap.add_argument("study", help="study folder or its kept copy")
    ap.add_argument("--out", help="output folder (default STUDY/verdicts)")
    ap.add_argument("--resamples", type=int, default=V.B_DEFAULT, help="bootstrap resamples (protocol: 20000)")
    ap.add_argument("--readme", metavar="README",
                    help="also rewrite README's block between <!-- verdict table --> and <!-- /verdict table -->")
    ap.add_argument("--readings", action="store_true",
                    help="the readings page: every variant against the study's baseline on the same populations")
    ap.add_argument("--states", action="store_true",
                    help="the state-count page: one population's analysis claims at each variant's state count")
    ap.add_argument("--dev", action="store_true",
                    help="the development page of connector training (configs/studies/connector_dev.toml): every "
                         "candidate, its cost and the candidate amendment A5 chooses")
    ap.add_argument("--budget", action="store_true",
                    help="the larger-budget page (configs/studies/connector_budget.toml): learning curves to 1000 "
                         "iterations and what they deploy to")
    ap.add_argument("--compare", default="",
                    help="with --budget: the development study's kept folder, for the same trainings at 100 iterations")
    a = ap.parse_args(argv)
    try:
        if a.dev:
            from . import connector_dev
            path = connector_dev.write(a.study, a.out or os.path.join(a.study, "connector_dev"))
        elif a.budget:
            from . import connector_dev
            path = connector_dev.write_budget(a.study, a.out or os.path.join(a.study, "budget"), a.compare)
        elif a.states:
            path = states_page(a.study, a.out or os.path.join(a.study, "states"))
        elif a.readings:
            path = readings_page(a.study, a.out or os.path.join(a.study, "readings"), B=a.resamples)
        else:
            path = write(a.study, a.out or os.path.join(a.study, "verdicts"), B=a.resamples, readme=a.readme or "")
    except (OSError, ValueError, KeyError, tomllib.TOMLDecodeError) as e:
        print(f"verdicts: {e}", file=sys.stderr)
        return 2
    print(f"verdicts: wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
