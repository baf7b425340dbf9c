"""Tests of postprocess/fig_scaling.py (the table of jobs/bench-scaling.sh) on synthetic run files whose stage
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

import fig_scaling as F  # noqa: E402


def write_run(path, stages):
    """stages: {name: (wall s, busy per rank, serial text or None)}"""
    with h5py.File(path, "w") as f:
        for name, (wall, busy, serial) in stages.items():
            g = f.create_group(name)
            g.attrs["wall_s_last_session"] = wall
            g.attrs["busy_s_per_rank_last_session"] = ",".join(str(b) for b in busy)
            if serial is not None:
                g.attrs["master_serial_s_last_session"] = serial


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


if __name__ == "__main__":
    unittest.main()
