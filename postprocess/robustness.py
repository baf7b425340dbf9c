#!/usr/bin/python3
"""The robustness page of a study folder (`divcoll study STUDY.toml --out DIR`): the paper's claims × the
study's variants, each cell the claim's effect with a 95% confidence interval over seeds and a verdict, and
the paper's Fig. 2A per variant with error bars over seeds.

    /usr/bin/python3 postprocess/robustness.py DIR [--out OUT]     (what `divcoll report DIR` runs)

Writes OUT/robustness.md and OUT/figures/fig2a_<variant>.png (OUT defaults to DIR/robustness), and beside each
run file DIR/<variant>/seed<k>.h5 its summary DIR/<variant>/seed<k>.summary.json: every number this page reads
from that run (each claim's verdict and effect under each reading, Fig. 2A's per-environment means) with the run's
config and commits, a few KB. A run whose .h5 is gone is read from its summary, so a study folder kept as its
manifest, base config and summaries (e.g. in postprocess/gallery/studies/) gives the same page, and seeds run
in different sessions or on a cluster can be gathered in one folder (`divcoll study --resume` counts a run
with a summary as complete).

Every claim is the one of claims.py, evaluated by claims.py on each run file (the "held in k/n seeds" count
uses its verdicts unchanged). The effect of a claim is the margin of the comparison behind claims.py's verdict,
signed so that a positive effect is the claim's direction (EFFECTS below says which margin, in which unit):
e.g. "trained collectives travel further than their agents alone" has the effect min over the four kinds
deployed as trained of (collective − agents alone) on flat, in BL. Per variant the effects of its seeds give
mean ± the Student t 95% interval over seeds (mean ± t(0.975, n−1)·s/√n, s the sample sd over seeds). Verdict:
**holds** if the interval lies above 0, **fails** if it lies below 0, **unresolved** if it contains 0, **too
few seeds** with fewer than 3 seeds (the interval is still shown from 2), not measured if the runs lack the
stage. "Comparable" claims (no difference expected) are the other way round: holds if the interval contains 0.
"""
from __future__ import annotations

import argparse
import copy
import os
import subprocess
import sys
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import claims as C  # noqa: E402
from divcoll_post import analysis as A  # noqa: E402

MIN_SEEDS = 3
LEVEL = 0.95


# ---- effects: the signed margin of each claim's comparison (positive = the claim's direction) -----------------

def _as_trained(r):
    return [t for t in r.types if t.split("@")[0].split("_")[1] == t.split("@")[1]]


def e_agents_trained(r):
    return None if r.fitness is None else float(r.fitness.mean()) - 3.0


def e_agents_drop(r):
    if not r.has["deploy"]:
        return None
    alone = 1 - r.novel_mean(r.alone) / r.alone[r.flat]
    return alone - max(1 - r.novel_mean(m) / m[r.flat] for m in r.coll.values())


def e_untrained_drop(r):
    if not r.curves or r.fitness is None:
        return None
    return 0.5 * float(r.fitness.mean()) - max(c[0] for c in r.curves.values())


def e_trained_beat_alone(r):
    if not r.has["deploy"]:
        return None
    return min(r.coll[t][r.flat] for t in _as_trained(r)) - r.alone[r.flat]


def e_weak_diverse_best_flat(r):
    if not r.has["deploy"]:
        return None
    others = [t for t in _as_trained(r) if t != "weak_diverse@diverse"]
    if not others:
        return None
    return r.coll["weak_diverse@diverse"][r.flat] - max(r.coll[t][r.flat] for t in others)


def e_all_drop_novel(r):
    if not r.has["deploy"]:
        return None
    return min(r.coll[t][r.flat] - r.novel_mean(r.coll[t]) for t in r.types)


def e_weak_diverse_best_novel(r):
    if not r.has["deploy"]:
        return None
    others = [t for t in r.types if t != "weak_diverse@diverse"]
    return r.novel_mean(r.coll["weak_diverse@diverse"]) - max(r.novel_mean(r.coll[t]) for t in others)


def e_transplant(r):
    if not r.has["deploy"]:
        return None
    dd, du = r.coll["weak_diverse@diverse"][r.flat], r.coll["weak_diverse@uniform"][r.flat]
    uu, ud = r.coll["weak_uniform@uniform"][r.flat], r.coll["weak_uniform@diverse"][r.flat]
    return min(0.25 * abs(dd) - (dd - du), uu - ud)


