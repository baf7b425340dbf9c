"""Tests of robustness.py's statistics: the Student t interval over seeds, the verdict rule against a claim's
region, and the runs read from their summaries."""

import os
import sys
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from divcoll_post import verdicts as V  # noqa: E402
from divcoll_post import robustness  # noqa: E402


class RobustnessTest(unittest.TestCase):
    def test_t_interval(self):
        m, lo, hi, n = robustness.t_interval([1.0, 2.0, 3.0])
        # mean 2, s = 1, t(0.975, 2) = 4.302653
        self.assertEqual(n, 3)
        self.assertAlmostEqual(m, 2.0)
        self.assertAlmostEqual(hi - m, 4.302652729749464 / np.sqrt(3), places=9)
        self.assertAlmostEqual(m - lo, hi - m)
        # None and NaN (a seed whose stage is missing) are left out
        self.assertEqual(robustness.t_interval([1.0, None, float("nan"), 3.0])[3], 2)
        m, lo, hi, n = robustness.t_interval([5.0])
        self.assertEqual((m, n), (5.0, 1))
        self.assertTrue(np.isnan(lo) and np.isnan(hi))

    def test_verdict(self):
        v = robustness.verdict
        self.assertEqual(v(*robustness.t_interval([1.0, 1.1, 0.9])), "holds")
        self.assertEqual(v(*robustness.t_interval([-1.0, -1.1, -0.9])), "fails")
        self.assertEqual(v(*robustness.t_interval([1.0, 2.0, -3.0])), "unresolved")
        self.assertEqual(v(*robustness.t_interval([1.0, 1.1])), "too few seeds")
        self.assertEqual(v(*robustness.t_interval([])), "not measured")
        # a claim of equivalence within ±0.5 holds when the interval lies inside, fails when it lies outside
        band = V.region(V.BY_ID["C02"])
        self.assertEqual(v(*robustness.t_interval([0.1, 0.0, -0.1]), band), "holds")
        self.assertEqual(v(*robustness.t_interval([1.0, 1.1, 0.9]), band), "fails")
        self.assertEqual(v(*robustness.t_interval([1.0, 0.0, -1.0]), band), "unresolved")

    def test_summary_run_reads_cells_readings_and_refuses_other_formats(self):
        import json
        import tempfile
        fig = {"environments": ["flat", "ice", "sand"], "types": list(V.MATCHED),
               "alone": {robustness.AS_RUN: [15.0, 6.0, 4.0], "training_length": [5.0, 2.0, 1.0]},
               "collectives": {t: [8.0, 5.0, 3.0] for t in V.MATCHED}}
        data = {"format": robustness.SUMMARY_FORMAT, "version": robustness.SUMMARY_VERSION,
                "config": {"deploy": {"pairs": 100}}, "git_commit": "abc", "base_git_commit": "def",
                "stages_complete": {"deploy": True}, "claims": {}, "fig2a": fig}
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "seed1.summary.json")
            with open(path, "w") as fh:
                json.dump(data, fh)
            r = robustness.SummaryRun(path)  # no arrays beside it: the claims that read Fig. 2A's means
            c07 = V.BY_ID["C07"]  # min over matched types of T(flat) − A(flat): 8 − 15
            self.assertEqual(r.cell(c07), ("did not hold", -7.0))
            self.assertEqual(r.cell(V.BY_ID["C27"]), ("not measured", None))
            self.assertEqual(r.flat, 0)
            self.assertAlmostEqual(r.novel_mean(r.coll["weak_uniform@uniform"]), 4.0)
            self.assertEqual(r.config["deploy"]["pairs"], 100)
            self.assertEqual(r.commits(), {"abc", "def"})
            t = r.reread("training_length")
            self.assertEqual(t.cell(c07), ("held", 3.0))
            np.testing.assert_array_equal(t.alone, [5.0, 2.0, 1.0])
            self.assertIsNone(r.reread("training_rate"))
            data["version"] = robustness.SUMMARY_VERSION + 1
            with open(path, "w") as fh:
                json.dump(data, fh)
            with self.assertRaises(ValueError):
                robustness.SummaryRun(path)
            self.assertEqual(robustness.summary_path(os.path.join(d, "v", "seed3.h5")),
                             os.path.join(d, "v", "seed3.summary.json"))

    def test_fig2a_numbers_over_seeds(self):
        def run(alone, coll, deploy=True):
            return robustness.SummaryRun("x", {
                "format": robustness.SUMMARY_FORMAT, "version": robustness.SUMMARY_VERSION, "config": {},
                "stages_complete": {"deploy": deploy}, "claims": {robustness.AS_RUN: {}},
                "fig2a": {"environments": ["ice", "flat", "sand"], "types": ["weak_diverse@diverse"],
                          "alone": {robustness.AS_RUN: alone}, "collectives": {"weak_diverse@diverse": coll}}})
        runs = [run([6.0, 15.0, 4.0], [3.0, 7.0, 1.0]), run([5.0, 16.0, 3.0], [4.0, 8.0, 2.0]),
                run([7.0, 17.0, 5.0], [5.0, 9.0, 3.0]), run([0.0, 99.0, 0.0], [0.0, 99.0, 0.0], deploy=False)]
        values = robustness.fig2a_values(runs)  # the run without a deploy stage is left out
        self.assertEqual([v[0] for v in values], ["agents alone", "weak_diverse@diverse"])
        self.assertEqual(values[0][1], [15.0, 16.0, 17.0])              # flat is found by name, not position
        self.assertEqual(values[1][2], [2.0, 3.0, 4.0])                 # novel: mean of the other environments
        rows = robustness.fig2a_table(values)
        half = 4.302652729749464 / np.sqrt(3)                           # s = 1 over 3 seeds
        self.assertEqual(rows[2], f"| agents alone | 16.00 [{16 - half:.2f}, {16 + half:.2f}] (15.00, 16.00, 17.00) | "
                                  f"5.00 [{5 - half:.2f}, {5 + half:.2f}] (5.00, 4.00, 6.00) |")
        self.assertTrue(rows[3].startswith("| weak_diverse on diverse | 8.00 ["))
        self.assertEqual(robustness.fig2a_values([runs[3]]), [])

if __name__ == "__main__":
    unittest.main()
