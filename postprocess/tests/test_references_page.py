"""The verdict page's reference connectors, the amendment statistics (C24b, the spread rule, claims on Holm's
threshold), the 1000-step column of the README table and the Fig. S2 table, on synthetic kept studies."""
import copy
import os
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)
from divcoll_post import verdict_page, verdicts as V  # noqa: E402
from test_verdicts import ENVS, kept_study, md_table, synthetic  # noqa: E402

REFS = ["free@uniform", "free@diverse", "passive@uniform", "passive@diverse", "follower@uniform", "follower@diverse"]


def with_references(a, shares=(1.0, 0.9, 0.3, 0.3, 0.6, 0.55)):
    """a run's arrays as verdicts_references.toml keeps them: the same agents alone, the references at `shares` of
    agents alone in every environment"""
    r = copy.deepcopy(a)
    alone = np.asarray(r["deploy"]["alone_bl"])
    r["deploy"]["references"] = REFS
    r["deploy"]["references_bl"] = (alone[:, None] * np.asarray(shares)[None, :]).tolist()
    r["deploy"]["references_ok"] = np.full((len(ENVS), len(REFS)), 100).tolist()
    return r


class References(unittest.TestCase):
    def setUp(self):
        rng = np.random.Generator(np.random.PCG64(3))
        self.runs = {s: synthetic(s, rng) for s in range(1, 5)}
        self.tmp = tempfile.TemporaryDirectory()
        self.study = os.path.join(self.tmp.name, "verdicts")
        kept_study(self.study, {"baseline": self.runs})

    def tearDown(self):
        self.tmp.cleanup()

    def test_the_page_shows_each_populations_references_as_shares_of_agents_alone(self):
        kept_study(verdict_page.references_folder(self.study),
                   {"references": {s: with_references(a) for s, a in self.runs.items()}})
        with open(verdict_page.write(self.study, os.path.join(self.tmp.name, "page"), B=500)) as fh:
            text = fh.read()
        rows = md_table(text, "| population | agents alone |")
        self.assertEqual([r[0] for r in rows[:-1]], ["1", "2", "3", "4"])
        header = [c.strip() for c in text.splitlines()[text.splitlines().index(
            next(ln for ln in text.splitlines() if ln.startswith("| population | agents alone |")))].strip("|").split("|")]
        for r in rows[:-1]:
            cells = dict(zip(header, r))
            self.assertTrue(cells["free@uniform"].endswith("(100%)"), cells)
            self.assertTrue(cells["passive@uniform"].endswith("(30%)"), cells)
            self.assertTrue(cells["follower@diverse"].endswith("(55%)"), cells)
        self.assertIn("| reference follower@uniform |", text)  # Fig. 2A's table has the references too

    def test_a_reference_run_of_other_agents_is_refused(self):
        other = {s: with_references(a) for s, a in self.runs.items()}
        other[2]["deploy"]["alone_bl"][3] += 1e-9
        kept_study(verdict_page.references_folder(self.study), {"references": other})
        pops = V.load_study(self.study, ["baseline"])
        with self.assertRaisesRegex(ValueError, "seed 2's agents alone differ"):
            verdict_page.attach_references(pops, verdict_page.references_folder(self.study))

    def test_without_references_the_page_says_so(self):
        with open(verdict_page.write(self.study, os.path.join(self.tmp.name, "page"), B=500)) as fh:
            text = fh.read()
        self.assertIn("No reference connectors for these populations", text)