def e_weak_diverse_most_envs(r):
    if not r.has["deploy"]:
        return None
    weak = [t for t in r.types if t.startswith("weak")]
    wins = sum(1 for e in r.novel if max(weak, key=lambda t: r.coll[t][e]) == "weak_diverse@diverse")
    beats = sum(1 for e in r.novel if r.coll["weak_diverse@diverse"][e] > r.alone[e])
    return (min(wins, beats) - len(r.novel) / 2) / len(r.novel)


def e_specialists(r):
    if not (r.has["specialists"] and r.has["deploy"]):
        return None
    gen = np.array([r.coll["weak_diverse@diverse"][r.envs.index(e)] for e in r.spec_envs])
    return float(np.max(gen - r.spec_best))


def e_scaling(r):
    if not r.has["scaling"]:
        return None
    adv = r.scale[:, 1] - r.scale[:, 0]
    return float(min(np.min(np.diff(adv)) if len(adv) > 1 else np.inf, adv[-1]))


def e_graded(r):
    if not (r.has["graded"] and r.has["deploy"]):
        return None
    rows = [(r.novel_mean(r.alone), r.novel_mean(r.coll["weak_diverse@diverse"]))] + list(r.graded.values())
    g = [p - a for a, p in rows]
    return min(g[0] - g[1], g[1] - g[2])


def e_diverse_disrupted_more(r):
    adv = C._adversity(r)
    if adv is None:
        return None
    return float(np.nanmean(adv.all_replicate_means(A.DIVERSE)) - np.nanmean(adv.all_replicate_means(A.UNIFORM)))


def e_worse_altered_more(r):
    adv = C._adversity(r)
    return None if adv is None else min(adv.mean(t, A.WORSE) - adv.mean(t, A.BETTER) for t in A.TYPES)


def e_diverse_change_worse_more(r):
    adv = C._adversity(r)
    return None if adv is None else adv.mean(A.DIVERSE, A.WORSE) - adv.mean(A.UNIFORM, A.WORSE)


def e_better_comparable(r):
    adv = C._adversity(r)
    return None if adv is None else adv.mean(A.DIVERSE, A.BETTER) - adv.mean(A.UNIFORM, A.BETTER)


def _majority(r, count, first, second):
    """(environments where the familiarity table's count `count` of type `first` exceeds `second`'s − half of them)
    / environments: positive when it is most environments"""
    fam = C._familiarity(r)
    if fam is None:
        return None
    tab, n = fam.best_table(), len(fam.envs)
    return (sum(1 for i in range(n) if tab[i, count, first] > tab[i, count, second]) - n / 2) / n


def e_more_familiar(r):
    return _majority(r, 0, 0, 1)  # states in shared cells, diverse-trained above uniform-trained


def e_uniform_more_novel_states(r):
    return _majority(r, 2, 1, 0)  # novel-only states, uniform-trained above diverse-trained


def e_wind_unfamiliar(r):
    fam = C._familiarity(r)
    if fam is None or A.WIND not in fam.envs:
        return None
    t = fam.best_table()[fam.envs.index(A.WIND)]
    return min(t[0, 0] - t[0, 1], (t[1, 1] + t[2, 1]) - (t[1, 0] + t[2, 0]))


