"""The paper's claims, each tested against a run file's numbers.

Each claim is a function of the run file returning (number text, verdict) where verdict is "held",
"did not hold" or "not measured" (its stage is missing or not complete, or its number is not finite). A claim is
judged only where the run has the counts its test needs (NEEDS: agents, pairs, replicates, iterations,
specialists, chains, states); a smaller run (the quick and tiny presets) gets "too small to judge", with the count
that is short. `scale(path)` compares the run's counts with the paper's. Means are over ok episodes only, and
"novel" means are means of per-environment means (summary.py). The claims of Fig. 3 and Table S1 read the
analysis stage's stored statistics (divcoll_post/analysis.py); "significantly" means Welch's p < 0.05. Used by
report.py; `claims(path)` lists them.
"""
import re
import tomllib

import h5py
import numpy as np

import summary
from divcoll_post import analysis as A
from divcoll_post.runfile import RunFileError


from divcoll_post.runfile import STAGES, text as _s  # noqa: E402


class Run:
    """the arrays the claims need, read once"""

    def __init__(self, path):
        self.path = path
        with h5py.File(path, "r") as f:
            self.has = {st: st in f and _s(f[st].attrs.get("status", "")) == "complete"
                        for st in STAGES}
            self.fitness = f["agents/final/fitness"][()] if "agents/final" in f else None
            self.gen0_untrained = None
            if "agents/gen_000/curve_u" in f:
                # travel before any gradient step, over the body length, of the random generation 0
                c = f["agents/gen_000/curve_u"][()][:, 0]
                fit, tu = f["agents/gen_000/fitness"][()], f["agents/gen_000/travel_u"][()]
                bl = np.where(fit != 0, tu / np.where(fit == 0, 1, fit), np.nan)
                self.gen0_untrained = c / bl
            self.curves = {}
            if "connectors" in f:
                for kind in _s(f["connectors"].attrs.get("kinds", "")).split(","):
                    if f"connectors/{kind}/curve_bl" in f:
                        self.curves[kind] = np.nanmean(f[f"connectors/{kind}/curve_bl"][()], axis=1)
            if self.has["deploy"]:
                d = f["deploy"]
                self.envs = _s(d.attrs["environments"]).split(",")
                self.types = _s(d.attrs["types"]).split(",")
                self.alone, _ = summary.env_means(d["agents/travel_bl"][()], d["agents/status"][()])
                self.alone = alone_under_protocol(f, self.alone)
                ct, cs = d["collectives/travel_bl"][()], d["collectives/status"][()]
                self.coll = {t: summary.env_means(ct[:, i], cs[:, i])[0] for i, t in enumerate(self.types)}
                self.novel = [i for i, e in enumerate(self.envs) if e != "flat"]
                self.flat = self.envs.index("flat")
            if self.has["specialists"]:
                s = f["specialists"]
                self.spec_envs = _s(s.attrs["environments"]).split(",")
                t, st = s["travel_bl"][()], s["status"][()]
                self.spec_best = np.array([np.nanmax([summary.ok_mean(t[e, r], st[e, r])[0] for r in range(t.shape[1])])
                                           for e in range(t.shape[0])])
            if self.has["scaling"]:
                sc = f["scaling"]
                self.sizes = list(sc["sizes"][()])
                self.scale_envs = _s(sc.attrs["environments"]).split(",")
                t, st = sc["travel_bl"][()], sc["status"][()]
                nov = [i for i, e in enumerate(self.scale_envs) if e != "flat"]
                self.scale = np.array([[np.mean(summary.env_means(t[:, si, v], st[:, si, v])[0][nov]) for v in range(2)]
                                       for si in range(len(self.sizes))])
            if self.has["graded"]:
                self.graded = {}
                genvs = _s(f["graded"].attrs["environments"]).split(",")
                nov = [i for i, e in enumerate(genvs) if e != "flat"]
                for pop in ["same_shape", "same_shape_springs"]:
                    g = f[f"graded/{pop}"]
                    a, _ = summary.env_means(g["deploy/agents/travel_bl"][()], g["deploy/agents/status"][()])
                    p, _ = summary.env_means(g["deploy/pairs/travel_bl"][()], g["deploy/pairs/status"][()])
                    self.graded[pop] = (np.mean(a[nov]), np.mean(p[nov]))

        # the analysis stage (Fig. 3, Table S1), read through divcoll_post.analysis once the file is closed
        self.analysis, self.analysis_error = None, ""
        if self.has["analysis"]:
            try:
                self.analysis = A.load_analysis(path)
            except RunFileError as e:
                self.analysis_error = f"cannot read the analysis stage: {e}"
        else:
            st, desc = A.analysis_status(path)
            self.analysis_error = "no analysis stage in the run file" if st is None else desc

    def novel_mean(self, arr):
        return float(np.mean(arr[self.novel]))


