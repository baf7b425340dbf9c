"""Tests of divcoll_post.estimate_paper on synthetic scaling-benchmark run files (run_np<N>.h5) whose busy
and wall times are set from known costs per work unit.

    cd <repo> && /usr/bin/python3 -m unittest postprocess/tests/test_estimate.py -v
"""

import contextlib
import io
import math
import os
import re
import subprocess
import sys
import tempfile
import unittest

import h5py

HERE = os.path.dirname(os.path.abspath(__file__))
POST = os.path.dirname(HERE)
sys.path.insert(0, POST)

from divcoll_post import estimate_paper as E  # noqa: E402

# a small quick config; every key left out takes configs/paper.toml's value
QUICK = """
[run]
name = "synthetic"
[agents]
population = 4
generations = 1
epochs = 2
episode_steps = 10
[connectors]
replicates = 1
iterations = 3
batch_pairs = 2
episode_steps = 10
kinds = ["weak_uniform", "weak_diverse"]
[deploy]
pairs = 2
episode_steps = 20
environments = ["flat", "ice"]
hidden_subsample = 10
[specialists]
replicates = 1
iterations = 2
[scaling]
sizes = [2, 4]
draws = 2
episode_steps = 20
[graded]
population = 3
[analysis]
max_states = 10
"""

G = 3.0  # the gradient factor the synthetic timings imply (connectors and deploy at the same cost per unit)
# work of each stage of QUICK by hand, in pair-step equivalents with g = 3 (an agent alone 1/2, a chain N/2):
N_FIT = 20  # 2 × min(max_states 10, pairs 2 × ceil(hidden_subsample 10 / pairs 2) = 10)
WORK = {
    # 2 generations × 4 agents × (2 epochs × 10 steps × g + 10 forward steps) / 2
    "agents": 2 * 4 * 0.5 * 10 * (2 * G + 1),
    # 3 iterations × (2 kinds × 1 replicate × 2 pairs) × 10 steps × g
    "connectors": 3 * 4 * 10 * G,
    # 2 environments × (4 agents alone × 20 / 2 + 4 types × 1 × 2 pairs × 20)
    "deploy": 2 * (4 * 10 + 8 * 20),
    # 1 novel environment: 2 iterations × 2 pairs × 10 × g, then 2 pairs × 20
    "specialists": 2 * 2 * 10 * G + 2 * 20,
    # 2 environments × 2 variants × 1 replicate × 2 draws × (N=2: 1 + N=4: 2) × 20
    "scaling": 2 * 4 * (1 + 2) * 20,
    # per population (2): evolution (same_shape) or one round of 2 × 2 epochs (same_shape_springs), connector
    # training 3 × 2 pairs × 10 × g, deployment 2 envs × (3 alone × 10 + 1 × 2 pairs × 20)
    "graded": (2 * 3 * 0.5 * 10 * (2 * G + 1) + 3 * 0.5 * 10 * (4 * G + 1)
               + 2 * 3 * 2 * 10 * G + 2 * 2 * (3 * 10 + 2 * 20)),
    # 2 environments × (4 agents alone × 10 + 2 types × 1 × 2 pairs × 20)
    "analysis": 2 * (4 * 10 + 4 * 20),
}
FIT_WORK = 2 * N_FIT * math.log2(N_FIT)  # 1 novel environment × 2 types × 1 replicate
ROUNDS = {"agents": 2, "connectors": 3, "deploy": 2, "specialists": 3, "scaling": 2, "graded": 11, "analysis": 5}
COST = {"agents": 1e-3, "connectors": 2e-3, "deploy": 2e-3, "specialists": 3e-3, "scaling": 4e-3,
        "graded": 5e-3, "analysis": 2e-3}  # s per pair-step equivalent
C_FIT = 1e-2  # s per n log2 n unit of a fit
OVERHEAD = 0.05  # s per round


def busy_of(stage):
    return COST[stage] * WORK[stage] + (C_FIT * FIT_WORK if stage == "analysis" else 0.0)


def write_run(path, ranks, stages=E.STAGES, overhead=OVERHEAD, config=QUICK, total_wall=False, ranks_attr=True):
    """A run file with each stage's busy time (split over ranks) and wall time = busy / ranks + overhead."""
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "divcoll-run"
        if config is not None:
            f.attrs["config"] = config
        if ranks_attr:
            f.attrs["ranks"] = ranks
        for st in stages:
            g = f.create_group(st)
            g.attrs["status"] = "complete"
            b = busy_of(st)
            wall = b / ranks + overhead * ROUNDS[st]
            g.attrs["wall_s_last_session"] = wall
            if total_wall:
                g.attrs["wall_s"] = wall
            g.attrs["busy_s_per_rank_last_session"] = ",".join(f"{b / ranks:.9f}" for _ in range(ranks))


