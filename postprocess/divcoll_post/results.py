"""Read-only access to the experiment stages of a divcoll run file, and the statistics the figures use.

Used by fig2.py, fig4.py, fig_s2.py and fig_s3.py. Layout read here (mpi/README.md "Run-file layout"; a dataset
that names its axes, as every one the run-file schema writes does, must name the ones below, and
environment / type lists come from the groups' attributes):

    /deploy        attributes environments (flat first), types, envs_done, status
                   agents/{travel_bl,status} (E × P); collectives/{travel_bl,status} (E × T × R × NP)
    /scaling       attributes environments, envs_done, status; sizes (S)
                   travel_bl, status (E × S × 2 × R × draws), variant 0 uniform, 1 diverse
    /specialists   attributes environments (the novel ones), status; travel_bl, status (E_novel × R_s × NP)
    /graded        attributes environments, populations, status; per population <p>/ (attributes status,
                   diversity_sources): deploy/agents/{travel_bl,status} (E × P_g),
                   deploy/pairs/{travel_bl,status} (E × R × NP)

Statistics (SPEC §8.3). Only ok episodes enter a mean: status == 0 and a finite travel. Episodes that
ended nan / unstable are counted (n_bad) and never averaged. Error bars:

- `bootstrap_ci`: percentile bootstrap 95% CI of the mean over episodes, B = 1000 resamples, fixed seed
  (BOOT_SEED), so the same numbers always give the same bars.
- a mean over several environments is the mean of the per-environment means (every environment weighs
  the same); its CI is a stratified bootstrap: episodes are resampled within each environment, the
  resampled environment means are averaged, and the 2.5 / 97.5 percentiles of those averages are taken.
- `sem`: standard error of the mean over episodes (sample sd / sqrt(n)), for the figures whose caption
  asks for it (Fig. S2).

A stage that is missing (or has no finished environment) raises StageMissing, a RunFileError whose
message reads like "run file has no scaling stage (run the scaling stage first)"; the scripts print it
and exit with status 2.
"""

from __future__ import annotations

import dataclasses
import os
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from .reader import (RunFileError, StageMissing, dataset, envs_done, labelled, list_attr, open_file,  # noqa: F401
                     require_stage, text)
from .reader import open as open_run
from .runfile import RunMeta, _meta

BOOT_RESAMPLES = 1000
BOOT_SEED = 0
CI_LEVEL = 0.95
FLAT = "flat"

# what a deployment type means, for legends: "<kind>@<deployed on>"
KIND_LABEL = {
    "weak_uniform": "weak, uniform-trained",
    "weak_diverse": "weak, diverse-trained",
    "strong_uniform": "strong, uniform-trained",
    "strong_diverse": "strong, diverse-trained",
}


# ---------------------------------------------------------------------------------------------------
# statistics


def code_version() -> str:
    """the commit of this postprocessing code ("<commit>-dirty" when postprocess/ has uncommitted changes; the
    pages and figures a script has just written elsewhere do not count), or "unknown" outside a git checkout"""
    import subprocess
    here = os.path.dirname(os.path.abspath(__file__))
    code = [os.path.dirname(here) + "/" + p for p in ("divcoll_post", "*.py")]
    try:
        commit = subprocess.run(["git", "-C", here, "rev-parse", "--short=12", "HEAD"], capture_output=True,
                                text=True, timeout=30).stdout.strip()
        changed = subprocess.run(["git", "-C", here, "status", "--porcelain", "--"] + code, capture_output=True,
                                 text=True, timeout=30).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return (commit + ("-dirty" if changed else "")) if commit else "unknown"


def ok_values(travel, status) -> np.ndarray:
    """1-D array of the travels of the ok episodes (status == 0 and finite travel), in storage order."""
    travel = np.asarray(travel, dtype=float)
    status = np.asarray(status)
    if travel.shape != status.shape:
        raise ValueError(f"travel {travel.shape} and status {status.shape} differ in shape")
    ok = (status == 0) & np.isfinite(travel)
    return travel[ok].ravel()