def alone_under_protocol(f, alone, protocol=None):
    """agents alone's per-environment means under the stored config's analysis.alone_protocol (or `protocol`, a
    reading applied at report time): same_length (the deployment's travel, as the collectives'), training_length
    (travel at deploy.early_step), training_rate (deployment travel × connectors.episode_steps /
    deploy.episode_steps); see `divcoll keys`. `alone` is the same-length means."""
    try:
        cfg = tomllib.loads(_s(f.attrs["config"]))
    except (KeyError, tomllib.TOMLDecodeError):
        return alone
    protocol = protocol or cfg.get("analysis", {}).get("alone_protocol", "same_length")
    if protocol == "training_length":
        d = f["deploy"]
        return summary.env_means(d["agents/travel_bl_early"][()], d["agents/status"][()])[0]
    if protocol == "training_rate":
        return alone * cfg["connectors"]["episode_steps"] / cfg["deploy"]["episode_steps"]
    return alone


def f3(x):
    return "—" if x is None or not np.isfinite(x) else f"{x:.2f}"


def verdict(ok):
    return "held" if ok else "did not hold"


def c_agents_trained(r):
    if r.fitness is None:
        return "", "not measured"
    txt = f"final population {f3(r.fitness.mean())} ± {f3(r.fitness.std())} BL"
    if r.gen0_untrained is not None:
        txt += f"; random untrained {f3(np.nanmean(r.gen0_untrained))} BL"
    return txt, verdict(r.fitness.mean() >= 3.0 and (r.gen0_untrained is None or abs(np.nanmean(r.gen0_untrained)) < 0.5))


def c_agents_drop(r):
    if not r.has["deploy"]:
        return "", "not measured"
    drops = {"agents alone": 1 - r.novel_mean(r.alone) / r.alone[r.flat]}
    for t, m in r.coll.items():
        drops[t] = 1 - r.novel_mean(m) / m[r.flat]
    worst = max(drops, key=drops.get)
    return (f"relative drop flat → novel: agents alone {drops['agents alone']:.0%}; largest: {worst} {drops[worst]:.0%}",
            verdict(worst == "agents alone"))


def c_untrained_drop(r):
    if not r.curves or r.fitness is None:
        return "", "not measured"
    first = {k: c[0] for k, c in r.curves.items()}
    txt = ", ".join(f"{k} {f3(v)}" for k, v in first.items()) + f" BL (batch mean before the first step) vs agents alone {f3(r.fitness.mean())} BL (1000 steps)"
    return txt, verdict(all(v < 0.5 * r.fitness.mean() for v in first.values()))


def c_trained_beat_alone(r):
    if not r.has["deploy"]:
        return "", "not measured"
    kinds = [t for t in r.types if t.split("@")[0].split("_")[1] == t.split("@")[1]]
    txt = ", ".join(f"{t} {f3(r.coll[t][r.flat])}" for t in kinds) + f" vs agents alone {f3(r.alone[r.flat])} BL on flat"
    return txt, verdict(all(r.coll[t][r.flat] > r.alone[r.flat] for t in kinds))