def call(argv):
    """estimate_paper.main in this process: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        rc = E.main(argv)
    return rc, out.getvalue(), err.getvalue()


def paper(**over):
    """configs/paper.toml with section.key overrides (key 'section__key')."""
    cfg = E.load_defaults()
    for k, v in over.items():
        s, key = k.split("__")
        cfg[s][key] = v
    return cfg


class Base(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.dir, name)

    def runs(self, overhead=OVERHEAD):
        write_run(self.path("run_np1.h5"), 1, overhead=overhead)
        write_run(self.path("run_np2.h5"), 2, overhead=overhead * 3)  # oversubscribed-looking, must be ignored
        return E.read_runs(self.dir, E.load_defaults())


class CostTest(Base):
    def test_work_model_matches_the_hand_counts(self):
        cfg = E.merge(E.load_defaults(), E.parse_toml(QUICK, "QUICK"))
        for st in E.STAGES:
            ph = E.stage_phases(cfg, st, G)
            self.assertAlmostEqual(sum(p.work for p in ph if p.kind == "sim"), WORK[st], places=6, msg=st)
            self.assertEqual(sum(p.rounds for p in ph), ROUNDS[st], st)
        fit = sum(p.work for p in E.stage_phases(cfg, "analysis", G) if p.kind == "fit")
        self.assertAlmostEqual(fit, FIT_WORK, places=6)

    def test_cost_per_unit_and_overhead_are_recovered_from_the_one_rank_run(self):
        costs, g, src = E.measure(self.runs())
        self.assertAlmostEqual(g, G, places=5)
        self.assertIn("measured", src)
        for st in E.STAGES:
            c = costs[st]
            self.assertEqual(c.ranks, 1, st)
            self.assertTrue(c.ref.endswith("run_np1.h5"), st)
            self.assertAlmostEqual(c.c_sim / COST[st], 1.0, places=5, msg=st)
            self.assertAlmostEqual(c.overhead, OVERHEAD, places=5, msg=st)
        self.assertAlmostEqual(costs["analysis"].c_fit / C_FIT, 1.0, places=5)
        # the model reproduces the reference run's wall time of every stage
        cfg = E.merge(E.load_defaults(), E.parse_toml(QUICK, "QUICK"))
        for st in E.STAGES:
            self.assertAlmostEqual(E.estimate_stage(cfg, st, costs[st], 1, g),
                                   busy_of(st) + OVERHEAD * ROUNDS[st], places=6, msg=st)

    def test_lowest_rank_count_is_the_reference_without_a_one_rank_run(self):
        write_run(self.path("run_np3.h5"), 3)
        write_run(self.path("run_np2.h5"), 2)
        costs, g, _ = E.measure(E.read_runs(self.dir, E.load_defaults()))
        self.assertEqual(costs["deploy"].ranks, 2)
        self.assertAlmostEqual(costs["agents"].c_sim / COST["agents"], 1.0, places=5)
        self.assertAlmostEqual(g, G, places=5)

    def test_gradient_factor_falls_back_to_the_benchmark_without_connectors(self):
        write_run(self.path("run_np1.h5"), 1, stages=("agents", "scaling"))
        costs, g, src = E.measure(E.read_runs(self.dir, E.load_defaults()))
        self.assertEqual(g, E.DEFAULT_GRAD_FACTOR)
        self.assertIn("BENCHMARKS", src)
        self.assertEqual(sorted(costs), ["agents", "scaling"])


class ScalingTest(Base):
    def setUp(self):
        super().setUp()
        self.costs, self.g, _ = E.measure(self.runs(overhead=0.0))

    def est(self, cfg, stage, p):
        return E.estimate_stage(cfg, stage, self.costs[stage], p, self.g)

    def test_doubling_a_paper_count_doubles_the_stage_at_2_cores(self):
        base = paper()
        for stage, key in (("agents", "agents__population"), ("agents", "agents__episode_steps"),
                            ("connectors", "connectors__iterations"), ("connectors", "connectors__batch_pairs"),
                            ("deploy", "deploy__episode_steps"), ("specialists", "specialists__replicates"),
                            ("scaling", "scaling__draws"), ("scaling", "scaling__episode_steps")):
            s, k = key.split("__")
            doubled = paper(**{key: 2 * base[s][k]})
            self.assertAlmostEqual(self.est(doubled, stage, 2) / self.est(base, stage, 2), 2.0, places=9,
                                   msg=key)

    def test_doubling_rounds_doubles_the_stage_with_its_overhead(self):
        costs, g, _ = E.measure(self.runs(overhead=0.3))
        self.assertAlmostEqual(costs["connectors"].overhead, 0.3, places=5)
        a = E.estimate_stage(paper(), "connectors", costs["connectors"], 2, g)
        b = E.estimate_stage(paper(connectors__iterations=200), "connectors", costs["connectors"], 2, g)
        self.assertAlmostEqual(b / a, 2.0, places=9)

    def test_more_cores_than_items_per_round_do_not_help(self):
        cfg = paper()
        self.assertEqual(E.max_items(cfg, "agents", self.g), 100)  # population
        self.assertEqual(E.max_items(cfg, "connectors", self.g), 4 * 10 * 100)  # kinds × replicates × pairs
        self.assertEqual(self.est(cfg, "agents", 100), self.est(cfg, "agents", 512))
        self.assertEqual(self.est(cfg, "agents", 100), self.est(cfg, "agents", 10_000))
        self.assertAlmostEqual(self.est(cfg, "agents", 50) / self.est(cfg, "agents", 100), 2.0, places=9)
        self.assertGreater(self.est(cfg, "agents", 64), self.est(cfg, "agents", 100))
        self.assertEqual(self.est(cfg, "connectors", 4000), self.est(cfg, "connectors", 8000))
        self.assertGreater(self.est(cfg, "connectors", 2000), self.est(cfg, "connectors", 4000))
        for st in E.STAGES:  # never worse with more cores
            t = [self.est(cfg, st, p) for p in (1, 2, 64, 512, 100_000)]
            self.assertEqual(t, sorted(t, reverse=True), st)


class CliTest(Base):
    def test_table_per_stage_and_total_for_each_core_count(self):
        self.runs()
        rc, out, err = call([self.dir, "--cores", "2", "64", "512"])
        self.assertEqual(rc, 0, err)
        with open(self.path("estimate.md")) as fh:
            md = fh.read()
        self.assertIn(md.strip(), out)
        lines = [l for l in md.splitlines() if l.startswith("| ")]
        self.assertRegex(lines[0], r"2 cores.*\| 64 cores \(h\) \| 512 cores \(h\) \|$")
        for st in E.STAGES + ["**total**"]:
            self.assertTrue(any(l.startswith(f"| {st} |") for l in lines), st)
        self.assertIn("ranks = cores", md)
        self.assertIn("perfect network", md)
        self.assertIn("no I/O contention", md)
        # the total is the sum of the stages (hours), per core count
        costs, g, _ = E.measure(E.read_runs(self.dir, E.load_defaults()))
        total2 = sum(E.estimate_stage(paper(), st, costs[st], 2, g) for st in E.STAGES) / 3600
        total_cell = re.search(r"\| \*\*total\*\* \|[^*]*\*\*([^*]+)\*\*", md).group(1)
        self.assertAlmostEqual(float(total_cell.replace(",", "")), total2, delta=0.01 * total2)

    def test_measured_run_is_compared_at_its_rank_count(self):
        self.runs()
        measured = self.path("paper_run.h5")
        # a "paper-scale" run whose config is the quick one at 1 rank: the model must give its wall time back
        write_run(measured, 1, stages=("agents", "connectors"), total_wall=True)
        rc, out, err = call([self.dir, "--measured", measured])
        self.assertEqual(rc, 0, err)
        rows = [l for l in out.splitlines() if l.startswith("| agents | 1 |") or l.startswith("| connectors | 1 |")]
        self.assertEqual(len(rows), 2, out)
        for r in rows:
            self.assertTrue(r.rstrip().endswith("| 1.00 |"), r)
        with open(self.path("estimate.md")) as fh:
            self.assertIn("| connectors | 1 |", fh.read())

    def test_bad_input_exits_2_with_one_line(self):
        self.runs()
        empty = self.path("empty")
        os.mkdir(empty)
        partial = self.path("partial")
        os.mkdir(partial)
        write_run(os.path.join(partial, "run_np1.h5"), 1, stages=E.STAGES[:-1])  # no analysis timing
        noconf = self.path("noconf")
        os.mkdir(noconf)
        write_run(os.path.join(noconf, "run_np1.h5"), 1, config=None)
        badtoml = self.path("bad.toml")
        with open(badtoml, "w") as fh:
            fh.write("[run\nstages = 3\n")
        unknown = self.path("unknown.toml")
        with open(unknown, "w") as fh:
            fh.write('[run]\nstages = ["agents", "fly"]\n')
        cases = [([self.path("missing")], "no such folder"),
                 ([empty], "no run_np<N>.h5"),
                 ([partial], "no quick run timed stage(s) analysis"),
                 ([noconf], "no config attribute"),
                 ([self.dir, "--paper", self.path("nope.toml")], "no such config file"),
                 ([self.dir, "--paper", badtoml], "not a valid TOML config"),
                 ([self.dir, "--paper", unknown], "unknown stage(s) fly"),
                 ([self.dir, "--measured", self.path("nope.h5")], "no such file"),
                 ([self.dir, "--cores", "0"], "--cores must be positive")]
        for argv, msg in cases:
            rc, out, err = call(argv)
            self.assertEqual(rc, 2, argv)
            self.assertIn(msg, err, argv)
            self.assertEqual(len(err.strip().splitlines()), 1, err)
            self.assertTrue(err.startswith("estimate_paper: "), err)
        # a paper config without the analysis stage needs no analysis timing
        only = self.path("only.toml")
        with open(only, "w") as fh:
            fh.write('[run]\nstages = ["agents", "connectors", "deploy"]\n')
        rc, out, err = call([partial, "--paper", only])
        self.assertEqual(rc, 0, err)
        self.assertNotIn("| analysis |", out)
        # and a real process exit status
        p = subprocess.run([sys.executable, "-m", "divcoll_post.estimate_paper", empty], capture_output=True,
                           text=True, timeout=60, env=dict(os.environ, PYTHONPATH=POST))
        self.assertEqual(p.returncode, 2)
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)


if __name__ == "__main__":
    unittest.main()