# claims.py's claim function -> (effect, what the effect is, unit, "equal" for a claim of no difference)
EFFECTS = {
    C.c_agents_trained: (e_agents_trained, "final population's mean fitness − 3", "BL", False),
    C.c_agents_drop: (e_agents_drop, "relative drop flat → novel of agents alone − the largest of any collective type", "", False),
    C.c_untrained_drop: (e_untrained_drop, "half the agents' fitness − the best untrained batch mean", "BL", False),
    C.c_trained_beat_alone: (e_trained_beat_alone, "min over kinds deployed as trained of (collective − agents alone) on flat", "BL", False),
    C.c_weak_diverse_best_flat: (e_weak_diverse_best_flat, "weak diverse@diverse − the best other kind as trained, flat", "BL", False),
    C.c_all_drop_novel: (e_all_drop_novel, "min over types of (flat − novel mean)", "BL", False),
    C.c_weak_diverse_best_novel: (e_weak_diverse_best_novel, "weak diverse@diverse − the best other type, novel mean", "BL", False),
    C.c_transplant: (e_transplant, "min(¼·abs(dd) − (dd − du), uu − ud) on flat, dd = diverse-trained on diverse pairs, du = on clones, uu, ud the same for uniform-trained", "BL", False),
    C.c_weak_diverse_most_envs: (e_weak_diverse_most_envs, "(min(environments best of weak, environments above alone) − half) / environments", "", False),
    C.c_specialists: (e_specialists, "max over environments of (generalist − best specialist)", "BL", False),
    C.c_scaling: (e_scaling, "min(growth of diverse − uniform from size to size, its value at the largest size)", "BL", False),
    C.c_graded: (e_graded, "min of the steps in (pairs − alone) from more to fewer sources of diversity", "BL", False),
    C.c_diverse_disrupted_more: (e_diverse_disrupted_more, "DTW per step, diverse-trained − uniform-trained, all agents", "u", False),
    C.c_worse_altered_more: (e_worse_altered_more, "min over the two types of (worse − better agent's DTW per step)", "u", False),
    C.c_diverse_change_worse_more: (e_diverse_change_worse_more, "worse agents' DTW per step, diverse-trained − uniform-trained", "u", False),
    C.c_better_comparable: (e_better_comparable, "better agents' DTW per step, diverse-trained − uniform-trained (claim: ≈ 0)", "u", True),
    C.c_more_familiar: (e_more_familiar, "(environments where diverse-trained has more shared-cell states − half) / environments", "", False),
    C.c_uniform_more_novel_states: (e_uniform_more_novel_states, "(environments where uniform-trained has more novel-only states − half) / environments", "", False),
    C.c_wind_unfamiliar: (e_wind_unfamiliar, "min(shared states diverse − uniform, one-sided states uniform − diverse), wind", "states", False),
}


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


def verdict(mean, lo, hi, n, equal=False):
    if n == 0:
        return "not measured"
    if n < MIN_SEEDS:
        return "too few seeds"
    if equal:
        return "holds" if lo <= 0 <= hi else "fails"
    return "holds" if lo > 0 else "fails" if hi < 0 else "unresolved"


def num(x):
    return "—" if x is None or not np.isfinite(x) else f"{x:+.3g}"


# ---- run summaries: what this page reads from one run file, kept beside it ----------------------------------------

SUMMARY_FORMAT = "divcoll-run-summary"
SUMMARY_VERSION = 1
AS_RUN = "as_run"  # the key of the claims as the run's own config reads them


def summary_path(run_path):
    return os.path.splitext(run_path)[0] + ".summary.json"


def _finite_or_none(x):
    return None if x is None or not np.isfinite(x) else float(x)


def _cell(fn, run):
    """(claims.py's verdict, the effect or None) of claim function `fn` on a claims.Run or a reading of one"""
    try:
        _, vd = fn(run)
        e = EFFECTS[fn][0](run)
    except (KeyError, ValueError, IndexError, ZeroDivisionError):
        vd, e = "not measured", None
    return vd, e


def summarize(run):
    """the summary dict of a claims.Run read from its run file"""
    import h5py
    readings = {AS_RUN: run}
    for protocol, _ in READINGS:
        rr = reread(run, protocol)
        if rr is not None:
            readings[protocol] = rr
    claims = {}
    for key, r in readings.items():
        claims[key] = {}
        for _, fn in C.CLAIMS:
            if key == AS_RUN or fn in ALONE_CLAIMS:
                vd, e = _cell(fn, r)
                claims[key][fn.__name__] = {"verdict": vd, "effect": _finite_or_none(e)}
    fig = None
    if run.has["deploy"]:
        fig = {"environments": run.envs, "types": run.types,
               "alone": {k: [float(x) for x in r.alone] for k, r in readings.items()},
               "collectives": {t: [float(x) for x in run.coll[t]] for t in run.types}}
    with h5py.File(run.path, "r") as f:
        attrs = {a: C._s(f.attrs[a]) for a in ("git_commit", "base_git_commit", "start_time", "end_time")
                 if a in f.attrs}
        # the run's config as its values (the run file's TOML text, comments and all, is about 12 KB)
        attrs["config"] = tomllib.loads(C._s(f.attrs["config"])) if "config" in f.attrs else {}
    return {"format": SUMMARY_FORMAT, "version": SUMMARY_VERSION, "run_file": os.path.basename(run.path),
            **attrs, "stages_complete": run.has, "claims": claims, "fig2a": fig}


def write_summary(run):
    """writes the summary of a claims.Run beside its run file (atomically); returns its path"""
    import json
    path = summary_path(run.path)
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(summarize(run), fh, indent=None, sort_keys=True)
        fh.write("\n")
    os.replace(tmp, path)
    return path


