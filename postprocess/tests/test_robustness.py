"""Tests of robustness.py's statistics: the Student t interval over seeds and the verdict rule, and that every
claim of claims.py has an effect."""

import os
import sys
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

import claims  # noqa: E402
import robustness  # noqa: E402


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
        # a claim of no difference holds when the interval contains 0
        self.assertEqual(v(*robustness.t_interval([1.0, 2.0, -3.0]), equal=True), "holds")
        self.assertEqual(v(*robustness.t_interval([1.0, 1.1, 0.9]), equal=True), "fails")

    def test_every_claim_has_an_effect(self):
        for text, fn in claims.CLAIMS:
            self.assertIn(fn, robustness.EFFECTS, text)


if __name__ == "__main__":
    unittest.main()
