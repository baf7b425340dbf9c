"""The development page of best-effort connector training (configs/studies/connector_dev.toml, protocol amendment
A5): per candidate training, each weak connector's flat travel as trained, as a share of its population's agents
alone and of the follower reference, the selection number S of A5 with the candidate it chooses, the cost, and the
learning curves (training batch and validation batch per iteration). Every number comes from the `*.arrays.json`
and `*.summary.json` kept beside the study's run summaries.

A5's rule: S(c) = the mean over the development populations and the two weak kinds k of T_k(flat) / A(flat), T_k the
kind deployed as trained (weak_uniform on clones, weak_diverse on diverse pairs), A agents alone, both over 3000
steps. The largest S wins among the eligible candidates (those that change only how connectors are trained);
candidates within TIE of the largest are tied, and a tie goes to the one that costs fewer pair-episodes, then to the
one that changes fewer keys."""

from __future__ import annotations

import dataclasses
import json
import os
import tomllib
from typing import Dict, List, Optional, Sequence

import numpy as np

from . import results as R

TIE = 0.02
KINDS = [("weak_uniform", "weak_uniform@uniform", "follower@uniform"),
         ("weak_diverse", "weak_diverse@diverse", "follower@diverse")]
# keys whose change alters the model (what a weak connector is), not its training: such candidates are readings (A5)
MODEL_KEYS = (
    "connectors.weak_stiffness", "connectors.damping", "connectors.amplitude", "connectors.follower",
    "connectors.network")


@dataclasses.dataclass
class Run:
    variant: str
    seed: int
    arrays: dict
    summary: dict

    @property
    def config(self) -> dict:
        return self.summary.get("config", {})


def load(folder: str) -> tuple:
    """(manifest, {variant: [Run]}, [variant doc/set in study order]) of a kept study folder"""
    with open(os.path.join(folder, "study.toml"), "rb") as fh:
        man = tomllib.load(fh)
    runs: Dict[str, List[Run]] = {}
    for r in man.get("run", []):
        base = os.path.splitext(os.path.join(folder, r["path"]))[0]
        a, s = base + ".arrays.json", base + ".summary.json"
        if not (os.path.exists(a) and os.path.exists(s)):
            continue
        with open(a) as fa, open(s) as fs:
            runs.setdefault(r["variant"], []).append(Run(r["variant"], r["seed"], json.load(fa), json.load(fs)))
    return man, runs, man.get("variant", [])


def pair_episodes(cfg: dict) -> float:
    """the pair-episodes one connector's training costs under a run config: the batch's episodes with gradient
    (grad_samples per step), the es/cmaes candidates' forward episodes, and keep-best's validation episodes"""
    c = cfg.get("connectors", {})
    it, b = c.get("iterations", 0), c.get("batch_pairs", 0)
    if c.get("optimizer") in ("es", "cmaes"):
        n = it * b * c.get("es_popsize", 0)
    else:
        n = it * b * c.get("grad_samples", 1)
    if c.get("keep_best"):
        n += (it + 1) * c.get("validation_pairs", 0)
    return float(n)


def flat_shares(run: Run) -> Dict[str, dict]:
    """per weak kind: travel as trained on flat (BL, mean over connectors), share of agents alone, share of the
    follower (NaN without references)"""
    dep = run.arrays["deploy"]
    f = dep["environments"].index("flat")
    alone = float(dep["alone_bl"][f])
    coll = np.asarray(dep["collectives_bl"], float)  # (E, T, R)
    refs = dict(zip(dep.get("references", []), np.asarray(dep.get("references_bl", [[]] * len(dep["environments"])),
                                                           float)[f])) if "references" in dep else {}
    out = {}
    for kind, typ, ref in KINDS:
        if typ not in dep["types"]:
            continue
        t = float(np.nanmean(coll[f, dep["types"].index(typ), :]))
        fol = float(refs.get(ref, np.nan))
        out[kind] = {"travel": t, "alone": alone, "share_alone": t / alone, "share_follower": t / fol,
                     "follower": fol, "free": float(refs.get(ref.replace("follower", "free"), np.nan)),
                     "passive": float(refs.get(ref.replace("follower", "passive"), np.nan))}
    return out


@dataclasses.dataclass
class Candidate:
    name: str
    doc: str
    keys: List[str]
    eligible: bool
    runs: List[Run]
    added: str = ""  # the date it joined the study after the selection's runs ("": from the start)
    S: float = float("nan")
    S_follower: float = float("nan")
    cost: float = float("nan")  # pair-episodes per connector
    wall_s: float = float("nan")  # connectors stage, mean per run

    def cells(self) -> Dict[tuple, dict]:
        return {(r.seed, k): v for r in self.runs for k, v in flat_shares(r).items()}