class SummaryRun:
    """a run read from its summary: what evaluate() and fig2a_values() use of a claims.Run. from_file: the summary was
    written from the run file beside it just now (else the folder holds the summary alone)"""

    def __init__(self, path, data=None, reading=AS_RUN, from_file=False):
        import json
        self.path, self.from_file = path, from_file
        if data is None:
            with open(path) as fh:
                data = json.load(fh)
            if data.get("format") != SUMMARY_FORMAT or data.get("version") != SUMMARY_VERSION:
                raise ValueError(f"{path} is not a divcoll run summary of version {SUMMARY_VERSION}")
        self.data, self.reading = data, reading
        self.has = data["stages_complete"]
        self.config = data.get("config", {})
        fig = data.get("fig2a")
        if fig:
            self.envs, self.types = fig["environments"], fig["types"]
            self.flat = self.envs.index("flat")
            self.novel = [i for i, e in enumerate(self.envs) if e != "flat"]
            self.alone = np.array(fig["alone"][reading], dtype=float)
            self.coll = {t: np.array(v, dtype=float) for t, v in fig["collectives"].items()}

    def novel_mean(self, arr):
        return float(np.mean(arr[self.novel]))

    def cell(self, fn):
        c = self.data["claims"][self.reading].get(fn.__name__)
        if c is None:
            return "not measured", None
        return c["verdict"], c["effect"]

    def reread(self, protocol):
        return SummaryRun(self.path, self.data, protocol, self.from_file) if protocol in self.data["claims"] else None

    def commits(self):
        return {self.data[a] for a in ("git_commit", "base_git_commit") if a in self.data}


def load_run(folder, rel):
    """the run at `rel` in the study folder, read from its summary: written anew from the run file when that is
    there, else the one kept; None if neither. The page reads every run the same way, from what is on disk."""
    path = os.path.join(folder, rel)
    if os.path.exists(path):
        from divcoll_post import verdicts as V
        V.write_arrays(path)  # the protocol's per-connector arrays (verdicts.py), kept beside the summary
        return SummaryRun(write_summary(C.Run(path)), from_file=True)
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


# claims whose verdict or effect reads agents alone (the only numbers analysis.alone_protocol changes)
ALONE_CLAIMS = {C.c_agents_drop, C.c_trained_beat_alone, C.c_weak_diverse_most_envs, C.c_graded}
# report-time readings of analysis.alone_protocol: a run made with same_length is also read under each of these
# (claims.alone_under_protocol); training_length needs deploy.early_step
READINGS = [("training_length", "agents alone at their training length (travel at deploy.early_step), collectives "
                                "over the deployment"),
            ("training_rate", "agents alone's deployment travel × connectors.episode_steps / deploy.episode_steps")]


def reread(run, protocol):
    """a copy of the claims.Run with agents alone read under `protocol` (None when the run cannot be)"""
    import h5py
    import summary
    if not run.has["deploy"]:
        return None
    with h5py.File(run.path, "r") as f:
        cfg = tomllib.loads(C._s(f.attrs["config"]))
        if protocol == "training_length" and (cfg.get("deploy", {}).get("early_step", 0) <= 0
                                              or "agents/travel_bl_early" not in f["deploy"]):
            return None
        d = f["deploy"]
        same, _ = summary.env_means(d["agents/travel_bl"][()], d["agents/status"][()])
        alone = C.alone_under_protocol(f, same, protocol)
    r = copy.copy(run)
    r.alone = alone
    return r


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
    """{column: {"source", "protocol", "set", "doc", "seeds", "runs", "cells": [(claim text, mean, lo, hi, n,
    verdict, held, n_eval)]}}; a report-time reading's cells of claims that do not read agents alone are
    verdict "as source" (the same numbers as its source variant's column)"""
    out = {}
    for name, source, protocol, sets, doc, runs in columns(folder, manifest):
        cells = []
        for text, fn in C.CLAIMS:
            eff, _, _, equal = EFFECTS[fn]
            if protocol is not None and fn not in ALONE_CLAIMS:
                cells.append((text, float("nan"), float("nan"), float("nan"), 0, "as source", 0, 0))
                continue
            values, held, measured = [], 0, 0
            for _, run in runs:
                vd, e = run.cell(fn)
                if vd != "not measured":
                    measured += 1
                    held += vd == "held"
                values.append(e)
            m, lo, hi, n = t_interval(values)
            cells.append((text, m, lo, hi, n, verdict(m, lo, hi, n, equal), held, measured))
        out[name] = {"source": source, "protocol": protocol, "set": sets, "doc": doc,
                     "seeds": [s for s, _ in runs], "runs": [r for _, r in runs], "cells": cells}
    return out


