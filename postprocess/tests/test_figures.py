"""Tests of divcoll_post/results.py and the figures fig2, fig4, fig_s2, fig_s3 (divcoll_post.figures) on
synthetic run files whose numbers are set by hand.

    cd <repo> && /usr/bin/python3 -m unittest postprocess/tests/test_figures.py -v
"""

import contextlib
import io
import os
import subprocess
import sys
import tempfile
import unittest

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
POST = os.path.dirname(HERE)
sys.path.insert(0, POST)

from divcoll_post import results as R  # noqa: E402
from divcoll_post.figures import fig2  # noqa: E402
from divcoll_post.figures import fig4  # noqa: E402
from divcoll_post.figures import fig_s2  # noqa: E402
from divcoll_post.figures import fig_s3  # noqa: E402

ENVS = ["flat", "ice", "gap"]
TYPES = [f"{k}@{d}" for k in ("weak_uniform", "weak_diverse", "strong_uniform", "strong_diverse")
         for d in ("uniform", "diverse")]
NR, NP, NAG = 2, 3, 4  # replicates, pairs, agents
HUGE = 1e9  # the travel stored in a not-ok episode: it must never reach a mean


def deploy_numbers():
    """Agents (E × P) and collectives (E × T × R × NP), with statuses. Every collective of type t in
    environment e travels base[e] + 0.1·t + 0.01·(r·NP + n), except the not-ok episodes set below."""
    at = np.array([[1.0, 1.2, 0.8, HUGE],  # flat: agent 3 ended nan
                   [0.5, 0.5, 0.5, 0.5],
                   [0.1, 0.3, 0.2, 0.2]])
    ast = np.zeros(at.shape, np.uint8)
    ast[0, 3] = 1
    base = [1.0, 0.2, 0.6]
    ct = np.zeros((len(ENVS), len(TYPES), NR, NP))
    for e in range(len(ENVS)):
        for t in range(len(TYPES)):
            ct[e, t] = base[e] + 0.1 * t + 0.01 * np.arange(NR * NP).reshape(NR, NP)
    cst = np.zeros(ct.shape, np.uint8)
    wd = TYPES.index("weak_diverse@diverse")
    ct[0, wd, 1, 2] = HUGE  # unstable episode on flat
    cst[0, wd, 1, 2] = 2
    ct[2, wd, 0, 0] = np.nan  # nan episode in gap
    cst[2, wd, 0, 0] = 1
    return at, ast, ct, cst


def schema_dataset(g, name, data, axes, **labels):
    """a dataset with the attributes the run-file schema gives it: its axes and the labels of its labelled axes"""
    g[name] = data
    g[name].attrs["axes"] = axes
    for axis, names in labels.items():
        g[name].attrs[f"labels_{axis}"] = ",".join(names)