def c_weak_diverse_best_flat(r):
    if not r.has["deploy"]:
        return "", "not measured"
    kinds = [t for t in r.types if t.split("@")[0].split("_")[1] == t.split("@")[1]]
    best = max(kinds, key=lambda t: r.coll[t][r.flat])
    return f"best on flat: {best} ({f3(r.coll[best][r.flat])} BL)", verdict(best == "weak_diverse@diverse")


def c_all_drop_novel(r):
    if not r.has["deploy"]:
        return "", "not measured"
    worse = [t for t in r.types if r.novel_mean(r.coll[t]) < r.coll[t][r.flat]]
    return f"{len(worse)} of {len(r.types)} types travel less in the novel environments", verdict(len(worse) == len(r.types))


def c_weak_diverse_best_novel(r):
    if not r.has["deploy"]:
        return "", "not measured"
    best = max(r.types, key=lambda t: r.novel_mean(r.coll[t]))
    return (f"best across the novel environments: {best} ({f3(r.novel_mean(r.coll[best]))} BL); weak_diverse@diverse "
            f"{f3(r.novel_mean(r.coll['weak_diverse@diverse']))}, agents alone {f3(r.novel_mean(r.alone))}"), \
        verdict(best == "weak_diverse@diverse")


def c_transplant(r):
    if not r.has["deploy"]:
        return "", "not measured"
    dd, du = r.coll["weak_diverse@diverse"][r.flat], r.coll["weak_diverse@uniform"][r.flat]
    uu, ud = r.coll["weak_uniform@uniform"][r.flat], r.coll["weak_uniform@diverse"][r.flat]
    ok = (dd - du) < 0.25 * abs(dd) and ud < uu
    return (f"flat: weak diverse-trained on diverse {f3(dd)} / on clones {f3(du)}; weak uniform-trained on clones "
            f"{f3(uu)} / on diverse {f3(ud)} BL"), verdict(ok)


def c_weak_diverse_most_envs(r):
    if not r.has["deploy"]:
        return "", "not measured"
    weak = [t for t in r.types if t.startswith("weak")]
    wins = sum(1 for e in r.novel if max(weak, key=lambda t: r.coll[t][e]) == "weak_diverse@diverse")
    beats = sum(1 for e in r.novel if r.coll["weak_diverse@diverse"][e] > r.alone[e])
    return (f"weak_diverse@diverse best of the weak types in {wins} of {len(r.novel)} novel environments, above agents "
            f"alone in {beats}"), verdict(wins > len(r.novel) / 2 and beats > len(r.novel) / 2)


def c_specialists(r):
    if not (r.has["specialists"] and r.has["deploy"]):
        return "", "not measured"
    gen = np.array([r.coll["weak_diverse@diverse"][r.envs.index(e)] for e in r.spec_envs])
    better = [e for e, g, s in zip(r.spec_envs, gen, r.spec_best) if g > s]
    return (f"the generalist beats the best specialist in {len(better)} of {len(r.spec_envs)} environments"
            + (f" ({', '.join(better)})" if better else "")), verdict(len(better) >= 1)


def c_scaling(r):
    if not r.has["scaling"]:
        return "", "not measured"
    adv = r.scale[:, 1] - r.scale[:, 0]
    txt = "; ".join(f"N={n}: diverse − uniform {adv[i]:+.2f} BL" for i, n in enumerate(r.sizes))
    return txt, verdict(all(np.diff(adv) > 0) and adv[-1] > 0)


def c_graded(r):
    if not (r.has["graded"] and r.has["deploy"]):
        return "", "not measured"
    main = (r.novel_mean(r.alone), r.novel_mean(r.coll["weak_diverse@diverse"]))
    rows = [("main", main)] + list(r.graded.items())
    gains = [p - a for _, (a, p) in rows]
    txt = "; ".join(f"{n}: pairs − alone {g:+.2f} BL" for (n, _), g in zip(rows, gains))
    return txt, verdict(gains[0] > gains[1] > gains[2])


def g3(x):
    return "—" if x is None or not np.isfinite(x) else f"{x:.3g}"


