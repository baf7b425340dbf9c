"""Tests of divcoll_post.figures.fig_scaling (the table of jobs/bench-scaling.sh) on synthetic run files whose stage
timing attributes are set by hand.

    cd <repo> && /usr/bin/python3 -m unittest postprocess/tests/test_fig_scaling.py -v
"""

import contextlib
import io
import os
import sys
import tempfile
import unittest

import h5py

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from divcoll_post.figures import fig_scaling as F  # noqa: E402


def write_run(path, stages, cpu=None):
    """stages: {name: (wall s, busy per rank, serial text or None)}; cpu: {name: (compute CPU s per rank, serving
    CPU s per rank)}"""
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "divcoll-run"
        for name, (wall, busy, serial) in stages.items():
            g = f.create_group(name)
            g.attrs["wall_s_last_session"] = wall
            g.attrs["busy_s_per_rank_last_session"] = ",".join(str(b) for b in busy)
            if serial is not None:
                g.attrs["master_serial_s_last_session"] = serial
            if cpu and name in cpu:
                g.attrs["compute_cpu_s_per_rank_last_session"] = ",".join(str(c) for c in cpu[name][0])
                g.attrs["serve_cpu_s_per_rank_last_session"] = ",".join(str(c) for c in cpu[name][1])


class FigScalingTest(unittest.TestCase):
    def test_parse_serial(self):
        self.assertEqual(F.parse_serial("input=0.5,items=0.25,writes=1,commits=0"),
                         {"input": 0.5, "items": 0.25, "writes": 1.0, "commits": 0.0})
        self.assertEqual(F.parse_serial(""), {})
        self.assertEqual(F.parse_serial("input=abc"), {})

    def test_table_has_speed_up_busy_and_serial_time(self):
        with tempfile.TemporaryDirectory() as d:
            write_run(os.path.join(d, "run_np1.h5"), {"agents": (10.0, [9.0], "input=0,items=0.1,writes=0.2,commits=0.1"),
                                                      "deploy": (20.0, [19.0], None)})
            write_run(os.path.join(d, "run_np2.h5"), {"agents": (5.0, [4.5, 4.0], "input=0.1,items=0.1,writes=0.3,commits=0.1"),
                                                      "deploy": (8.0, [7.0, 8.0], None)})
            with contextlib.redirect_stdout(io.StringIO()):
                self.assertEqual(F.main([d, "--cores", "2"]), 0)
            md = open(os.path.join(d, "scaling.md")).read()
            agents = next(line for line in md.splitlines() if line.startswith("| agents"))
            self.assertIn("10.0 s, busy 90%", agents)
            self.assertIn("serial 0.40 s", agents)  # 1 rank: 0 + 0.1 + 0.2 + 0.1
            self.assertIn("5.0 s (×2.00), busy 85% (per rank 90%/80%), imbalance 1.06, serial 0.60 s", agents)
            deploy = next(line for line in md.splitlines() if line.startswith("| deploy"))
            self.assertIn("8.0 s (×2.50)", deploy)
            self.assertNotIn("serial", deploy)  # runs made before the attribute existed
            self.assertIn("**13.0 s** (×2.31)", md)
            csv = open(os.path.join(d, "scaling.csv")).read().splitlines()
            self.assertEqual(csv[0].split(",")[6], "master_serial_s")
            self.assertTrue(os.path.getsize(os.path.join(d, "scaling.png")) > 0)

    def test_two_one_rank_runs_at_once_give_the_cap_for_two_ranks(self):
        with tempfile.TemporaryDirectory() as d:
            write_run(os.path.join(d, "run_np1.h5"), {"agents": (10.0, [9.0], None), "deploy": (20.0, [19.0], None)})
            write_run(os.path.join(d, "run_np2.h5"), {"agents": (6.0, [5.0, 5.0], None), "deploy": (11.0, [10.0, 10.0], None)})
            # at once, each is slower than alone: agents 11 and 13 s (cap 2 x 10 / 12 = 1.67), deploy 20 s (cap 2.00)
            write_run(os.path.join(d, "concurrent_a.h5"), {"agents": (11.0, [10.0], None), "deploy": (20.0, [19.0], None)})
            write_run(os.path.join(d, "concurrent_b.h5"), {"agents": (13.0, [12.0], None), "deploy": (20.0, [19.0], None)})
            with contextlib.redirect_stdout(io.StringIO()):
                self.assertEqual(F.main([d, "--cores", "2"]), 0)
            md = open(os.path.join(d, "scaling.md")).read().splitlines()
            self.assertIn("two 1-rank runs at once", md[0])
            self.assertEqual(md[1].count("---"), 4)  # stage, 1 rank, 2 ranks, at once
            agents = next(line for line in md if line.startswith("| agents"))
            # 2 ranks: 10 / 6 = x1.67, which is 100% of the cap x1.67
            self.assertIn("6.0 s (×1.67, 100% of the cap)", agents)
            self.assertIn("11.0 s, 13.0 s: cap ×1.67", agents)
            deploy = next(line for line in md if line.startswith("| deploy"))
            self.assertIn("11.0 s (×1.82, 91% of the cap)", deploy)
            self.assertIn("20.0 s, 20.0 s: cap ×2.00", deploy)
            total = next(line for line in md if line.startswith("| total"))
            # cap of the whole: 2 x 30 / mean(31, 33) = 1.875; 2 ranks 30 / 17 = 1.765 = 94% of it
            self.assertIn("**17.0 s** (×1.76, 94% of the cap)", total)
            self.assertIn("31.0 s, 33.0 s: **cap ×1.88**", total)

    def test_cpu_shares_of_the_computing_and_serving_threads(self):
        with tempfile.TemporaryDirectory() as d:
            write_run(os.path.join(d, "run_np1.h5"), {"agents": (10.0, [9.0], None)}, {"agents": ([9.0], [0.0])})
            # busy 5 + 4 s, on a core 4.5 + 3.6 s = 90%; serving 0.1 + 0.2 s of 2 x 5 s = 3.0% of a core
            write_run(os.path.join(d, "run_np2.h5"), {"agents": (5.0, [5.0, 4.0], None)},
                      {"agents": ([4.5, 3.6], [0.1, 0.2])})
            with contextlib.redirect_stdout(io.StringIO()):
                self.assertEqual(F.main([d, "--cores", "2"]), 0)
            md = open(os.path.join(d, "scaling.md")).read()
            agents = next(line for line in md.splitlines() if line.startswith("| agents"))
            self.assertIn("computing on a core 90% of busy, serving 3.0% of a core", agents)
            # implied: 2 x (9 / 10) busy x 0.9 on a core / (9 / 10) busy at 1 rank = 1.80
            self.assertIn("; implied ×1.80", agents)
            self.assertEqual(agents.count("computing on a core"), 1)  # not at 1 rank

    def test_without_both_concurrent_runs_there_is_no_cap_column(self):
        with tempfile.TemporaryDirectory() as d:
            write_run(os.path.join(d, "run_np1.h5"), {"agents": (10.0, [9.0], None)})
            write_run(os.path.join(d, "run_np2.h5"), {"agents": (6.0, [5.0, 5.0], None)})
            write_run(os.path.join(d, "concurrent_a.h5"), {"agents": (11.0, [10.0], None)})
            with contextlib.redirect_stdout(io.StringIO()):
                self.assertEqual(F.main([d, "--cores", "2"]), 0)
            md = open(os.path.join(d, "scaling.md")).read()
            self.assertNotIn("cap", md)
            self.assertEqual(F.read_concurrent(d), {})


if __name__ == "__main__":
    unittest.main()