class PairsAgainstAlone(unittest.TestCase):
    def test_each_environment_shows_the_pairs_difference_from_agents_alone(self):
        rng = np.random.Generator(np.random.PCG64(4))
        runs = {s: synthetic(s, rng) for s in range(1, 5)}
        pops = []
        for s, a in runs.items():
            alone = np.asarray(a["deploy"]["alone_bl"], float)
            coll = np.asarray(a["deploy"]["collectives_bl"], float)
            # the matched weak pairs travel 2 BL less than alone on flat, 0.5 BL more in the last environment,
            # except in population 4, where they travel 0.5 BL less there
            for t in (V.WU, V.WD):
                ti = a["deploy"]["types"].index(t)
                coll[0, ti, :] = alone[0] - 2.0
                coll[-1, ti, :] = alone[-1] + (0.5 if s < 4 else -0.5)
            a["deploy"]["collectives_bl"] = coll.tolist()
            pops.append(V.Population(s, [a]))
        lines = verdict_page.pairs_vs_alone_lines([("paper-faithful", pops), ("best-effort", pops[:2])], B=300)
        rows = {r[0]: r for r in md_table("\n".join(lines), "| environment | agents alone |")}
        self.assertEqual(set(rows), set(ENVS))
        flat, last = rows["flat"], rows[ENVS[-1]]
        self.assertTrue(flat[2].startswith("-2.00 [-2.00, -2.00] (0/4)"), flat)
        self.assertTrue(last[2].startswith("+0.25 ["), last)
        self.assertTrue(last[2].endswith("(3/4)"), last)
        self.assertEqual(last[4], "+0.50 (2/2)")  # two populations: no interval
        self.assertEqual(verdict_page.pairs_vs_alone_lines([("paper-faithful", [])]), [])

    def test_each_environment_also_shows_the_pair_against_the_free_pair_on_the_same_pairs(self):
        rng = np.random.Generator(np.random.PCG64(6))
        pops = []
        for s in range(1, 5):
            a = with_references(synthetic(s, rng))
            alone = np.asarray(a["deploy"]["alone_bl"], float)
            coll = np.asarray(a["deploy"]["collectives_bl"], float)
            refs = np.asarray(a["deploy"]["references_bl"], float)
            # in the last environment the free pair travels 0.3 BL beyond agents alone (placement), the matched
            # weak pairs 0.5 BL: 0.2 of it is the tether's; on flat the pairs lose 2 BL to both
            for t in (V.WU, V.WD):
                ti = a["deploy"]["types"].index(t)
                coll[0, ti, :] = alone[0] - 2.0
                coll[-1, ti, :] = alone[-1] + 0.5
                refs[-1, REFS.index(verdict_page.FREE[t])] = alone[-1] + 0.3
            a["deploy"]["collectives_bl"] = coll.tolist()
            a["deploy"]["references_bl"] = refs.tolist()
            pops.append(V.Population(s, [a]))
        no_refs = V.Population(5, [synthetic(5, rng)])
        lines = verdict_page.pairs_vs_alone_lines([("paper-faithful", pops + [no_refs]), ("best-effort", pops[:2])],
                                                  B=300)
        rows = {r[0]: r for r in md_table("\n".join(lines), "| environment | free pair − agents alone |")}
        self.assertEqual(set(rows), set(ENVS))
        flat, last = rows["flat"], rows[ENVS[-1]]
        free_d = np.mean([-0.1 * p.alone()[0] for p in pops])  # free@diverse: 0.9 of agents alone (with_references)
        self.assertEqual(flat[1], f"+0.00 / {free_d:+.2f}")
        self.assertTrue(flat[2].startswith("-2.00 [-2.00, -2.00] (0/4)"), flat)  # the population without references
        self.assertEqual(last[1], "+0.30 / +0.30")                                # is left out of this table
        self.assertTrue(last[2].startswith("+0.20 [+0.20, +0.20] (4/4)"), last)
        self.assertEqual(last[4], "+0.20 (2/2)")
        self.assertIn("paper-faithful 4, best-effort 2", "\n".join(lines))


class AmendmentStatistics(unittest.TestCase):
    def test_c24b_is_the_log_ratio_of_exclusive_states(self):
        rng = np.random.Generator(np.random.PCG64(5))
        a = synthetic(1, rng, R=2)
        w = ENVS[1:].index("wind")
        fam = {t: np.full((12, 2, 3), 100.0) for t in (V.WU, V.WD)}
        fam[V.WU][w] = [19000.0, 30.0, 50.0]  # 80 exclusive
        fam[V.WD][w] = [19900.0, 15.0, 25.0]  # 40 exclusive
        a["analysis"]["familiarity"] = {t: v.tolist() for t, v in fam.items()}
        p = V.Population(1, [a])
        self.assertAlmostEqual(float(V.e_wind_exclusive_ratio(p, None, "same_length")[0]), np.log(2.0), places=12)
        self.assertEqual(V.BY_ID["C24b"].family, "A6")  # its own Holm family: family M's adjustments stay

    def test_c24c_is_c24_at_the_calibrated_counts_and_missing_without_them(self):
        rng = np.random.Generator(np.random.PCG64(5))
        a = synthetic(1, rng, R=2)
        w = ENVS[1:].index("wind")
        cal = {t: np.full((12, 2, 3), 100.0) for t in (V.WU, V.WD)}
        cal[V.WU][w] = [60.0, 20.0, 20.0]  # 0.6 of wind's states in shared cells
        cal[V.WD][w] = [75.0, 15.0, 10.0]  # 0.75
        p = V.Population(1, [a])
        with self.assertRaises(KeyError):  # a run without analysis.calibrated_cell_scale: not measured
            V.e_wind_unfamiliar_calibrated(p, None, "same_length")
        a["analysis"]["familiarity_calibrated"] = {t: v.tolist() for t, v in cal.items()}
        a["analysis"]["calibrated_cell_scale"] = 12.0
        p = V.Population(1, [a])
        self.assertAlmostEqual(float(V.e_wind_unfamiliar_calibrated(p, None, "same_length")[0]), 0.15, places=12)
        self.assertNotAlmostEqual(float(V.e_wind_unfamiliar(p, None, "same_length")[0]), 0.15)
        self.assertEqual(V.BY_ID["C24c"].family, "A6")
        self.assertIn("cell scale 12", V.d_wind_calibrated(p, "same_length"))

    def test_the_spread_rules_differ_on_heavy_tailed_resamples(self):
        point = np.array([1.0, 1.2, 0.8, 1.1])
        th = np.r_[np.random.Generator(np.random.PCG64(1)).normal(1.0, 0.1, 1990), np.full(10, 40.0)]
        _, se_iqr, _, _ = V.interval(point, th)
        _, se_sd, _, _ = V.interval(point, th, "sd")
        self.assertLess(se_iqr, 0.2)
        self.assertGreater(se_sd, 1.0)

    def test_claims_near_alpha_are_on_the_threshold(self):
        c = V.BY_ID["C11"]
        near, far = V.Result(c, 10), V.Result(c, 10)
        near.p_support_holm, near.p_contra_holm = 1.0, 0.0254
        far.p_support_holm, far.p_contra_holm = 1.0, 0.2
        self.assertEqual(verdict_page.on_threshold([near, far]), [near])


