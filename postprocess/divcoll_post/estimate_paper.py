"""Estimate of the paper-scale wall time per stage from the measured throughput of a scaling benchmark.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.estimate_paper OUT [--paper configs/paper.toml]
        [--cores 2 64 512] [--measured PAPER_RUN.h5] [--farm FARM.csv]

OUT holds run_np<N>.h5 written by jobs/bench-scaling.sh (the quick preset at N ranks). Per stage, the cost of
one work unit (core-seconds) is the busy time summed over ranks divided by the work units of that run (the run
with the fewest ranks that has the stage), and the per-round overhead is what its wall time leaves beyond the
modelled compute time. The paper config's stages are then modelled as task-farm rounds:

    time(p) = sum over phases of rounds x max(ceil(items / p) x mean item time, longest item time)
              + rounds x overhead per round,   item time = units per item x cost per unit,

so a stage cannot use more ranks than the items of one round. With --farm (jobs/bench-farm.sh's CSV) the
rounds beyond 2 cores also pay for the master: p - 1 workers, the first blocks sent one after another, and
no faster than the master serves items (divcoll_post.farm_model). Writes OUT/estimate.md and prints it. With
--measured, prints (and appends) the estimate against the wall time of each complete stage of a paper-scale
run file at its rank count. Exit status 2 on bad input (one line on stderr).

Work units ("pair-step equivalents"): one forward control step of a pair of agents joined by a connector; an
agent alone counts 1/2, a chain of N agents N/2, a step with gradient (taped forward + reverse pass) counts
g times a forward step, g measured as the connectors stage's cost per pair-step over the deploy stage's (both
in the quick runs; jobs/BENCHMARKS.md's 2.6 without them). PaCMAP fits are their own unit: n log2 n for a
fit of n states, costed with what the analysis stage's busy time leaves after its re-simulated episodes at
the deploy stage's cost per unit.
"""
import argparse
import glob
import math
import os
import re
import sys
import tomllib
from dataclasses import dataclass, field

import h5py

from . import farm_model
from .reader import STAGES, RunFileError, open_file, text as _s

HERE = os.path.dirname(os.path.abspath(__file__))
# every key's built-in default: configs/paper.toml of the repository this package lives in
DEFAULTS = os.path.join(os.path.dirname(os.path.dirname(HERE)), "configs", "paper.toml")
DEFAULT_GRAD_FACTOR = 2.6  # jobs/BENCHMARKS.md: a pair's forward steps/s over its forward+backward steps/s
UNIT = "pair-step eq."


class InputError(Exception):
    """Bad input: reported on one line with exit status 2."""


# ---- configs ---------------------------------------------------------------------------------------------

def parse_toml(text, where):
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{where}: not a valid TOML config ({e})") from None


def merge(base, over):
    """base's sections with over's keys on top (a key left out of a config takes its default)."""
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in base.items()}
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k].update(v)
        else:
            out[k] = v
    return out


def load_defaults():
    if not os.path.isfile(DEFAULTS):
        return {}
    with open(DEFAULTS, "rb") as fh:
        return parse_toml(fh.read().decode(), DEFAULTS)


def load_config(path, defaults):
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such config file")
    with open(path, "rb") as fh:
        return merge(defaults, parse_toml(fh.read().decode(errors="replace"), path))


def stages_of(cfg, where):
    """The stages a config runs (run.stages; graded only when graded.enabled)."""
    st = cfg.get("run", {}).get("stages", STAGES)
    if isinstance(st, str):
        st = STAGES if st == "all" else [st]
    bad = [s for s in st if s not in STAGES]
    if bad:
        raise InputError(f"{where}: run.stages lists unknown stage(s) {', '.join(map(str, bad))}")
    out = [s for s in STAGES if s in st]
    if "graded" in out and not cfg.get("graded", {}).get("enabled", True):
        out.remove("graded")
    return out


def _get(cfg, section, key, where):
    try:
        return cfg[section][key]
    except (KeyError, TypeError):
        raise InputError(f"{where}: config has no {section}.{key} (and no default for it)") from None


# ---- the work model --------------------------------------------------------------------------------------

@dataclass
class Phase:
    """`rounds` identical task-farm rounds; one round holds count items of `units` each, for each (count,
    units) in `items`. kind "sim": pair-step equivalents; "fit": PaCMAP n log2 n."""
    name: str
    rounds: int
    items: list
    kind: str = "sim"

    @property
    def n_items(self):
        return sum(c for c, _ in self.items)

    @property
    def work(self):
        return self.rounds * sum(c * u for c, u in self.items)