def _adversity(r):
    return r.analysis.adversity if r.analysis is not None else None


def _familiarity(r):
    return r.analysis.familiarity if r.analysis is not None else None


def c_diverse_disrupted_more(r):
    adv = _adversity(r)
    if adv is None:
        return r.analysis_error, "not measured"
    m = {t: np.nanmean(adv.all_replicate_means(t)) for t in A.TYPES}
    p = A.welch(adv.all_replicate_means(A.UNIFORM), adv.all_replicate_means(A.DIVERSE))[2]
    return (f"mean DTW per step, all agents: diverse-trained {g3(m[A.DIVERSE])} u, uniform-trained {g3(m[A.UNIFORM])} u "
            f"(Welch p = {g3(p)})"), verdict(m[A.DIVERSE] > m[A.UNIFORM])


def c_worse_altered_more(r):
    adv = _adversity(r)
    if adv is None:
        return r.analysis_error, "not measured"
    txt = "; ".join(f"{'diverse' if t == A.DIVERSE else 'uniform'}-trained: worse {g3(adv.mean(t, A.WORSE))} u, "
                    f"better {g3(adv.mean(t, A.BETTER))} u" for t in A.TYPES)
    return txt, verdict(all(adv.mean(t, A.WORSE) > adv.mean(t, A.BETTER) for t in A.TYPES))


def c_diverse_change_worse_more(r):
    adv = _adversity(r)
    if adv is None:
        return r.analysis_error, "not measured"
    d, u, p = adv.mean(A.DIVERSE, A.WORSE), adv.mean(A.UNIFORM, A.WORSE), adv.p(A.WORSE)
    return (f"worse agents: diverse-trained {g3(d)} u vs uniform-trained {g3(u)} u, Welch p = {g3(p)} ({A.stars(p)})",
            verdict(d > u and np.isfinite(p) and p < 0.05))


def c_better_comparable(r):
    adv = _adversity(r)
    if adv is None:
        return r.analysis_error, "not measured"
    d, u, p = adv.mean(A.DIVERSE, A.BETTER), adv.mean(A.UNIFORM, A.BETTER), adv.p(A.BETTER)
    if not np.isfinite(p):
        return f"better agents: diverse-trained {g3(d)} u vs uniform-trained {g3(u)} u, no Welch p", "not measured"
    return (f"better agents: diverse-trained {g3(d)} u vs uniform-trained {g3(u)} u, Welch p = {g3(p)} ({A.stars(p)})",
            verdict(p >= 0.05))


def c_more_familiar(r):
    fam = _familiarity(r)
    if fam is None:
        return r.analysis_error, "not measured"
    tab = fam.best_table()
    wins = [e for i, e in enumerate(fam.envs) if tab[i, 0, 0] > tab[i, 0, 1]]
    sig = [e for i, e in enumerate(fam.envs) if tab[i, 0, 0] > tab[i, 0, 1] and tab[i, 0, 2] < 0.05]
    return (f"more states in shared cells for the diverse-trained connector in {len(wins)} of {len(fam.envs)} novel "
            f"environments ({len(sig)} with p < 0.05)"), verdict(len(wins) > len(fam.envs) / 2)


def c_uniform_more_novel_states(r):
    fam = _familiarity(r)
    if fam is None:
        return r.analysis_error, "not measured"
    tab = fam.best_table()
    more = [e for i, e in enumerate(fam.envs) if tab[i, 2, 1] > tab[i, 2, 0]]
    return (f"more novel-only states for the uniform-trained connector in {len(more)} of {len(fam.envs)} novel "
            f"environments"), verdict(len(more) > len(fam.envs) / 2)


def c_wind_unfamiliar(r):
    fam = _familiarity(r)
    if fam is None:
        return r.analysis_error, "not measured"
    if A.WIND not in fam.envs:
        return "no wind environment in the familiarity results", "not measured"
    t = fam.best_table()[fam.envs.index(A.WIND)]
    d_one, u_one = t[1, 0] + t[2, 0], t[1, 1] + t[2, 1]
    return (f"wind, mean states: in both: diverse-trained {t[0, 0]:.1f}, uniform-trained {t[0, 1]:.1f}; unique to "
            f"training or wind: diverse-trained {d_one:.1f}, uniform-trained {u_one:.1f}"), \
        verdict(t[0, 0] > t[0, 1] and u_one > d_one)


