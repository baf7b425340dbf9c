"""Tests of summary.py on a synthetic run file: not-ok episodes are counted and never averaged, novel
means are means of environment means, the claims' lines follow the numbers."""

import os
import sys
import tempfile
import unittest

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from divcoll_post import single_run as claims  # noqa: E402
from divcoll_post import summary  # noqa: E402
from divcoll_post import results  # noqa: E402


# the paper's counts: claims are judged only where a run has the counts their tests need
PAPER = ('[run]\nname = "synthetic"\n[agents]\npopulation = 100\ngenerations = 15\n[connectors]\nreplicates = 10\n'
         'iterations = 100\nbatch_pairs = 100\n[deploy]\npairs = 100\nenvironments = ["flat", "ice", "gap"]\n')
QUICK = PAPER.replace("population = 100", "population = 24").replace("replicates = 10", "replicates = 2")


class SummaryTest(unittest.TestCase):
    config = PAPER

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.dir.name, "run.h5")
        envs = ["flat", "ice", "gap"]
        types = ["weak_uniform@uniform", "weak_uniform@diverse"]
        with h5py.File(self.path, "w") as f:
            f.attrs["format"] = "divcoll-run"
            f.attrs["seed"] = 1
            f.attrs["config"] = self.config
            d = f.create_group("deploy")
            d.attrs["status"] = "complete"
            d.attrs["environments"] = ",".join(envs)
            d.attrs["types"] = ",".join(types)
            d.attrs["envs_done"] = 3
            # agents alone: flat 1.0; ice 0.5; gap 0.1 — one flat episode is nan and holds a huge number
            a = np.array([[1.0, 1.0, 1e9], [0.5, 0.5, 0.5], [0.1, 0.1, 0.1]])
            s = np.zeros((3, 3), np.uint8)
            s[0, 2] = 1
            d["agents/travel_bl"] = a
            d["agents/status"] = s
            # collectives (E, T, R=1, N=2): type 0 beats agents on flat (2.0), type 1 does not (0.5)
            c = np.zeros((3, 2, 1, 2))
            c[0, 0], c[0, 1] = 2.0, 0.5
            c[1, 0], c[1, 1] = 0.2, 1.0
            c[2, 0], c[2, 1] = 0.2, 0.6
            d["collectives/travel_bl"] = c
            d["collectives/status"] = np.zeros(c.shape, np.uint8)

    def tearDown(self):
        self.dir.cleanup()

    def test_not_ok_episodes_are_counted_and_left_out(self):
        text = summary.summarize(self.path)
        row = [l for l in text.splitlines() if l.startswith("| independent agents")][0]
        cells = [c.strip() for c in row.split("|")[1:-1]]
        self.assertEqual(cells[1], "1.000")  # the nan episode's 1e9 is not in the mean
        self.assertEqual(cells[2], "0.300")  # (0.5 + 0.1) / 2: a mean of environment means
        self.assertEqual(cells[3], "1")

    def test_provenance_names_the_kernel_path_and_cpu_when_the_file_has_them(self):
        self.assertNotIn("kernels", summary.summarize(self.path).splitlines()[2])
        with h5py.File(self.path, "a") as f:
            f.attrs["kernels"] = "avx2"
            f.attrs["cpu"] = "AMD EPYC (x86_64)"
            f.attrs["build_target"] = "x86-64 baseline"
        self.assertIn("; kernels avx2 on AMD EPYC (x86_64), built for x86-64 baseline",
                      summary.summarize(self.path).splitlines()[2])

    def test_claim_lines_follow_the_numbers(self):
        text = summary.summarize(self.path)
        self.assertIn("beating independent agents on flat: 1 of 2", text)
        self.assertIn("best type in the novel environments: weak_uniform@diverse (0.800 BL)", text)

    def test_claims_follow_the_numbers_and_missing_stages_are_not_measured(self):
        got = {c.text: (number, v) for c, number, v, _ in claims.claims(self.path)}
        by_start = lambda s: next(v for k, v in got.items() if k.startswith(s))  # noqa: E731
        # C03: agents alone drop from 1.0 BL on flat (the nan episode left out) to (0.5 + 0.1) / 2 in the novel ones
        number, v = by_start("Deployed alone, agents are severely compromised")
        self.assertEqual(v, "too small to judge")  # held, but three environments are fewer than the claim needs
        self.assertEqual(next(n for c, _, _, n in claims.claims(self.path) if c.id == "C03"),
                         "short: environments 3 (needs ≥ 7)")
        self.assertIn("agents alone 70%", number)
        self.assertIn("effect +0.45", number)
        # C07 compares the four kinds deployed as trained: this run has two types only
        self.assertEqual(by_start("Trained collectives of all four kinds")[1], "not measured")
        self.assertEqual(by_start("Trained agents travel")[1], "not measured")  # no agents stage in the file
        self.assertEqual(by_start("The advantage of diversity grows")[1], "not measured")

    def test_scale_names_the_preset_and_the_papers_counts(self):
        name, rows = claims.scale(self.path)
        self.assertEqual(name, "synthetic")
        row = next(r for r in rows if r[1] == "deploy.pairs")
        self.assertEqual(row[2:], (100, 100))
        self.assertEqual(next(r for r in rows if r[1] == "deploy.environments")[2], 3)

    def test_a_claim_from_a_nan_is_not_measured(self):
        with h5py.File(self.path, "r+") as f:
            a = f["deploy/agents/travel_bl"][()]
            a[0] = np.nan  # every flat episode of agents alone: their flat mean is NaN
            f["deploy/agents/travel_bl"][...] = a
        got = {c.text: (number, v) for c, number, v, _ in claims.claims(self.path)}
        number, v = next(val for k, val in got.items() if k.startswith("Deployed alone, agents are severely"))
        self.assertIn("nan", number)
        self.assertEqual(v, "not measured")

    def test_ok_mean_of_nothing_is_nan_not_zero(self):
        m, bad = results.ok_mean([1.0, 2.0], [1, 2])
        self.assertTrue(np.isnan(m))
        self.assertEqual(bad, 2)


class SmallRunTest(SummaryTest):
    """the same numbers from a run at the quick preset's counts: every judged claim is too small to judge, and
    says which count is short"""
    config = QUICK

    def test_claims_follow_the_numbers_and_missing_stages_are_not_measured(self):
        got = {c.text: (v, needs) for c, _, v, needs in claims.claims(self.path)}
        v, needs = next(val for k, val in got.items() if k.startswith("Deployed alone, agents are severely"))
        self.assertEqual(v, "too small to judge")
        self.assertIn("agents 24 (needs ≥ 50)", needs)
        self.assertIn("connector replicates 2 (needs ≥ 5)", needs)
        self.assertNotIn("deployed pairs", needs)  # pairs are large enough
        self.assertEqual(next(val for k, val in got.items() if k.startswith("Trained agents travel"))[0], "not measured")


class StageTimingTest(unittest.TestCase):
    """the stage table's last-session column: ranks, busy share of rank-time, rank 0's share, max / mean busy"""

    def test_busy_shares_and_imbalance_from_the_attributes(self):
        attrs = {"wall_s_last_session": 10.0, "busy_s_per_rank_last_session": "9,6"}
        self.assertEqual(summary.busy_text(attrs), "2, 75%, 90%, 1.20")

    def test_a_stage_without_timing_says_so(self):
        self.assertEqual(summary.busy_text({}), "–")
        self.assertEqual(summary.busy_text({"wall_s_last_session": 0.0, "busy_s_per_rank_last_session": "1"}), "–")


if __name__ == "__main__":
    unittest.main()