def agent_item(steps, epochs, g):
    """One agent's training: `epochs` rollouts with gradient and a last forward evaluation, alone (1/2)."""
    return 0.5 * steps * (epochs * g + 1)


def stage_phases(cfg, stage, g, where="config"):
    """The work of one stage of a resolved config as task-farm phases (src/stages/<name>.cpp)."""
    def v(section, key):
        return _get(cfg, section, key, where)

    P, G = v("agents", "population"), v("agents", "generations")
    EP, SA = v("agents", "epochs"), v("agents", "episode_steps")
    K, R, I, B, SC = (len(v("connectors", "kinds")), v("connectors", "replicates"), v("connectors", "iterations"),
                      v("connectors", "batch_pairs"), v("connectors", "episode_steps"))
    envs, NP, SD = v("deploy", "environments"), v("deploy", "pairs"), v("deploy", "episode_steps")
    E = len(envs)
    EN = sum(1 for e in envs if e != "flat")
    if stage == "agents":
        # generation 0 and every later generation: population items, each a whole training
        return [Phase("evolution", G + 1, [(P, agent_item(SA, EP, g))])]
    if stage == "connectors":
        # every kind x replicate in lock-step: one round per iteration of K*R*B pair episodes with gradient
        return [Phase("training", I, [(K * R * B, SC * g)])]
    if stage == "deploy":
        # one round per environment: the agents alone and 2*K types x R replicates x NP pairs, forward
        return [Phase("episodes", E, [(P, 0.5 * SD), (2 * K * R * NP, SD)])]
    if stage == "specialists":
        RS, IS = v("specialists", "replicates"), v("specialists", "iterations")
        return [Phase("training", IS, [(EN * RS * B, SC * g)]),
                Phase("deployment", 1 if EN * RS * NP else 0, [(EN * RS * NP, SD)])]
    if stage == "scaling":
        sizes, D, SS = v("scaling", "sizes"), v("scaling", "draws"), v("scaling", "episode_steps")
        # one round per environment: per size, uniform and diverse chains x R x draws; a chain of N ~ N/2 pairs
        return [Phase("chains", E, [(2 * R * D, 0.5 * n * SS) for n in sizes])]
    if stage == "graded":
        GP = v("graded", "population")
        return [Phase("same_shape evolution", G + 1, [(GP, agent_item(SA, EP, g))]),
                # no evolution: GP controllers, each trained (generations+1) x epochs epochs, in one round
                Phase("same_shape_springs training", 1, [(GP, agent_item(SA, (G + 1) * EP, g))]),
                Phase("connectors (weak diverse, 2 populations)", 2 * I, [(R * B, SC * g)]),
                Phase("deployment (2 populations)", 2, [(E * GP, 0.5 * SD), (E * R * NP, SD)])]
    if stage == "analysis":
        hs, ms = v("deploy", "hidden_subsample"), v("analysis", "max_states")
        per_episode = SD * 5
        k = per_episode if hs == 0 else min(per_episode, -(-hs // NP))
        n = 2 * min(ms, NP * k)  # training + novel states of one fit
        out = [Phase("adversity: agents alone", E, [(P, 0.5 * SD)]),
               Phase("adversity: pairs of 2 types", E, [(2 * R * NP, SD)])]
        if "flat" in envs and EN > 0 and n >= 4:
            out.append(Phase("familiarity: PaCMAP fits", EN, [(2 * R, n * math.log2(n))], kind="fit"))
        return out
    raise InputError(f"unknown stage {stage}")


@dataclass
class FarmCost:
    """The task farm's master measured by jobs/bench-farm.sh (divcoll_post.farm_model): µs of its CPU per
    item, µs per task message."""
    c_serve: float
    c_task: float
    source: str


def read_farm(path):
    try:
        top, rows = farm_model.read_costs(path)
    except farm_model.InputError as e:
        raise InputError(str(e)) from None
    r = rows.get("during", rows["after"])
    return FarmCost(float(r["master_cpu_us_per_item"]), float(r["task_us_per_msg"]),
                    f"{os.path.basename(path)} at {top} ranks")


def round_time(items, p, cost, farm=None):
    """One round of a dynamic task farm on p ranks: all of them compute (farm None), or, with the master's
    measured cost, p - 1 workers beyond 2 ranks, the first blocks sent one after another, and never faster
    than the master can serve the items (divcoll_post.farm_model)."""
    n = sum(c for c, _ in items)
    if n == 0:
        return 0.0
    mean = sum(c * u for c, u in items) * cost / n
    longest = max(u for c, u in items if c > 0) * cost
    if farm is None:
        return max(math.ceil(n / p) * mean, longest)
    w = p if p <= 2 else p - 1
    return max(math.ceil(n / w) * mean + min(w, n) * farm.c_task * 1e-6, longest, n * farm.c_serve * 1e-6)


# ---- measured costs --------------------------------------------------------------------------------------

@dataclass
class StageTiming:
    wall: float
    busy: list


@dataclass
class Run:
    path: str
    ranks: int
    cfg: dict
    timings: dict = field(default_factory=dict)


@dataclass
class StageCost:
    stage: str
    ref: str          # run file the cost comes from
    ranks: int        # its rank count
    c_sim: float      # core-s per pair-step equivalent
    c_fit: float      # core-s per n log2 n unit of a PaCMAP fit
    overhead: float   # s per round beyond the modelled compute (master's work, I/O, checkpoints)
    note: str = ""

    def cost(self, kind):
        return self.c_fit if kind == "fit" else self.c_sim


def read_run(path, defaults):
    m = re.search(r"run_np(\d+)\.h5$", path)
    try:
        with open_file(path) as f:
            if "config" not in f.attrs:
                raise InputError(f"{path}: no config attribute (not a divcoll run file?)")
            cfg = merge(defaults, parse_toml(_s(f.attrs["config"]), f"{path} (stored config)"))
            ranks = int(f.attrs["ranks"]) if "ranks" in f.attrs else (int(m.group(1)) if m else None)
            if not ranks or ranks < 1:
                raise InputError(f"{path}: no rank count (root attribute ranks)")
            run = Run(path, ranks, cfg)
            for st in STAGES:
                if st not in f or not isinstance(f[st], h5py.Group):
                    continue
                a = f[st].attrs
                if "status" in a and _s(a["status"]) != "complete":
                    continue
                if "wall_s_last_session" not in a:
                    continue
                busy = [float(x) for x in _s(a.get("busy_s_per_rank_last_session", "")).split(",") if x.strip()]
                if busy:
                    run.timings[st] = StageTiming(float(a["wall_s_last_session"]), busy)
            return run
    except InputError:
        raise
    except RunFileError as e:
        raise InputError(str(e)) from None
    except (OSError, ValueError, KeyError) as e:
        raise InputError(f"{path}: cannot read ({e})") from None


def read_runs(out, defaults):
    if not os.path.isdir(out):
        raise InputError(f"{out}: no such folder")
    found = [(int(m.group(1)), p) for p in glob.glob(os.path.join(out, "run_np*.h5"))
             if (m := re.search(r"run_np(\d+)\.h5$", p))]
    paths = [p for _, p in sorted(found)]
    if not paths:
        raise InputError(f"{out}: no run_np<N>.h5 (run jobs/bench-scaling.sh first)")
    return [read_run(p, defaults) for p in paths]


def reference(runs, stage):
    """The run with the fewest ranks that timed `stage` (1 rank when there is one)."""
    have = [r for r in runs if stage in r.timings]
    return min(have, key=lambda r: r.ranks) if have else None


def compute_time(phases, p, c_sim, c_fit, farm=None):
    return sum(ph.rounds * round_time(ph.items, p, c_fit if ph.kind == "fit" else c_sim, farm) for ph in phases)


def grad_factor(runs):
    """g = cost per pair-step with gradient (connectors) / cost per forward pair-step (deploy); (g, source)."""
    rc, rd = reference(runs, "connectors"), reference(runs, "deploy")
    if rc is None or rd is None:
        return DEFAULT_GRAD_FACTOR, "jobs/BENCHMARKS.md (no connectors or deploy timing in the quick runs)"
    wc = sum(ph.work for ph in stage_phases(rc.cfg, "connectors", 1.0, rc.path))
    wd = sum(ph.work for ph in stage_phases(rd.cfg, "deploy", 1.0, rd.path))
    bc, bd = sum(rc.timings["connectors"].busy), sum(rd.timings["deploy"].busy)
    if wc <= 0 or wd <= 0 or bc <= 0 or bd <= 0:
        return DEFAULT_GRAD_FACTOR, "jobs/BENCHMARKS.md (no connectors or deploy work measured)"
    return (bc / wc) / (bd / wd), "measured: connectors' cost per pair-step / deploy's"


def measure(runs, g=None):
    """Per stage, its StageCost from the quick runs; and the gradient factor used."""
    if g is None:
        g, g_src = grad_factor(runs)
    else:
        g_src = "given"
    costs = {}
    for st in ["deploy"] + [s for s in STAGES if s != "deploy"]:  # analysis borrows deploy's cost
        ref = reference(runs, st)
        if ref is None:
            continue
        t = ref.timings[st]
        phases = stage_phases(ref.cfg, st, g, ref.path)
        w_sim = sum(ph.work for ph in phases if ph.kind == "sim")
        w_fit = sum(ph.work for ph in phases if ph.kind == "fit")
        busy = sum(t.busy)
        note = ""
        c_sim = busy / w_sim if w_sim > 0 else 0.0
        c_fit = 0.0
        if w_fit > 0:
            dep = costs.get("deploy")
            if dep is None:
                note = "fits not separated (no deploy timing): all busy time put on the re-simulation"
            elif busy - dep.c_sim * w_sim > 0:
                c_sim = dep.c_sim
                c_fit = (busy - c_sim * w_sim) / w_fit
            else:
                note = "fits not separated (re-simulation alone exceeds the busy time)"
        rounds = sum(ph.rounds for ph in phases)
        over = max(0.0, t.wall - compute_time(phases, ref.ranks, c_sim, c_fit)) / rounds if rounds else 0.0
        costs[st] = StageCost(st, ref.path, ref.ranks, c_sim, c_fit, over, note)
    return costs, g, g_src


# ---- the estimate ----------------------------------------------------------------------------------------

def estimate_stage(cfg, stage, cost, p, g, where="config", farm=None):
    """Seconds of `stage` of config `cfg` on p ranks."""
    phases = stage_phases(cfg, stage, g, where)
    return compute_time(phases, p, cost.c_sim, cost.c_fit, farm) + cost.overhead * sum(ph.rounds for ph in phases)


def max_items(cfg, stage, g):
    return max((ph.n_items for ph in stage_phases(cfg, stage, g) if ph.rounds > 0), default=0)


def fmt_h(h):
    if h >= 100:
        return f"{h:,.0f}"
    if h >= 10:
        return f"{h:.1f}"
    if h >= 1:
        return f"{h:.2f}"
    if h >= 0.01:
        return f"{h:.3f}"
    return f"{h:.2g}"


def estimate_table(paper_cfg, paper_path, stages, costs, g, g_src, cores, out, farm=None):
    here = os.cpu_count()
    head = ["stage", f"work ({UNIT})", "max items per round", f"cost (µs per {UNIT})", "overhead per round (s)"]
    head += [f"{p} core{'s' if p > 1 else ''}{' (this machine)' if p == here else ''} (h)" for p in cores]
    md = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    totals = [0.0] * len(cores)
    for st in stages:
        c = costs[st]
        phases = stage_phases(paper_cfg, st, g, paper_path)
        w_sim = sum(ph.work for ph in phases if ph.kind == "sim")
        w_fit = sum(ph.work for ph in phases if ph.kind == "fit")
        work = f"{w_sim:.3g}" + (f" + {w_fit:.3g} fit units (n log2 n)" if w_fit else "")
        cost = f"{c.c_sim * 1e6:.3g}" + (f"; {c.c_fit * 1e6:.3g} per fit unit" if w_fit else "")
        if c.note:
            cost += f" ({c.note})"
        cells = []
        for i, p in enumerate(cores):
            h = estimate_stage(paper_cfg, st, c, p, g, paper_path, farm if p > 2 else None) / 3600
            totals[i] += h
            cells.append(fmt_h(h))
        md.append(f"| {st} | {work} | {max_items(paper_cfg, st, g)} | {cost} | {c.overhead:.3g} | "
                  + " | ".join(cells) + " |")
    md.append("| **total** | | | | | " + " | ".join(f"**{fmt_h(h)}**" for h in totals) + " |")
    refs = sorted({(os.path.basename(costs[s].ref), costs[s].ranks) for s in stages}, key=lambda x: x[1])
    ref_text = ", ".join(f"`{n}` ({r} rank{'s' if r > 1 else ''})" for n, r in refs)
    caption = (
        f"Estimated wall time (hours) of the stages of `{paper_path}` from the quick runs in `{out}` "
        f"(cost per unit from {ref_text}). "
        f"Per stage: rounds × max(ceil(items / p) × mean item time, longest item time) + rounds × the overhead per "
        f"round the quick run left beyond its compute; item time = units × cost per unit. A {UNIT} is one forward "
        f"step of a pair of agents with their connector (an agent alone 1/2, a chain of N agents N/2, a step with "
        f"gradient g = {g:.2f} forward steps, {g_src}); a PaCMAP fit of n states costs n log2 n fit units (its "
        f"kNN is exact, O(n²), so at the paper's n the fits may take longer). "
        f"Assumptions: one rank per core (ranks = cores), each core as fast as this machine's, a perfect network "
        f"(no message latency), no I/O contention (checkpoints and HDF5 writes cost per round what they cost in "
        f"the quick run), dynamic load balancing over items of equal cost within a round, failed episodes cost "
        f"a full episode. A stage cannot use more cores than the items of one round (max items per round)."
        + (f" Beyond 2 cores the master only coordinates (p - 1 workers), sends the first blocks one after another "
           f"({farm.c_task:.2f} µs each) and serves at most one item per {farm.c_serve:.2f} µs (measured by "
           f"jobs/bench-farm.sh, {farm.source})." if farm else ""))
    return md, caption, totals


def compare_measured(path, defaults, costs, g):
    """Rows (stage, ranks, estimate s, measured s) for the complete timed stages of a paper-scale run file."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such file")
    try:
        with open_file(path) as f:
            if "config" not in f.attrs:
                raise InputError(f"{path}: no config attribute (not a divcoll run file?)")
            if "ranks" not in f.attrs:
                raise InputError(f"{path}: no root attribute ranks")
            cfg = merge(defaults, parse_toml(_s(f.attrs["config"]), f"{path} (stored config)"))
            ranks = int(f.attrs["ranks"])
            measured = {}
            for st in STAGES:
                if st in f and isinstance(f[st], h5py.Group):
                    a = f[st].attrs
                    w = a.get("wall_s", a.get("wall_s_last_session"))
                    if w is not None and _s(a.get("status", "complete")) == "complete":
                        measured[st] = float(w)
    except InputError:
        raise
    except RunFileError as e:
        raise InputError(str(e)) from None
    except (OSError, ValueError, KeyError) as e:
        raise InputError(f"{path}: cannot read ({e})") from None
    rows = []
    for st, w in measured.items():
        est = estimate_stage(cfg, st, costs[st], ranks, g, path) if st in costs else None
        rows.append((st, ranks, est, w))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", help="folder with run_np<N>.h5 of jobs/bench-scaling.sh")
    ap.add_argument("--paper", default=DEFAULTS, help="the config to estimate (default configs/paper.toml)")
    ap.add_argument("--cores", type=int, nargs="+", default=[2, 64, 512], help="core (= rank) counts")
    ap.add_argument("--measured", help="a paper-scale run file: its stages' wall time against the estimate")
    ap.add_argument("--farm", help="farm.csv of jobs/bench-farm.sh: the master's measured cost per item, beyond 2 cores")
    a = ap.parse_args(argv)
    try:
        if any(p < 1 for p in a.cores):
            raise InputError(f"--cores must be positive, not {' '.join(map(str, a.cores))}")
        defaults = load_defaults()
        paper = load_config(a.paper, defaults)
        stages = stages_of(paper, a.paper)
        runs = read_runs(a.out, defaults)
        costs, g, g_src = measure(runs)
        missing = [s for s in stages if s not in costs]
        if missing:
            raise InputError(f"{a.out}: no quick run timed stage(s) {', '.join(missing)} of {a.paper} "
                             f"(not in the quick config's run.stages, or not complete)")
        farm = read_farm(a.farm) if a.farm else None
        md, caption, _ = estimate_table(paper, a.paper, stages, costs, g, g_src, a.cores, a.out, farm)
        text = md + ["", caption]
        if a.measured:
            rows = compare_measured(a.measured, defaults, costs, g)
            text += ["", f"Estimate against `{a.measured}` (its own config, at its rank count):", "",
                     "| stage | ranks | estimate (h) | measured (h) | estimate / measured |", "|---|---|---|---|---|"]
            for st, r, est, w in rows:
                if est is None:
                    text.append(f"| {st} | {r} | — (no quick timing) | {fmt_h(w / 3600)} ({w:.0f} s) | — |")
                else:
                    text.append(f"| {st} | {r} | {fmt_h(est / 3600)} ({est:.0f} s) | {fmt_h(w / 3600)} ({w:.0f} s) | "
                                f"{est / w if w > 0 else float('nan'):.2f} |")
            if not rows:
                text.append("| (no complete stage with a wall time) | | | | |")
    except InputError as e:
        print(f"estimate_paper: {e}", file=sys.stderr)
        return 2
    dest = os.path.join(a.out, "estimate.md")
    with open(dest, "w") as fh:
        fh.write("\n".join(text) + "\n")
    print("\n".join(text))
    print(f"estimate_paper: wrote {dest}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
