"""The single-run view of the pre-registered claims (verdicts.CLAIMS): each claim's effect on one run file, judged
against the claim's own region (verdicts.region: above 0, above −δ, within ±δ or inside the band), beside the run's
numbers behind it. The report of a run file (report.py) and the robustness page's per-seed values (robustness.py)
read the claims through here; the verdict page judges the same effects over populations (verdicts.judge).

A run's effect is the claim's effect at all of the run's connectors (`effect(population, None, protocol)`), from the
arrays `verdicts.extract` reads, with agents alone under the run's `analysis.alone_protocol`. Verdicts: held / did
not hold; not measured (a stage it needs is not complete, or the effect is not finite); too small to judge (the run
lacks the counts the claim's `counts` asks for, named).
"""

from __future__ import annotations

import re
import tomllib
from typing import List, Optional, Tuple

from . import verdicts as V
from .reader import STAGES, RunFileError, open_file, stage_status
from .runfile import read_meta

HELD, NOT_HELD, TOO_SMALL, NOT_MEASURED = "held", "did not hold", "too small to judge", "not measured"
VERDICTS = (HELD, NOT_HELD, TOO_SMALL, NOT_MEASURED)

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


def config(path) -> dict:
    """the run's stored (resolved) config"""
    text = read_meta(path).config
    return tomllib.loads(text) if text else {}


def key(cfg, k):
    sec, name = k.split(".")
    v = cfg.get(sec, {}).get(name)
    if k == "deploy.environments" and isinstance(v, list):
        return len(v)
    return v


def scale(path):
    """(preset name, [(what, key, this run, paper)]) for the report's header"""
    cfg = config(path)
    rows = []
    for k, what, paper in SCALE:
        v = key(cfg, k)
        rows.append((what, k, ", ".join(map(str, v)) if isinstance(v, list) else v, paper))
    return cfg.get("run", {}).get("name", "?"), rows


def short_of(cfg, counts) -> str:
    """the counts below their minimum, as text ('' when the run is large enough)"""
    short = []
    for k, least, what in counts:
        if k == "scaling.chains":
            v = (key(cfg, "connectors.replicates") or 0) * (key(cfg, "scaling.draws") or 0)
        elif k == "scaling.n_sizes":
            v = len(key(cfg, "scaling.sizes") or [])
        else:
            v = key(cfg, k)
        if v is None or v < least:
            short.append(f"{what} {v} (needs ≥ {least})")
    return "; ".join(short)


def not_finite(number: str) -> bool:
    """a number text built from a NaN or infinity (f3/g3 print those as —)"""
    return "—" in number or re.search(r"\b(nan|inf)\b", number, re.I) is not None


def protocol_of(cfg) -> str:
    return cfg.get("analysis", {}).get("alone_protocol", "same_length")


def _stage_notes(path, stages) -> str:
    """why the stages a claim needs are not there: 'analysis stage status 'running'', 'no analysis stage ...'"""
    notes = []
    with open_file(path) as f:
        for st in stages:
            status = stage_status(f, st)
            if status is None:
                notes.append(f"no {st} stage in the run file")
            else:
                if status != "complete":
                    notes.append(f"{st} stage status '{status}'")
    return "; ".join(notes)


def evaluate(c: V.Claim, pop: V.Population, protocol: str) -> Tuple[str, Optional[float], str]:
    """(the run's numbers, its effect or None, held / did not hold / not measured) of claim c on one population"""
    if not all(pop.has(s) for s in c.needs):
        return "", None, NOT_MEASURED
    try:
        number = c.describe(pop, protocol) if c.describe else ""
        e = float(c.effect(pop, None, protocol)[0])
    except (KeyError, ValueError, IndexError, ZeroDivisionError) as err:
        return f"cannot evaluate: {err}", None, NOT_MEASURED
    h = V.holds(c, e)
    if h is None or not_finite(number):
        return number, None if h is None else e, NOT_MEASURED
    return number, e, HELD if h else NOT_HELD


def effect_text(c: V.Claim, e: Optional[float]) -> str:
    lo, hi = V.region(c)
    where = {"greater": "> 0", "noninferior": f"> −{c.margin:g}", "equivalent": f"within ±{c.margin:g}",
             "band": f"in ({lo:g}, {hi:g})"}[c.form]
    val = "—" if e is None else f"{e:+.3g}"
    return f"effect {val} {c.unit}".rstrip() + f" (holds {where})"


def claims(path, claims=None) -> List[Tuple[V.Claim, str, str, str]]:
    """[(claim, the run's numbers and effect, verdict, the counts the judgement needs)] for every claim of the
    registry (or `claims`)"""
    cfg = config(path)
    pop = V.Population(cfg.get("run", {}).get("seed"), [V.extract(path)])
    protocol = protocol_of(cfg)
    out = []
    for c in claims or V.CLAIMS:
        number, e, v = evaluate(c, pop, protocol)
        if v == NOT_MEASURED and not number:
            number = _stage_notes(path, [s for s in c.needs if s in STAGES])
        elif e is not None:
            number = f"{number}; {effect_text(c, e)}" if number else effect_text(c, e)
        short = short_of(cfg, c.counts)
        if v in (HELD, NOT_HELD) and short:
            v = TOO_SMALL
        need = ", ".join(f"{what} ≥ {least}" for _, least, what in c.counts)
        out.append((c, number, v, f"short: {short}" if short else f"has {need}"))
    return out


__all__ = ["claims", "evaluate", "scale", "config", "key", "short_of", "SCALE", "VERDICTS", "RunFileError"]
