"""Read-only access to the analysis stage of a divcoll run file (SPEC §8: DTW adversity, PaCMAP familiarity)
and the Python side of its statistics. Used by fig3.py, table_s1.py, summary.py and verdicts/describe.py.

Layout read here (src/stages/analysis.hpp):

    /analysis   attributes status, types ("weak_uniform@uniform,weak_diverse@diverse"), environments (13, flat
                first), novel_environments (12), dtw_envs_done, familiarity_envs_done; string lists are
                comma-joined strings as in every other stage (an HDF5 string array is accepted too)
      adversity/<type>/dtw          (E × R × pairs × 2) DTW per step per agent slot (0 posterior, 1 anterior),
                                    NaN unless the pair and both agents alone were ok; attribute ties
      adversity/<type>/worse_slot   (E × R × pairs) uint8, the slot of the agent that travelled less alone
      adversity/replicate_means     (types × 2 × R) per replicate: mean DTW of the worse (0) / better (1) agents
      adversity/summary             (types × 2 × 3) mean over replicates, bootstrap 95% CI low, high
      adversity/welch               (2 × 3) worse / better: t, df, p of Welch's test, uniform vs diverse type
      familiarity/<type>/counts     (novel E × R × 6) states in both / train-only / novel-only cells, then the
                                    numbers of such cells
      familiarity/<type>/n_states   (novel E × R × 2) training and novel states in the fit
      familiarity/<type>/embedding  (novel E × R × 2·max_states × 2, float32) training states first, then the
                                    novel ones, NaN padding
      familiarity/table             (novel E × 3 × 3) per count (both, train-only, novel-only): mean over
                                    replicates of the diverse type, of the uniform type, Welch's p

The type axes of replicate_means / summary follow the `types` attribute; the table's columns are always
(diverse, uniform, p). Only the first dtw_envs_done / familiarity_envs_done environments are read.
"""

from __future__ import annotations

import dataclasses
from typing import Dict, List, Optional, Tuple

import numpy as np

from .reader import (RunFileError, StageMissing, dataset, int_attr, list_attr, open_file, require_stage,
                     stage_status, text)

UNIFORM = "weak_uniform@uniform"  # uniform-trained weak connector on clones
DIVERSE = "weak_diverse@diverse"  # diverse-trained weak connector on diverse pairs
TYPES = (UNIFORM, DIVERSE)
TYPE_LABEL = {UNIFORM: "uniform-trained (clones)", DIVERSE: "diverse-trained (diverse pairs)"}
WORSE, BETTER = 0, 1
COUNT_NAMES = ("both", "train-only", "novel-only")
COUNT_LABEL = {"both": "in both training and novel cells", "train-only": "only in training cells",
               "novel-only": "only in novel cells"}
WIND = "wind"


def stars(p) -> str:
    """'***' p < 0.001, '**' < 0.01, '*' < 0.05, 'n.s.' otherwise; '—' when p is not a number."""
    if p is None or not np.isfinite(p):
        return "—"
    return "***" if p < 0.001 else "**" if p < 0.01 else "*" if p < 0.05 else "n.s."


