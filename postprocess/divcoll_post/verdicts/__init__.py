"""The pre-registered protocol (configs/studies/verdicts_protocol.md) as code: the arrays each run keeps, every
claim's effect, the hierarchical bootstrap, Holm's procedure and the four verdicts.

A run's arrays (`extract(run.h5)`, kept as `<run>.arrays.json` beside its summary) hold per connector and
environment what the claims read, so a study folder kept without its run files still gives every number.
`Population` turns one run's arrays (and, for the supplement stages, the arrays of the run that computed
them for the same seed) into batched views for connector draws; `CLAIMS` is the registry, one entry a claim;
`judge` evaluates a family of claims over populations.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import tomllib
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

ARRAYS_FORMAT = "divcoll-verdict-arrays"
ARRAYS_VERSION = 1
B_DEFAULT = 20000
BOOT_SEED = 20261204
ALPHA = 0.025  # familywise, one-sided hypotheses (Holm)
WEAK_TYPES = ["weak_uniform@uniform", "weak_uniform@diverse", "weak_diverse@uniform", "weak_diverse@diverse"]
STRONG_TYPES = ["strong_uniform@uniform", "strong_uniform@diverse", "strong_diverse@uniform", "strong_diverse@diverse"]
MATCHED = ["weak_uniform@uniform", "weak_diverse@diverse", "strong_uniform@uniform", "strong_diverse@diverse"]
WU, WD = "weak_uniform@uniform", "weak_diverse@diverse"
SEVERE = 0.25  # "severe": a relative drop of more than a quarter (protocol §5)


from ..reader import complete, list_attr, open_file, text as _s  # noqa: E402
from ..results import ok_means  # noqa: E402


def _lists(a):
    return np.asarray(a, float).tolist()


# ---- a run's arrays -----------------------------------------------------------------------------------------------

def extract(path: str) -> dict:
    """the arrays the protocol reads, from a run file (stages that are not complete are left out)"""
    out = {"format": ARRAYS_FORMAT, "version": ARRAYS_VERSION, "run_file": os.path.basename(path)}
    with open_file(path) as f:
        cfg = tomllib.loads(_s(f.attrs["config"])) if "config" in f.attrs else {}
        out["seed"] = cfg.get("run", {}).get("seed")
        out["git_commit"] = _s(f.attrs.get("git_commit", ""))
        out["episode_steps"] = {"connectors": cfg.get("connectors", {}).get("episode_steps"),
                                "deploy": cfg.get("deploy", {}).get("episode_steps")}
        if complete(f, "agents"):
            fit = f["agents/final/fitness"][()]
            out["agents"] = {"fitness_mean": float(np.mean(fit)), "fitness_sd": float(np.std(fit))}
            if "agents/gen_000/curve_u" in f:
                c = f["agents/gen_000/curve_u"][()][:, 0]
                fit, tu = f["agents/gen_000/fitness"][()], f["agents/gen_000/travel_u"][()]
                bl = np.where(fit != 0, tu / np.where(fit == 0, 1, fit), np.nan)
                out["agents"]["gen0_mean"] = float(np.nanmean(c / bl))
        if complete(f, "connectors"):
            kinds = list_attr(f["connectors"], "kinds")
            out["connectors"] = {"untrained_bl": {k: _lists(f[f"connectors/{k}/curve_bl"][()][0]) for k in kinds
                                                  if f"connectors/{k}/curve_bl" in f}}
            # learning curves (iteration, replicate): the training batch's travel and, with keep_best, the
            # validation batch's and the iteration whose weights were kept
            curves = {}
            for k in kinds:
                g = f"connectors/{k}"
                if f"{g}/curve_bl" not in f:
                    continue
                curves[k] = {"train_bl": _lists(f[f"{g}/curve_bl"][()])}
                if f"{g}/val_bl" in f:
                    curves[k]["val_bl"] = _lists(f[f"{g}/val_bl"][()])
                if f"{g}/best_iteration" in f:
                    curves[k]["best_iteration"] = _lists(f[f"{g}/best_iteration"][()])
            out["connectors"]["curves"] = curves
            out["connectors"]["wall_s"] = float(f["connectors"].attrs.get("wall_s", float("nan")))
        if complete(f, "deploy"):
            d = f["deploy"]
            envs, types = list_attr(d, "environments"), list_attr(d, "types")
            alone, _ = ok_means(d["agents/travel_bl"][()], d["agents/status"][()], 1)
            coll, nok = ok_means(d["collectives/travel_bl"][()], d["collectives/status"][()], 3)  # (E, T, R)
            dep = {"environments": envs, "types": types, "alone_bl": _lists(alone), "collectives_bl": _lists(coll),
                   "collectives_ok": np.asarray(nok).tolist()}
            if "agents/travel_bl_early" in d and cfg.get("deploy", {}).get("early_step", 0) > 0:
                dep["alone_bl_early"] = _lists(ok_means(d["agents/travel_bl_early"][()], d["agents/status"][()], 1)[0])
                dep["early_step"] = cfg["deploy"]["early_step"]
            if "references/travel_bl" in d:  # deploy.references: free, passive, follower on uniform and diverse pairs
                ref, rok = ok_means(d["references/travel_bl"][()], d["references/status"][()], 2)  # (E, RT)
                dep["references"] = list_attr(d, "references")
                dep["references_bl"] = _lists(ref)
                dep["references_ok"] = np.asarray(rok).tolist()
                if "references/travel_bl_early" in d and "early_step" in dep:
                    dep["references_bl_early"] = _lists(
                        ok_means(d["references/travel_bl_early"][()], d["references/status"][()], 2)[0])
            out["deploy"] = dep
        if complete(f, "analysis"):
            a = f["analysis"]
            adv, fam, fam_cal = {}, {}, {}
            for t in list_attr(a, "types"):
                g = a[f"adversity/{t}"]
                dtw, ws = g["dtw"][()], g["worse_slot"][()]  # (E, R, P, 2), (E, R, P)
                worse = np.take_along_axis(dtw, ws[..., None].astype(int), axis=3)[..., 0]
                better = np.take_along_axis(dtw, 1 - ws[..., None].astype(int), axis=3)[..., 0]
                with np.errstate(invalid="ignore"):
                    adv[t] = {"all": _lists(np.nanmean(dtw, axis=(0, 2, 3))),
                              "worse": _lists(np.nanmean(worse, axis=(0, 2))),
                              "better": _lists(np.nanmean(better, axis=(0, 2)))}
                c = a[f"familiarity/{t}/counts"][()]  # (E_novel, R, 6)
                fam[t] = _lists(c[..., :3])
                if f"familiarity/{t}/counts_calibrated" in a:  # analysis.calibrated_cell_scale > 0 (A6's C24c)
                    fam_cal[t] = _lists(a[f"familiarity/{t}/counts_calibrated"][()][..., :3])
            out["analysis"] = {"novel_environments": list_attr(a, "novel_environments"), "dtw": adv,
                               "familiarity": fam}
            if fam_cal:
                out["analysis"]["familiarity_calibrated"] = fam_cal
                out["analysis"]["calibrated_cell_scale"] = cfg["analysis"]["calibrated_cell_scale"]
        if complete(f, "specialists"):
            s = f["specialists"]
            m, _ = ok_means(s["travel_bl"][()], s["status"][()], 2)  # (E_s, R_s)
            out["specialists"] = {"environments": list_attr(s, "environments"), "travel_bl": _lists(m)}
        if complete(f, "scaling"):
            sc = f["scaling"]
            m, _ = ok_means(sc["travel_bl"][()], sc["status"][()], 4)  # (E, S, 2, R)
            out["scaling"] = {"environments": list_attr(sc, "environments"), "sizes": [int(x) for x in sc["sizes"][()]],
                              "travel_bl": _lists(m)}
        if complete(f, "graded"):
            g = f["graded"]
            pops = {}
            for pop in list_attr(g, "populations"):
                gp = g[pop]
                al, _ = ok_means(gp["deploy/agents/travel_bl"][()], gp["deploy/agents/status"][()], 1)
                pa, _ = ok_means(gp["deploy/pairs/travel_bl"][()], gp["deploy/pairs/status"][()], 2)  # (E, R)
                pops[pop] = {"alone_bl": _lists(al), "pairs_bl": _lists(pa)}
            out["graded"] = {"environments": list_attr(g, "environments"), "populations": pops}
    return out


def arrays_path(run_path: str) -> str:
    return os.path.splitext(run_path)[0] + ".arrays.json"


def write_arrays(run_path: str) -> str:
    path = arrays_path(run_path)
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(extract(run_path), fh, sort_keys=True)
        fh.write("\n")
    os.replace(tmp, path)
    return path


def read_arrays(path: str) -> dict:
    with open(path) as fh:
        a = json.load(fh)
    if a.get("format") != ARRAYS_FORMAT or a.get("version") != ARRAYS_VERSION:
        raise ValueError(f"{path} is not a divcoll verdict-arrays file of version {ARRAYS_VERSION}")
    return a


# ---- a population, batched over connector draws -----------------------------------------------------------------

def _arr(x):
    return np.asarray(x, dtype=float)


class Population:
    """one agent population's arrays (merged from the runs of one seed). `view(draws)` gives the claims' inputs
    with a leading batch axis: draws[unit] is an (b, R_unit) index array of connectors (None: all, b = 1)."""

    def __init__(self, seed, parts: Sequence[dict]):
        self.seed = seed
        self.a = {}
        for p in parts:  # later parts (supplement runs) add their stages; shared stages are the same numbers
            for k, v in p.items():
                self.a.setdefault(k, v)
        dep = self.a.get("deploy")
        self.units = {}  # unit name -> number of connectors
        if dep:
            self.envs, self.types = dep["environments"], dep["types"]
            self.flat = self.envs.index("flat")
            self.novel = [i for i, e in enumerate(self.envs) if e != "flat"]
            self.coll = _arr(dep["collectives_bl"])  # (E, T, R)
            for t in self.types:
                self.units[t.split("@")[0]] = self.coll.shape[2]
        sp = self.a.get("specialists")
        if sp:
            self.spec = _arr(sp["travel_bl"])  # (E_s, R_s)
            for i in range(self.spec.shape[0]):
                self.units[f"specialist:{i}"] = self.spec.shape[1]
        gr = self.a.get("graded")
        if gr:
            for pop, v in gr["populations"].items():
                self.units[f"graded:{pop}"] = _arr(v["pairs_bl"]).shape[1]

    def has(self, stage):
        return stage in self.a

    def draws(self, rng, b):
        return {u: rng.integers(0, r, size=(b, r)) for u, r in self.units.items()}

    @staticmethod
    def _pick(x, idx, axis):
        """mean over connector axis `axis` of x after picking idx (b, R): result has a leading b axis"""
        x = np.moveaxis(np.asarray(x, float), axis, -1)  # (..., R)
        if idx is None:
            return np.nanmean(x, axis=-1)[None]
        picked = x[..., idx]  # (..., b, R)
        m = np.nanmean(picked, axis=-1)  # (..., b)
        return np.moveaxis(m, -1, 0)

    def T(self, draws=None):
        """(b, E, T): every type's travel per environment, mean over (drawn) connectors"""
        out = []
        for ti, t in enumerate(self.types):
            idx = None if draws is None else draws[t.split("@")[0]]
            out.append(self._pick(self.coll[:, ti, :], idx, 1))  # (b, E)
        return np.stack(out, axis=2)

    def alone(self, protocol="same_length"):
        dep = self.a["deploy"]
        if protocol == "training_length":
            if "alone_bl_early" not in dep:
                raise KeyError("deploy.early_step")
            return _arr(dep["alone_bl_early"])
        x = _arr(dep["alone_bl"])
        if protocol == "training_rate":
            st = self.a["episode_steps"]
            return x * st["connectors"] / st["deploy"]
        return x

    def references(self, protocol="same_length"):
        """{name@deployment: (E,) travel}: the reference connectors (free, passive, follower; deploy.references) of
        this population, at 3000 steps or (training_length) at step 1000; {} when the runs did not deploy them"""
        dep = self.a.get("deploy", {})
        if "references" not in dep:
            return {}
        key = "references_bl_early" if protocol == "training_length" else "references_bl"
        if key not in dep:
            return {}
        x = _arr(dep[key])  # (E, RT)
        return {n: x[:, i] for i, n in enumerate(dep["references"])}

    def untrained(self, draws=None):
        """(b, kinds): each kind's batch travel before the first step, mean over (drawn) connectors"""
        u = self.a["connectors"]["untrained_bl"]
        return np.stack([self._pick(_arr(v), None if draws is None else draws.get(k), 0) for k, v in u.items()],
                        axis=1)

    def dtw(self, t, which, draws=None):
        v = _arr(self.a["analysis"]["dtw"][t][which])
        return self._pick(v, None if draws is None else draws[t.split("@")[0]], 0)  # (b,)

    def familiarity(self, t, draws=None, calibrated=False):
        """(b, E_novel, 3): states in both / training-only / novel-only cells, mean over (drawn) connectors; with
        calibrated, at analysis.calibrated_cell_scale (KeyError when the run did not count there)"""
        v = _arr(self.a["analysis"]["familiarity_calibrated" if calibrated else "familiarity"][t])  # (E, R, 3)
        return self._pick(v, None if draws is None else draws[t.split("@")[0]], 1)

    def specialists_best(self, draws=None):
        """(b, E_s): the best specialist's travel per environment (over drawn specialists)"""
        out = []
        for i in range(self.spec.shape[0]):
            row = self.spec[i]
            if draws is None:
                out.append(np.array([np.nanmax(row)]))
            else:
                out.append(np.nanmax(row[draws[f"specialist:{i}"]], axis=1))
        return np.stack(out, axis=1)

    def scaling(self, draws=None):
        """(b, S, 2): novel mean travel of the uniform (0) and diverse (1) chains per size"""
        sc = self.a["scaling"]
        x = _arr(sc["travel_bl"])  # (E, S, 2, R)
        nov = [i for i, e in enumerate(sc["environments"]) if e != "flat"]
        out = []
        for v, unit in enumerate(["weak_uniform", "weak_diverse"]):
            m = self._pick(x[:, :, v, :], None if draws is None else draws[unit], 2)  # (b, E, S)
            out.append(np.mean(m[:, nov, :], axis=1))
        return np.stack(out, axis=2)

    def graded_gain(self, pop, draws=None):
        """(b,): novel mean of graded population `pop`'s pairs − its agents alone"""
        g = self.a["graded"]
        nov = [i for i, e in enumerate(g["environments"]) if e != "flat"]
        v = g["populations"][pop]
        pairs = self._pick(_arr(v["pairs_bl"]), None if draws is None else draws[f"graded:{pop}"], 1)  # (b, E)
        return np.mean(pairs[:, nov], axis=1) - np.mean(_arr(v["alone_bl"])[nov])