def candidates(folder: str) -> List[Candidate]:
    man, runs, variants = load(folder)
    out = []
    for v in variants:
        keys = list(v.get("set", []))
        # A5: a variant with `added` joined after the choice was made, so it is reported and never chosen
        added = v.get("added", "")
        elig = not added and not any(k.split("=")[0].strip() in MODEL_KEYS for k in keys)
        c = Candidate(v["name"], v.get("doc", ""), keys, elig, sorted(runs.get(v["name"], []), key=lambda r: r.seed),
                      added)
        cells = c.cells()
        if cells:
            c.S = float(np.mean([x["share_alone"] for x in cells.values()]))
            c.S_follower = float(np.nanmean([x["share_follower"] for x in cells.values()]))
            c.cost = pair_episodes(c.runs[0].config)
            c.wall_s = float(np.nanmean([r.arrays.get("connectors", {}).get("wall_s", np.nan) for r in c.runs]))
        out.append(c)
    return out


def eligibility(c: Candidate) -> str:
    """the table's word: yes, reading (changes the model), or the date a candidate was added after the choice"""
    if c.added:
        return f"added {c.added}, reported only"
    return "yes" if c.eligible else "reading"


def select(cands: Sequence[Candidate], seeds: Sequence[int]) -> Optional[Candidate]:
    """A5's choice among the eligible candidates that have every development population: the largest S, ties
    (within TIE) to fewer pair-episodes, then to fewer changed keys; None when no candidate is complete"""
    full = [c for c in cands if c.eligible and np.isfinite(c.S) and sorted({r.seed for r in c.runs}) == sorted(seeds)]
    if not full:
        return None
    best = max(c.S for c in full)
    tied = [c for c in full if c.S >= best - TIE]
    return min(tied, key=lambda c: (c.cost, len(c.keys), -c.S))


def curves_figure(cands: Sequence[Candidate], path: str) -> bool:
    """learning curves: per weak kind, each candidate's validation-batch travel per iteration (keep-best runs) or
    its training batch's (the others), mean over the development populations"""
    plt = R.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2), sharey=False)
    drawn = False
    cmap = plt.get_cmap("tab20")
    for ax, (kind, _, _) in zip(axes, KINDS):
        for i, c in enumerate(cands):
            ys, which = [], "train_bl"
            for r in c.runs:
                cv = r.arrays.get("connectors", {}).get("curves", {}).get(kind)
                if not cv:
                    continue
                which = "val_bl" if "val_bl" in cv else "train_bl"
                ys.append(np.nanmean(np.asarray(cv[which], float), axis=1))
            if not ys:
                continue
            n = min(len(y) for y in ys)
            y = np.nanmean([y[:n] for y in ys], axis=0)
            ax.plot(np.arange(n), y, color=cmap(i % 20), lw=1.2, ls="-" if c.eligible else ":",
                    label=f"{c.name} ({'validation' if which == 'val_bl' else 'training batch'})")
            drawn = True
        ax.set_title(f"{kind}: travel per iteration (1000 steps, mean of the populations)", fontsize=8)
        ax.set_xlabel("iteration")
        ax.set_ylabel("pair travel, BL")
    axes[1].legend(fontsize=6, loc="lower right", ncol=2)
    if drawn:
        R.save_figure(plt, fig, path)
    else:
        plt.close(fig)
    return drawn