def write_run(path, stages=("deploy", "scaling", "specialists", "graded"), deploy_envs_done=None):
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "divcoll-run"
        f.attrs["version"] = 1
        f.attrs["seed"] = 7
        f.attrs["git_commit"] = "abc123def456"
        f.attrs["config"] = ('[run]\nseed = 7\nname = "synthetic"\n[deploy]\nepisode_steps = 100\n'
                             '[scaling]\nepisode_steps = 100\n')
        if "deploy" in stages:
            d = f.create_group("deploy")
            d.attrs["status"] = "complete" if deploy_envs_done is None else "running"
            d.attrs["environments"] = ",".join(ENVS)
            d.attrs["types"] = ",".join(TYPES)
            d.attrs["envs_done"] = len(ENVS) if deploy_envs_done is None else deploy_envs_done
            at, ast, ct, cst = deploy_numbers()
            if deploy_envs_done is not None:  # rows not yet written hold HDF5's fill value: 0, status 0
                at[deploy_envs_done:] = 0.0
                ast[deploy_envs_done:] = 0
                ct[deploy_envs_done:] = 0.0
                cst[deploy_envs_done:] = 0
            for name, a in (("travel_bl", at), ("status", ast)):
                schema_dataset(d, f"agents/{name}", a, "env,agent", env=ENVS)
            for name, a in (("travel_bl", ct), ("status", cst)):
                schema_dataset(d, f"collectives/{name}", a, "env,type,replicate,pair", env=ENVS, type=TYPES)
            schema_dataset(d, "diverse_pairs", np.array([[0, 1], [1, 2], [3, 0]], np.int32), "pair,slot",
                           slot=["posterior", "anterior"])
        if "scaling" in stages:
            s = f.create_group("scaling")
            s.attrs["status"] = "complete"
            s.attrs["environments"] = ",".join(ENVS)
            s.attrs["variants"] = "uniform,diverse"
            s.attrs["envs_done"] = len(ENVS)
            s["sizes"] = np.array([3, 5], np.int64)
            t = np.zeros((len(ENVS), 2, 2, NR, 2))
            for e in range(len(ENVS)):
                for si in range(2):
                    for v in range(2):
                        t[e, si, v] = 0.3 * e + 0.1 * si + 0.05 * v + np.array([[0.0, 0.02], [0.04, 0.06]])
            st = np.zeros(t.shape, np.uint8)
            t[1, 0, 1, 0, 0], st[1, 0, 1, 0, 0] = HUGE, 2  # ice, size 3, diverse: one unstable chain
            s["travel_bl"], s["status"] = t, st
        if "specialists" in stages:
            sp = f.create_group("specialists")
            sp.attrs["status"] = "complete"
            sp.attrs["environments"] = "ice,gap"
            sp.attrs["replicates"] = 3
            t = np.zeros((2, 3, NP))
            st = np.zeros(t.shape, np.uint8)
            # ice: replicate 0 holds a nan episode with a huge number (its ok mean is 0.2), 1 is best (0.5), 2 0.4
            t[0, 0] = [0.2, 0.2, HUGE]
            st[0, 0, 2] = 1
            t[0, 1] = [0.4, 0.5, 0.6]
            t[0, 2] = [0.4, 0.4, 0.4]
            # gap: replicate 2 has no ok episode at all (huge values), replicate 0 (0.7) beats 1 (0.3)
            t[1, 0] = [0.7, 0.6, 0.8]
            t[1, 1] = [0.3, 0.3, 0.3]
            t[1, 2] = [HUGE, HUGE, HUGE]
            st[1, 2] = 2
            sp["travel_bl"], sp["status"] = t, st
        if "graded" in stages:
            g = f.create_group("graded")
            g.attrs["status"] = "complete"
            g.attrs["environments"] = ",".join(ENVS)
            g.attrs["populations"] = "same_shape,same_shape_springs"
            for k, (pop, src) in enumerate([("same_shape", "behaviour,springs,pairing"),
                                            ("same_shape_springs", "behaviour,pairing")]):
                p = g.create_group(pop)
                p.attrs["status"] = "complete"
                p.attrs["diversity_sources"] = src
                a = np.array([[1.0, 1.0, 1.0], [0.4 + k, 0.6 + k, 0.5 + k], [0.2, 0.2, HUGE]])
                ast = np.zeros(a.shape, np.uint8)
                ast[2, 2] = 1
                pr = np.zeros((len(ENVS), NR, 2))
                pr[0], pr[1], pr[2] = 2.0, 0.9 - 0.1 * k, 0.3
                p["deploy/agents/travel_bl"], p["deploy/agents/status"] = a, ast
                p["deploy/pairs/travel_bl"], p["deploy/pairs/status"] = pr, np.zeros(pr.shape, np.uint8)


def hand_ok_mean(values, status):
    v = [x for x, s in zip(np.ravel(values), np.ravel(status)) if s == 0 and np.isfinite(x)]
    return sum(v) / len(v)


def png_ok(test, path):
    test.assertTrue(os.path.isfile(path), path)
    with open(path, "rb") as fh:
        test.assertEqual(fh.read(8), b"\x89PNG\r\n\x1a\n", path)
    test.assertGreater(os.path.getsize(path), 20_000, path)


def pdf_ok(test, path):
    test.assertTrue(os.path.isfile(path), path)
    with open(path, "rb") as fh:
        test.assertEqual(fh.read(5), b"%PDF-", path)
    test.assertGreater(os.path.getsize(path), 5_000, path)