# the paper's counts (configs/paper.toml) and the run's, by config key: (key, what it counts, paper value)
SCALE = [
    ("agents.population", "agents in the evolved population", 100),
    ("agents.generations", "generations of evolution", 15),
    ("agents.epochs", "gradient-descent epochs per training", 15),
    ("connectors.replicates", "connector replicates per kind", 10),
    ("connectors.iterations", "connector training iterations", 100),
    ("connectors.batch_pairs", "pairs per training batch", 100),
    ("deploy.pairs", "deployed pairs per replicate", 100),
    ("deploy.environments", "environments", 13),
    ("deploy.episode_steps", "steps per deployment", 3000),
    ("specialists.replicates", "specialists per novel environment", 10),
    ("specialists.iterations", "specialist training iterations", 100),
    ("scaling.sizes", "chain sizes", "5, 10, 20"),
    ("scaling.draws", "chains per replicate, size and variant", 100),
    ("graded.population", "agents per graded population", 100),
    ("analysis.max_states", "hidden states per environment in one PaCMAP fit", 10000),
]


def config(path):
    with h5py.File(path, "r") as f:
        return tomllib.loads(_s(f.attrs.get("config", "")))


def key(cfg, k):
    sec, name = k.split(".")
    v = cfg.get(sec, {}).get(name)
    if k == "deploy.environments" and isinstance(v, list):
        return len(v)
    return v


def scale(path):
    """(preset name, [(what, key, this run, paper)]) for the report's header"""
    cfg = config(path)
    name = cfg.get("run", {}).get("name", "?")
    rows = []
    for k, what, paper in SCALE:
        v = key(cfg, k)
        rows.append((what, k, ", ".join(map(str, v)) if isinstance(v, list) else v, paper))
    return name, rows


# the counts each claim's test needs: (config key, minimum, why). Thresholds sit at about half the paper's counts:
# enough replicates for a Welch test between replicate means, enough pairs for a mean over pairs to settle, enough
# training for the "trained" in a claim to mean trained.
AGENTS = [("agents.population", 50, "agents"), ("agents.generations", 10, "generations")]
TRAINED = [("connectors.replicates", 5, "connector replicates"), ("connectors.iterations", 50, "training iterations"),
           ("connectors.batch_pairs", 50, "pairs per batch")]
DEPLOY = AGENTS + TRAINED + [("deploy.pairs", 50, "deployed pairs")]
NOVEL = DEPLOY + [("deploy.environments", 7, "environments")]
NEEDS = {
    "c_agents_trained": AGENTS,
    "c_agents_drop": NOVEL,
    "c_untrained_drop": AGENTS + [("connectors.batch_pairs", 50, "pairs per batch")],
    "c_trained_beat_alone": DEPLOY,
    "c_weak_diverse_best_flat": DEPLOY,
    "c_all_drop_novel": NOVEL,
    "c_weak_diverse_best_novel": NOVEL,
    "c_transplant": DEPLOY,
    "c_weak_diverse_most_envs": NOVEL,
    "c_specialists": NOVEL + [("specialists.replicates", 5, "specialists per environment"),
                              ("specialists.iterations", 50, "specialist iterations")],
    "c_scaling": DEPLOY + [("scaling.chains", 100, "chains per size and variant (replicates × draws)"),
                           ("scaling.n_sizes", 3, "chain sizes")],
    "c_graded": NOVEL + [("graded.population", 50, "agents per graded population")],
}
ANALYSIS_NEEDS = DEPLOY + [("analysis.max_states", 5000, "hidden states per PaCMAP fit")]