def write(folder: str, out: str) -> str:
    """DIR/connector_dev.md and its learning-curve figure"""
    os.makedirs(out, exist_ok=True)
    man, _, _ = load(folder)
    cands = candidates(folder)
    seeds = sorted({r["seed"] for r in man.get("run", [])})
    done = [c for c in cands if c.runs]
    commits = sorted({r.summary.get("git_commit", "") for c in done for r in c.runs} - {""})
    lines = ["# Best-effort connector training: the development grid", "",
             f"Study `{man.get('name', '?')}` ([configs/studies/connector_dev.toml](../../../configs/studies/"
             "connector_dev.toml)) under protocol amendment A5 ([configs/studies/verdicts_protocol.md](../../../configs/"
             f"studies/verdicts_protocol.md)): development populations {', '.join(map(str, seeds))} (no verdict study "
             "uses them), the paper's per-connector budget (100 iterations × 100 pairs × 1000 steps), the two weak kinds, "
             "deployed on flat for 3000 steps beside agents alone and the reference connectors. Run files made by "
             f"divcoll {', '.join(commits) or '—'}; page by postprocess/ at {R.code_version()}.", ""]
    n_runs = sum(len(c.runs) for c in cands)
    planned = len(man.get("run", []))
    if n_runs < planned:
        lines += [f"**Interim**: {n_runs} of {planned} runs are in; S is over the populations each candidate has, "
                  "and no candidate is chosen until every eligible one has every development population.", ""]
    lines += ["S = mean over populations and kinds of the kind's flat travel as trained / agents alone (A5's selection "
              "number); *of follower* the same over the follower reference's travel. Cost: pair-episodes of 1000 steps "
              "per connector (with gradient for gradient methods, forward for es and keep-best's validation), and the "
              "connectors stage's wall time per run (2 connectors, 2 ranks, on a shared 2-core machine; each run's "
              "time is from the sitting it ran in, and runs of different sittings differ by up to several times on "
              "this machine: compare costs by pair-episodes).", "",
              "| candidate | eligible | S (of agents alone) | of follower | per population and kind: BL (of alone) | "
              "pair-episodes | wall s | keys |", "|---|---|---|---|---|---|---|---|"]
    for c in cands:
        if not c.runs:
            lines.append(f"| {c.name} | {eligibility(c)} | not run yet | | | | | "
                         f"{', '.join(f'`{k}`' for k in c.keys) or 'defaults'} |")
            continue
        per = "; ".join(f"{s}/{k.split('_')[1][0]}: {v['travel']:.2f} ({v['share_alone']:.0%})"
                        for (s, k), v in sorted(c.cells().items()))
        lines.append(f"| {c.name} | {eligibility(c)} | {c.S:.3f} | {c.S_follower:.2f} | {per} | "
                     f"{c.cost:,.0f} | {c.wall_s:.0f} | {', '.join(f'`{k}`' for k in c.keys) or 'defaults'} |")
    ref_rows = {}
    for c in done:
        if c.eligible:  # a reading's references are its own model's (its stiffness, its dashpot)
            for (s, k), v in c.cells().items():
                ref_rows[(s, k)] = v
    if ref_rows:
        lines += ["", "References on the same populations and pairs (flat, 3000 steps; the same in every eligible "
                  "candidate's run of a population; a reading's *of follower* is against its own model's follower, at "
                  "its stiffness and dashpot):", "", "| population | kind's pairs | agents alone | free | passive | follower |",
                  "|---|---|---|---|---|---|"]
        for (s, k), v in sorted(ref_rows.items()):
            dep = "clones" if k == "weak_uniform" else "diverse pairs"
            lines.append(f"| {s} | {dep} | {v['alone']:.2f} | {v['free']:.2f} ({v['free'] / v['alone']:.0%}) | "
                         f"{v['passive']:.2f} ({v['passive'] / v['alone']:.0%}) | "
                         f"{v['follower']:.2f} ({v['follower'] / v['alone']:.0%}) |")
    chosen = select(cands, seeds)
    lines += ["", "## The choice", ""]
    if chosen is None:
        lines.append("None yet: A5 chooses once every eligible candidate has run on every development population.")
    else:
        lines.append(f"**{chosen.name}** (S = {chosen.S:.3f}, {chosen.S_follower:.2f} of the follower; "
                     f"{', '.join(f'`{k}`' for k in chosen.keys) or 'the defaults'}), by A5's rule "
                     f"(largest S among the eligible candidates, ties within {TIE} to the cheaper).")
        tied = [c for c in cands if c is not chosen and c.eligible and np.isfinite(c.S) and c.S >= chosen.S - TIE]
        if tied:
            lines.append("Tied with it (within " + f"{TIE}): " + ", ".join(
                f"{c.name} (S = {c.S:.3f}, {c.cost:,.0f} pair-episodes, {len(c.keys)} keys)" for c in tied)
                + "; the tie went to the cheaper, then the one with fewer keys changed, then the larger S.")
    if curves_figure(cands, os.path.join(out, "curves.png")):
        lines += ["", "## Learning curves", "", "![learning curves](curves.png)", "",
                  "Solid: eligible candidates; dotted: readings of the model. Keep-best candidates show the validation "
                  "batch (32 fixed pairs, scored before every step), the others the training batch."]
    path = os.path.join(out, "connector_dev.md")
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return path


def curve_at(c: Candidate, kind: str, it: int, window: int = 10) -> float:
    """the candidate's learning curve of `kind` (validation batch with keep-best, training batch otherwise; mean over
    connectors, then over its populations) averaged over the `window` iterations up to `it` (fewer at the start; a
    training batch's last row stands for the end); NaN when no run reaches that iteration"""
    ys = []
    for r in c.runs:
        cv = r.arrays.get("connectors", {}).get("curves", {}).get(kind)
        if not cv:
            continue
        y = np.nanmean(np.asarray(cv["val_bl" if "val_bl" in cv else "train_bl"], float), axis=1)
        if len(y) >= it:  # a training batch's curve has one row per step: its last is iteration I − 1
            at = min(it, len(y) - 1)
            ys.append(float(np.mean(y[max(0, at - window + 1):at + 1])))
    return float(np.mean(ys)) if ys else float("nan")


