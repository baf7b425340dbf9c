"""Tests of divcoll_post.farm_model (the efficiency of task-farm rounds from the master's measured cost) and of
divcoll_post.estimate_paper --farm, on synthetic bench-farm CSVs.

    cd <repo> && /usr/bin/python3 -m unittest postprocess/tests/test_farm_model.py -v
"""
import contextlib
import io
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from divcoll_post import estimate_paper as E  # noqa: E402
from divcoll_post import farm_model as F  # noqa: E402

HEAD = ("ranks,computing,items,item_ms,result_bytes,block,depth,fold,round_s,ideal_s,efficiency,"
        "master_cpu_us_per_item,task_us_per_msg,task_us_per_item,result_us_per_msg,result_us_per_item,"
        "bytes_per_result,task_msgs_per_round,result_msgs_per_round,fold_us_per_result")


def row(ranks, block, fold, serve, task, fold_us, round_s=1):
    return (f"{ranks},{ranks - 1},4000,2,11800,{block},2,{fold},{round_s},1,1,{serve},{task},0,0,0,11817,100,100,"
            f"{fold_us}")


def waiting_master_row(ranks, fold, a, b_us, item_ms=6.0, items=4000):
    """A row whose master spends a share a of each round waiting and b_us per item: CPU per item a w / n + b."""
    w = items * item_ms * 1e-3 / (ranks - 1)
    return row(ranks, 0, fold, a * w / items * 1e6 + b_us, 2.0, 3.0, round_s=w)


def write_csv(folder, rows):
    path = os.path.join(folder, "farm.csv")
    with open(path, "w") as fh:
        fh.write("\n".join([HEAD] + rows) + "\n")
    return path


class RoundModel(unittest.TestCase):
    def test_free_master_gives_the_share_of_the_workers(self):
        # 10 items of 1 s on 3 ranks: 2 workers, 5 items each -> 5 s, efficiency 10 / (3 * 5)
        T, e = F.round_time(10, 1.0, 3, 0.0, 0.0, 0.0)
        self.assertAlmostEqual(T, 5.0)
        self.assertAlmostEqual(e, 10 / 15)
        # 2 ranks: the master computes too
        T, e = F.round_time(10, 1.0, 2, 0.0, 0.0, 0.0)
        self.assertAlmostEqual((T, e), (5.0, 1.0))

    def test_a_slow_master_bounds_the_round(self):
        # 1000 items of 1 ms on 101 ranks: 10 ms of work per worker, but 100 µs per item at the master = 100 ms
        T, e = F.round_time(1000, 1e-3, 101, 100.0, 0.0, 0.0)
        self.assertAlmostEqual(T, 0.1)
        self.assertAlmostEqual(e, 1.0 / (101 * 0.1))

    def test_first_wave_and_fold_after_add_to_the_round(self):
        T0, _ = F.round_time(100, 1e-2, 11, 0.0, 0.0, 0.0)
        T1, _ = F.round_time(100, 1e-2, 11, 0.0, 10.0, 0.0)
        T2, _ = F.round_time(100, 1e-2, 11, 0.0, 0.0, 5.0)
        self.assertAlmostEqual(T1 - T0, 10 * 10e-6)   # 10 workers' first blocks
        self.assertAlmostEqual(T2 - T0, 100 * 5e-6)   # 100 results folded after the round

    def test_no_items(self):
        self.assertEqual(F.round_time(0, 1.0, 8, 1.0, 1.0, 1.0), (0.0, 1.0))


