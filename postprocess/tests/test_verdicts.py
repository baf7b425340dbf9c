"""The protocol's estimator (divcoll_post/verdicts/) on synthetic populations with known effects, and the verdict
page recomputed from kept arrays (postprocess/gallery/studies/verdicts)."""
import contextlib
import html
import io
import os
import re
import shutil
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from divcoll_post import robustness, verdict_page, verdicts as V  # noqa: E402
from divcoll_post.reader import list_attr  # noqa: E402

ENVS = ["flat", "decline", "gap", "ice", "incline", "low_gravity", "obstacle", "sand", "step_down", "step_up",
        "sticky", "treadmill", "wind"]
TYPES = V.WEAK_TYPES + V.STRONG_TYPES
KEPT = os.path.join(os.path.dirname(HERE), "gallery", "studies", "verdicts")


def synthetic(seed, rng, R=3, alone_flat=15.0, beat=-5.0, wdd_bonus=2.0, worse_diff=0.003, worse_sd=0.01,
              better_sd=0.0003):
    """one population's arrays: collectives `beat` BL from agents alone on flat, weak diverse@diverse `wdd_bonus`
    above the other types, the two types' worse-agent DTW `worse_diff` apart (population sd `worse_sd`), their
    better-agent DTW equal up to `better_sd`"""
    E, T = len(ENVS), len(TYPES)
    alone = np.full(E, 6.0)
    alone[0] = alone_flat
    pop = rng.normal(0, 0.3)
    coll = np.empty((E, T, R))
    for ti, t in enumerate(TYPES):
        base = np.full(E, 3.5)
        base[0] = alone_flat + beat
        if t == V.WD:
            base += wdd_bonus
        coll[:, ti, :] = base[:, None] + pop + rng.normal(0, 0.2, size=(E, R))
    w = rng.normal(worse_diff, worse_sd)
    b = rng.normal(0, better_sd)
    dtw = {V.WU: {"all": list(0.10 + rng.normal(0, 0.002, R)), "worse": list(0.11 + rng.normal(0, 0.001, R)),
                  "better": list(0.09 + rng.normal(0, 0.0002, R))},
           V.WD: {"all": list(0.10 + rng.normal(0, 0.002, R)), "worse": list(0.11 + w + rng.normal(0, 0.001, R)),
                  "better": list(0.09 + b + rng.normal(0, 0.0002, R))}}
    fam = {t: (rng.uniform(100, 200, size=(12, R, 3))).tolist() for t in (V.WU, V.WD)}
    return {"format": V.ARRAYS_FORMAT, "version": V.ARRAYS_VERSION, "seed": seed, "git_commit": "synthetic",
            "episode_steps": {"connectors": 1000, "deploy": 3000},
            "agents": {"fitness_mean": 5.0 + rng.normal(0, 0.1), "gen0_mean": rng.normal(0, 0.02)},
            "connectors": {"untrained_bl": {k: list(rng.uniform(0.5, 1.0, R)) for k in
                                            ["weak_uniform", "weak_diverse", "strong_uniform", "strong_diverse"]}},
            "deploy": {"environments": ENVS, "types": TYPES, "alone_bl": alone.tolist(),
                       "alone_bl_early": (alone / 3).tolist(), "early_step": 1000, "collectives_bl": coll.tolist(),
                       "collectives_ok": np.full((E, T, R), 100).tolist()},
            "analysis": {"novel_environments": ENVS[1:], "dtw": dtw, "familiarity": fam}}


def kept_study(d, arrays, manifest=""):
    """a study folder as `divcoll report --keep` leaves it, in d: arrays = {variant: {seed: a run's arrays}};
    manifest: more top-level keys of its study.toml"""
    import json
    runs = []
    for v, by_seed in arrays.items():
        os.makedirs(os.path.join(d, v), exist_ok=True)
        for seed, a in by_seed.items():
            with open(os.path.join(d, v, f"seed{seed}.arrays.json"), "w") as fh:
                json.dump(a, fh)
            runs.append(f'[[run]]\nvariant = "{v}"\nseed = {seed}\npath = "{v}/seed{seed}.h5"\nstatus = "complete"\n'
                        'reuses = ""\nfrom = ""\n')
    with open(os.path.join(d, "study.toml"), "w") as fh:
        fh.write('format = "divcoll-study"\nname = "synthetic"\n' + manifest
                 + "".join(f'[[variant]]\nname = "{v}"\nset = []\n' for v in arrays) + "\n".join(runs))


def md_table(text, head):
    """the rows of the Markdown table whose header starts with `head`, each a list of cells as plain text"""
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith(head))
    rows = []
    for ln in lines[i + 2:]:
        if not ln.startswith("|"):
            break
        rows.append([re.sub(r"\*\*|`", "", c.strip()) for c in ln.strip().strip("|").split("|")])
    return rows


