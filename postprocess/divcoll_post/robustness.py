"""The robustness page of a study folder (`divcoll study STUDY.toml --out DIR`): the pre-registered claims
(divcoll_post.verdicts.CLAIMS) × the study's variants, each cell the claim's effect with a 95% confidence interval
over seeds and a verdict, and the paper's Fig. 2A per variant with error bars over seeds.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.robustness DIR [--out OUT]   (what `divcoll report DIR` runs)

Writes OUT/robustness.md and OUT/figures/fig2a_<variant>.png (OUT defaults to DIR/robustness), and beside each
run file DIR/<variant>/seed<k>.h5 its summary DIR/<variant>/seed<k>.summary.json (each claim's single-run verdict and
effect under each reading, Fig. 2A's per-environment means, the run's config and commits) and its arrays
DIR/<variant>/seed<k>.arrays.json (verdicts.extract). A run whose .h5 is gone is read from its arrays (a summary
alone, as kept by older studies, gives only the claims that read the deployment's travel), so a study folder kept as
its manifest, base config, summaries and arrays (e.g. in postprocess/gallery/studies/) gives the same page.

A claim's per-seed value is its single-run view (divcoll_post/single_run.py): the registry's effect at all of the
run's connectors, "held" when it lies in the claim's region (verdicts.region). Per variant the effects of its seeds
give mean ± the Student t 95% interval over seeds (mean ± t(0.975, n−1)·s/√n, s the sample sd over seeds). Verdict:
**holds** if the interval lies inside the claim's region, **fails** if it lies wholly outside, **unresolved**
otherwise, **too few seeds** with fewer than 3 seeds (the interval is still shown from 2), not measured if the runs
lack the stage.
"""
from __future__ import annotations

import argparse
import os
import sys
import tomllib

import numpy as np


from . import results as R, single_run as S  # noqa: E402
from . import verdict_page  # noqa: E402
from . import verdicts as V  # noqa: E402
from .reader import open_file, text  # noqa: E402
from .results import load_deploy, ok_mean  # noqa: E402

MIN_SEEDS = 3
LEVEL = 0.95


def t_interval(values, level=LEVEL):
    """(mean, lo, hi, n) of the finite values: Student t interval over seeds; lo = hi = nan below 2 values"""
    from scipy import stats
    v = np.array([x for x in values if x is not None and np.isfinite(x)], dtype=float)
    n = v.size
    if n == 0:
        return float("nan"), float("nan"), float("nan"), 0
    m = float(v.mean())
    if n < 2:
        return m, float("nan"), float("nan"), n
    h = float(stats.t.ppf(0.5 + level / 2, n - 1) * v.std(ddof=1) / np.sqrt(n))
    return m, m - h, m + h, n


def verdict(mean, lo, hi, n, region=(0.0, np.inf)):
    """the interval [lo, hi] over n seeds against the claim's region (verdicts.region)"""
    if n == 0:
        return "not measured"
    if n < MIN_SEEDS:
        return "too few seeds"
    a, b = region
    if a < lo and hi < b:
        return "holds"
    if hi <= a or lo >= b:
        return "fails"
    return "unresolved"


def num(x):
    return "—" if x is None or not np.isfinite(x) else f"{x:+.3g}"


# ---- run summaries: what this page reads from one run file, kept beside it ----------------------------------------

SUMMARY_FORMAT = "divcoll-run-summary"
SUMMARY_VERSION = 2  # claims by registry id; version 1 (older kept studies) keyed them by the old single-run claims
AS_RUN = "as_run"  # the key of the claims as the run's own config reads them
# report-time readings of analysis.alone_protocol: a run made with same_length is also read under each of these
# (verdicts.Population.alone); training_length needs deploy.early_step
READINGS = [("training_length", "agents alone at their training length (travel at deploy.early_step), collectives "
                                "over the deployment"),
            ("training_rate", "agents alone's deployment travel × connectors.episode_steps / deploy.episode_steps")]


