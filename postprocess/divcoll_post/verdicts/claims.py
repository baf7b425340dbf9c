"""The registry of the paper's claims (configs/studies/verdicts_protocol.md): `CLAIMS`, one `Claim` entry a claim,
each naming its statement, its effect (effects.py) and the rule it is judged by, and for the single-run view the
counts a run needs, the numbers behind it (describe.py) and the episodes its row links.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Callable, List, Optional, Tuple, Union

import numpy as np

from .describe import (_d_dtw, _d_fam, d_all_drop, d_alone_drop, d_beat_alone, d_beat_alone_1000, d_best_flat,
                       d_best_novel, d_disrupted, d_fitness, d_graded, d_greatest_drop, d_least_drop, d_most_envs,
                       d_random, d_scaling, d_specialists, d_strong, d_transplant, d_untrained, d_vs_alone_novel,
                       d_wind, d_wind_calibrated, d_worse_better)
from .effects import (WD, e_all_drop, e_alone_greatest_drop, e_alone_severe, e_beat_alone, e_beat_alone_1000,
                      e_better_comparable, e_disrupted_more, e_fitness, e_generalist_beats_specialist, e_graded,
                      e_more_familiar, e_random, e_scaling_better, e_scaling_grows, e_strong_poor,
                      e_transplant_interaction, e_transplant_small_loss, e_uniform_more_novel_only,
                      e_uniform_more_train_only, e_untrained_severe, e_wdd_best_flat, e_wdd_best_novel,
                      e_wdd_least_drop, e_wdd_most_envs, e_wdd_vs_alone_novel, e_wind_exclusive_ratio,
                      e_wind_unfamiliar, e_wind_unfamiliar_calibrated, e_worse_altered_more, e_worse_changed_more)

# the episodes a claim's row links (report_episodes.py): types by name or one of these selectors
EPISODE_TYPES = {"named": "the types the row's numbers name", "matched": "the four kinds deployed as trained",
                 "weak": "the four weak types", "all": "every type",
                 "pair": "weak_uniform@uniform, weak_diverse@diverse"}


@dataclasses.dataclass(frozen=True, kw_only=True)
class Episodes:
    """the episodes a claim's row links in the report of one run (report_episodes.py)"""
    note: str = ""  # said before the links (why the claim's own episodes are not there, what is linked instead)
    alone: bool  # link the agents deployed alone
    types: Union[str, Tuple[str, ...]]  # the collective types: names, or a selector of EPISODE_TYPES
    envs: str  # the environments: flat, novel, all, wind, none, specialists (their own), chains (the scaling stage's)


@dataclasses.dataclass(kw_only=True)
class Claim:
    id: str
    family: str  # "M" main text, "S" supplement and Fig. 4, "A6" amendment A6's claims
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
    episodes: Episodes = Episodes(alone=False, types=(), envs="none")


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
NOT_EXPORTED_DTW = Episodes(note="each tethered agent is compared with its own episode alone "
                                 "(`--what alone --agent I`); the pairs:", alone=False, types="pair", envs="all")

# the margins δ: travel (BL), relative drop, DTW per step (u), share of the novel environments, share of states
BL, DROP, U, ENV, SHARE = 0.5, 0.05, 0.005, 1 / 12, 0.02