def html_table(page, first_headers):
    """the body rows of the HTML table whose header cells start with `first_headers`, each a list of cell texts"""
    for table in re.findall(r"<table>(.*?)</table>", page, re.S):
        heads = [html.unescape(re.sub(r"<[^>]+>", "", h)) for h in re.findall(r"<th>(.*?)</th>", table, re.S)]
        if heads[:len(first_headers)] == list(first_headers):
            body = table.split("<tbody>", 1)[1]
            return [[html.unescape(re.sub(r"<[^>]+>", "", c)) for c in re.findall(r"<td[^>]*>(.*?)</td>", tr, re.S)]
                    for tr in re.findall(r"<tr>(.*?)</tr>", body, re.S)]
    raise AssertionError(f"no table with headers {first_headers}")


def populations(n, **kw):
    rng = np.random.Generator(np.random.PCG64(7))
    return [V.Population(s, [synthetic(s, rng, **kw)]) for s in range(1, n + 1)]


class KnownEffects(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.res = {r.claim.id: r for r in V.judge(populations(10), [c for c in V.CLAIMS if c.family == "M"], B=4000)}

    def test_a_clear_effect_in_the_papers_direction_is_supported(self):
        r = self.res["C09"]  # weak diverse@diverse 2 BL above every other type on flat
        self.assertAlmostEqual(r.estimate, 2.0, delta=0.3)
        self.assertGreater(r.lo, V.BY_ID["C09"].margin)
        self.assertEqual(r.verdict, "supported")

    def test_an_effect_against_the_paper_is_contradicted(self):
        r = self.res["C07"]  # collectives 5 BL below agents alone on flat (3 BL for the best)
        self.assertLess(r.hi, 0)
        self.assertEqual(r.verdict, "contradicted")

    def test_a_difference_inside_the_margin_is_equivalent(self):
        r = self.res["C20"]  # better agents' DTW equal up to 0.0003 u, margin 0.005 u
        self.assertGreater(r.lo, -V.BY_ID["C20"].margin)
        self.assertLess(r.hi, V.BY_ID["C20"].margin)
        self.assertEqual(r.verdict, "equivalent")

    def test_a_small_noisy_effect_is_inconclusive_with_its_power(self):
        pops = populations(4, worse_diff=0.004, worse_sd=0.012)
        r = {x.claim.id: x for x in V.judge(pops, [V.BY_ID["C19"]], B=4000)}["C19"]
        self.assertLess(r.lo, 0)
        self.assertGreater(r.hi, V.BY_ID["C19"].margin)
        self.assertEqual(r.verdict, "inconclusive")
        self.assertTrue(0 <= r.power < 0.8)
        self.assertGreater(r.n80, 4)

    def test_a_positive_but_negligible_effect_is_contradicted_as_negligible(self):
        pops = populations(10, worse_diff=0.002, worse_sd=0.0002)
        r = V.judge(pops, [V.BY_ID["C19"]], B=4000)[0]
        self.assertGreater(r.lo, 0)
        self.assertLess(r.hi, V.BY_ID["C19"].margin)
        self.assertEqual(r.verdict, "contradicted (negligible)")

    def test_holm_adjusts_in_order_and_is_monotone(self):
        adj = V.holm([0.01, 0.04, 0.03, float("nan"), 0.005])
        np.testing.assert_allclose(adj[[4, 0, 2, 1]], [0.02, 0.03, 0.06, 0.06])
        self.assertTrue(np.isnan(adj[3]))

    def test_the_interval_covers_the_population_mean_not_the_connector_noise(self):
        # between-population sd 0.3 BL over 10 populations: the interval's half-width is near 1.96 * 0.3 / sqrt(10)
        r = self.res["C09"]
        self.assertLess(r.hi - r.lo, 0.6)
        self.assertGreater(r.hi - r.lo, 0.02)

    def test_connector_draws_change_the_effect_inside_a_population(self):
        p = populations(1)[0]
        rng = np.random.Generator(np.random.PCG64(1))
        vals = V.e_wdd_best_flat(p, p.draws(rng, 200), "same_length")
        self.assertEqual(vals.shape, (200,))
        self.assertGreater(np.std(vals), 0)


class Page(unittest.TestCase):
    def test_the_page_is_made_from_kept_arrays_alone(self):
        d = tempfile.mkdtemp()
        try:
            rng = np.random.Generator(np.random.PCG64(3))
            kept_study(d, {"baseline": {s: synthetic(s, rng) for s in (1, 2, 3, 4)}})
            path = verdict_page.write(d, os.path.join(d, "verdicts"), B=2000)
            with open(path) as fh:
                text = fh.read()
            for c in V.CLAIMS:
                self.assertIn(f"| {c.id} |", text)
            res = {r.claim.id: r for r in V.judge(V.load_study(d, ["baseline"]),
                                                   [c for c in V.CLAIMS if c.family == "M"], B=2000)}
            self.assertIn(verdict_page.cell(res["C09"]), text)
            self.assertTrue(os.path.exists(os.path.join(d, "verdicts", "forest.png")))
        finally:
            shutil.rmtree(d)

    def test_the_study_report_writes_the_verdict_page_in_markdown_and_html_with_one_table(self):
        # `divcoll report STUDY` runs robustness.py: beside the robustness page, the verdict page as verdicts.md and a
        # self-contained verdicts.html carrying the same verdict table and the forest plot
        d = tempfile.mkdtemp()
        try:
            rng = np.random.Generator(np.random.PCG64(3))
            # with what robustness.py reads of a study's manifest besides the runs
            kept_study(d, {"baseline": {s: synthetic(s, rng) for s in (1, 2, 3, 4)}},
                       manifest='base = "base.toml"\nseeds = [1, 2, 3, 4]\nscale = []\n')
            out = os.path.join(d, "page")
            with contextlib.redirect_stdout(io.StringIO()) as said:
                self.assertEqual(robustness.main([d, "--out", out, "--resamples", "500"]), 0)
            md_path, html_path = (os.path.join(out, "verdicts", f"verdicts.{x}") for x in ("md", "html"))
            self.assertIn(f"wrote the verdict page {md_path}", said.getvalue())
            with open(md_path) as fh:
                md = fh.read()
            with open(html_path) as fh:
                page = fh.read()
            with open(os.path.join(out, "robustness.md")) as fh:
                self.assertIn("(verdicts/verdicts.html)", fh.read())
            head = ("id", "claim", "paper")
            rows = md_table(md, "| id | claim | paper |")  # the registered families M and S (amendments: own tables)
            self.assertEqual(len(rows), len([c for c in V.CLAIMS if c.family in ("M", "S")]))
            self.assertEqual(html_table(page, head), rows)
            self.assertIn(".v-supported", page)
            self.assertIn('class="v-supported"', page)  # C09's cell ends in its verdict
            self.assertEqual(page.count('src="data:image/png;base64,'), md.count("![")), "every figure embedded"
            self.assertNotIn('src="forest.png"', page)
        finally:
            shutil.rmtree(d)

    def test_the_readings_page_pairs_each_reading_with_its_baseline(self):
        d = tempfile.mkdtemp()
        try:
            arrays = {}
            for v, bonus in (("baseline", 2.0), ("shifted", 3.0)):
                rng = np.random.Generator(np.random.PCG64(5))  # the same populations but for the bonus
                arrays[v] = {s: synthetic(s, rng, wdd_bonus=bonus) for s in (1, 2, 3, 4)}
            kept_study(d, arrays)
            path = verdict_page.readings_page(d, os.path.join(d, "readings"), B=2000)
            with open(path) as fh:
                row = [ln for ln in fh if ln.startswith("| C09 |")][0]
            # the shifted reading moves weak diverse@diverse's lead on flat by exactly 1 BL in every population (the
            # interval is wider: the two runs' connectors are drawn independently)
            lo, hi = (float(x) for x in row.split("Δ +1.000 [")[1].split("]")[0].split(", "))
            self.assertLess(lo, 1.0)
            self.assertGreater(hi, 1.0)
        finally:
            shutil.rmtree(d)

    def test_the_states_page_gives_each_variants_effect_of_every_analysis_claim(self):
        d = tempfile.mkdtemp()
        try:
            arrays = {v: {1: synthetic(1, np.random.Generator(np.random.PCG64(k)))} for k, v in ((5, "n10k"), (6, "n30k"))}
            kept_study(d, arrays)
            path = verdict_page.states_page(d, os.path.join(d, "states"))
            with open(path) as fh:
                md = fh.read()
            rows = md_table(md, "| id | claim | n10k | n30k |")
            analysis = [c for c in V.CLAIMS if "analysis" in c.needs]
            self.assertEqual([r[0] for r in rows], [c.id for c in analysis])
            for c, row in zip(analysis, rows):
                for v, text in zip(("n10k", "n30k"), row[2:]):
                    pop = V.Population(1, [arrays[v][1]])
                    try:
                        e = float(c.effect(pop, None, "same_length")[0])
                    except KeyError:  # C24c without counts at a calibrated cell scale
                        self.assertEqual(text, "—", (c.id, v))
                        continue
                    self.assertTrue(text.startswith(verdict_page.num(e)), (c.id, v, text, e))
        finally:
            shutil.rmtree(d)

    @unittest.skipUnless(os.path.exists(os.path.join(KEPT, "study.toml")), "no kept verdicts study")
    def test_the_committed_page_is_recomputed_from_the_kept_arrays(self):
        committed = os.path.join(os.path.dirname(HERE), "gallery", "verdicts", "verdicts.md")
        d = tempfile.mkdtemp()
        try:
            path = verdict_page.write(KEPT, d)
            table = lambda t: [ln for ln in t.splitlines() if ln.startswith("|")]  # noqa: E731
            with open(path) as a, open(committed) as b:
                self.assertEqual(table(a.read()), table(b.read()))
            # and the README's results table is the same study's
            with open(os.path.join(os.path.dirname(os.path.dirname(HERE)), "README.md")) as fh:
                readme = fh.read()
            block = readme[readme.index(verdict_page.README_BEGIN) + len(verdict_page.README_BEGIN):
                           readme.index(verdict_page.README_END)]
            self.assertEqual(block.strip().splitlines(), verdict_page.readme_table(KEPT))
        finally:
            shutil.rmtree(d)


BIN = os.path.abspath(os.environ.get("DIVCOLL_BINARY", os.path.join(os.path.dirname(os.path.dirname(HERE)), "build",
                                                                   "divcoll")))


@unittest.skipUnless(os.path.exists(BIN), f"no divcoll binary at {BIN} (set DIVCOLL_BINARY)")
class Extract(unittest.TestCase):
    """a run's kept arrays are the run file's own numbers"""

    @classmethod
    def setUpClass(cls):
        import subprocess
        cls.tmp = tempfile.mkdtemp()
        cls.path = os.path.join(cls.tmp, "tiny.h5")
        repo = os.path.dirname(os.path.dirname(HERE))
        subprocess.run([BIN, "run", os.path.join(repo, "configs", "tiny.toml"), "--out", cls.path,
                        "connectors.replicates=2", "deploy.early_step=50"], check=True, capture_output=True)
        cls.a = V.extract(cls.path)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp)

    def test_dtw_per_connector_is_the_analysis_stages_replicate_means(self):
        import h5py
        with h5py.File(self.path, "r") as f:
            rm = f["analysis/adversity/replicate_means"][()]
            types = list_attr(f["analysis"], "types")
        for ti, t in enumerate(types):
            np.testing.assert_allclose(self.a["analysis"]["dtw"][t]["worse"], rm[ti, 0], rtol=1e-12)
            np.testing.assert_allclose(self.a["analysis"]["dtw"][t]["better"], rm[ti, 1], rtol=1e-12)

    def test_travel_is_the_mean_over_ok_episodes(self):
        import h5py
        with h5py.File(self.path, "r") as f:
            t, st = f["deploy/collectives/travel_bl"][()], f["deploy/collectives/status"][()]
            fit = f["agents/final/fitness"][()]
        coll = np.array(self.a["deploy"]["collectives_bl"])
        self.assertEqual(coll.shape, t.shape[:3])
        e, ti, r = 1, 3, 1
        ok = st[e, ti, r] == 0
        self.assertAlmostEqual(coll[e, ti, r], t[e, ti, r][ok].mean(), places=12)
        self.assertAlmostEqual(self.a["agents"]["fitness_mean"], fit.mean(), places=12)
        self.assertIn("alone_bl_early", self.a["deploy"])
        # and a population built from them has every claim of the main text computable
        p = V.Population(1, [self.a])
        for c in V.CLAIMS:
            if c.family == "M" and c.id != "C24":  # the tiny preset has no wind
                self.assertEqual(np.asarray(c.effect(p, None, "same_length")).shape, (1,), c.id)

    def test_the_page_draws_the_supplement_figures_from_a_runs_arrays(self):
        d = tempfile.mkdtemp()
        try:
            kept_study(d, {v: {s: dict(self.a, seed=s) for s in (1, 2)} for v in ("baseline", "supplement")})
            path = verdict_page.write(d, os.path.join(d, "v"), B=500)
            with open(path) as fh:
                text = fh.read()
            for fig in ("fig4", "fig_s2", "fig_s3"):
                self.assertTrue(os.path.exists(os.path.join(d, "v", "figures", fig + ".png")), fig)
            for c in ("C25", "C26", "C27", "C28"):
                row = [ln for ln in text.splitlines() if ln.startswith(f"| {c} |")][0]
                self.assertIn("too few populations", row)
        finally:
            shutil.rmtree(d)


if __name__ == "__main__":
    unittest.main()