# ---- the claims -------------------------------------------------------------------------------------------------

@dataclasses.dataclass
class Claim:
    id: str
    family: str  # "M" main text, "S" supplement and Fig. 4
    text: str
    where: str
    paper: str
    effect_text: str
    form: str  # greater, noninferior, equivalent, band
    margin: float  # δ (greater, noninferior, equivalent)
    unit: str
    needs: tuple  # stages
    effect: Callable  # (Population, draws or None, protocol) -> (b,) array
    band: Optional[tuple] = None
    reads_alone: bool = False
    # the single-run view (the report of one run file, the robustness page's per-seed value): the config counts a
    # run needs for its one value to be judged, what of this run's numbers to show, and the episodes to link
    counts: tuple = ()  # ((config key, minimum, what it counts), ...)
    describe: Optional[Callable] = None  # (Population, protocol) -> text of the run's numbers behind the effect
    episodes: tuple = ("", False, (), "none")  # (note, link agents alone?, types, environments): see EPISODE_TYPES


def region(c: Claim) -> tuple:
    """(low, high): the effects for which the claim holds, open at both ends (greater: above 0; noninferior: above
    −δ; equivalent: within ±δ; band: inside the band). One run holds the claim when its effect lies inside; an interval
    over seeds holds it when it lies inside, fails it when it lies wholly outside."""
    if c.form == "greater":
        return 0.0, math.inf
    if c.form == "noninferior":
        return -c.margin, math.inf
    if c.form == "band":
        return tuple(c.band)
    return -c.margin, c.margin