CLAIMS: List[Claim] = [
    Claim(id="C01", family="M", form="band", margin=0.0, band=(3.0, 4.0), unit="BL", needs=("agents",),
          text="Trained agents travel almost 4 BL on flat",
          where="Results, Component training", paper="almost four",
          effect_text="mean 1000-step travel of the final population", effect=e_fitness,
          counts=N_AGENTS, describe=d_fitness,
          episodes=Episodes(note="agents-stage training episodes are not exported; the deployment alone on flat:",
                            alone=True, types=(), envs="flat")),

    Claim(id="C02", family="M", form="equivalent", margin=BL, unit="BL", needs=("agents",),
          text="Random agents travel about 0 BL",
          where="Results, Component training", paper="averaged zero",
          effect_text="mean 1000-step travel of generation 0 before any gradient step", effect=e_random,
          counts=N_AGENTS, describe=d_random,
          episodes=Episodes(note="generation 0's training episodes are not exported", alone=False, types=(),
                            envs="none")),

    Claim(id="C03", family="M", form="greater", margin=DROP, unit="", needs=("deploy",), reads_alone=True,
          text="Deployed alone, agents are severely compromised in the novel environments",
          where="Results, Component training", paper="about 4 → just over 2 BL",
          effect_text="drop(A) − 0.25", effect=e_alone_severe,
          counts=N_NOVEL, describe=d_alone_drop,
          episodes=Episodes(alone=True, types=(), envs="all")),

    Claim(id="C04", family="M", form="greater", margin=DROP, unit="", needs=("deploy",), reads_alone=True,
          text="Independent agents suffer the greatest average decrease in the novel environments",
          where="Results", paper="Fig. 2A",
          effect_text="drop(A) − max over the 8 types of drop(T)", effect=e_alone_greatest_drop,
          counts=N_NOVEL, describe=d_greatest_drop,
          episodes=Episodes(alone=True, types="named", envs="all")),

    Claim(id="C05", family="M", form="greater", margin=DROP, unit="", needs=("deploy",),
          text="Weak diverse-trained connectors on diverse pairs suffer the least decrease",
          where="Results", paper="Fig. 2A",
          effect_text="min over the other 7 types of drop(T) − drop(T wd@d)", effect=e_wdd_least_drop,
          counts=N_NOVEL, describe=d_least_drop,
          episodes=Episodes(alone=False, types="named", envs="all")),

    Claim(id="C06", family="M", form="greater", margin=DROP, unit="", needs=("agents", "connectors"),
          text="Untrained connectors cause a severe drop in behaviour",
          where="Results, Connector training", paper="severe (not shown)",
          effect_text="1 − max over kinds of untrained batch travel / agents' 1000-step travel − 0.25",
          effect=e_untrained_severe,
          counts=N_UNTRAINED, describe=d_untrained,
          episodes=Episodes(note="connector-training batches are not exported", alone=False, types=(), envs="none")),

    Claim(id="C07", family="M", form="greater", margin=BL, unit="BL", needs=("deploy",), reads_alone=True,
          text="Trained collectives of all four kinds travel further than independent agents (flat, same episode "
               "length)",
          where="Results, Connector training", paper="Fig. 2A",
          effect_text="min over matched types of T(flat) − A(flat)", effect=e_beat_alone,
          counts=N_DEPLOY, describe=d_beat_alone,
          episodes=Episodes(alone=True, types="matched", envs="flat")),

    Claim(id="C08", family="M", form="greater", margin=BL, unit="BL", needs=("deploy",),
          text="The same, with agents alone at their training length (1000 steps)",
          where="Results, Connector training", paper="Fig. 2A",
          effect_text="min over matched types of T(flat) − A1000(flat)", effect=e_beat_alone_1000,
          counts=N_DEPLOY, describe=d_beat_alone_1000,
          episodes=Episodes(note="agents alone at 1000 steps are the same episodes, read at deploy.early_step:",
                            alone=True, types="matched", envs="flat")),

    Claim(id="C09", family="M", form="greater", margin=BL, unit="BL", needs=("deploy",),
          text="Weak diverse collectives achieve the best performance on flat",
          where="Results, Connector training", paper="Fig. 2A",
          effect_text="T wd@d(flat) − max over the other matched types", effect=e_wdd_best_flat,
          counts=N_DEPLOY, describe=d_best_flat,
          episodes=Episodes(alone=False, types="matched", envs="flat")),

    Claim(id="C10", family="M", form="greater", margin=BL, unit="BL", needs=("deploy",),
          text="Every collective type travels less in the novel environments",
          where="Results, Collective deployment", paper="Fig. 2A",
          effect_text="min over the 8 types of T(flat) − N(T)", effect=e_all_drop,
          counts=N_NOVEL, describe=d_all_drop,
          episodes=Episodes(alone=False, types="all", envs="all")),

    Claim(id="C11", family="M", form="greater", margin=BL, unit="BL", needs=("deploy",),
          text="Weak diverse collectives fare best across the novel environments",
          where="Results, Collective deployment", paper="Fig. 2A",
          effect_text="N(T wd@d) − max over the other 7 types", effect=e_wdd_best_novel,
          counts=N_NOVEL, describe=d_best_novel,
          episodes=Episodes(alone=True, types="named", envs="novel")),

    Claim(id="C12", family="M", form="noninferior", margin=BL, unit="BL", needs=("deploy",),
          text="Transplanted onto clones, diverse-trained weak connectors lose only a little",
          where="Fig. 2B", paper="Fig. 2B",
          effect_text="T wd@u(flat) − T wd@d(flat)", effect=e_transplant_small_loss,
          counts=N_DEPLOY, describe=d_transplant,
          episodes=Episodes(alone=False, types="weak", envs="flat")),

    Claim(id="C13", family="M", form="greater", margin=BL, unit="BL", needs=("deploy",),
          text="Diverse-trained connectors exploit diversity, uniform-trained ones cannot (kind × deployment)",
          where="Fig. 2B", paper="Fig. 2B",
          effect_text="[T wd@d − T wd@u] − [T wu@d − T wu@u] (flat)", effect=e_transplant_interaction,
          counts=N_DEPLOY, describe=d_transplant,
          episodes=Episodes(alone=False, types="weak", envs="flat")),

    Claim(id="C14", family="M", form="greater", margin=BL, unit="BL", needs=("deploy",),
          text="Strong connectors deploy poorly (why Figs 2C-N drop them)",
          where="Results, Collective deployment", paper="Fig. 2A",
          effect_text="mean of N(T) over weak types − over strong types", effect=e_strong_poor,
          counts=N_NOVEL, describe=d_strong,
          episodes=Episodes(alone=False, types="all", envs="novel")),

    Claim(id="C15", family="M", form="greater", margin=ENV, unit="", needs=("deploy",),
          text="In most novel environments weak diverse collectives fare best of the weak types",
          where="Figs 2C-N", paper="most",
          effect_text="#(wd@d best of the weak types)/12 − 1/2", effect=e_wdd_most_envs,
          counts=N_NOVEL, describe=d_most_envs,
          episodes=Episodes(alone=False, types="weak", envs="novel")),

    Claim(id="C16", family="M", form="greater", margin=BL, unit="BL", needs=("deploy",), reads_alone=True,
          text="They fare much better than independent agents in those environments",
          where="Figs 2C-N", paper="Figs 2C-N",
          effect_text="N(T wd@d − A)", effect=e_wdd_vs_alone_novel,
          counts=N_NOVEL, describe=d_vs_alone_novel,
          episodes=Episodes(alone=True, types=(WD,), envs="novel")),

    Claim(id="C17", family="M", form="greater", margin=U, unit="u", needs=("analysis",),
          text="Tethered agents in diverse collectives are disrupted more than clones in uniform ones",
          where="Fig. 3A", paper="Fig. 3A",
          effect_text="D wd@d(all) − D wu@u(all)", effect=e_disrupted_more,
          counts=N_ANALYSIS, describe=d_disrupted,
          episodes=NOT_EXPORTED_DTW),

    Claim(id="C18", family="M", form="greater", margin=U, unit="u", needs=("analysis",),
          text="Worse agents are altered more than better ones, for both connector types",
          where="Fig. 3A", paper="Fig. 3A",
          effect_text="min over wu@u, wd@d of D(worse) − D(better)", effect=e_worse_altered_more,
          counts=N_ANALYSIS, describe=d_worse_better,
          episodes=NOT_EXPORTED_DTW),

    Claim(id="C19", family="M", form="greater", margin=U, unit="u", needs=("analysis",),
          text="Diverse-trained connectors change the worse agent more than uniform-trained ones",
          where="Fig. 3A", paper="p < 0.001",
          effect_text="D wd@d(worse) − D wu@u(worse)", effect=e_worse_changed_more,
          counts=N_ANALYSIS, describe=_d_dtw("worse"),
          episodes=NOT_EXPORTED_DTW),

    Claim(id="C20", family="M", form="equivalent", margin=U, unit="u", needs=("analysis",),
          text="Their effect on the better agents is comparable",
          where="Fig. 3A", paper="same mild impact",
          effect_text="D wd@d(better) − D wu@u(better)", effect=e_better_comparable,
          counts=N_ANALYSIS, describe=_d_dtw("better"),
          episodes=NOT_EXPORTED_DTW),

    Claim(id="C21", family="M", form="greater", margin=ENV, unit="", needs=("analysis",),
          text="Novel environments feel more familiar to diverse-trained connectors (more states in shared cells)",
          where="Table S1", paper="9 of 12",
          effect_text="#(F wd@d(both) > F wu@u(both))/12 − 1/2", effect=e_more_familiar,
          counts=N_ANALYSIS, describe=_d_fam(0, "states in shared cells", True),
          episodes=Episodes(alone=False, types="pair", envs="all")),

    Claim(id="C22", family="M", form="greater", margin=ENV, unit="", needs=("analysis",),
          text="Uniform-trained connectors meet more states exclusive to the novel environment",
          where="Table S1", paper="9 of 12",
          effect_text="#(F wu@u(novel-only) > F wd@d(novel-only))/12 − 1/2", effect=e_uniform_more_novel_only,
          counts=N_ANALYSIS, describe=_d_fam(2, "novel-only states", False),
          episodes=Episodes(alone=False, types="pair", envs="all")),

    Claim(id="C23", family="M", form="greater", margin=ENV, unit="", needs=("analysis",),
          text="Uniform-trained connectors meet more states exclusive to training",
          where="Table S1", paper="7 of 12",
          effect_text="#(F wu@u(train-only) > F wd@d(train-only))/12 − 1/2", effect=e_uniform_more_train_only,
          counts=N_ANALYSIS, describe=_d_fam(1, "training-only states", False),
          episodes=Episodes(alone=False, types="pair", envs="all")),

    Claim(id="C24", family="M", form="greater", margin=SHARE, unit="", needs=("analysis",),
          text="Wind feels more unfamiliar to the uniform-trained connector",
          where="Fig. 3B-C", paper="158,118 vs 131,303 in both",
          effect_text="share of wind's fit in shared cells, wd@d − wu@u", effect=e_wind_unfamiliar,
          counts=N_ANALYSIS, describe=d_wind,
          episodes=Episodes(alone=False, types="pair", envs="wind")),

    # amendment A6: judged in a family of its own, so that family M's Holm adjustments stay as registered
    Claim(id="C24b", family="A6", form="greater", margin=math.log(1.1), unit="", needs=("analysis",),
          text="Wind meets more exclusive states with the uniform-trained connector (scale-free)",
          where="Fig. 3B-C", paper="ratio ≈ 1.64",
          effect_text="ln(exclusive states of wind's fit, wu@u / wd@d)", effect=e_wind_exclusive_ratio,
          counts=N_ANALYSIS, describe=d_wind,
          episodes=Episodes(alone=False, types="pair", envs="wind")),

    Claim(id="C24c", family="A6", form="greater", margin=SHARE, unit="", needs=("analysis",),
          text="Wind feels more unfamiliar to the uniform-trained connector (calibrated cells)",
          where="Fig. 3B-C", paper="158,118 vs 131,303 in both",
          effect_text="share of wind's fit in shared cells at the calibrated cell scale, wd@d − wu@u",
          effect=e_wind_unfamiliar_calibrated,
          counts=N_ANALYSIS, describe=d_wind_calibrated,
          episodes=Episodes(alone=False, types="pair", envs="wind")),

    Claim(id="C25", family="S", form="greater", margin=BL, unit="BL", needs=("scaling",),
          text="The advantage of diversity grows with collective size",
          where="Fig. 4", paper="Fig. 4",
          effect_text="adv(20) − adv(5), adv = N(diverse chains) − N(uniform chains)", effect=e_scaling_grows,
          counts=N_SCALING, describe=d_scaling,
          episodes=Episodes(alone=False, types=(), envs="chains")),

    Claim(id="C26", family="S", form="greater", margin=BL, unit="BL", needs=("scaling",),
          text="Diverse-trained connectors adapt better than uniform-trained ones in larger collectives",
          where="Fig. 4", paper="Fig. 4",
          effect_text="mean over sizes of adv", effect=e_scaling_better,
          counts=N_SCALING, describe=d_scaling,
          episodes=Episodes(alone=False, types=(), envs="chains")),

    Claim(id="C27", family="S", form="greater", margin=BL, unit="BL", needs=("deploy", "specialists"),
          text="Generalists sometimes beat specialists trained in the environment",
          where="Results; Fig. S2", paper="in some cases",
          effect_text="max over novel e of T wd@d(e) − best specialist(e)", effect=e_generalist_beats_specialist,
          counts=N_SPECIALISTS, describe=d_specialists,
          episodes=Episodes(alone=False, types=(WD,), envs="specialists")),

    Claim(id="C28", family="S", form="greater", margin=BL, unit="BL", needs=("deploy", "graded"), reads_alone=True,
          text="More sources of diversity give more resilience",
          where="Fig. S3", paper="Fig. S3",
          effect_text="g(all sources) − g(same shape and springs), g = N(pairs) − N(alone)", effect=e_graded,
          counts=N_GRADED, describe=d_graded,
          episodes=Episodes(note="graded-stage episodes are not exported; the main population's:", alone=True,
                            types=(WD,), envs="novel")),

]
BY_ID = {c.id: c for c in CLAIMS}