def summary_path(run_path):
    return os.path.splitext(run_path)[0] + ".summary.json"


def _finite_or_none(x):
    return None if x is None or not np.isfinite(x) else float(x)


def _readings(pop, protocol):
    """{reading: protocol} the run can be read under: its own, then the report-time readings"""
    out = {AS_RUN: protocol}
    if protocol == "same_length" and pop.has("deploy"):
        for r, _ in READINGS:
            if r == "training_length" and "alone_bl_early" not in pop.a["deploy"]:
                continue
            out[r] = r
    return out


def summarize(path):
    """the summary dict of a run file (and its arrays, written beside it)"""
    V.write_arrays(path)
    arrays = V.read_arrays(V.arrays_path(path))
    cfg = S.config(path)
    pop = V.Population(arrays.get("seed"), [arrays])
    readings = _readings(pop, S.protocol_of(cfg))
    claims = {}
    for key, protocol in readings.items():
        claims[key] = {}
        for c in V.CLAIMS:
            if key == AS_RUN or c.reads_alone:
                _, e, vd = S.evaluate(c, pop, protocol)
                claims[key][c.id] = {"verdict": vd, "effect": _finite_or_none(e)}
    fig = None
    if pop.has("deploy"):
        dep = load_deploy(path)
        fig = {"environments": dep.envs, "types": dep.types,
               "alone": {k: [float(x) for x in pop.alone(p)] for k, p in readings.items()},
               "collectives": {t: [ok_mean(*dep.collective(t, e))[0] for e in dep.envs] for t in dep.types}}
    with open_file(path) as f:
        attrs = {a: text(f.attrs[a]) for a in ("git_commit", "base_git_commit", "start_time", "end_time")
                 if a in f.attrs}
    attrs["config"] = cfg  # the run's config as its values (the run file's TOML text, comments and all, is ~12 KB)
    return {"format": SUMMARY_FORMAT, "version": SUMMARY_VERSION, "run_file": os.path.basename(path),
            **attrs, "stages_complete": {st: pop.has(st) for st in S.STAGES}, "claims": claims, "fig2a": fig}


def write_summary(path):
    """writes the summary of a run file beside it (atomically); returns its path"""
    import json
    out = summary_path(path)
    tmp = out + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(summarize(path), fh, indent=None, sort_keys=True)
        fh.write("\n")
    os.replace(tmp, out)
    return out


class SummaryRun:
    """a run read from its summary and, where kept, its arrays: each claim's single-run value from the arrays
    (a summary alone: from its Fig. 2A means, the claims that read the deployment's travel only). from_file: both
    were written from the run file beside them just now"""

    def __init__(self, path, data=None, reading=AS_RUN, from_file=False, pop=None):
        import json
        self.path, self.from_file = path, from_file
        if data is None:
            with open(path) as fh:
                data = json.load(fh)
            if data.get("format") != SUMMARY_FORMAT or data.get("version") not in (1, SUMMARY_VERSION):
                raise ValueError(f"{path} is not a divcoll run summary of version 1 or {SUMMARY_VERSION}")
        self.data, self.reading = data, reading
        self.has = data["stages_complete"]
        self.config = data.get("config", {})
        if pop is None:
            arrays = os.path.splitext(os.path.splitext(path)[0])[0] + ".arrays.json"
            if os.path.exists(arrays):
                a = V.read_arrays(arrays)
                pop = V.Population(a.get("seed"), [a])
            elif data.get("fig2a"):
                pop = V.population_from_summary(path) if os.path.exists(path) else None
        self.pop = pop
        fig = data.get("fig2a")
        if fig:
            self.envs, self.types = fig["environments"], fig["types"]
            self.flat = self.envs.index("flat")
            self.novel = [i for i, e in enumerate(self.envs) if e != "flat"]
            self.alone = np.array(fig["alone"][reading], dtype=float)
            self.coll = {t: np.array(v, dtype=float) for t, v in fig["collectives"].items()}

    def novel_mean(self, arr):
        return float(np.mean(arr[self.novel]))

    def protocol(self):
        return S.protocol_of(self.config) if self.reading == AS_RUN else self.reading

    def cell(self, claim):
        """(single-run verdict, effect or None) of a registry claim"""
        if self.pop is None:
            return "not measured", None
        _, e, vd = S.evaluate(claim, self.pop, self.protocol())
        return vd, e

    def reread(self, protocol):
        """this run under report-time reading `protocol`, None when the run cannot be read so"""
        fig = self.data.get("fig2a") or {}
        if protocol not in fig.get("alone", {}):
            return None
        return SummaryRun(self.path, self.data, protocol, self.from_file, self.pop)

    def commits(self):
        return {self.data[a] for a in ("git_commit", "base_git_commit") if a in self.data}