def holds(c: Claim, x: float) -> Optional[bool]:
    """the single-run verdict of effect x: True / False, None when x is not finite"""
    if x is None or not np.isfinite(x):
        return None
    lo, hi = region(c)
    return bool(lo < x < hi)


def _drop(x, flat, novel):
    """relative drop flat -> novel along the last axis (environments)"""
    return 1 - np.mean(x[..., novel], axis=-1) / x[..., flat]


def _ti(p, t):
    return p.types.index(t)


def e_fitness(p, d, pr):
    return np.array([p.a["agents"]["fitness_mean"]])


def e_random(p, d, pr):
    return np.array([p.a["agents"]["gen0_mean"]])


def e_alone_severe(p, d, pr):
    a = p.alone(pr)
    return np.array([_drop(a, p.flat, p.novel) - SEVERE])


def e_alone_greatest_drop(p, d, pr):
    T = p.T(d)  # (b, E, T)
    dr = _drop(np.moveaxis(T, 1, 2), p.flat, p.novel)  # (b, T)
    return _drop(p.alone(pr), p.flat, p.novel) - dr.max(axis=1)


def e_wdd_least_drop(p, d, pr):
    T = p.T(d)
    dr = _drop(np.moveaxis(T, 1, 2), p.flat, p.novel)
    i = _ti(p, WD)
    others = np.delete(dr, i, axis=1)
    return others.min(axis=1) - dr[:, i]


def e_untrained_severe(p, d, pr):
    u = p.untrained(d)  # (b, kinds)
    return 1 - u.max(axis=1) / p.a["agents"]["fitness_mean"] - SEVERE


def _beat_alone(p, d, alone):
    T = p.T(d)
    m = np.stack([T[:, p.flat, _ti(p, t)] for t in MATCHED], axis=1)
    return m.min(axis=1) - alone[p.flat]


def e_beat_alone(p, d, pr):
    return _beat_alone(p, d, p.alone(pr))


def e_beat_alone_1000(p, d, pr):
    return _beat_alone(p, d, p.alone("training_length"))


def e_wdd_best_flat(p, d, pr):
    T = p.T(d)
    others = np.stack([T[:, p.flat, _ti(p, t)] for t in MATCHED if t != WD], axis=1)
    return T[:, p.flat, _ti(p, WD)] - others.max(axis=1)


def e_all_drop(p, d, pr):
    T = p.T(d)
    return (T[:, p.flat, :] - T[:, p.novel, :].mean(axis=1)).min(axis=1)


def e_wdd_best_novel(p, d, pr):
    N = p.T(d)[:, p.novel, :].mean(axis=1)  # (b, T)
    i = _ti(p, WD)
    return N[:, i] - np.delete(N, i, axis=1).max(axis=1)


def e_transplant_small_loss(p, d, pr):
    T = p.T(d)
    return T[:, p.flat, _ti(p, "weak_diverse@uniform")] - T[:, p.flat, _ti(p, WD)]


def e_transplant_interaction(p, d, pr):
    T = p.T(d)[:, p.flat, :]
    g = lambda t: T[:, _ti(p, t)]  # noqa: E731
    return (g(WD) - g("weak_diverse@uniform")) - (g("weak_uniform@diverse") - g(WU))


def e_strong_poor(p, d, pr):
    N = p.T(d)[:, p.novel, :].mean(axis=1)
    w = np.stack([N[:, _ti(p, t)] for t in WEAK_TYPES], axis=1).mean(axis=1)
    s = np.stack([N[:, _ti(p, t)] for t in STRONG_TYPES], axis=1).mean(axis=1)
    return w - s


def e_wdd_most_envs(p, d, pr):
    T = p.T(d)[:, p.novel, :]
    i = _ti(p, WD)
    others = np.stack([T[:, :, _ti(p, t)] for t in WEAK_TYPES if t != WD], axis=2).max(axis=2)
    return (T[:, :, i] > others).sum(axis=1) / len(p.novel) - 0.5


def e_wdd_vs_alone_novel(p, d, pr):
    T = p.T(d)
    return T[:, p.novel, _ti(p, WD)].mean(axis=1) - p.alone(pr)[p.novel].mean()


def e_disrupted_more(p, d, pr):
    return p.dtw(WD, "all", d) - p.dtw(WU, "all", d)


def e_worse_altered_more(p, d, pr):
    return np.minimum(p.dtw(WU, "worse", d) - p.dtw(WU, "better", d), p.dtw(WD, "worse", d) - p.dtw(WD, "better", d))


