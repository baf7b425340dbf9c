"""The claims' effects: each `e_*(population, draws, protocol)` gives a (b,) array, the claim's effect at each of b
connector draws (draws None: at all of the population's connectors, b = 1), with agents alone under `protocol`
(analysis.alone_protocol). The registry (claims.py) names which effect a claim reads.
"""

from __future__ import annotations

import numpy as np

WEAK_TYPES = ["weak_uniform@uniform", "weak_uniform@diverse", "weak_diverse@uniform", "weak_diverse@diverse"]
STRONG_TYPES = ["strong_uniform@uniform", "strong_uniform@diverse", "strong_diverse@uniform", "strong_diverse@diverse"]
MATCHED = ["weak_uniform@uniform", "weak_diverse@diverse", "strong_uniform@uniform", "strong_diverse@diverse"]
WU, WD = "weak_uniform@uniform", "weak_diverse@diverse"
SEVERE = 0.25  # "severe": a relative drop of more than a quarter (protocol §5)


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