def load_run(folder, rel):
    """the run at `rel` in the study folder: its summary and arrays written anew from the run file when that is
    there, else the ones kept; None if neither. The page reads every run the same way, from what is on disk."""
    path = os.path.join(folder, rel)
    if os.path.exists(path):
        return SummaryRun(write_summary(path), from_file=True)
    if os.path.exists(summary_path(path)):
        return SummaryRun(summary_path(path))
    return None


# ---- the study folder -----------------------------------------------------------------------------------------

def load_manifest(folder):
    path = os.path.join(folder, "study.toml")
    if not os.path.exists(path):
        raise FileNotFoundError(f"{folder} is not a study folder (no study.toml; make one with `divcoll study`)")
    with open(path, "rb") as fh:
        m = tomllib.load(fh)
    if m.get("format") != "divcoll-study":
        raise ValueError(f"{path} is not a divcoll study manifest")
    return m


def columns(folder, manifest):
    """[(column name, source variant, protocol or None, overrides, doc, [(seed, claims.Run)])]: each variant, then
    its runs read under each report-time reading when they were made with analysis.alone_protocol = same_length"""
    out = []
    for v in manifest["variant"]:
        runs = []
        for r in manifest["run"]:
            if r["variant"] != v["name"] or r["status"] != "complete":
                continue
            run = load_run(folder, r["path"])
            if run is not None:
                runs.append((r["seed"], run))
        out.append((v["name"], v["name"], None, list(v["set"]), v.get("doc", ""), runs))
        if any("analysis.alone_protocol=" in s for s in v["set"]):
            continue
        if any(run.config.get("analysis", {}).get("alone_protocol", "same_length") != "same_length"
               for _, run in runs):
            continue
        for protocol, doc in READINGS:
            rr = [(seed, x) for seed, x in ((seed, run.reread(protocol)) for seed, run in runs) if x is not None]
            if runs and not rr:
                continue
            out.append((f"{v['name']} · {protocol}", v["name"], protocol,
                        list(v["set"]) + [f"analysis.alone_protocol={protocol} (read at report time)"],
                        f"{v.get('doc', '')}; read with {doc}", rr))
    return out


def evaluate(folder, manifest):
    """{column: {"source", "protocol", "set", "doc", "seeds", "runs", "cells": [(claim, mean, lo, hi, n,
    verdict, held, n_eval)]}} in the registry's order; a report-time reading's cells of claims that do not read
    agents alone are verdict "as source" (the same numbers as its source variant's column)"""
    out = {}
    for name, source, protocol, sets, doc, runs in columns(folder, manifest):
        cells = []
        for c in V.CLAIMS:
            if protocol is not None and not c.reads_alone:
                cells.append((c, float("nan"), float("nan"), float("nan"), 0, "as source", 0, 0))
                continue
            values, held, measured = [], 0, 0
            for _, run in runs:
                vd, e = run.cell(c)
                if vd != "not measured":
                    measured += 1
                    held += vd == "held"
                values.append(e)
            m, lo, hi, n = t_interval(values)
            cells.append((c, m, lo, hi, n, verdict(m, lo, hi, n, V.region(c)), held, measured))
        out[name] = {"source": source, "protocol": protocol, "set": sets, "doc": doc,
                     "seeds": [s for s, _ in runs], "runs": [r for _, r in runs], "cells": cells}
    return out