def n_not_ok(travel, status) -> int:
    travel = np.asarray(travel, dtype=float)
    return int(((np.asarray(status) != 0) | ~np.isfinite(travel)).sum())


def ok_mean(travel, status) -> Tuple[float, int]:
    """(mean over ok episodes, count of not-ok episodes); the mean is NaN when no episode is ok."""
    v = ok_values(travel, status)
    return (float(v.mean()) if v.size else float("nan")), n_not_ok(travel, status)


def ok_means(travel, status, axis):
    """(mean over `axis` of the ok entries (status 0, finite travel), NaN where none; the ok counts): the ok mean of
    every cell of an array at once (e.g. axis 3 of deploy's (env, type, replicate, pair) collectives)"""
    travel = np.asarray(travel, float)
    ok = (np.asarray(status) == 0) & np.isfinite(travel)
    n = ok.sum(axis=axis)
    s = np.where(ok, travel, 0.0).sum(axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, s / np.maximum(n, 1), np.nan), n


def env_means(travel, status) -> Tuple[np.ndarray, int]:
    """(ok mean of each environment of arrays shaped (E, ...), count of not-ok episodes over all of them)"""
    out, bad = [], 0
    for e in range(np.shape(travel)[0]):
        m, b = ok_mean(travel[e], status[e])
        out.append(m)
        bad += b
    return np.array(out), bad


def sem(values) -> float:
    """Standard error of the mean (sample sd / sqrt(n)); 0 for one value, NaN for none."""
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 0:
        return float("nan")
    if v.size == 1:
        return 0.0
    return float(v.std(ddof=1) / np.sqrt(v.size))