class BestEffort(unittest.TestCase):
    """the best-effort confirmation kept beside a verdicts study (<study>_besteffort): judged by the same rules on
    its own populations, shown beside the paper-faithful verdicts on the page and in the README table"""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.study = os.path.join(self.tmp.name, "verdicts")
        rng = np.random.Generator(np.random.PCG64(21))
        kept_study(self.study, {"baseline": {s: synthetic(s, rng) for s in range(1, 5)}})

    def tearDown(self):
        self.tmp.cleanup()

    def test_without_a_confirmation_the_page_says_so_and_the_readme_has_one_training(self):
        with open(verdict_page.write(self.study, os.path.join(self.tmp.name, "page"), B=300)) as fh:
            text = fh.read()
        self.assertIn("No kept run of the confirmation yet", text)
        self.assertNotIn("best-effort", verdict_page.readme_table(self.study, B=300)[-3])

    def test_the_confirmation_is_judged_on_its_own_populations_beside_the_paper_faithful_one(self):
        rng = np.random.Generator(np.random.PCG64(22))
        # the best-effort populations: weak diverse pairs far beyond agents alone (C07 turns supported), with
        # references; seeds of their own
        runs = {}
        for s in range(11, 15):
            a = with_references(synthetic(s, rng, beat=+6.0))
            runs[s] = a
        kept_study(verdict_page.besteffort_folder(self.study), {"baseline": runs})
        jb = verdict_page.judge_besteffort(self.study, B=300)
        self.assertEqual([p.seed for p in jb.main], [11, 12, 13, 14])
        j = verdict_page.judge_study(self.study, B=300)
        self.assertNotEqual(next(r for r in j.res if r.claim.id == "C07").verdict,
                            next(r for r in jb.res if r.claim.id == "C07").verdict)
        with open(verdict_page.write(self.study, os.path.join(self.tmp.name, "page"), B=300)) as fh:
            text = fh.read()
        self.assertIn("best-effort training (M′ n = 4, S′ n = 0)", text)
        moved = md_table(text, "| id | claim | paper-faithful | best-effort |")
        self.assertIn("C07", [r[0] for r in moved])
        self.assertIn("| 11 |", text)  # the confirmation's reference table, per population
        rows = {r[0]: r for r in md_table("\n".join(verdict_page.readme_table(self.study, B=300)), "| | claim |")}
        c07 = next(r for r in jb.res if r.claim.id == "C07")
        self.assertEqual(rows["C07"][7], c07.verdict)
        self.assertRegex(rows["C07"][8], r"\]")  # its 1000-step verdict too


class ReadmeAndS2(unittest.TestCase):
    def test_the_readme_table_has_the_1000_step_verdict_of_every_claim_that_reads_agents_alone(self):
        rng = np.random.Generator(np.random.PCG64(9))
        with tempfile.TemporaryDirectory() as d:
            kept_study(d, {"baseline": {s: synthetic(s, rng) for s in range(1, 5)}})
            lines = verdict_page.readme_table(d, B=500)
        rows = {r[0]: r for r in md_table("\n".join(lines), "| | claim |")}
        for c in V.CLAIMS:
            if c.family == "M" and c.reads_alone:
                self.assertRegex(rows[c.id][5], r"\]", c.id)  # an interval with its verdict
        self.assertEqual(rows["C09"][5], "")  # C09 reads no agents alone

    def test_the_s2_table_gives_each_generalist_its_own_mean_and_interval(self):
        rng = np.random.Generator(np.random.PCG64(11))
        pops = []
        for s in range(1, 4):
            a = synthetic(s, rng)
            a["specialists"] = {"environments": ENVS[1:], "travel_bl": rng.uniform(1, 2, size=(12, 3)).tolist()}
            pops.append(V.Population(s, [a]))
        with tempfile.TemporaryDirectory() as d:
            made = dict((n, rows) for n, _, rows in verdict_page.supplement_figs(pops, d))
        for lab, m, lo, hi in made["Fig. S2"]:
            self.assertLessEqual(lo, m, lab)
            self.assertLessEqual(m, hi, lab)


if __name__ == "__main__":
    unittest.main()
