"""Tests of divcoll_post.farm_trace (where a multi-rank run's time goes, from the farm's trace) on synthetic
traces whose every share is known.

    cd <repo> && /usr/bin/python3 -m unittest postprocess/tests/test_farm_trace.py -v
"""
import contextlib
import io
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from divcoll_post import farm_trace as T  # noqa: E402


def write(folder, rank, lines):
    path = os.path.join(folder, f"tr.{rank}")
    with open(path, "w") as fh:
        fh.write("\n".join(f"{k} {t:.6f} {a:.6f} 0" for k, t, a in lines) + "\n")


# Two rounds on two ranks, times in seconds from 100. Round 1: 100.0-101.0; round 2: 101.5-102.0.
# Master (rank 0): items 100.0-100.6 and 101.5-101.9 (tail 0.4 in round 1, 0.1 in round 2); outside 0.5.
# Worker (rank 1): items 100.1-100.5 and 100.7-101.0 (first item's wait 0.1, one wait between items of 0.2,
# taken apart below), then 101.5-102.0; outside 0.5.
MASTER = [("F", 100.0, 2), ("C", 100.6, 100.0), ("G", 100.05, 0), ("R", 100.55, 0), ("G", 100.58, 1),
          ("E", 101.0, 0), ("F", 101.5, 2), ("C", 101.9, 101.5), ("E", 102.0, 0)]
WORKER = [("F", 100.0, 0), ("T", 100.08, 0), ("C", 100.5, 100.1), ("S", 100.52, 0), ("T", 100.65, 0),
          ("C", 101.0, 100.7), ("E", 101.0, 0), ("F", 101.4, 0), ("C", 102.0, 101.5), ("E", 102.0, 0)]


class Decompose(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        write(self.tmp.name, 0, MASTER)
        write(self.tmp.name, 1, WORKER)
        self.prefix = os.path.join(self.tmp.name, "tr")

    def tearDown(self):
        self.tmp.cleanup()

    def test_shares_add_up_and_match_the_construction(self):
        ranks = [T.load(f"{self.prefix}.{r}") for r in range(2)]
        per_rank, wall, rounds = T.decompose(ranks)
        self.assertEqual(rounds, 2)
        self.assertAlmostEqual(wall, 2.0)
        m, w = per_rank
        self.assertAlmostEqual(m["busy"], 1.0)
        self.assertAlmostEqual(m["tail"], 0.5)
        self.assertAlmostEqual(m["outside"], 0.5)
        self.assertAlmostEqual(w["busy"], 1.2)
        self.assertAlmostEqual(w["start"], 0.2)  # 0.1 in each round
        self.assertAlmostEqual(w["gaps"], 0.2)
        self.assertAlmostEqual(w["outside"], 0.4)
        for d in per_rank:  # every second of the traced time is in exactly one column
            self.assertAlmostEqual(sum(d[k] for k in ("busy", "outside", "start", "tail", "gaps")), wall)

    def test_a_wait_between_items_is_taken_apart(self):
        ranks = [T.load(f"{self.prefix}.{r}") for r in range(2)]
        parts = T.handoffs(ranks[0], ranks[1])
        self.assertEqual(len(parts), 1)  # the wait across the round boundary is not one
        want = (0.02, 0.03, 0.03, 0.07, 0.05, 0.2)
        for got, exp in zip(parts[0], want):
            self.assertAlmostEqual(got, exp)

    def test_main_prints_the_table(self):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            self.assertEqual(T.main([self.prefix, "--ranks", "2"]), 0)
        self.assertIn("| 1 | 3 | 1.200 s (60.0%) | 0.400 s (20.0%) | 0.200 s (10.0%)", out.getvalue())
        self.assertIn("rank 1: 1 waits between two items of a round, 0.200 s", out.getvalue())

    def test_bad_input_exits_2(self):
        with open(f"{self.prefix}.1", "a") as fh:
            fh.write("X 1 2 3\n")
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            self.assertEqual(T.main([self.prefix, "--ranks", "2"]), 2)
        self.assertIn("not a farm trace line", err.getvalue())
        with contextlib.redirect_stderr(io.StringIO()):
            self.assertEqual(T.main([self.prefix, "--ranks", "3"]), 2)  # no tr.2


if __name__ == "__main__":
    unittest.main()