MILESTONES = (0, 100, 250, 500, 1000)


def write_budget(folder: str, out: str, compare: str = "") -> str:
    """DIR/budget.md and its learning-curve figure (DIR/curves.png): amendment A5's larger budget, the same trainings
    run ten times longer (configs/studies/connector_budget.toml); `compare`: the development study's kept folder, whose
    runs of the same trainings at the paper's budget (the variant's name without `_1000`) the page sets beside them"""
    os.makedirs(out, exist_ok=True)
    man, _, _ = load(folder)
    cands = [c for c in candidates(folder) if c.runs]
    if not cands:
        raise ValueError(f"{folder}: no run of the study is kept yet")
    seeds = sorted({r.seed for c in cands for r in c.runs})
    commits = sorted({r.summary.get("git_commit", "") for c in cands for r in c.runs} - {""})
    iters = sorted({int(r.config.get("connectors", {}).get("iterations", 0)) for c in cands for r in c.runs})
    lines = ["# What a larger budget buys: connector training to " + "/".join(map(str, iters)) + " iterations", "",
             f"Study `{man.get('name', '?')}` ([configs/studies/connector_budget.toml](../../../configs/studies/"
             "connector_budget.toml)), protocol amendment A5's larger budget (descriptive: no candidate is chosen and "
             f"no verdict reads it): populations {', '.join(map(str, seeds))}, the two weak kinds, one connector each, "
             "batches of 100 pairs of 1000 steps, deployed on flat for 3000 steps beside agents alone and the "
             f"reference connectors. Run files made by divcoll {', '.join(commits) or '—'}; page by postprocess/ at "
             f"{R.code_version()}.", ""]
    planned = len(man.get("run", []))
    n_runs = sum(len(c.runs) for c in cands)
    if n_runs < planned:
        lines += [f"**Interim**: {n_runs} of {planned} runs are in.", ""]
    lines += ["Deployed as trained: flat travel of the kind as trained / agents alone (S: mean over populations and "
              "kinds, as A5's selection number) and / the follower; a keep-best training deploys its best weights on "
              "the validation pairs, the paper-faithful one its last.", "",
              "| training | S (of agents alone) | of follower | per population and kind: BL (of alone) | "
              "pair-episodes | wall s | keys |", "|---|---|---|---|---|---|---|"]
    for c in cands:
        per = "; ".join(f"{s}/{k.split('_')[1][0]}: {v['travel']:.2f} ({v['share_alone']:.0%})"
                        for (s, k), v in sorted(c.cells().items()))
        lines.append(f"| {c.name} | {c.S:.3f} | {c.S_follower:.2f} | {per} | {c.cost:,.0f} | {c.wall_s:.0f} | "
                     f"{', '.join(f'`{k}`' for k in c.keys) or 'defaults'} |")
    if compare:
        base = {c.name: c for c in candidates(compare)}
        rows = [(c, base.get(c.name.removesuffix("_1000"))) for c in cands]
        rows = [(c, b) for c, b in rows if b is not None and b.runs]
        if rows:
            lines += ["", f"Against the same training at the paper's budget (the development study, `{compare}`; the "
                      "same agents and deployment pairs, over the populations this study has):", "",
                      "| training | S at the paper's budget | S here | difference | of follower there → here |",
                      "|---|---|---|---|---|"]
            for c, b in rows:
                # on the populations both have: the development study's S over the budget run's populations
                have = {r.seed for r in c.runs}
                cells = [v for (s, _), v in b.cells().items() if s in have]
                bs = float(np.mean([v["share_alone"] for v in cells]))
                bf = float(np.nanmean([v["share_follower"] for v in cells]))
                lines.append(f"| {b.name} → {c.name} | {bs:.3f} | {c.S:.3f} | {c.S - bs:+.3f} | {bf:.2f} → "
                             f"{c.S_follower:.2f} |")
    marks = [m for m in MILESTONES if m <= max(iters)]
    lines += ["", "The learning curves: a pair's travel in 1000 steps (BL), mean over the populations, averaged over "
              "the 10 iterations up to each mark (keep-best trainings: the 32 fixed validation pairs; the others: the "
              "training batch, a new draw of diverse pairs every iteration).", "",
              "| training | kind | " + " | ".join(f"iteration {m}" for m in marks) + " |",
              "|---|---|" + "---|" * len(marks)]
    for c in cands:
        for kind, _, _ in KINDS:
            vals = [curve_at(c, kind, m) for m in marks]
            cells = " | ".join("—" if np.isnan(v) else f"{v:.2f}" for v in vals)
            lines.append(f"| {c.name} | {kind} | {cells} |")
    if curves_figure(cands, os.path.join(out, "curves.png")):
        lines += ["", "![learning curves](curves.png)", ""]
    path = os.path.join(out, "budget.md")
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return path