def call(main, argv):
    """Run a script's main() in this process: (exit status, stderr text)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(argv)
    return rc, err.getvalue()


class Base(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.full = os.path.join(cls.tmp.name, "full.h5")
        write_run(cls.full)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.tmp.name, name)


class StatisticsTest(unittest.TestCase):
    def test_ok_mean_leaves_out_not_ok_episodes(self):
        m, bad = R.ok_mean([1.0, 2.0, HUGE, np.nan], [0, 0, 2, 0])
        self.assertAlmostEqual(m, 1.5)
        self.assertEqual(bad, 2)  # the unstable one and the ok-status NaN
        m, bad = R.ok_mean([HUGE], [1])
        self.assertTrue(np.isnan(m))
        self.assertEqual(bad, 1)

    def test_bootstrap_ci_is_seeded_brackets_the_mean_and_ignores_not_ok(self):
        rng = np.random.default_rng(3)
        v = rng.normal(1.0, 0.5, 200)
        lo, hi = R.bootstrap_ci(v)
        self.assertEqual((lo, hi), R.bootstrap_ci(v))  # fixed seed: the same bars every time
        self.assertLess(lo, v.mean())
        self.assertGreater(hi, v.mean())
        # roughly mean ± 1.96 SEM for a normal sample of 200
        self.assertAlmostEqual(hi - lo, 2 * 1.96 * R.sem(v), delta=0.3 * (hi - lo))
        np.testing.assert_allclose(R.bootstrap_ci([0.7, 0.7, 0.7]), (0.7, 0.7), rtol=1e-12)
        self.assertTrue(np.isnan(R.bootstrap_ci([])).all())
        st = R.stat([(np.r_[v, HUGE], np.r_[np.zeros(200), 1])])
        self.assertLess(st.hi, 2.0)  # the huge not-ok episode is not resampled
        self.assertEqual((st.lo, st.hi), (lo, hi))

    def test_stratified_ci_is_about_the_mean_of_environment_means(self):
        # env A has 100 episodes near 0, env B 2 episodes at exactly 10: the mean of env means is 5, the
        # pooled mean would be ~0.2
        a = np.linspace(-0.1, 0.1, 100)
        st = R.stat([(a, np.zeros(100)), (np.array([10.0, 10.0]), np.zeros(2))])
        self.assertAlmostEqual(st.mean, 5.0)
        self.assertLess(st.lo, 5.0)
        self.assertGreater(st.hi, 5.0)
        self.assertLess(st.hi - st.lo, 0.1)

    def test_sem(self):
        self.assertAlmostEqual(R.sem([1.0, 2.0, 3.0]), 1.0 / np.sqrt(3))
        st = R.stat([(np.array([1.0, 2.0, 3.0, HUGE]), np.array([0, 0, 0, 2]))], err="sem")
        self.assertAlmostEqual(st.mean, 2.0)
        self.assertAlmostEqual(st.hi - st.mean, 1.0 / np.sqrt(3))


class ReaderTest(Base):
    def test_fig2_bars_are_hand_computed_ok_means(self):
        at, ast, ct, cst = deploy_numbers()
        S = fig2.compute(R.load_deploy(self.full))
        self.assertAlmostEqual(S["flat"]["agents"].mean, 1.0)  # (1.0 + 1.2 + 0.8) / 3, the 1e9 left out
        self.assertEqual(S["flat"]["agents"].n_bad, 1)
        wd = TYPES.index("weak_diverse@diverse")
        flat_wd = hand_ok_mean(ct[0, wd], cst[0, wd])
        self.assertAlmostEqual(S["flat"]["weak_diverse@diverse"].mean, flat_wd)
        self.assertLess(S["flat"]["weak_diverse@diverse"].hi, 10)
        # novel: the mean of the ice and gap means (gap has a nan episode left out)
        ice, gap = hand_ok_mean(ct[1, wd], cst[1, wd]), hand_ok_mean(ct[2, wd], cst[2, wd])
        self.assertAlmostEqual(S["novel"]["weak_diverse@diverse"].mean, (ice + gap) / 2)
        self.assertAlmostEqual(S["env"]["gap"]["weak_diverse@diverse"].mean, gap)
        self.assertAlmostEqual(S["novel"]["agents"].mean, (0.5 + 0.2) / 2)
        su = TYPES.index("strong_uniform@diverse")
        self.assertAlmostEqual(S["env"]["ice"]["strong_uniform@diverse"].mean, ct[1, su].mean())
        for g in ("flat", "novel"):
            for t, st in S[g].items():
                self.assertLessEqual(st.lo, st.mean + 1e-12, (g, t))
                self.assertGreaterEqual(st.hi, st.mean - 1e-12, (g, t))

    def test_partly_done_deploy_reads_only_finished_environments(self):
        p = self.path("partial.h5")
        write_run(p, stages=("deploy",), deploy_envs_done=2)
        dep = R.load_deploy(p)
        self.assertEqual(dep.envs, ["flat", "ice"])
        S = fig2.compute(dep)
        # gap's zero-filled rows (status 0) would pull the novel mean down if they were read
        self.assertAlmostEqual(S["novel"]["agents"].mean, 0.5)
        self.assertEqual(list(S["env"]), ["ice"])

    def test_best_specialist_is_the_replicate_with_the_highest_ok_mean(self):
        sp = R.load_specialists(self.full)
        self.assertEqual(sp.best("ice"), (1, 0.5))  # not replicate 0, whose nan episode holds 1e9
        np.testing.assert_allclose(sp.replicate_means("ice"), [0.2, 0.5, 0.4])
        r, m = sp.best("gap")
        self.assertEqual(r, 0)  # replicate 2 has no ok episode: it is not the best
        self.assertAlmostEqual(m, 0.7)
        rows = fig_s2.compute(R.load_deploy(self.full), sp)
        self.assertEqual([row[0] for row in rows], ["ice", "gap"])
        e, a, g, r, s = rows[0]
        self.assertEqual(r, 1)
        self.assertAlmostEqual(s.mean, 0.5)
        self.assertAlmostEqual(s.hi - s.mean, R.sem([0.4, 0.5, 0.6]))  # S2's error bars are SEM
        _, _, ct, cst = deploy_numbers()
        wd = TYPES.index("weak_diverse@diverse")
        self.assertAlmostEqual(rows[1][2].mean, hand_ok_mean(ct[2, wd], cst[2, wd]))
        self.assertAlmostEqual(rows[1][1].mean, 0.2)

    def test_fig4_points(self):
        sc = R.load_scaling(self.full)
        S = fig4.compute(sc, R.load_deploy(self.full))
        self.assertEqual(list(S), [fig4.NOVEL, "flat", "ice", "gap"])
        pts = {n: (s, src) for n, s, src in S["ice"]["diverse"]}
        self.assertEqual(sorted(pts), [2, 3, 5])
        # size 3, diverse, ice: 0.3 + 0.05 + {0, .02, .04, .06} with the 0.0 chain unstable
        self.assertAlmostEqual(pts[3][0].mean, 0.35 + 0.04)
        self.assertEqual(pts[3][0].n_bad, 1)
        self.assertEqual(pts[3][1], "scaling")
        # size 2 is the deploy stage's weak_diverse@diverse pairs
        _, _, ct, cst = deploy_numbers()
        wd = TYPES.index("weak_diverse@diverse")
        self.assertEqual(pts[2][1], "deploy")
        self.assertAlmostEqual(pts[2][0].mean, hand_ok_mean(ct[1, wd], cst[1, wd]))
        self.assertAlmostEqual(S["ice"]["agents"].mean, 0.5)
        # novel panel: the mean of ice and gap means, uniform, size 5
        u5 = {n: s for n, s, _ in S[fig4.NOVEL]["uniform"]}[5]
        self.assertAlmostEqual(u5.mean, ((0.3 + 0.1 + 0.03) + (0.6 + 0.1 + 0.03)) / 2)
        S2 = fig4.compute(sc, None, pair=False, agents=False)
        self.assertEqual([n for n, _, _ in S2["gap"]["uniform"]], [3, 5])
        self.assertIsNone(S2["gap"]["agents"])

    def test_fig_s3_values_and_diversity_sources(self):
        pops = [R.main_population(R.load_deploy(self.full))] + R.load_graded(self.full)
        rows = fig_s3.compute(pops)
        names = [p.name for p, *_ in rows]
        self.assertEqual(names, ["main", "same_shape", "same_shape_springs"])
        by = {p.name: (p, novel, a, q) for p, novel, a, q in rows}
        p, novel, a, q = by["same_shape"]
        self.assertEqual(novel, ["ice", "gap"])
        self.assertAlmostEqual(a.mean, (0.5 + 0.2) / 2)  # gap's nan agent with 1e9 left out
        self.assertAlmostEqual(q.mean, (0.9 + 0.3) / 2)
        self.assertEqual(p.diversity_sources, ["behaviour", "springs", "pairing"])
        self.assertAlmostEqual(by["same_shape_springs"][2].mean, (1.5 + 0.2) / 2)
        self.assertAlmostEqual(by["main"][2].mean, (0.5 + 0.2) / 2)
        self.assertEqual(by["main"][0].diversity_sources, ["behaviour", "springs", "shape", "pairing"])


class ScriptsTest(Base):
    def test_every_script_writes_png_and_pdf(self):
        out = self.path("figs")
        for mod, stem in ((fig2, fig2.STEM), (fig4, fig4.STEM), (fig_s2, fig_s2.STEM), (fig_s3, fig_s3.STEM)):
            rc, err = call(mod.main, [self.full, "--out", out, "--dpi", "60", "--boot", "200"])
            self.assertEqual(rc, 0, f"{mod.__name__}: {err}")
            png_ok(self, os.path.join(out, stem + ".png"))
            pdf_ok(self, os.path.join(out, stem + ".pdf"))

    def test_missing_stage_is_refused_with_exit_2_and_a_message(self):
        only_deploy = self.path("only_deploy.h5")
        write_run(only_deploy, stages=("deploy",))
        no_deploy = self.path("no_deploy.h5")
        write_run(no_deploy, stages=("scaling", "specialists", "graded"))
        out = self.path("refused")
        cases = [(fig4, only_deploy, "run file has no scaling stage (run the scaling stage first)"),
                 (fig_s2, only_deploy, "run file has no specialists stage (run the specialists stage first)"),
                 (fig_s3, only_deploy, "run file has no graded stage (run the graded stage first)"),
                 (fig2, no_deploy, "run file has no deploy stage (run the deploy stage first)"),
                 (fig_s2, no_deploy, "run file has no deploy stage")]
        for mod, path, msg in cases:
            rc, err = call(mod.main, [path, "--out", out])
            self.assertEqual(rc, 2, mod.__name__)
            self.assertIn(msg, err, mod.__name__)
        self.assertFalse(os.path.exists(out))  # nothing drawn
        # and a real process exit status, with the message on stderr
        p = subprocess.run([sys.executable, "-m", "divcoll_post.figures.fig4", only_deploy, "--out", out],
                           capture_output=True, text=True, timeout=60, env=dict(os.environ, PYTHONPATH=POST))
        self.assertEqual(p.returncode, 2)
        self.assertIn("fig4: ", p.stderr)
        self.assertIn("run file has no scaling stage (run the scaling stage first)", p.stderr)

    def test_not_a_run_file_exit_2(self):
        txt = self.path("notes.txt")
        with open(txt, "w") as fh:
            fh.write("not hdf5\n")
        rc, err = call(fig2.main, [txt, "--out", self.path("x")])
        self.assertEqual(rc, 2)
        self.assertIn("not an HDF5 file", err)

    def test_fig_s3_without_deploy_still_draws_the_graded_populations(self):
        p = self.path("graded_only.h5")
        write_run(p, stages=("graded",))
        out = self.path("graded_only")
        rc, err = call(fig_s3.main, [p, "--out", out, "--dpi", "60", "--boot", "100"])
        self.assertEqual(rc, 0, err)
        self.assertIn("warning", err)
        png_ok(self, os.path.join(out, fig_s3.STEM + ".png"))


if __name__ == "__main__":
    unittest.main()