def provenance(runs):
    """text: the divcoll commits of the complete runs (SummaryRun), and the commit of this postprocessing tree"""
    commits = set()
    for run in runs:
        commits |= run.commits()
    here = R.code_version()
    return (f"Run files made by divcoll {', '.join(sorted(commits)) or '—'}; page written by postprocess/ at "
            f"{here}.")


# ---- the summary figure: every claim's effect per column --------------------------------------------------------

def summary_figure(res, path):
    """one panel per claim measured in some column: mean effect and its t 95% interval over seeds per column"""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = list(res)
    rows = [i for i in range(len(V.CLAIMS)) if any(res[c]["cells"][i][4] > 0 for c in names)]
    if not rows:
        return False
    ncol = 4
    nrow = (len(rows) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.2 * ncol, 2.5 * nrow), squeeze=False)
    colors = {"holds": "#1a9641", "fails": "#d7191c", "unresolved": "#777777", "too few seeds": "#bbbbbb"}
    for ax, i in zip(axes.flat, rows):
        claim = V.CLAIMS[i]
        shown = [c for c in names if res[c]["cells"][i][4] > 0 and np.isfinite(res[c]["cells"][i][1])]
        for k, c in enumerate(shown):
            _, m, lo, hi, n, vd, _, _ = res[c]["cells"][i]
            col = colors.get(vd, "#777777")
            if np.isfinite(lo):
                ax.errorbar(k, m, yerr=[[m - lo], [hi - m]], fmt="o", color=col, capsize=3, markersize=4)
            else:
                ax.plot(k, m, "o", color=col, markersize=4)
        ax.axhline(0, color="black", linewidth=0.6)
        ax.set_xticks(range(len(shown)))
        ax.set_xticklabels([c.replace(" · ", "\n· ").replace("_", " ") for c in shown], fontsize=5, rotation=60,
                           ha="right")
        ax.set_xlim(-0.5, len(shown) - 0.5)
        words = f"{claim.id} {claim.text}".split()
        title = " ".join(words[:9]) + (" …" if len(words) > 9 else "")
        ax.set_title(title, fontsize=6)
        unit = claim.unit
        ax.set_ylabel(f"effect ({unit})" if unit else "effect", fontsize=6)
        ax.tick_params(axis="y", labelsize=6)
    for ax in list(axes.flat)[len(rows):]:
        ax.axis("off")
    fig.suptitle("Claims × variants: effect (positive = the paper's direction), mean and t 95% interval over seeds; "
                 "green holds, red fails, grey unresolved / too few seeds", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


# ---- Fig. 2A per variant ----------------------------------------------------------------------------------------

def fig2a_values(runs):
    """[(label, flat values per seed, novel-mean values per seed)] of agents alone and every collective type, over
    the runs with a complete deploy stage (the numbers behind Fig. 2A and its table)"""
    runs = [r for r in runs if r.has["deploy"]]
    if not runs:
        return []
    out = []
    for k, lab in enumerate(["agents alone"] + runs[0].types):
        flat, novel = [], []
        for r in runs:
            arr = r.alone if k == 0 else r.coll.get(lab)
            if arr is None:
                continue
            flat.append(float(arr[r.flat]))
            novel.append(r.novel_mean(arr))
        out.append((lab, flat, novel))
    return out


def fig2a_table(values):
    """markdown rows of Fig. 2A's numbers: mean over seeds [t 95% interval] and each seed's value, flat and novel"""
    def cell(vals):
        m, lo, hi, n = t_interval(vals)
        ci = f" [{lo:.2f}, {hi:.2f}]" if np.isfinite(lo) else ""
        return f"{m:.2f}{ci} ({', '.join(f'{v:.2f}' for v in vals)})"
    lines = ["| travel, BL: mean over seeds [t 95% interval] (each seed) | flat | novel (mean of the environment means) |",
             "|---|---|---|"]
    for lab, flat, novel in values:
        lines.append(f"| {lab.replace('@', ' on ')} | {cell(flat)} | {cell(novel)} |")
    return lines


def fig2a(variant, values, seeds, path):
    """flat and novel travel of agents alone and every collective type (fig2a_values): mean over seeds, t 95%
    interval over seeds as the error bar, each seed a dot"""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if not values:
        return False
    labels = [lab for lab, _, _ in values]
    fig, axes = plt.subplots(1, 2, figsize=(max(6, 0.9 * len(labels) + 2), 3.6), sharey=True)
    for ax, where in zip(axes, ["flat", "novel"]):
        for k, (lab, flat, novel) in enumerate(values):
            vals = flat if where == "flat" else novel
            m, lo, hi, n = t_interval(vals)
            kind = lab.split("@")[0]
            color = "#404040" if k == 0 else ("#2166ac" if "diverse" in kind else "#e66101")
            hatch = "//" if lab.endswith("@uniform") else None
            ax.bar(k, m if np.isfinite(m) else 0, color=color, alpha=0.35 if "strong" in kind else 0.8, hatch=hatch,
                   edgecolor="black", linewidth=0.5)
            if np.isfinite(lo):
                ax.errorbar(k, m, yerr=[[m - lo], [hi - m]], color="black", capsize=3, linewidth=1)
            ax.scatter(np.full(len(vals), k) + np.linspace(-0.15, 0.15, len(vals)), vals, s=8, color="black", zorder=3)
        ax.set_xticks(range(len(labels)))
        ax.set_xticklabels([lab.replace("_", "\n").replace("@", "\non ") for lab in labels], fontsize=6)
        ax.set_title(f"{where}" + (" (mean of environment means)" if where == "novel" else ""), fontsize=8)
        ax.axhline(0, color="black", linewidth=0.5)
    axes[0].set_ylabel("travel (BL)")
    fig.suptitle(f"Fig. 2A, variant {variant}: mean over seeds {', '.join(map(str, seeds))} "
                 f"(bars: t 95% interval over seeds; dots: seeds)", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return True


# ---- the page ---------------------------------------------------------------------------------------------------

def verdicts_section(folder, out, B):
    """the study's verdict page (verdict_page.py: the protocol's judgement over populations, from the arrays
    evaluate() just wrote or found) in out/verdicts, as verdicts.md and verdicts.html; the robustness page's lines
    that link to it, or say why there is none"""
    dest = os.path.join(out, "verdicts")
    try:
        path = verdict_page.write(folder, dest, B=B, html=True)
    except (ValueError, KeyError) as e:  # no run of the main variant with kept arrays, arrays it cannot read
        return None, [f"No verdict page: {e}.", ""]
    rel = os.path.relpath(path, out)
    return path, [f"The verdict page of this study (the pre-registered protocol's judgement over populations, "
                  f"configs/studies/verdicts_protocol.md): [{rel}]({rel}) and "
                  f"[{rel[:-3]}.html]({rel[:-3]}.html).", ""]


def write_page(folder, out, verdicts_B=None):
    """OUT/robustness.md with its figures; unless verdicts_B is None, also the study's verdict page in OUT/verdicts
    (verdicts_section, verdicts_B bootstrap resamples); returns (robustness.md, the cells, verdicts.md or None)"""
    man = load_manifest(folder)
    res = evaluate(folder, man)
    verdicts_path, verdicts_lines = (None, []) if verdicts_B is None else verdicts_section(folder, out, verdicts_B)
    # every complete run once (the report-time readings are columns of the same runs)
    runs = [run for col in res.values() if col["protocol"] is None for run in col["runs"]]
    from_summaries = sum(not run.from_file for run in runs)
    fig_dir = os.path.join(out, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    variants = list(res)
    done = sum(1 for r in man["run"] if r["status"] == "complete")
    lines = [f"# Robustness of the paper's claims: study {man['name']}", ""]
    if man.get("doc"):
        lines += [man["doc"], ""]
    lines += verdicts_lines
    lines += [f"Study folder `{os.path.abspath(folder)}`; base config `{man['base']}`; seeds "
              f"{', '.join(map(str, man['seeds']))}; {done} of {len(man['run'])} runs complete. Every run: "
              + (", ".join(f"`{s}`" for s in man["scale"]) or "the base config as it is") + ". "
              + provenance(runs)
              + (f" {from_summaries} run(s) read from their summaries (`*.summary.json`; the run files are not in "
                 "the folder)." if from_summaries else ""), "",
              "| variant | overrides | reading | runs (seeds) | reuses |", "|---|---|---|---|---|"]
    for name, col in res.items():
        rs = [r for r in man["run"] if r["variant"] == col["source"]]
        reuse = sorted({f"{r['reuses'].split('/')[0]} (before {r['from']})" for r in rs if r["reuses"]})
        if col["protocol"] is not None:
            reuse = [f"the runs of {col['source']}"]
        lines.append(f"| {name} | {', '.join(f'`{s}`' for s in col['set']) or '—'} | {col['doc']} | "
                     f"{len(col['seeds'])} ({', '.join(map(str, col['seeds']))}) | {', '.join(reuse) or '—'} |")
    if any(col["protocol"] for col in res.values()):
        lines += ["", "Columns `V · PROTOCOL` are variant V's run files read with `analysis.alone_protocol = PROTOCOL` "
                      "at report time: that key changes only the agents-alone numbers the claims compare with, so only "
                      "the claims that read agents alone are evaluated again; the others are the same as V's "
                      "(\"as source\")."]
    if runs:
        short = S.short_of(runs[0].config, V.N_NOVEL)
        if short:
            lines += ["", f"A single run of this scale is below the counts the claims need to judge one run ({short}); "
                          "here the evidence is the interval over seeds, and \"held k/n\" counts the single-run verdicts "
                          "per seed."]
    lines += ["", "## Claims × variants", "",
              "Each cell: the claim's effect (definitions below), mean over seeds with its Student t "
              f"{LEVEL:.0%} interval over seeds, then in how many seeds the single-run effect held (lay in the claim's "
              f"region), and the verdict (holds: interval inside the region; fails: wholly outside; unresolved: "
              f"across its edge; too few seeds: fewer than {MIN_SEEDS}).", ""]
    if summary_figure(res, os.path.join(out, "robustness.png")):
        lines += ["![every claim's effect per variant](robustness.png)", ""]
    lines += ["| claim | " + " | ".join(variants) + " |", "|---|" + "---|" * len(variants)]
    counts = {v: {} for v in variants}
    for ci, c in enumerate(V.CLAIMS):
        unit = c.unit
        row = [f"**{c.id}** {c.text}"]
        for v in variants:
            _, m, lo, hi, n, vd, held, meas = res[v]["cells"][ci]
            counts[v][vd] = counts[v].get(vd, 0) + 1
            if vd in ("not measured", "as source"):
                row.append(vd)
                continue
            ci_txt = f" [{num(lo)}, {num(hi)}]" if np.isfinite(lo) else ""
            row.append(f"{num(m)}{ci_txt} {unit} · held {held}/{meas} · **{vd}**")
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", "| verdicts | " + " | ".join(variants) + " |", "|---|" + "---|" * len(variants)]
    for vd in ["holds", "fails", "unresolved", "too few seeds", "not measured", "as source"]:
        lines.append(f"| {vd} | " + " | ".join(str(counts[v].get(vd, 0)) for v in variants) + " |")
    lines += ["", "## Effects", "", "| claim | effect | holds when | unit |", "|---|---|---|---|"]
    for c in V.CLAIMS:
        lines.append(f"| **{c.id}** {c.text} | {c.effect_text} | {S.effect_text(c, None).split('(')[1].rstrip(')')} | "
                     f"{c.unit or '—'} |")
    lines += ["", "## Fig. 2A per variant", ""]
    for v in variants:
        png = os.path.join(fig_dir, f"fig2a_{v.replace(' · ', '__')}.png")
        values = fig2a_values(res[v]["runs"])
        if fig2a(v, values, res[v]["seeds"], png):
            rel = os.path.relpath(png, out)
            lines += [f"### {v}", "", f"![{rel}]({rel})", ""] + fig2a_table(values) + [""]
        else:
            lines += [f"### {v}", "", "No complete deploy stage in this variant's runs.", ""]
    path = os.path.join(out, "robustness.md")
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return path, res, verdicts_path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", help="study folder (divcoll study --out DIR)")
    ap.add_argument("--out", help="output folder (default DIR/robustness)")
    ap.add_argument("--divcoll", help="accepted for `divcoll report`; unused")
    ap.add_argument("--resamples", type=int, default=V.B_DEFAULT,
                    help=f"bootstrap resamples of the verdict page (protocol: {V.B_DEFAULT})")
    ap.add_argument("--no-verdicts", action="store_true", help="only the robustness page, not the verdict page")
    ap.add_argument("--keep", metavar="DEST", help="also copy the study as its manifest, base config and run summaries "
                                                   "(no run files) into DEST, e.g. postprocess/gallery/studies/NAME")
    a = ap.parse_args(argv)
    out = a.out or os.path.join(a.study, "robustness")
    try:
        path, res, verdicts_path = write_page(a.study, out, None if a.no_verdicts else a.resamples)
        kept = keep(a.study, a.keep) if a.keep else None
    except (OSError, ValueError, KeyError, tomllib.TOMLDecodeError) as e:
        print(f"robustness: {e}", file=sys.stderr)
        return 2
    n = sum(len(r["cells"]) for r in res.values())
    print(f"robustness: wrote {path} ({len(V.CLAIMS)} claims × {len(res)} variants = {n} cells)")
    if verdicts_path:
        print(f"robustness: wrote the verdict page {verdicts_path} and {verdicts_path[:-3]}.html")
    elif not a.no_verdicts:
        print("robustness: no verdict page (no run of the study's baseline variant with kept arrays)")
    if kept is not None:
        print(f"robustness: kept the study in {a.keep} ({kept} run summaries; `divcoll report {a.keep}` redraws the page)")
    return 0


def keep(folder, dest):
    """copies the study's manifest, base config and run summaries into dest; returns the number of summaries"""
    import shutil
    man = load_manifest(folder)
    os.makedirs(dest, exist_ok=True)
    for name in ("study.toml", man.get("base_copy", "base.toml")):
        shutil.copy2(os.path.join(folder, name), os.path.join(dest, name))
    n = 0
    for r in man["run"]:
        src = summary_path(os.path.join(folder, r["path"]))
        if r["status"] == "complete" and os.path.exists(src):
            os.makedirs(os.path.dirname(os.path.join(dest, r["path"])), exist_ok=True)
            shutil.copy2(src, summary_path(os.path.join(dest, r["path"])))
            arrays = os.path.splitext(os.path.join(folder, r["path"]))[0] + ".arrays.json"
            if os.path.exists(arrays):
                shutil.copy2(arrays, os.path.splitext(os.path.join(dest, r["path"]))[0] + ".arrays.json")
            n += 1
    return n


if __name__ == "__main__":
    sys.exit(main())
