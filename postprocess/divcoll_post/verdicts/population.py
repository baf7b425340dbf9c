"""One agent population's arrays, batched over connector draws, and where populations come from: a study folder's
kept arrays (`load_study`) or a run summary alone (`population_from_summary`).
"""

from __future__ import annotations

import json
import os
import tomllib
from typing import Dict, List, Sequence

import numpy as np

from .arrays import arrays_path, read_arrays


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