def e_worse_changed_more(p, d, pr):
    return p.dtw(WD, "worse", d) - p.dtw(WU, "worse", d)


def e_better_comparable(p, d, pr):
    return p.dtw(WD, "better", d) - p.dtw(WU, "better", d)


def _fam_share_count(p, d, col, diverse_more):
    fd, fu = p.familiarity(WD, d)[..., col], p.familiarity(WU, d)[..., col]  # (b, E)
    wins = (fd > fu) if diverse_more else (fu > fd)
    return wins.sum(axis=1) / fd.shape[1] - 0.5


def e_more_familiar(p, d, pr):
    return _fam_share_count(p, d, 0, True)


def e_uniform_more_novel_only(p, d, pr):
    return _fam_share_count(p, d, 2, False)


def e_uniform_more_train_only(p, d, pr):
    return _fam_share_count(p, d, 1, False)


def e_wind_unfamiliar(p, d, pr, calibrated=False):
    e = p.a["analysis"]["novel_environments"].index("wind")
    fd, fu = p.familiarity(WD, d, calibrated)[:, e, :], p.familiarity(WU, d, calibrated)[:, e, :]
    return fd[:, 0] / fd.sum(axis=1) - fu[:, 0] / fu.sum(axis=1)


def e_wind_unfamiliar_calibrated(p, d, pr):
    """C24c (amendment A6): C24's effect at the calibrated cell scale"""
    return e_wind_unfamiliar(p, d, pr, calibrated=True)