class Costs(unittest.TestCase):
    def test_guided_rows_of_the_largest_rank_count_are_used(self):
        with tempfile.TemporaryDirectory() as d:
            path = write_csv(d, [row(8, 0, "after", 1.0, 1.0, 1.0), row(32, 1, "after", 99.0, 99.0, 99.0),
                                 row(32, 0, "after", 5.0, 2.0, 3.0), row(32, 0, "during", 7.0, 2.0, 3.0)])
            top, rows = F.read_costs(path)
            self.assertEqual(top, 32)
            self.assertEqual(float(rows["after"]["master_cpu_us_per_item"]), 5.0)
            self.assertEqual(float(rows["during"]["master_cpu_us_per_item"]), 7.0)
            farm = E.read_farm(path)
            self.assertEqual((farm.c_serve, farm.c_task), (7.0, 2.0))

    def test_fit_separates_waiting_from_the_cost_per_item(self):
        with tempfile.TemporaryDirectory() as d:
            path = write_csv(d, [waiting_master_row(p, f, 0.02, b) for p in (8, 16, 32)
                                 for f, b in (("after", 5.0), ("during", 8.0))])
            top, rows = F.read_costs(path)
            a, b, c = rows["during"]["fit"]
            self.assertAlmostEqual(a, 0.02, places=9)
            self.assertAlmostEqual(b, 8.0, places=6)
            self.assertAlmostEqual(c, 8.0 / 0.98, places=6)
            self.assertAlmostEqual(F.serve_cost(rows["after"], "fit"), 5.0 / 0.98, places=6)
            # the 32-rank row alone still counts the waiting: a w / n on top of b
            self.assertGreater(F.serve_cost(rows["during"], "top"), 8.0 + 0.02 * 0.7 / 4000 * 1e6 - 1e-9)
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                self.assertEqual(F.main([path, "--ranks", "512", "--item-ms", "6"]), 0)
            T, e = F.round_time(4000, 6e-3, 512, 8.0 / 0.98, 2.0, 0.0)
            self.assertIn(f"{e:.0%} ({T * 1e3:.0f} ms)", out.getvalue())
            self.assertIn("waiting 2.0% of a core", out.getvalue())

    def test_one_rank_count_cannot_be_fitted(self):
        with tempfile.TemporaryDirectory() as d:
            path = write_csv(d, [row(32, 0, "after", 5.0, 2.0, 3.0)])
            _, rows = F.read_costs(path)
            self.assertIsNone(rows["after"]["fit"])
            self.assertEqual(F.serve_cost(rows["after"], "fit"), 5.0)

    def test_table_has_a_row_per_stage_item_time_and_fold(self):
        with tempfile.TemporaryDirectory() as d:
            path = write_csv(d, [row(32, 0, "after", 5.0, 2.0, 3.0), row(32, 0, "during", 7.0, 2.0, 3.0)])
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                self.assertEqual(F.main([path, "--ranks", "64", "512", "--item-ms", "10", "--cost", "top"]), 0)
            lines = [x for x in out.getvalue().splitlines() if x.startswith("| connectors") or x.startswith("| specialists")]
            self.assertEqual(len(lines), 4)  # 2 stages x 1 item time x 2 folds
            # connectors: 4 kinds x 10 replicates x 100 pairs; at 64 ranks ceil(4000 / 63) = 64 items of 10 ms
            T, e = F.round_time(4000, 0.01, 64, 7.0, 2.0, 0.0)
            self.assertIn(f"{e:.0%} ({T * 1e3:.0f} ms)", lines[1])

    def test_bad_input_exits_2(self):
        with tempfile.TemporaryDirectory() as d:
            err = io.StringIO()
            with contextlib.redirect_stderr(err):
                self.assertEqual(F.main([os.path.join(d, "none.csv")]), 2)
            self.assertTrue(err.getvalue().startswith("farm_model: "))
            bad = os.path.join(d, "bad.csv")
            with open(bad, "w") as fh:
                fh.write("a,b\n1,2\n")
            with contextlib.redirect_stderr(io.StringIO()):
                self.assertEqual(F.main([bad]), 2)


class EstimateWithFarm(unittest.TestCase):
    def test_farm_cost_bounds_rounds_at_many_ranks(self):
        farm = E.FarmCost(c_serve=50.0, c_task=1.0, source="test")
        items = [(4000, 1.0)]
        # 2 ranks: both compute; only the two first blocks' messages are added
        self.assertAlmostEqual(E.round_time(items, 2, 1e-2, farm) - E.round_time(items, 2, 1e-2), 2e-6)
        plain, slow = E.round_time(items, 512, 1e-2), E.round_time(items, 512, 1e-2, farm)
        self.assertAlmostEqual(plain, 8 * 1e-2)
        self.assertAlmostEqual(slow, 4000 * 50e-6)  # the master serves 4000 items at 50 µs: 0.2 s


if __name__ == "__main__":
    unittest.main()