def _boot_means(values: np.ndarray, rng: np.random.Generator, n_boot: int) -> np.ndarray:
    n = values.size
    out = np.empty(n_boot)
    chunk = max(1, int(4_000_000 // max(n, 1)))  # keep the index matrix small at paper scale
    for s in range(0, n_boot, chunk):
        b = min(chunk, n_boot - s)
        idx = rng.integers(0, n, size=(b, n))
        out[s:s + b] = values[idx].mean(axis=1)
    return out


def bootstrap_ci(values, n_boot: int = BOOT_RESAMPLES, seed: int = BOOT_SEED,
                 level: float = CI_LEVEL) -> Tuple[float, float]:
    """Percentile bootstrap CI of the mean of `values` (already the ok episodes). (nan, nan) for none;
    (v, v) for one value."""
    return stratified_bootstrap_ci([values], n_boot=n_boot, seed=seed, level=level)


def stratified_bootstrap_ci(groups: Sequence, n_boot: int = BOOT_RESAMPLES, seed: int = BOOT_SEED,
                            level: float = CI_LEVEL) -> Tuple[float, float]:
    """Percentile bootstrap CI of the mean of the group means, resampling within each group.
    A group with no values makes the statistic undefined: (nan, nan)."""
    groups = [np.asarray(g, dtype=float).ravel() for g in groups]
    if not groups or any(g.size == 0 for g in groups):
        return float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    acc = np.zeros(n_boot)
    for g in groups:
        acc += _boot_means(g, rng, n_boot)
    acc /= len(groups)
    a = (1.0 - level) / 2.0
    lo, hi = np.percentile(acc, [100 * a, 100 * (1 - a)])
    return float(lo), float(hi)


@dataclasses.dataclass
class Stat:
    """One bar or point: the mean (of environment means, when pooled over environments), its error bar
    [lo, hi], the ok episodes behind it and the not-ok ones left out."""

    mean: float
    lo: float
    hi: float
    n_ok: int
    n_bad: int
    n_groups: int = 1  # environments averaged

    @property
    def yerr(self) -> Tuple[float, float]:
        """(below, above) for matplotlib's yerr; 0 when undefined."""
        if not (np.isfinite(self.mean) and np.isfinite(self.lo) and np.isfinite(self.hi)):
            return 0.0, 0.0
        return max(self.mean - self.lo, 0.0), max(self.hi - self.mean, 0.0)


def stat(groups: Sequence[Tuple[np.ndarray, np.ndarray]], err: str = "ci",
         n_boot: int = BOOT_RESAMPLES, seed: int = BOOT_SEED) -> Stat:
    """Mean of the per-group ok means of [(travel, status), ...] (one group per environment) with its
    error bar: err = "ci" (percentile bootstrap 95%, stratified by group) or "sem" (one group only:
    mean ± standard error; several groups: sqrt(sum SEM_e²)/E, the SEM of a mean of independent means)."""
    vals = [ok_values(t, s) for t, s in groups]
    bad = sum(n_not_ok(t, s) for t, s in groups)
    n_ok = int(sum(v.size for v in vals))
    if not vals or any(v.size == 0 for v in vals):
        return Stat(float("nan"), float("nan"), float("nan"), n_ok, bad, len(vals))
    m = float(np.mean([v.mean() for v in vals]))
    if err == "ci":
        lo, hi = stratified_bootstrap_ci(vals, n_boot=n_boot, seed=seed)
    elif err == "sem":
        e = float(np.sqrt(sum(sem(v) ** 2 for v in vals)) / len(vals))
        lo, hi = m - e, m + e
    else:
        raise ValueError(f"unknown error bar {err!r}")
    return Stat(m, lo, hi, n_ok, bad, len(vals))


# ---------------------------------------------------------------------------------------------------
# reading


def _config(meta: RunMeta) -> dict:
    if not meta.config:
        return {}
    try:
        import tomllib

        return tomllib.loads(meta.config)
    except Exception:
        return {}


def config_value(meta: RunMeta, section: str, key: str, default=None):
    """A key of the run's stored (resolved) config, or `default`."""
    return _config(meta).get(section, {}).get(key, default)


def _env_index(envs: List[str]) -> Dict[str, int]:
    return {e: i for i, e in enumerate(envs)}


@dataclasses.dataclass
class Deploy:
    """/deploy, cut to the environments that are done, as the labelled reader gives it (xarray.DataArrays with
    the run file's dimensions and labels). Environments in run-file order, flat first."""

    envs: List[str]
    types: List[str]
    agents_travel: "xarray.DataArray"  # (env, agent) BL
    agents_status: "xarray.DataArray"  # (env, agent)
    coll_travel: "xarray.DataArray"  # (env, type, replicate, pair) BL
    coll_status: "xarray.DataArray"  # (env, type, replicate, pair)
    envs_total: int
    status: str
    diverse_pairs: Optional[np.ndarray] = None

    @property
    def novel(self) -> List[str]:
        return [e for e in self.envs if e != FLAT]

    @property
    def replicates(self) -> int:
        return int(self.coll_travel.sizes["replicate"])

    @property
    def pairs(self) -> int:
        return int(self.coll_travel.sizes["pair"])

    @property
    def agents_alone(self) -> int:
        """agents alone per environment"""
        return int(self.agents_travel.sizes["agent"])

    def agents(self, env: str):
        """(travel, status) of every agent alone in `env`."""
        return self.agents_travel.sel(env=env), self.agents_status.sel(env=env)

    def collective(self, type_: str, env: str):
        """(travel, status) (replicate × pair) of deployment type `type_` ("<kind>@uniform|diverse") in `env`."""
        if type_ not in self.types:
            raise StageMissing(f"deployment type {type_} is not in this run file (types: {', '.join(self.types)})")
        return self.coll_travel.sel(env=env, type=type_), self.coll_status.sel(env=env, type=type_)

    def agents_stat(self, envs: Sequence[str], err: str = "ci", **kw) -> Stat:
        return stat([self.agents(e) for e in envs], err=err, **kw)

    def collective_stat(self, type_: str, envs: Sequence[str], err: str = "ci", **kw) -> Stat:
        return stat([self.collective(type_, e) for e in envs], err=err, **kw)


def _labels(a, dim: str, want: List[str], where: str):
    """refuse an array whose labels along `dim` are not the stage's list `want`"""
    got = [str(x) for x in a[dim].values] if dim in a.coords else None
    if got != want:
        raise RunFileError(f"{where}/{a.name}: {dim} labels {','.join(got) if got else '(none)'}, expected the "
                           f"stage's {','.join(want)}")


def load_deploy(path) -> Deploy:
    with open_run(path) as run:
        g = require_stage(run, path, "deploy")
        where = f"{path}: /deploy"
        envs = list_attr(g, "environments", where)
        types = list_attr(g, "types", where)
        done = envs_done(g, len(envs))
        if done == 0:
            raise StageMissing(f"{path}: the deploy stage has no finished environment yet "
                               f"(status '{text(g.attrs.get('status', '?'))}'; run the deploy stage first)")
        alone, pairs = ("env", "agent"), ("env", "type", "replicate", "pair")
        at, ast = (labelled(run, f"deploy/agents/{k}", alone) for k in ("travel_bl", "status"))
        ct, cst = (labelled(run, f"deploy/collectives/{k}", pairs) for k in ("travel_bl", "status"))
        for a in (at, ast, ct, cst):
            _labels(a, "env", envs, where)
        for a in (ct, cst):
            _labels(a, "type", types, where)
        if ast.shape != at.shape or cst.shape != ct.shape:
            raise RunFileError(f"{where}: status shapes {ast.shape}, {cst.shape} differ from the travels' "
                               f"{at.shape}, {ct.shape}")
        dp = run["deploy/diverse_pairs"].values if "deploy/diverse_pairs" in run else None
        finished = envs[:done]
        return Deploy(envs=finished, types=types, agents_travel=at.sel(env=finished),
                      agents_status=ast.sel(env=finished), coll_travel=ct.sel(env=finished),
                      coll_status=cst.sel(env=finished), envs_total=len(envs),
                      status=text(g.attrs.get("status", "?")), diverse_pairs=dp)


@dataclasses.dataclass
class Scaling:
    """/scaling, cut to the environments that are done."""

    envs: List[str]
    sizes: List[int]
    travel: np.ndarray  # (E, S, 2, R, draws) BL; variant 0 uniform, 1 diverse
    status: np.ndarray
    envs_total: int
    stage_status: str

    VARIANTS = ("uniform", "diverse")

    def chains(self, env: str, size: int, variant: str) -> Tuple[np.ndarray, np.ndarray]:
        e, s, v = self.envs.index(env), self.sizes.index(int(size)), self.VARIANTS.index(variant)
        return self.travel[e, s, v], self.status[e, s, v]

    def stat(self, envs: Sequence[str], size: int, variant: str, err: str = "ci", **kw) -> Stat:
        return stat([self.chains(e, size, variant) for e in envs], err=err, **kw)


def load_scaling(path) -> Scaling:
    with open_file(path) as f:
        g = require_stage(f, path, "scaling")
        where = f"{path}: /scaling"
        envs = list_attr(g, "environments", where)
        done = envs_done(g, len(envs))
        if done == 0:
            raise StageMissing(f"{path}: the scaling stage has no finished environment yet "
                               f"(status '{text(g.attrs.get('status', '?'))}'; run the scaling stage first)")
        sizes = [int(x) for x in np.asarray(dataset(f, path, "scaling/sizes")).ravel()]
        chains = ("env", "size", "variant", "replicate", "draw")
        t = dataset(f, path, "scaling/travel_bl", axes=chains)
        st = dataset(f, path, "scaling/status", t.shape, chains)
        if "variants" in g.attrs and tuple(list_attr(g, "variants", where)) != Scaling.VARIANTS:
            raise RunFileError(f"{where}: variants {text(g.attrs['variants'])}, expected {','.join(Scaling.VARIANTS)}")
        if t.ndim != 5 or t.shape[0] != len(envs) or t.shape[1] != len(sizes) or t.shape[2] != 2:
            raise RunFileError(f"{where}/travel_bl: shape {t.shape}, expected "
                               f"({len(envs)}, {len(sizes)}, 2, replicates, draws)")
        return Scaling(envs=envs[:done], sizes=sizes, travel=t[:done], status=st[:done],
                       envs_total=len(envs), stage_status=text(g.attrs.get("status", "?")))


@dataclasses.dataclass
class Specialists:
    envs: List[str]  # the novel environments, each specialist trained and deployed in its own
    travel: np.ndarray  # (E_novel, R_s, NP) BL
    status: np.ndarray
    stage_status: str

    def replicate_means(self, env: str) -> np.ndarray:
        """(R_s,) ok-mean of each replicate in its environment (NaN when none of its episodes is ok)."""
        e = self.envs.index(env)
        return np.array([ok_mean(self.travel[e, r], self.status[e, r])[0] for r in range(self.travel.shape[1])])

    def best(self, env: str) -> Tuple[int, float]:
        """(replicate, ok-mean) of the best specialist of `env`: the highest ok-mean, ties to the lowest
        index; (-1, nan) when no replicate has an ok episode."""
        m = self.replicate_means(env)
        if not np.isfinite(m).any():
            return -1, float("nan")
        r = int(np.nanargmax(m))
        return r, float(m[r])

    def best_stat(self, env: str, err: str = "sem", **kw) -> Tuple[int, Stat]:
        r, _ = self.best(env)
        e = self.envs.index(env)
        if r < 0:
            return r, Stat(float("nan"), float("nan"), float("nan"), 0, n_not_ok(self.travel[e], self.status[e]))
        return r, stat([(self.travel[e, r], self.status[e, r])], err=err, **kw)


def load_specialists(path) -> Specialists:
    with open_file(path) as f:
        g = require_stage(f, path, "specialists")
        envs = list_attr(g, "environments", f"{path}: /specialists")
        spec = ("env", "replicate", "pair")
        t = dataset(f, path, "specialists/travel_bl", axes=spec)
        st = dataset(f, path, "specialists/status", t.shape, spec)
        if t.ndim != 3 or t.shape[0] != len(envs):
            raise RunFileError(f"{path}: /specialists/travel_bl: shape {t.shape}, expected "
                               f"({len(envs)}, replicates, pairs)")
        return Specialists(envs=envs, travel=t, status=st, stage_status=text(g.attrs.get("status", "?")))


@dataclasses.dataclass
class GradedPopulation:
    name: str
    diversity_sources: List[str]
    envs: List[str]
    agents_travel: np.ndarray  # (E, P_g)
    agents_status: np.ndarray
    pairs_travel: np.ndarray  # (E, R, NP)
    pairs_status: np.ndarray

    def agents(self, env):
        e = self.envs.index(env)
        return self.agents_travel[e], self.agents_status[e]

    def pairs(self, env):
        e = self.envs.index(env)
        return self.pairs_travel[e], self.pairs_status[e]

    def agents_stat(self, envs, err="ci", **kw) -> Stat:
        return stat([self.agents(e) for e in envs], err=err, **kw)

    def pairs_stat(self, envs, err="ci", **kw) -> Stat:
        return stat([self.pairs(e) for e in envs], err=err, **kw)


# the main population's sources of diversity (SPEC §7.5: behaviour, springs, shape, pairing)
MAIN_SOURCES = ["behaviour", "springs", "shape", "pairing"]
DIVERSITY_SOURCES = ["behaviour", "springs", "shape", "pairing"]


def main_population(dep: Deploy, type_: str = "weak_diverse@diverse") -> GradedPopulation:
    """The main population as a graded setting: agents alone and `type_` collectives (E × R × NP)."""
    if type_ not in dep.types:
        raise StageMissing(f"deployment type {type_} is not in this run file (types: {', '.join(dep.types)})")
    return GradedPopulation(name="main", diversity_sources=list(MAIN_SOURCES), envs=list(dep.envs),
                            agents_travel=dep.agents_travel.values, agents_status=dep.agents_status.values,
                            pairs_travel=dep.coll_travel.sel(type=type_).values,
                            pairs_status=dep.coll_status.sel(type=type_).values)


def load_graded(path) -> List[GradedPopulation]:
    """The graded populations in the order of /graded's `populations` attribute; a population whose
    status is not complete raises StageMissing."""
    import h5py

    with open_file(path) as f:
        g = require_stage(f, path, "graded")
        where = f"{path}: /graded"
        envs = list_attr(g, "environments", where)
        pops = list_attr(g, "populations", where)
        out = []
        for p in pops:
            if p not in g or not isinstance(g[p], h5py.Group):
                raise StageMissing(f"{where}/{p} missing (the graded stage has status "
                                   f"'{text(g.attrs.get('status', '?'))}': run the graded stage to the end first)")
            gp = g[p]
            if text(gp.attrs.get("status", "")) != "complete":
                raise StageMissing(f"{where}/{p} has status '{text(gp.attrs.get('status', '?'))}' "
                                   f"(run the graded stage to the end first)")
            base = f"graded/{p}/deploy"
            alone, pairs = ("env", "agent"), ("env", "replicate", "pair")
            at = dataset(f, path, f"{base}/agents/travel_bl", axes=alone)
            ast = dataset(f, path, f"{base}/agents/status", at.shape, alone)
            pt = dataset(f, path, f"{base}/pairs/travel_bl", axes=pairs)
            pst = dataset(f, path, f"{base}/pairs/status", pt.shape, pairs)
            if at.ndim != 2 or at.shape[0] != len(envs) or pt.ndim != 3 or pt.shape[0] != len(envs):
                raise RunFileError(f"{where}/{p}/deploy: shapes {at.shape} and {pt.shape}, expected "
                                   f"({len(envs)}, population) and ({len(envs)}, replicates, pairs)")
            src = list_attr(gp, "diversity_sources", default=[])
            out.append(GradedPopulation(name=p, diversity_sources=src, envs=envs, agents_travel=at,
                                        agents_status=ast, pairs_travel=pt, pairs_status=pst))
        return out


def load_meta(path) -> RunMeta:
    with open_file(path) as f:
        return _meta(f, path)


def run_title(meta: RunMeta) -> str:
    """'run "quick", seed 1, commit 9ab266a2c0d0' for figure titles."""
    seed = meta.seed if meta.seed is not None else "?"
    commit = meta.git_commit or "?"
    return f"run \"{meta.name}\" (seed {seed}, commit {commit})"


def error_bar_note(n_boot: int = BOOT_RESAMPLES, seed: int = BOOT_SEED) -> str:
    return (f"error bars: 95% percentile bootstrap CI over episodes ({n_boot} resamples, seed {seed}; "
            f"stratified by environment for means over environments)")


# ---------------------------------------------------------------------------------------------------
# the scripts' common command line


def save(fig, out_dir: str, stem: str, dpi: int = 150, software: str = "divcoll") -> List[str]:
    os.makedirs(out_dir, exist_ok=True)
    paths = []
    for ext in ("png", "pdf"):
        p = os.path.join(out_dir, f"{stem}.{ext}")
        fig.savefig(p, dpi=dpi, metadata=None if ext == "pdf" else {"Software": software})
        paths.append(p)
    return paths


def parse_args(doc: str, argv=None, extra=None):
    import argparse

    ap = argparse.ArgumentParser(description=doc.strip().split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="divcoll run file (HDF5)")
    ap.add_argument("--out", default=os.path.join("out", "figures"), help="output directory (default out/figures)")
    ap.add_argument("--dpi", type=int, default=150, help="PNG resolution (default 150)")
    ap.add_argument("--boot", type=int, default=BOOT_RESAMPLES,
                    help=f"bootstrap resamples (default {BOOT_RESAMPLES})")
    ap.add_argument("--boot-seed", type=int, default=BOOT_SEED, help=f"bootstrap seed (default {BOOT_SEED})")
    if extra:
        extra(ap)
    return ap.parse_args(argv)


def run_script(name: str, draw, args) -> int:
    """Call draw(args) -> list of written paths; RunFileError -> message on stderr, exit 2."""
    import sys

    try:
        paths = draw(args)
    except RunFileError as e:
        print(f"{name}: {e}", file=sys.stderr)
        return 2
    for p in paths:
        print(p)
    return 0


def pyplot():
    """matplotlib's pyplot on the Agg backend (files only, no display)"""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(plt, fig, path):
    """a page's figure as PNG at 120 dpi, laid out tight, then closed"""
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
