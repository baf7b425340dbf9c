"""divcoll_post.tether: the page of `divcoll tether`'s tables, one population or several, on synthetic tether.csv
files whose answers are known: each agent against the free tether of the same pair, the push as a share of the
tether's force, episodes that did not end ok left out, and the populations' range.

    /usr/bin/python3 -m unittest postprocess/tests/test_tether.py"""
import csv
import gzip
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from divcoll_post import tether  # noqa: E402

HEADER = ["environment", "deployment", "connector", "pair", "posterior", "anterior", "status", "pair_travel_bl",
          "posterior_travel_bl", "anterior_travel_bl", "posterior_impulse_x", "anterior_impulse_x", "posterior_work",
          "anterior_work", "force_time"]


def write_csv(path, shift):
    """two pairs on flat, diverse: under the free tether the posterior is the slower agent of pair 0 and the anterior of
    pair 1; the trained tether takes 1 + shift BL from the faster agent and gives 0.5 to the slower, pushes the slower
    agent with 10% of its force and takes 20 units of work; a third, unstable pair is left out"""
    rows = []
    for q, (p_bl, a_bl) in enumerate([(2.0, 3.0), (4.0, 1.0), (1.0, 1.0)]):
        free = dict(environment="flat", deployment="diverse", connector="free", pair=q, posterior=q, anterior=q + 1,
                    status="ok", pair_travel_bl=(p_bl + a_bl) / 2, posterior_travel_bl=p_bl, anterior_travel_bl=a_bl,
                    posterior_impulse_x=0, anterior_impulse_x=0, posterior_work=0, anterior_work=0, force_time=0)
        slow_is_p = p_bl <= a_bl
        tp = p_bl + (0.5 if slow_is_p else -(1 + shift))
        ta = a_bl + (-(1 + shift) if slow_is_p else 0.5)
        push_p = 10.0 if slow_is_p else -10.0
        trained = dict(free, connector="trained", status="ok" if q < 2 else "unstable", pair_travel_bl=(tp + ta) / 2,
                       posterior_travel_bl=tp, anterior_travel_bl=ta, posterior_impulse_x=push_p,
                       anterior_impulse_x=-push_p, posterior_work=-15, anterior_work=-5, force_time=100.0)
        rows += [free, trained]
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "wt", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, HEADER)
        w.writeheader()
        w.writerows(rows)


class Tether(unittest.TestCase):
    def test_each_agent_against_the_free_tether_over_populations(self):
        with tempfile.TemporaryDirectory() as d:
            paths = [os.path.join(d, f"besteffort_seed{s}", "tether.csv.gz") for s in (3, 4)]
            for p in paths:
                os.makedirs(os.path.dirname(p))
            write_csv(paths[0], 0.0)
            write_csv(paths[1], 1.0)
            one = tether.read(paths[0])[("flat", "diverse", "trained")]
            self.assertAlmostEqual(one["slower"], 0.5)
            self.assertAlmostEqual(one["faster"], -1.0)
            self.assertAlmostEqual(one["pair"], -0.25)
            self.assertAlmostEqual(one["push"], 0.1)
            self.assertAlmostEqual(one["work"], -20.0)
            pops, table, envs = tether.summarise(paths)
            self.assertEqual((pops, envs), (["3", "4"], ["flat"]))
            page = tether.page(paths, os.path.join(d, "out"))
            with open(page, encoding="utf-8") as fh:
                text = fh.read()
            self.assertIn("| flat | trained | 2.00 [1.75, 2.25] | -0.50 [-0.75, -0.25] | +0.50 [+0.50, +0.50] | "
                          "-1.50 [-2.00, -1.00] | "
                          "+10.0 [+10.0, +10.0]% | -20 [-20, -20] |", text)
            self.assertTrue(os.path.getsize(os.path.join(d, "out", "tether.png")) > 1000)

    def test_one_population_with_the_provenance_divcoll_tether_passes(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "tether.csv")
            write_csv(path, 0.0)
            prov = "Run file `r.h5`; command `divcoll tether`."
            self.assertEqual(tether.main([path, "--out", d, "--provenance", prov, "--divcoll", "/bin/true"]), 0)
            with open(os.path.join(d, "tether.md"), encoding="utf-8") as fh:
                text = fh.read()
            self.assertIn(prov, text)
            self.assertIn("Means over the pairs.", text)
            self.assertIn("| flat | trained | 2.25 | -0.25 | +0.50 | -1.00 | +10.0% | -20 |", text)

    def test_a_missing_file_is_refused(self):
        self.assertEqual(tether.main(["/nonexistent/tether.csv", "--out", "/tmp/x"]), 2)


if __name__ == "__main__":
    unittest.main()
