"""The protocol's estimator (configs/studies/verdicts_protocol.md §3): the hierarchical bootstrap over populations
and their connectors, the interval of a claim's mean effect, its two one-sided hypotheses, Holm's procedure over a
family's hypotheses and the four verdicts (`judge`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Dict, List, Sequence

import numpy as np

from .claims import Claim
from .population import Population

B_DEFAULT = 20000
BOOT_SEED = 20261204
ALPHA = 0.025  # familywise, one-sided hypotheses (Holm)


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