def e_wind_exclusive_ratio(p, d, pr):
    """C24b (amendment A6): ln(E wu@u / E wd@d), E the wind fit's states in cells holding one source only"""
    e = p.a["analysis"]["novel_environments"].index("wind")
    fd, fu = p.familiarity(WD, d)[:, e, :], p.familiarity(WU, d)[:, e, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log((fu[:, 1] + fu[:, 2]) / (fd[:, 1] + fd[:, 2]))


def e_scaling_grows(p, d, pr):
    s = p.scaling(d)  # (b, S, 2)
    adv = s[:, :, 1] - s[:, :, 0]
    return adv[:, -1] - adv[:, 0]


def e_scaling_better(p, d, pr):
    s = p.scaling(d)
    return (s[:, :, 1] - s[:, :, 0]).mean(axis=1)


def e_generalist_beats_specialist(p, d, pr):
    T = p.T(d)
    envs = p.a["specialists"]["environments"]
    gen = np.stack([T[:, p.envs.index(e), _ti(p, WD)] for e in envs], axis=1)
    return (gen - p.specialists_best(d)).max(axis=1)


def e_graded(p, d, pr):
    T = p.T(d)
    main = T[:, p.novel, _ti(p, WD)].mean(axis=1) - p.alone(pr)[p.novel].mean()
    return main - p.graded_gain("same_shape_springs", d)


# ---- the single-run view: the counts a run needs, and the numbers the report shows beside the effect ---------------

# the counts a claim's single-run value needs before it is judged: (config key, minimum, what it counts). Thresholds sit
# at about half the paper's counts: enough replicates for a mean over connectors, enough pairs for a mean over pairs
# to settle, enough training for the "trained" in a claim to mean trained.
N_AGENTS = (("agents.population", 50, "agents"), ("agents.generations", 10, "generations"))
N_TRAINED = (("connectors.replicates", 5, "connector replicates"), ("connectors.iterations", 50, "training iterations"),
             ("connectors.batch_pairs", 50, "pairs per batch"))
N_DEPLOY = N_AGENTS + N_TRAINED + (("deploy.pairs", 50, "deployed pairs"),)
N_NOVEL = N_DEPLOY + (("deploy.environments", 7, "environments"),)
N_UNTRAINED = N_AGENTS + (("connectors.batch_pairs", 50, "pairs per batch"),)
N_SPECIALISTS = N_NOVEL + (("specialists.replicates", 5, "specialists per environment"),
                           ("specialists.iterations", 50, "specialist iterations"))
N_SCALING = N_DEPLOY + (("scaling.chains", 100, "chains per size and variant (replicates × draws)"),
                        ("scaling.n_sizes", 3, "chain sizes"))
N_GRADED = N_NOVEL + (("graded.population", 50, "agents per graded population"),)
N_ANALYSIS = N_DEPLOY + (("analysis.max_states", 5000, "hidden states per PaCMAP fit"),)

# the episodes a claim's row links (report_episodes.py): types by name or one of these selectors
EPISODE_TYPES = {"named": "the types the row's numbers name", "matched": "the four kinds deployed as trained",
                 "weak": "the four weak types", "all": "every type", "pair": "weak_uniform@uniform, weak_diverse@diverse"}
NOT_EXPORTED_DTW = ("each tethered agent is compared with its own episode alone (`--what alone --agent I`); the pairs:",
                    False, "pair", "all")


def f3(x):
    return "—" if x is None or not np.isfinite(x) else f"{x:.2f}"


def g3(x):
    return "—" if x is None or not np.isfinite(x) else f"{x:.3g}"


def _one(p):
    """(E, T) travel per environment and type, mean over the run's connectors"""
    return p.T(None)[0]


def _novel(p, x):
    return float(np.mean(np.asarray(x)[p.novel]))


def _drops(p, pr):
    T, a = _one(p), p.alone(pr)
    out = {"agents alone": 1 - _novel(p, a) / a[p.flat]}
    for i, t in enumerate(p.types):
        out[t] = 1 - _novel(p, T[:, i]) / T[p.flat, i]
    return out


def d_fitness(p, pr):
    a = p.a["agents"]
    sd = a.get("fitness_sd")
    return f"final population {f3(a['fitness_mean'])}" + (f" ± {f3(sd)}" if sd is not None else "") + " BL"


def d_random(p, pr):
    return f"random untrained (generation 0 before any gradient step) {f3(p.a['agents'].get('gen0_mean', np.nan))} BL"


def d_alone_drop(p, pr):
    return f"relative drop flat → novel of agents alone {_drops(p, pr)['agents alone']:.0%} (severe: more than 25%)"


def d_greatest_drop(p, pr):
    dr = _drops(p, pr)
    worst = max(dr, key=dr.get)
    return f"relative drop flat → novel: agents alone {dr['agents alone']:.0%}; largest: {worst} {dr[worst]:.0%}"


def d_least_drop(p, pr):
    dr = _drops(p, pr)
    del dr["agents alone"]
    least = min((t for t in dr if t != WD), key=dr.get)
    return f"relative drop flat → novel: {WD} {dr[WD]:.0%}; least of the other types: {least} {dr[least]:.0%}"


def d_untrained(p, pr):
    u = p.untrained(None)[0]
    kinds = list(p.a["connectors"]["untrained_bl"])
    return (", ".join(f"{k} {f3(v)}" for k, v in zip(kinds, u)) + " BL (batch mean before the first step) vs agents "
            f"alone {f3(p.a['agents']['fitness_mean'])} BL (1000 steps)")


def _d_beat(p, alone, what):
    T = _one(p)
    return ", ".join(f"{t} {f3(T[p.flat, _ti(p, t)])}" for t in MATCHED) + f" vs agents alone {f3(alone[p.flat])} BL {what}"


def d_beat_alone(p, pr):
    return _d_beat(p, p.alone(pr), "on flat")


def d_beat_alone_1000(p, pr):
    return _d_beat(p, p.alone("training_length"), "on flat at 1000 steps")


def d_best_flat(p, pr):
    T = _one(p)
    best = max(MATCHED, key=lambda t: T[p.flat, _ti(p, t)])
    return f"best on flat: {best} ({f3(T[p.flat, _ti(p, best)])} BL)"


def d_all_drop(p, pr):
    T = _one(p)
    worse = [t for i, t in enumerate(p.types) if _novel(p, T[:, i]) < T[p.flat, i]]
    return f"{len(worse)} of {len(p.types)} types travel less in the novel environments"


def d_best_novel(p, pr):
    T = _one(p)
    best = max(p.types, key=lambda t: _novel(p, T[:, _ti(p, t)]))
    return (f"best across the novel environments: {best} ({f3(_novel(p, T[:, _ti(p, best)]))} BL); {WD} "
            f"{f3(_novel(p, T[:, _ti(p, WD)]))}, agents alone {f3(_novel(p, p.alone(pr)))}")


def d_transplant(p, pr):
    T = _one(p)[p.flat]
    g = lambda t: f3(T[_ti(p, t)])  # noqa: E731
    return (f"flat: weak diverse-trained on diverse {g(WD)} / on clones {g('weak_diverse@uniform')}; weak "
            f"uniform-trained on clones {g(WU)} / on diverse {g('weak_uniform@diverse')} BL")


def d_strong(p, pr):
    T = _one(p)
    n = lambda ts: np.mean([_novel(p, T[:, _ti(p, t)]) for t in ts])  # noqa: E731
    return f"novel mean over the weak types {f3(n(WEAK_TYPES))} BL, over the strong types {f3(n(STRONG_TYPES))} BL"


def d_most_envs(p, pr):
    T, a = _one(p), p.alone(pr)
    wins = sum(1 for e in p.novel if max(WEAK_TYPES, key=lambda t: T[e, _ti(p, t)]) == WD)
    beats = sum(1 for e in p.novel if T[e, _ti(p, WD)] > a[e])
    return (f"{WD} best of the weak types in {wins} of {len(p.novel)} novel environments, above agents alone in "
            f"{beats}")


def d_vs_alone_novel(p, pr):
    return (f"novel mean: {WD} {f3(_novel(p, _one(p)[:, _ti(p, WD)]))} BL, agents alone "
            f"{f3(_novel(p, p.alone(pr)))} BL")


def _welch(p, which):
    from ..analysis import stars, welch
    a = p.a["analysis"]["dtw"]
    pv = welch(a[WU][which], a[WD][which])[2]
    return f"Welch p = {g3(pv)} ({stars(pv)})"


def d_disrupted(p, pr):
    return (f"mean DTW per step, all agents: diverse-trained {g3(p.dtw(WD, 'all')[0])} u, uniform-trained "
            f"{g3(p.dtw(WU, 'all')[0])} u ({_welch(p, 'all')})")


def d_worse_better(p, pr):
    return "; ".join(f"{'diverse' if t == WD else 'uniform'}-trained: worse {g3(p.dtw(t, 'worse')[0])} u, better "
                     f"{g3(p.dtw(t, 'better')[0])} u" for t in (WU, WD))


def _d_dtw(which):
    def d(p, pr):
        return (f"{which} agents: diverse-trained {g3(p.dtw(WD, which)[0])} u vs uniform-trained "
                f"{g3(p.dtw(WU, which)[0])} u, {_welch(p, which)}")
    return d


def _d_fam(col, what, diverse_more):
    def d(p, pr):
        fd, fu = p.familiarity(WD)[0][:, col], p.familiarity(WU)[0][:, col]
        wins = (fd > fu) if diverse_more else (fu > fd)
        who = "diverse" if diverse_more else "uniform"
        return f"more {what} for the {who}-trained connector in {int(wins.sum())} of {len(fd)} novel environments"
    return d


def d_wind(p, pr):
    if "wind" not in p.a["analysis"]["novel_environments"]:
        raise KeyError("no wind environment in the familiarity results")
    e = p.a["analysis"]["novel_environments"].index("wind")
    fd, fu = p.familiarity(WD)[0][e], p.familiarity(WU)[0][e]
    return (f"wind, mean states: in both: diverse-trained {fd[0]:.1f}, uniform-trained {fu[0]:.1f}; unique to training "
            f"or wind: diverse-trained {fd[1] + fd[2]:.1f}, uniform-trained {fu[1] + fu[2]:.1f}")


def d_wind_calibrated(p, pr):
    e = p.a["analysis"]["novel_environments"].index("wind")
    fd, fu = p.familiarity(WD, None, True)[0][e], p.familiarity(WU, None, True)[0][e]
    return (f"wind at cell scale {p.a['analysis']['calibrated_cell_scale']:g}, share of states in shared cells: "
            f"diverse-trained {fd[0] / fd.sum():.3f}, uniform-trained {fu[0] / fu.sum():.3f}")


def d_scaling(p, pr):
    s = p.scaling(None)[0]
    return "; ".join(f"N={n}: diverse − uniform {s[i, 1] - s[i, 0]:+.2f} BL" for i, n in
                     enumerate(p.a["scaling"]["sizes"]))


def d_specialists(p, pr):
    T, envs = _one(p), p.a["specialists"]["environments"]
    best = p.specialists_best(None)[0]
    better = [e for e, s in zip(envs, best) if T[p.envs.index(e), _ti(p, WD)] > s]
    return (f"the generalist beats the best specialist in {len(better)} of {len(envs)} environments"
            + (f" ({', '.join(better)})" if better else ""))


def d_graded(p, pr):
    main = _novel(p, _one(p)[:, _ti(p, WD)]) - _novel(p, p.alone(pr))
    rows = [("main", main)] + [(pop, float(p.graded_gain(pop)[0])) for pop in p.a["graded"]["populations"]]
    return "; ".join(f"{n}: pairs − alone {g:+.2f} BL" for n, g in rows)


BL, DROP, U, ENV, SHARE = 0.5, 0.05, 0.005, 1 / 12, 0.02

CLAIMS: List[Claim] = [
    Claim("C01", "M", "Trained agents travel almost 4 BL on flat", "Results, Component training", "almost four",
          "mean 1000-step travel of the final population", "band", 0.0, "BL", ("agents",), e_fitness, band=(3.0, 4.0),
          counts=N_AGENTS, describe=d_fitness,
          episodes=("agents-stage training episodes are not exported; the deployment alone on flat:", True, (), "flat")),
    Claim("C02", "M", "Random agents travel about 0 BL", "Results, Component training", "averaged zero",
          "mean 1000-step travel of generation 0 before any gradient step", "equivalent", BL, "BL", ("agents",),
          e_random,
          counts=N_AGENTS, describe=d_random,
          episodes=("generation 0's training episodes are not exported", False, (), "none")),
    Claim("C03", "M", "Deployed alone, agents are severely compromised in the novel environments",
          "Results, Component training", "about 4 → just over 2 BL", "drop(A) − 0.25", "greater", DROP, "",
          ("deploy",), e_alone_severe, reads_alone=True,
          counts=N_NOVEL, describe=d_alone_drop,
          episodes=("", True, (), "all")),
    Claim("C04", "M", "Independent agents suffer the greatest average decrease in the novel environments",
          "Results", "Fig. 2A", "drop(A) − max over the 8 types of drop(T)", "greater", DROP, "", ("deploy",),
          e_alone_greatest_drop, reads_alone=True,
          counts=N_NOVEL, describe=d_greatest_drop,
          episodes=("", True, "named", "all")),
    Claim("C05", "M", "Weak diverse-trained connectors on diverse pairs suffer the least decrease", "Results",
          "Fig. 2A", "min over the other 7 types of drop(T) − drop(T wd@d)", "greater", DROP, "", ("deploy",),
          e_wdd_least_drop,
          counts=N_NOVEL, describe=d_least_drop,
          episodes=("", False, "named", "all")),
    Claim("C06", "M", "Untrained connectors cause a severe drop in behaviour", "Results, Connector training",
          "severe (not shown)", "1 − max over kinds of untrained batch travel / agents' 1000-step travel − 0.25",
          "greater", DROP, "", ("agents", "connectors"), e_untrained_severe,
          counts=N_UNTRAINED, describe=d_untrained,
          episodes=("connector-training batches are not exported", False, (), "none")),
    Claim("C07", "M", "Trained collectives of all four kinds travel further than independent agents (flat, same "
          "episode length)", "Results, Connector training", "Fig. 2A", "min over matched types of T(flat) − A(flat)",
          "greater", BL, "BL", ("deploy",), e_beat_alone, reads_alone=True,
          counts=N_DEPLOY, describe=d_beat_alone,
          episodes=("", True, "matched", "flat")),
    Claim("C08", "M", "The same, with agents alone at their training length (1000 steps)",
          "Results, Connector training", "Fig. 2A", "min over matched types of T(flat) − A1000(flat)", "greater", BL,
          "BL", ("deploy",), e_beat_alone_1000,
          counts=N_DEPLOY, describe=d_beat_alone_1000,
          episodes=("agents alone at 1000 steps are the same episodes, read at deploy.early_step:", True, "matched", "flat")),
    Claim("C09", "M", "Weak diverse collectives achieve the best performance on flat", "Results, Connector training",
          "Fig. 2A", "T wd@d(flat) − max over the other matched types", "greater", BL, "BL", ("deploy",),
          e_wdd_best_flat,
          counts=N_DEPLOY, describe=d_best_flat,
          episodes=("", False, "matched", "flat")),
    Claim("C10", "M", "Every collective type travels less in the novel environments", "Results, Collective deployment",
          "Fig. 2A", "min over the 8 types of T(flat) − N(T)", "greater", BL, "BL", ("deploy",), e_all_drop,
          counts=N_NOVEL, describe=d_all_drop,
          episodes=("", False, "all", "all")),
    Claim("C11", "M", "Weak diverse collectives fare best across the novel environments",
          "Results, Collective deployment", "Fig. 2A", "N(T wd@d) − max over the other 7 types", "greater", BL, "BL",
          ("deploy",), e_wdd_best_novel,
          counts=N_NOVEL, describe=d_best_novel,
          episodes=("", True, "named", "novel")),
    Claim("C12", "M", "Transplanted onto clones, diverse-trained weak connectors lose only a little", "Fig. 2B",
          "Fig. 2B", "T wd@u(flat) − T wd@d(flat)", "noninferior", BL, "BL", ("deploy",), e_transplant_small_loss,
          counts=N_DEPLOY, describe=d_transplant,
          episodes=("", False, "weak", "flat")),
    Claim("C13", "M", "Diverse-trained connectors exploit diversity, uniform-trained ones cannot (kind × deployment)",
          "Fig. 2B", "Fig. 2B", "[T wd@d − T wd@u] − [T wu@d − T wu@u] (flat)", "greater", BL, "BL", ("deploy",),
          e_transplant_interaction,
          counts=N_DEPLOY, describe=d_transplant,
          episodes=("", False, "weak", "flat")),
    Claim("C14", "M", "Strong connectors deploy poorly (why Figs 2C-N drop them)", "Results, Collective deployment",
          "Fig. 2A", "mean of N(T) over weak types − over strong types", "greater", BL, "BL", ("deploy",),
          e_strong_poor,
          counts=N_NOVEL, describe=d_strong,
          episodes=("", False, "all", "novel")),
    Claim("C15", "M", "In most novel environments weak diverse collectives fare best of the weak types", "Figs 2C-N",
          "most", "#(wd@d best of the weak types)/12 − 1/2", "greater", ENV, "", ("deploy",), e_wdd_most_envs,
          counts=N_NOVEL, describe=d_most_envs,
          episodes=("", False, "weak", "novel")),
    Claim("C16", "M", "They fare much better than independent agents in those environments", "Figs 2C-N",
          "Figs 2C-N", "N(T wd@d − A)", "greater", BL, "BL", ("deploy",), e_wdd_vs_alone_novel, reads_alone=True,
          counts=N_NOVEL, describe=d_vs_alone_novel,
          episodes=("", True, (WD,), "novel")),
    Claim("C17", "M", "Tethered agents in diverse collectives are disrupted more than clones in uniform ones",
          "Fig. 3A", "Fig. 3A", "D wd@d(all) − D wu@u(all)", "greater", U, "u", ("analysis",), e_disrupted_more,
          counts=N_ANALYSIS, describe=d_disrupted,
          episodes=NOT_EXPORTED_DTW),
    Claim("C18", "M", "Worse agents are altered more than better ones, for both connector types", "Fig. 3A", "Fig. 3A",
          "min over wu@u, wd@d of D(worse) − D(better)", "greater", U, "u", ("analysis",), e_worse_altered_more,
          counts=N_ANALYSIS, describe=d_worse_better,
          episodes=NOT_EXPORTED_DTW),
    Claim("C19", "M", "Diverse-trained connectors change the worse agent more than uniform-trained ones", "Fig. 3A",
          "p < 0.001", "D wd@d(worse) − D wu@u(worse)", "greater", U, "u", ("analysis",), e_worse_changed_more,
          counts=N_ANALYSIS, describe=_d_dtw("worse"),
          episodes=NOT_EXPORTED_DTW),
    Claim("C20", "M", "Their effect on the better agents is comparable", "Fig. 3A", "same mild impact",
          "D wd@d(better) − D wu@u(better)", "equivalent", U, "u", ("analysis",), e_better_comparable,
          counts=N_ANALYSIS, describe=_d_dtw("better"),
          episodes=NOT_EXPORTED_DTW),
    Claim("C21", "M", "Novel environments feel more familiar to diverse-trained connectors (more states in shared "
          "cells)", "Table S1", "9 of 12", "#(F wd@d(both) > F wu@u(both))/12 − 1/2", "greater", ENV, "",
          ("analysis",), e_more_familiar,
          counts=N_ANALYSIS, describe=_d_fam(0, "states in shared cells", True),
          episodes=("", False, "pair", "all")),
    Claim("C22", "M", "Uniform-trained connectors meet more states exclusive to the novel environment", "Table S1",
          "9 of 12", "#(F wu@u(novel-only) > F wd@d(novel-only))/12 − 1/2", "greater", ENV, "", ("analysis",),
          e_uniform_more_novel_only,
          counts=N_ANALYSIS, describe=_d_fam(2, "novel-only states", False),
          episodes=("", False, "pair", "all")),
    Claim("C23", "M", "Uniform-trained connectors meet more states exclusive to training", "Table S1", "7 of 12",
          "#(F wu@u(train-only) > F wd@d(train-only))/12 − 1/2", "greater", ENV, "", ("analysis",),
          e_uniform_more_train_only,
          counts=N_ANALYSIS, describe=_d_fam(1, "training-only states", False),
          episodes=("", False, "pair", "all")),
    Claim("C24", "M", "Wind feels more unfamiliar to the uniform-trained connector", "Fig. 3B-C",
          "158,118 vs 131,303 in both", "share of wind's fit in shared cells, wd@d − wu@u", "greater", SHARE, "",
          ("analysis",), e_wind_unfamiliar,
          counts=N_ANALYSIS, describe=d_wind,
          episodes=("", False, "pair", "wind")),
    # amendment A6: judged in a family of its own, so that family M's Holm adjustments stay as registered
    Claim("C24b", "A6", "Wind meets more exclusive states with the uniform-trained connector (scale-free)",
          "Fig. 3B-C", "ratio ≈ 1.64", "ln(exclusive states of wind's fit, wu@u / wd@d)", "greater", math.log(1.1),
          "", ("analysis",), e_wind_exclusive_ratio,
          counts=N_ANALYSIS, describe=d_wind,
          episodes=("", False, "pair", "wind")),
    Claim("C24c", "A6", "Wind feels more unfamiliar to the uniform-trained connector (calibrated cells)",
          "Fig. 3B-C", "158,118 vs 131,303 in both",
          "share of wind's fit in shared cells at the calibrated cell scale, wd@d − wu@u", "greater", SHARE, "",
          ("analysis",), e_wind_unfamiliar_calibrated,
          counts=N_ANALYSIS, describe=d_wind_calibrated,
          episodes=("", False, "pair", "wind")),
    Claim("C25", "S", "The advantage of diversity grows with collective size", "Fig. 4", "Fig. 4",
          "adv(20) − adv(5), adv = N(diverse chains) − N(uniform chains)", "greater", BL, "BL", ("scaling",),
          e_scaling_grows,
          counts=N_SCALING, describe=d_scaling,
          episodes=("", False, (), "chains")),
    Claim("C26", "S", "Diverse-trained connectors adapt better than uniform-trained ones in larger collectives",
          "Fig. 4", "Fig. 4", "mean over sizes of adv", "greater", BL, "BL", ("scaling",), e_scaling_better,
          counts=N_SCALING, describe=d_scaling,
          episodes=("", False, (), "chains")),
    Claim("C27", "S", "Generalists sometimes beat specialists trained in the environment", "Results; Fig. S2",
          "in some cases", "max over novel e of T wd@d(e) − best specialist(e)", "greater", BL, "BL",
          ("deploy", "specialists"), e_generalist_beats_specialist,
          counts=N_SPECIALISTS, describe=d_specialists,
          episodes=("", False, (WD,), "specialists")),
    Claim("C28", "S", "More sources of diversity give more resilience", "Fig. S3", "Fig. S3",
          "g(all sources) − g(same shape and springs), g = N(pairs) − N(alone)", "greater", BL, "BL",
          ("deploy", "graded"), e_graded, reads_alone=True,
          counts=N_GRADED, describe=d_graded,
          episodes=("graded-stage episodes are not exported; the main population's:", True, (WD,), "novel")),
]
BY_ID = {c.id: c for c in CLAIMS}


# ---- the estimator ------------------------------------------------------------------------------------------------

@dataclasses.dataclass
class Result:
    claim: Claim
    n: int
    estimate: float = float("nan")
    lo: float = float("nan")
    hi: float = float("nan")
    t_lo: float = float("nan")
    t_hi: float = float("nan")
    se: float = float("nan")
    per_population: Dict = dataclasses.field(default_factory=dict)
    p_support: float = float("nan")
    p_contra: float = float("nan")
    p_support_holm: float = float("nan")
    p_contra_holm: float = float("nan")
    verdict: str = "not measured"
    power: float = float("nan")
    n80: float = float("nan")
    reason: str = ""


def _p_above(est, se, df, c):
    """one-sided p of 'θ > c is shown': Student t with df degrees of freedom on (est − c) / se"""
    from scipy.stats import t as tdist
    if not se > 0:
        return 0.0 if est > c else 1.0
    return float(tdist.sf((est - c) / se, df))


def _p_below(est, se, df, c):
    return _p_above(-est, se, df, -c)


def hypotheses(form, margin, band, est, se, df):
    """(p of the supporting hypothesis, p of the contradicting one) for estimate est with standard error se"""
    up = lambda c: _p_above(est, se, df, c)  # noqa: E731
    down = lambda c: _p_below(est, se, df, c)  # noqa: E731
    if form == "greater":
        return up(0.0), down(margin)
    if form == "noninferior":
        return up(-margin), down(-margin)
    a, b = band if form == "band" else (-margin, margin)
    return max(up(a), down(b)), min(1.0, 2 * min(up(b), down(a)))


def holm(ps: Sequence[float]) -> np.ndarray:
    """Holm-adjusted p-values (NaN stay NaN and do not count)"""
    ps = np.asarray(ps, float)
    out = np.full(ps.shape, np.nan)
    idx = [i for i in np.argsort(ps, kind="stable") if np.isfinite(ps[i])]
    m, run = len(idx), 0.0
    for k, i in enumerate(idx):
        run = max(run, min(1.0, (m - k) * ps[i]))
        out[i] = run
    return out


def power_at_edge(form, margin, band, se, n, level):
    """(power of the supporting hypothesis at the claim's edge, populations for 80%): the estimate taken as
    Student t on n − 1 degrees of freedom around the edge with the bootstrap's standard error, which shrinks as
    1/√n with more populations; test at `level` (Holm's smallest)"""
    from scipy.stats import t as tdist
    if not (np.isfinite(se) and se > 0 and n >= 2):
        return float("nan"), float("nan")
    h = margin if form in ("greater", "noninferior") else (band[1] - band[0]) / 2 if form == "band" else margin

    def power(m):
        s_m = se * math.sqrt(n / m)
        crit = tdist.ppf(1 - level, m - 1)
        one = float(tdist.sf(crit - h / s_m, m - 1))
        return one if form in ("greater", "noninferior") else max(0.0, 2 * one - 1)
    n80 = next((m for m in range(2, 10001) if power(m) >= 0.8), float("nan"))
    return power(n), float(n80)


def bootstrap(pops: Sequence[Population], fn, protocol="same_length", B=B_DEFAULT, seed=BOOT_SEED):
    """(per-population effects at all connectors, B resampled means): populations with replacement, inside each
    its connectors (per unit) with replacement"""
    n = len(pops)
    point = np.array([float(fn(p, None, protocol)[0]) for p in pops])
    rng = np.random.Generator(np.random.PCG64(seed))
    pick = rng.integers(0, n, size=(B, n))
    theta = np.zeros((B, n))
    for j in range(n):
        for i, p in enumerate(pops):
            rows = np.nonzero(pick[:, j] == i)[0]
            if rows.size == 0:
                continue
            vals = np.asarray(fn(p, p.draws(rng, rows.size), protocol), float)
            theta[rows, j] = np.broadcast_to(vals, (rows.size,))
    return point, theta.mean(axis=1)


def _t975(n):
    from scipy.stats import t as tdist
    return float(tdist.ppf(0.975, n - 1))


def interval(point, th, spread="iqr"):
    """(estimate, standard error, 95% low, high) of the mean of the per-population effects `point` from the
    bootstrap's resampled means `th`: the spread of the resamples as their interquartile range / 1.349 (the
    normal's sd, so that the rare resamples where a ratio's denominator nears 0 do not set it; amendment A4),
    corrected for the bootstrap's (n − 1)/n shrinkage of a mean's variance, with Student t quantiles on n − 1
    degrees of freedom (protocol §3, amendment A2)"""
    n = len(point)
    est = float(np.mean(point))
    if spread == "sd":  # the rule before amendment A4: the resamples' standard deviation
        se = float(np.std(th, ddof=1) * math.sqrt(n / (n - 1)))
    else:
        q25, q75 = np.quantile(th, [0.25, 0.75])
        se = float((q75 - q25) / 1.349 * math.sqrt(n / (n - 1)))
    q = _t975(n)
    return est, se, est - q * se, est + q * se


def judge(pops: Sequence[Population], claims: Sequence[Claim], protocol="same_length", B=B_DEFAULT,
          seed=BOOT_SEED, alpha=ALPHA, spread="iqr") -> List[Result]:
    """every claim of one family over the populations that have its stages; Holm over the family's hypotheses.
    spread: the bootstrap spread rule of the standard error (iqr, the registered one since A4; sd, the one before)"""
    results = []
    for k, c in enumerate(claims):
        ps = [p for p in pops if all(p.has(s) for s in c.needs)]
        r = Result(c, len(ps))
        if len(ps) < 2:
            r.reason = f"{len(ps)} population(s) with {', '.join(c.needs)}"
            try:
                r.per_population = {p.seed: float(c.effect(p, None, protocol)[0]) for p in ps}
            except (KeyError, ValueError, IndexError) as e:
                r.reason = f"the runs lack {e}"
            if r.per_population:
                r.estimate = float(np.mean(list(r.per_population.values())))
                r.verdict = "too few populations"
            results.append(r)
            continue
        try:
            point, th = bootstrap(ps, c.effect, protocol, B, seed + k)
        except (KeyError, ValueError, IndexError) as e:
            r.reason = f"the runs lack {e}"
            results.append(r)
            continue
        n = len(ps)
        r.per_population = {p.seed: float(v) for p, v in zip(ps, point)}
        r.estimate, r.se, r.lo, r.hi = interval(point, th, spread)
        half = _t975(n) * np.std(point, ddof=1) / math.sqrt(n)
        r.t_lo, r.t_hi = r.estimate - half, r.estimate + half
        r.p_support, r.p_contra = hypotheses(c.form, c.margin, c.band, r.estimate, r.se, n - 1)
        results.append(r)
    measured = [r for r in results if np.isfinite(r.p_support)]
    H = 2 * len(measured)
    adj = holm([x for r in measured for x in (r.p_support, r.p_contra)])
    for i, r in enumerate(measured):
        r.p_support_holm, r.p_contra_holm = float(adj[2 * i]), float(adj[2 * i + 1])
        sup, con = r.p_support_holm <= alpha, r.p_contra_holm <= alpha
        eq = r.claim.form == "equivalent"
        if sup and con:
            r.verdict = "contradicted (negligible)"
        elif sup:
            r.verdict = "equivalent" if eq else "supported"
        elif con:
            r.verdict = "contradicted"
        else:
            r.verdict = "inconclusive"
            r.power, r.n80 = power_at_edge(r.claim.form, r.claim.margin, r.claim.band, r.se, r.n, alpha / H)
    return results


def population_from_summary(path: str) -> Population:
    """a population read from a run summary (`*.summary.json`, robustness.py) alone: its Fig. 2A means per
    environment, every connector of a type pooled into one mean. Only the claims that read deploy's travel can be
    computed, and without the connector level (each population's connector mean is fixed in the bootstrap)."""
    with open(path) as fh:
        s = json.load(fh)
    fig = s["fig2a"]
    cfg = s.get("config", {})
    coll = np.array([[fig["collectives"][t] for t in fig["types"]]]).transpose(2, 1, 0)  # (E, T, 1)
    dep = {"environments": fig["environments"], "types": fig["types"], "alone_bl": fig["alone"]["as_run"],
           "collectives_bl": coll.tolist()}
    if "training_length" in fig["alone"]:
        dep["alone_bl_early"] = fig["alone"]["training_length"]
    a = {"seed": cfg.get("run", {}).get("seed"), "git_commit": s.get("git_commit", ""), "deploy": dep,
         "episode_steps": {"connectors": cfg.get("connectors", {}).get("episode_steps"),
                           "deploy": cfg.get("deploy", {}).get("episode_steps")}}
    return Population(a["seed"], [a])


# ---- a study folder -----------------------------------------------------------------------------------------------

def load_study(folder: str, variants: Sequence[str]) -> List[Population]:
    """the populations of a study folder: per seed, the arrays of the runs of `variants` (in order) merged"""
    with open(os.path.join(folder, "study.toml"), "rb") as fh:
        man = tomllib.load(fh)
    by_seed: Dict[int, List[dict]] = {}
    for v in variants:
        for r in man["run"]:
            if r["variant"] != v:
                continue
            path = arrays_path(os.path.join(folder, r["path"]))
            if os.path.exists(path):
                by_seed.setdefault(r["seed"], []).append(read_arrays(path))
    return [Population(seed, parts) for seed, parts in sorted(by_seed.items())]