def provenance(runs):
    """text: the divcoll commits of the complete runs (SummaryRun), and the commit of this postprocessing tree"""
    commits = set()
    for run in runs:
        commits |= run.commits()
    try:
        here = subprocess.run(["git", "-C", HERE, "describe", "--always", "--dirty", "--abbrev=12"],
                              capture_output=True, text=True, timeout=30).stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        here = "unknown"
    return (f"Run files made by divcoll {', '.join(sorted(commits)) or '—'}; page written by postprocess/ at "
            f"{here}.")


# ---- the summary figure: every claim's effect per column --------------------------------------------------------

def summary_figure(res, path):
    """one panel per claim measured in some column: mean effect and its t 95% interval over seeds per column"""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = list(res)
    rows = [i for i in range(len(C.CLAIMS)) if any(res[c]["cells"][i][4] > 0 for c in names)]
    if not rows:
        return False
    ncol = 4
    nrow = (len(rows) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.2 * ncol, 2.5 * nrow), squeeze=False)
    colors = {"holds": "#1a9641", "fails": "#d7191c", "unresolved": "#777777", "too few seeds": "#bbbbbb"}
    for ax, i in zip(axes.flat, rows):
        text, fn = C.CLAIMS[i]
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
        words = text.split()
        title = " ".join(words[:9]) + (" …" if len(words) > 9 else "")
        ax.set_title(title, fontsize=6)
        unit = EFFECTS[fn][2]
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

def write_page(folder, out):
    man = load_manifest(folder)
    res = evaluate(folder, man)
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
                      "at report time: that key changes only the agents-alone numbers claims.py compares with, so only "
                      "the claims that read agents alone are evaluated again; the others are the same as V's "
                      "(\"as source\")."]
    if runs:
        short = C.short_of(runs[0].config, C.NOVEL)
        if short:
            lines += ["", f"A single run of this scale is below the counts claims.py needs to judge one run ({short}); "
                          "here the evidence is the interval over seeds, and \"held k/n\" counts claims.py's raw test "
                          "per seed."]
    lines += ["", "## Claims × variants", "",
              "Each cell: the claim's effect (positive = the paper's direction; definitions below), mean over seeds "
              f"with its Student t {LEVEL:.0%} interval over seeds, then how many seeds claims.py's own test held "
              f"in, and the verdict (holds: interval above 0; fails: below 0; unresolved: contains 0; too few seeds: "
              f"fewer than {MIN_SEEDS}).", ""]
    if summary_figure(res, os.path.join(out, "robustness.png")):
        lines += ["![every claim's effect per variant](robustness.png)", ""]
    lines += ["| claim | " + " | ".join(variants) + " |", "|---|" + "---|" * len(variants)]
    counts = {v: {} for v in variants}
    for ci, (text, fn) in enumerate(C.CLAIMS):
        unit = EFFECTS[fn][2]
        row = [text]
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
    lines += ["", "## Effects", "", "| claim | effect (positive = the claim's direction) | unit |", "|---|---|---|"]
    for text, fn in C.CLAIMS:
        _, what, unit, equal = EFFECTS[fn]
        lines.append(f"| {text} | {what}{' (holds if the interval contains 0)' if equal else ''} | {unit or '—'} |")
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
    return path, res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", help="study folder (divcoll study --out DIR)")
    ap.add_argument("--out", help="output folder (default DIR/robustness)")
    ap.add_argument("--divcoll", help="accepted for `divcoll report`; unused")
    ap.add_argument("--keep", metavar="DEST", help="also copy the study as its manifest, base config and run summaries "
                                                   "(no run files) into DEST, e.g. postprocess/gallery/studies/NAME")
    a = ap.parse_args(argv)
    out = a.out or os.path.join(a.study, "robustness")
    try:
        path, res = write_page(a.study, out)
        kept = keep(a.study, a.keep) if a.keep else None
    except (OSError, ValueError, tomllib.TOMLDecodeError) as e:
        print(f"robustness: {e}", file=sys.stderr)
        return 2
    n = sum(len(r["cells"]) for r in res.values())
    print(f"robustness: wrote {path} ({len(C.CLAIMS)} claims × {len(res)} variants = {n} cells)")
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