def short_of(cfg, needs):
    """the counts below their minimum, as text ('' when the run is large enough)"""
    short = []
    for k, least, what in needs:
        if k == "scaling.chains":
            v = (key(cfg, "connectors.replicates") or 0) * (key(cfg, "scaling.draws") or 0)
        elif k == "scaling.n_sizes":
            v = len(key(cfg, "scaling.sizes") or [])
        else:
            v = key(cfg, k)
        if v is None or v < least:
            short.append(f"{what} {v} (needs ≥ {least})")
    return "; ".join(short)


def not_finite(number):
    """a claim's number text built from a NaN or infinity (f3/g3 print those as —)"""
    return "—" in number or re.search(r"\b(nan|inf)\b", number, re.I) is not None


CLAIMS = [
    ("Trained agents travel almost 4 BL on flat; random ones about 0", c_agents_trained),
    ("Independent agents suffer the greatest drop in the novel environments", c_agents_drop),
    ("Untrained connectors cause a severe drop in behaviour", c_untrained_drop),
    ("Trained collectives of all four kinds travel further than independent agents (flat)", c_trained_beat_alone),
    ("Weak connectors trained and deployed with diversity do best on flat", c_weak_diverse_best_flat),
    ("Every collective type travels less in the novel environments than on flat", c_all_drop_novel),
    ("Weak connectors with diversity in training and deployment do best across the novel environments",
     c_weak_diverse_best_novel),
    ("Transplant: diverse-trained weak connectors lose little on clones; uniform-trained ones cannot exploit diversity",
     c_transplant),
    ("In most novel environments weak diverse collectives are best (of the weak types) and beat agents alone",
     c_weak_diverse_most_envs),
    ("Generalists sometimes beat specialists trained in the environment (Fig. S2)", c_specialists),
    ("The advantage of diversity grows with collective size (Fig. 4)", c_scaling),
    ("More sources of diversity give more resilience (Fig. S3)", c_graded),
    ("Tethered agents within diverse collectives were disrupted more than agent clones within uniform collectives "
     "(mean DTW distance, Fig. 3A)", c_diverse_disrupted_more),
    ("Adversity was tamed: worse-performing agents were altered more than better-performing ones, for both connector "
     "types (Fig. 3A)", c_worse_altered_more),
    ("Diversely trained connectors caused a significantly larger change in the worse-performing agent's behaviour "
     "than uniformly trained connectors did (Fig. 3A; paper p < 0.001, here p < 0.05 required)",
     c_diverse_change_worse_more),
    ("The connectors' effect on better-performing agents was comparable between the two types (Fig. 3A; no "
     "significant Welch difference)", c_better_comparable),
    ("New environments feel more familiar to diversely trained connectors: in most novel environments more of their "
     "hidden states fall in cells shared with training (PaCMAP, Table S1)", c_more_familiar),
    ("Uniformly trained connectors encounter more states exclusive to the novel environment in most environments "
     "(Table S1)", c_uniform_more_novel_states),
    ("Wind felt more unfamiliar to the uniformity-trained connector: fewer percepts in both training and wind, more "
     "unique to one of them (Fig. 3B-C)", c_wind_unfamiliar),
]


def claims(path):
    """[(claim, number text, verdict, needs)]: verdict held / did not hold / not measured / too small to judge;
    needs = the counts the test needs (and which are short)"""
    r = Run(path)
    cfg = config(path)
    out = []
    for text, fn in CLAIMS:
        needs = NEEDS.get(fn.__name__, ANALYSIS_NEEDS)
        try:
            number, v = fn(r)
        except (KeyError, ValueError, IndexError) as e:
            number, v = f"cannot evaluate: {e}", "not measured"
        if v != "not measured" and not_finite(number): v = "not measured"  # noqa: E701 (one line: reliab may edit it)
        short = short_of(cfg, needs)
        if v in ("held", "did not hold") and short:
            v = "too small to judge"
        need = ", ".join(f"{what} ≥ {least}" for _, least, what in needs)
        out.append((text, number, v, f"short: {short}" if short else f"has {need}"))
    return out
