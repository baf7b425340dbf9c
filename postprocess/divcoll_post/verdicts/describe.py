"""The single-run view's numbers: each `d_*(population, protocol)` gives the text of one run's numbers behind a
claim's effect (the report of a run file, the robustness page), at all of the run's connectors.
"""

from __future__ import annotations

import numpy as np

from .effects import MATCHED, STRONG_TYPES, WD, WEAK_TYPES, WU, _ti


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