def welch(a, b) -> Tuple[float, float, float]:
    """(t, df, two-sided p) of Welch's t-test a vs b over the finite values; NaNs when either has < 2 values
    or both variances are 0 (as src/analysis/stats.cpp)."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if a.size < 2 or b.size < 2:
        return float("nan"), float("nan"), float("nan")
    va, vb = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
    if va + vb == 0:
        return float("nan"), float("nan"), float("nan")
    from scipy import stats as ss

    t = (a.mean() - b.mean()) / np.sqrt(va + vb)
    df = (va + vb) ** 2 / (va ** 2 / (a.size - 1) + vb ** 2 / (b.size - 1))
    return float(t), float(df), float(2 * ss.t.sf(abs(t), df))


def classify_cells(train_xy, novel_xy) -> Tuple[np.ndarray, np.ndarray]:
    """ANALYSIS.md §1.12: round every 2-D coordinate half to even (numpy.round), cell = (ix, iy); a cell is
    "both" when it holds training and novel states, else "train-only" / "novel-only". Returns (label of
    every state, training states first: 0 both, 1 train-only, 2 novel-only; counts (6,): states in both /
    train-only / novel-only cells, then the numbers of both / train-only / novel-only cells)."""
    train_xy = np.asarray(train_xy, np.float64).reshape(-1, 2)
    novel_xy = np.asarray(novel_xy, np.float64).reshape(-1, 2)
    nt = train_xy.shape[0]
    xy = np.concatenate([train_xy, novel_xy])
    if xy.shape[0] == 0:
        return np.zeros(0, np.int64), np.zeros(6)
    cells = np.round(xy).astype(np.int64)
    _, inv = np.unique(cells, axis=0, return_inverse=True)
    inv = inv.ravel()
    n_cells = int(inv.max()) + 1
    has_t = np.zeros(n_cells, bool)
    has_n = np.zeros(n_cells, bool)
    has_t[inv[:nt]] = True
    has_n[inv[nt:]] = True
    cell_class = np.where(has_t & has_n, 0, np.where(has_t, 1, 2))
    label = cell_class[inv]
    counts = np.array([np.sum(label == k) for k in range(3)] + [np.sum(cell_class == k) for k in range(3)], float)
    return label, counts


@dataclasses.dataclass
class Adversity:
    types: List[str]  # the type axis of replicate_means / summary
    envs: List[str]  # environments done (flat first)
    dtw: Dict[str, np.ndarray]  # type -> (E_done, R, NP, 2)
    worse_slot: Dict[str, np.ndarray]  # type -> (E_done, R, NP)
    replicate_means: np.ndarray  # (T, 2, R)
    summary: np.ndarray  # (T, 2, 3)
    welch: np.ndarray  # (2, 3)
    ties: Dict[str, Optional[int]]
    deploy_mismatches: Optional[int]

    def mean(self, type_: str, which: int) -> float:
        return float(self.summary[self.types.index(type_), which, 0])

    def ci(self, type_: str, which: int) -> Tuple[float, float]:
        s = self.summary[self.types.index(type_), which]
        return float(s[1]), float(s[2])

    def p(self, which: int) -> float:
        return float(self.welch[which, 2])

    @property
    def replicates(self) -> int:
        return int(self.replicate_means.shape[2])

    @property
    def pairs(self) -> int:
        d = next(iter(self.dtw.values()), None)
        return int(d.shape[2]) if d is not None else 0

    def all_replicate_means(self, type_: str) -> np.ndarray:
        """(R,) per replicate the mean DTW of every agent (both slots) over the environments and pairs done,
        finite values only (the large bars of the paper's Fig. 3A)."""
        d = self.dtw[type_]
        out = np.full(d.shape[1], np.nan)
        for r in range(d.shape[1]):
            v = d[:, r].ravel()
            v = v[np.isfinite(v)]
            if v.size:
                out[r] = v.mean()
        return out

    def recomputed_replicate_means(self, type_: str) -> np.ndarray:
        """(2, R) the worse / better per-replicate means recomputed from dtw and worse_slot (pooled over the
        environments and pairs done, finite values only), to check the stored replicate_means."""
        d, w = self.dtw[type_], self.worse_slot[type_].astype(np.int64)
        worse = np.take_along_axis(d, w[..., None], axis=3)[..., 0]
        better = np.take_along_axis(d, (1 - w)[..., None], axis=3)[..., 0]
        out = np.full((2, d.shape[1]), np.nan)
        for k, arr in enumerate((worse, better)):
            for r in range(d.shape[1]):
                v = arr[:, r].ravel()
                v = v[np.isfinite(v)]
                if v.size:
                    out[k, r] = v.mean()
        return out


@dataclasses.dataclass
class Familiarity:
    envs: List[str]  # novel environments done
    counts: Dict[str, np.ndarray]  # type -> (E_done, R, 6)
    n_states: Dict[str, np.ndarray]  # type -> (E_done, R, 2)
    table: Optional[np.ndarray]  # (E_done, 3, 3) as stored; None when absent

    @property
    def replicates(self) -> int:
        return int(next(iter(self.counts.values())).shape[1])

    def recomputed_table(self) -> np.ndarray:
        """(E_done, 3, 3) the table recomputed from counts: nan-mean over replicates of the diverse type, of
        the uniform type, Welch's p."""
        E = len(self.envs)
        out = np.full((E, 3, 3), np.nan)
        for e in range(E):
            for k in range(3):
                d, u = self.counts[DIVERSE][e, :, k], self.counts[UNIFORM][e, :, k]
                out[e, k, 0] = np.nanmean(d) if np.isfinite(d).any() else np.nan
                out[e, k, 1] = np.nanmean(u) if np.isfinite(u).any() else np.nan
                out[e, k, 2] = welch(d, u)[2]
        return out

    def best_table(self) -> np.ndarray:
        return self.table if self.table is not None else self.recomputed_table()


@dataclasses.dataclass
class Analysis:
    path: str
    status: str
    types: List[str]
    environments: List[str]
    novel_environments: List[str]
    dtw_envs_done: int
    familiarity_envs_done: int
    adversity: Optional[Adversity]
    familiarity: Optional[Familiarity]

    @property
    def complete(self) -> bool:
        return self.status == "complete"

    def progress(self) -> str:
        return (f"status '{self.status}', DTW {self.dtw_envs_done} of {len(self.environments)} environments, "
                f"familiarity {self.familiarity_envs_done} of {len(self.novel_environments)} novel environments")

    def embedding(self, type_: str, env: str, replicate: int) -> Tuple[np.ndarray, np.ndarray]:
        """(training xy (n_t × 2), novel xy (n_n × 2)) of one PaCMAP fit, read from the file (only that slice)."""
        fam = self.familiarity
        if fam is None or env not in fam.envs:
            raise StageMissing(f"{self.path}: no familiarity fit for environment '{env}' "
                               f"(done: {', '.join(fam.envs) if fam else 'none'})")
        e = fam.envs.index(env)
        if not 0 <= replicate < fam.replicates:
            raise RunFileError(f"{self.path}: replicate {replicate} out of range 0..{fam.replicates - 1}")
        nt, nn = (int(x) for x in fam.n_states[type_][e, replicate])
        with open_file(self.path) as f:
            name = f"analysis/familiarity/{type_}/embedding"
            if name not in f:
                raise StageMissing(f"{self.path}: /{name} missing ({self.progress()})")
            d = f[name]
            if d.ndim != 4 or d.shape[3] != 2 or d.shape[0] < len(fam.envs) or d.shape[1] != fam.replicates:
                raise RunFileError(f"{self.path}: /{name} has shape {d.shape}, expected "
                                   f"({len(self.novel_environments)}, {fam.replicates}, 2·max_states, 2)")
            if nt + nn > d.shape[2]:
                raise RunFileError(f"{self.path}: /{name}: n_states {nt} + {nn} exceed the {d.shape[2]} rows")
            xy = np.asarray(d[e, replicate, :nt + nn], np.float64)
        if not np.isfinite(xy).all():
            raise RunFileError(f"{self.path}: /{name}[{env}, {replicate}] has NaN among its {nt + nn} states")
        return xy[:nt], xy[nt:]


def load_analysis(path, need: Tuple[str, ...] = ("adversity", "familiarity")) -> Analysis:
    """The analysis stage, cut to the environments done. A part named in `need` whose datasets are missing
    (or that has no environment done) raises StageMissing; a part not needed is None when missing."""
    import h5py

    with open_file(path) as f:
        g = require_stage(f, path, "analysis")
        where = f"{path}: /analysis"
        status = text(g.attrs.get("status", "?"))
        types = list_attr(g, "types", where)
        envs = list_attr(g, "environments", where)
        novel = list_attr(g, "novel_environments", where)
        complete = status == "complete"
        dtw_done = max(0, min(len(envs), int_attr(g, "dtw_envs_done", len(envs) if complete else 0)))
        fam_done = max(0, min(len(novel), int_attr(g, "familiarity_envs_done", len(novel) if complete else 0)))
        a = Analysis(path=str(path), status=status, types=types, environments=envs, novel_environments=novel,
                     dtw_envs_done=dtw_done, familiarity_envs_done=fam_done, adversity=None, familiarity=None)
        missing = [t for t in TYPES if t not in types]
        if missing:
            raise StageMissing(f"{where}: types {', '.join(types)} lack {', '.join(missing)}")
        T = len(types)

        def part(name, fn):
            try:
                return fn()
            except StageMissing:
                if name in need:
                    raise
                return None

        def adversity():
            if dtw_done == 0:
                raise StageMissing(f"{path}: the analysis stage has no DTW environment done yet ({a.progress()}; "
                                   f"run the analysis stage first)")
            dtw, ws, ties = {}, {}, {}
            for t in TYPES:
                d = dataset(f, path, f"analysis/adversity/{t}/dtw")
                if d.ndim != 4 or d.shape[0] != len(envs) or d.shape[3] != 2:
                    raise RunFileError(f"{where}/adversity/{t}/dtw: shape {d.shape}, expected "
                                       f"({len(envs)}, replicates, pairs, 2)")
                dtw[t] = d[:dtw_done].astype(float)
                ws[t] = dataset(f, path, f"analysis/adversity/{t}/worse_slot", d.shape[:3])[:dtw_done]
                gt = f[f"analysis/adversity/{t}"]
                ties[t] = int_attr(gt, "ties", -1) if "ties" in gt.attrs else None
            R = dtw[TYPES[0]].shape[1]
            rm = dataset(f, path, "analysis/adversity/replicate_means", (T, 2, R))
            sm = dataset(f, path, "analysis/adversity/summary", (T, 2, 3))
            wl = dataset(f, path, "analysis/adversity/welch", (2, 3))
            ga = f["analysis/adversity"]
            mism = int_attr(ga, "deploy_mismatches", -1) if "deploy_mismatches" in ga.attrs else None
            return Adversity(types=types, envs=envs[:dtw_done], dtw=dtw, worse_slot=ws, replicate_means=rm,
                             summary=sm, welch=wl, ties=ties, deploy_mismatches=mism)

        def familiarity():
            if fam_done == 0:
                raise StageMissing(f"{path}: the analysis stage has no familiarity environment done yet "
                                   f"({a.progress()}; run the analysis stage first)")
            counts, ns = {}, {}
            for t in TYPES:
                c = dataset(f, path, f"analysis/familiarity/{t}/counts")
                if c.ndim != 3 or c.shape[0] != len(novel) or c.shape[2] != 6:
                    raise RunFileError(f"{where}/familiarity/{t}/counts: shape {c.shape}, expected "
                                       f"({len(novel)}, replicates, 6)")
                counts[t] = c[:fam_done].astype(float)
                ns[t] = dataset(f, path, f"analysis/familiarity/{t}/n_states", c.shape[:2] + (2,))[:fam_done]
            table = None
            if "analysis/familiarity/table" in f and isinstance(f["analysis/familiarity/table"], h5py.Dataset):
                table = dataset(f, path, "analysis/familiarity/table", (len(novel), 3, 3))[:fam_done].astype(float)
            return Familiarity(envs=novel[:fam_done], counts=counts, n_states=ns, table=table)

        a.adversity = part("adversity", adversity)
        a.familiarity = part("familiarity", familiarity)
        return a


def analysis_status(path) -> Tuple[Optional[str], str]:
    """(status or None when there is no /analysis group, a one-line description) without reading datasets."""
    with open_file(path) as f:
        st = stage_status(f, "analysis")
        if st is None:
            return None, "the run file has no analysis stage"
        g = f["analysis"]
        n_e = len(list_attr(g, "environments", "")) if "environments" in g.attrs else "?"
        n_n = len(list_attr(g, "novel_environments", "")) if "novel_environments" in g.attrs else "?"
        return st, (f"analysis stage status '{st}' (DTW {int_attr(g, 'dtw_envs_done', 0)} of {n_e} environments, "
                    f"familiarity {int_attr(g, 'familiarity_envs_done', 0)} of {n_n} novel environments)")
