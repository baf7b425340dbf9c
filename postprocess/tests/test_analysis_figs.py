"""Tests of the analysis-stage outputs (fig3.py, table_s1.py, divcoll_post/analysis.py, the Fig. 3 / Table S1
claims and the report's analysis sections) on synthetic run files written with h5py.

    cd <repo> && /usr/bin/python3 -m unittest postprocess/tests/test_analysis_figs.py -v
"""

import os
import sys
import tempfile
import unittest

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
POST = os.path.dirname(HERE)
sys.path.insert(0, POST)
sys.path.insert(0, HERE)

from divcoll_post import analysis as A  # noqa: E402
from test_figures import call, pdf_ok, png_ok, schema_dataset  # noqa: E402
from divcoll_post import single_run as claims  # noqa: E402
from divcoll_post.figures import fig3  # noqa: E402
from divcoll_post import report  # noqa: E402
from divcoll_post import summary  # noqa: E402
from divcoll_post.figures import table_s1  # noqa: E402

ENVS = ["flat", "ice", "wind"]
NOVEL = ["ice", "wind"]
TYPES = [A.UNIFORM, A.DIVERSE]
NR, NP, MAXS = 4, 5, 40  # replicates, pairs, max_states per environment


def read(path):
    with open(path) as fh:
        return fh.read()


def hand_counts(train, novel):
    """the cell classification written independently of divcoll_post: Python's round() (half to even) and a
    dict of cell -> set of labels"""
    cells = {}
    keys = []
    for lab, pts in ((0, train), (1, novel)):
        for x, y in pts:
            k = (round(float(x)), round(float(y)))
            cells.setdefault(k, set()).add(lab)
            keys.append(k)
    kind = {k: (0 if len(v) == 2 else 1 if v == {0} else 2) for k, v in cells.items()}
    states = [0, 0, 0]
    for k in keys:
        states[kind[k]] += 1
    ncell = [sum(1 for v in kind.values() if v == c) for c in range(3)]
    return np.array(states + ncell, float)


def fit(rng, nt, nn, shift):
    """training states around the origin, novel ones shifted by `shift` (0: the same distribution); a few
    exact .5 coordinates so that rounding half to even matters"""
    tr = rng.normal(0.0, 2.0, (nt, 2))
    nv = rng.normal(0.0, 2.0, (nn, 2)) + [shift, 0.0]
    tr[0] = [0.5, 0.5]  # cell (0, 0) half to even, (1, 1) half up
    tr[1] = [2.5, -1.5]  # cell (2, -2)
    if shift == 0:
        nv[0] = [-0.4, 0.3]  # shares cell (0, 0) with tr[0] only when rounded half to even
    return tr.astype(np.float32).astype(float), nv.astype(np.float32).astype(float)


def adversity_numbers(flip=False):
    """dtw (type -> E × R × NP × 2), worse slot; the worse agent of a diverse-trained connector is disrupted
    more (about 2.0) than the uniform-trained one's (about 1.0); the better ones about 0.5 for both"""
    rng = np.random.default_rng(5)
    dtw, ws = {}, {}
    level = {A.UNIFORM: 1.0, A.DIVERSE: 2.0}
    for t in TYPES:
        lv = level[t] if not flip else level[A.DIVERSE if t == A.UNIFORM else A.UNIFORM]
        d = np.empty((len(ENVS), NR, NP, 2))
        w = rng.integers(0, 2, (len(ENVS), NR, NP)).astype(np.uint8)
        worse = lv + rng.normal(0, 0.1, w.shape)
        better = 0.5 + rng.normal(0, 0.1, w.shape)
        np.put_along_axis(d, w[..., None].astype(int), worse[..., None], axis=3)
        np.put_along_axis(d, (1 - w)[..., None].astype(int), better[..., None], axis=3)
        d[1, 0, 2, :] = np.nan  # a not-ok episode
        dtw[t], ws[t] = d, w
    return dtw, ws


def write_analysis(f, status="complete", flip=False, novel=NOVEL, tamper=False, table=True):
    envs = ["flat"] + list(novel)
    g = f.create_group("analysis")
    g.attrs["status"] = status
    g.attrs["types"] = ",".join(TYPES)
    g.attrs["environments"] = ",".join(envs)
    g.attrs["novel_environments"] = ",".join(novel)
    g.attrs["dtw_envs_done"] = len(envs) if status == "complete" else 1
    g.attrs["familiarity_envs_done"] = len(novel) if status == "complete" else 0
    dtw, ws = adversity_numbers(flip)
    rm = np.zeros((2, 2, NR))
    for ti, t in enumerate(TYPES):
        f[f"analysis/adversity/{t}/dtw"] = dtw[t]
        f[f"analysis/adversity/{t}/worse_slot"] = ws[t]
        f[f"analysis/adversity/{t}"].attrs["ties"] = 0
        d = dtw[t]
        w = ws[t].astype(int)[..., None]
        worse = np.take_along_axis(d, w, axis=3)[..., 0]
        better = np.take_along_axis(d, 1 - w, axis=3)[..., 0]
        for r in range(NR):
            rm[ti, 0, r] = np.nanmean(worse[:, r])
            rm[ti, 1, r] = np.nanmean(better[:, r])
    f["analysis/adversity/replicate_means"] = rm
    sm = np.zeros((2, 2, 3))
    for ti in range(2):
        for k in range(2):
            v = rm[ti, k]
            sm[ti, k] = [v.mean(), v.min(), v.max()]  # any CI around the mean will do here
    f["analysis/adversity/summary"] = sm
    wl = np.array([A.welch(rm[0, k], rm[1, k]) for k in range(2)])
    f["analysis/adversity/welch"] = wl
    f["analysis/adversity"].attrs["deploy_mismatches"] = 0
    rng = np.random.default_rng(11)
    counts = {t: np.zeros((len(novel), NR, 6)) for t in TYPES}
    for t in TYPES:
        emb = np.full((len(novel), NR, 2 * MAXS, 2), np.nan, np.float32)
        ns = np.zeros((len(novel), NR, 2), np.int64)
        for e in range(len(novel)):
            for r in range(NR):
                nt, nn = MAXS - r, MAXS - 2 * r  # uneven, so the NaN padding sits in different places
                familiar = (t == A.DIVERSE) != flip
                tr, nv = fit(rng, nt, nn, 0.0 if familiar else 7.0)
                emb[e, r, :nt] = tr
                emb[e, r, nt:nt + nn] = nv
                ns[e, r] = nt, nn
                counts[t][e, r] = hand_counts(tr, nv)
        g = f.require_group("analysis/familiarity")
        schema_dataset(g, f"{t}/embedding", emb, "novel_env,replicate,state,component", novel_env=novel)
        schema_dataset(g, f"{t}/n_states", ns, "novel_env,replicate,source", novel_env=novel,
                       source=["training", "novel"])
        c = counts[t].copy()
        if tamper and t == A.UNIFORM:
            c[:, 0, 0] += 3
        schema_dataset(g, f"{t}/counts", c, "novel_env,replicate,count", novel_env=novel,
                       count=["states_both", "states_train_only", "states_novel_only", "cells_both",
                              "cells_train_only", "cells_novel_only"])
    if table:
        tab = np.zeros((len(novel), 3, 3))
        for e in range(len(novel)):
            for k in range(3):
                d, u = counts[A.DIVERSE][e, :, k], counts[A.UNIFORM][e, :, k]
                tab[e, k] = [d.mean(), u.mean(), A.welch(d, u)[2]]
        schema_dataset(f["analysis/familiarity"], "table", tab, "novel_env,cell_class,table_column", novel_env=novel,
                       cell_class=["both", "train_only", "novel_only"],
                       table_column=["diverse_mean", "uniform_mean", "welch_p"])
    return counts


PAPER_COUNTS = ("[agents]\npopulation = 100\ngenerations = 15\n[connectors]\nreplicates = 10\niterations = 100\n"
                "batch_pairs = 100\n[deploy]\npairs = 100\n")


def write_run(path, analysis=True, **kw):
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "divcoll-run"
        f.attrs["version"] = 1
        f.attrs["seed"] = 3
        f.attrs["git_commit"] = "0123456789ab"
        # the counts of the paper (claims are judged only at a scale large enough for their tests)
        f.attrs["config"] = ('[run]\nseed = 3\nname = "synthetic"\n[analysis]\ndtw_every = 10\ndtw_band = 0.1\n'
                             'max_states = 10000\nbootstrap_resamples = 1000\n' + PAPER_COUNTS)
        if analysis:
            return write_analysis(f, **kw)
    return None


class Base(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.full = os.path.join(cls.tmp.name, "full.h5")
        cls.counts = write_run(cls.full)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.tmp.name, name)


class CellsTest(unittest.TestCase):
    def test_half_to_even(self):
        # 0.5 -> 0 and -0.5 -> 0 (half to even): the training and the novel state share cell (0, 0)
        label, c = A.classify_cells([[0.5, 0.5]], [[-0.5, -0.4]])
        np.testing.assert_array_equal(label, [0, 0])
        np.testing.assert_array_equal(c, [2, 0, 0, 1, 0, 0])
        # 1.5 -> 2, 2.5 -> 2: shared; 3.5 -> 4 is its own cell
        label, c = A.classify_cells([[1.5, 0.0], [3.5, 0.0]], [[2.5, 0.2]])
        np.testing.assert_array_equal(label, [0, 1, 0])
        np.testing.assert_array_equal(c, [2, 1, 0, 1, 1, 0])
        label, c = A.classify_cells(np.zeros((0, 2)), [[0.1, 0.1], [5, 5]])
        np.testing.assert_array_equal(label, [2, 2])
        np.testing.assert_array_equal(c, [0, 0, 2, 0, 0, 2])

    def test_welch_matches_the_reference_numbers(self):
        # ANALYSIS.md §4.3
        t, df, p = A.welch(np.arange(1, 11), np.arange(11, 21))
        self.assertAlmostEqual(t, -7.38549, places=4)
        self.assertAlmostEqual(df, 18.0, places=6)
        self.assertAlmostEqual(p / 7.503e-7, 1.0, places=3)
        a = [1.0, 1.2, 0.9, 1.1, 1.05, 0.95, 1.15, 0.85, 1.0, 1.1]
        b = [1.3, 2.0, 1.1, 2.5, 1.6, 1.2, 2.2, 1.4, 1.9, 1.0]
        t, df, p = A.welch(a, b)
        self.assertAlmostEqual(df, 9.8607, places=3)
        self.assertAlmostEqual(p, 0.005017, places=5)
        self.assertTrue(np.isnan(A.welch([1.0, 1.0], [1.0, 1.0])[2]))
        self.assertEqual([A.stars(x) for x in (1e-4, 0.005, 0.03, 0.2, np.nan)], ["***", "**", "*", "n.s.", "—"])


class ReaderTest(Base):
    def test_recomputed_cells_match_the_counts_of_a_consistent_file(self):
        an = A.load_analysis(self.full)
        self.assertEqual(an.familiarity.envs, NOVEL)
        n_shared = 0
        for t in TYPES:
            for e, env in enumerate(NOVEL):
                for r in range(NR):
                    tr, nv = an.embedding(t, env, r)
                    self.assertEqual((len(tr), len(nv)), (MAXS - r, MAXS - 2 * r))
                    _, c = A.classify_cells(tr, nv)
                    np.testing.assert_array_equal(c, an.familiarity.counts[t][e, r], (t, env, r))
                    np.testing.assert_array_equal(c, self.counts[t][e, r])
                    self.assertEqual(c[:3].sum(), len(tr) + len(nv))
                    n_shared += c[0]
        self.assertGreater(n_shared, 0)
        # the diverse-trained connector's states overlap training more (the synthetic file is built so)
        tab = an.familiarity.best_table()
        self.assertTrue((tab[:, 0, 0] > tab[:, 0, 1]).all())
        np.testing.assert_allclose(tab, an.familiarity.recomputed_table(), equal_nan=True)

    def test_stored_replicate_means_agree_with_dtw(self):
        an = A.load_analysis(self.full)
        self.assertEqual(fig3.check_replicate_means(an.adversity), [])
        B = fig3.adversity_bars(an.adversity, n_boot=200)
        self.assertGreater(B["worse"][A.DIVERSE][0], B["worse"][A.UNIFORM][0])
        self.assertLess(B["worse_p"], 0.001)
        # all agents: the mean of the replicate means of every finite DTW, both slots
        d = an.adversity.dtw[A.DIVERSE]
        want = np.mean([np.nanmean(d[:, r]) for r in range(NR)])
        self.assertAlmostEqual(B["all"][A.DIVERSE][0], want)
        lo, hi = B["all"][A.DIVERSE][1:3]
        self.assertLessEqual(lo, want)
        self.assertGreaterEqual(hi, want)

    def test_partial_stage_reads_only_what_is_done(self):
        p = self.path("running.h5")
        write_run(p, status="running")
        an = A.load_analysis(p, need=("adversity",))
        self.assertEqual(an.adversity.envs, ["flat"])
        self.assertIsNone(an.familiarity)
        with self.assertRaises(A.StageMissing):
            A.load_analysis(p, need=("familiarity",))


class ScriptsTest(Base):
    def test_fig3_and_table_s1_write_their_files(self):
        out = self.path("figs")
        rc, err = call(fig3.main, [self.full, "--out", out, "--dpi", "60", "--boot", "200"])
        self.assertEqual(rc, 0, err)
        self.assertNotIn("warning", err)
        png_ok(self, os.path.join(out, fig3.STEM + ".png"))
        pdf_ok(self, os.path.join(out, fig3.STEM + ".pdf"))
        rc, err = call(table_s1.main, [self.full, "--out", out])
        self.assertEqual(rc, 0, err)
        text = read(os.path.join(out, table_s1.NAME))
        rows = [ln for ln in text.splitlines() if ln.startswith("| ice") or ln.startswith("| wind")]
        self.assertEqual(len(rows), 2)
        for ln in rows:
            cells = [c.strip() for c in ln.split("|")[1:-1]]
            self.assertTrue(cells[1].startswith("**"), ln)  # diverse "both" is the larger mean: bold
            self.assertFalse(cells[2].startswith("**"), ln)
            self.assertTrue(cells[3].endswith("*"), ln)  # p < 0.05 marked
            self.assertEqual(cells[-1], "diverse")
        self.assertIn("in 2 of 2 environments (2 with p < 0.05)", text)
        self.assertIn(f"| {MAXS - 1.5:g} + {MAXS - 3:g} |", text)  # states per fit: means over replicates

    def test_fig3_falls_back_to_the_first_novel_environment_without_wind(self):
        p = self.path("nowind.h5")
        write_run(p, novel=["ice", "gap"])
        out = self.path("nowind")
        rc, err = call(fig3.main, [p, "--out", out, "--dpi", "50", "--boot", "100"])
        self.assertEqual(rc, 0, err)
        self.assertIn("wind has no familiarity fit in this run file; showing ice", err)
        png_ok(self, os.path.join(out, fig3.STEM + ".png"))

    def test_fig3_reports_counts_that_disagree_with_the_embedding(self):
        p = self.path("tampered.h5")
        write_run(p, tamper=True)
        rc, err = call(fig3.main, [p, "--out", self.path("tampered"), "--dpi", "50", "--boot", "100"])
        self.assertEqual(rc, 0, err)
        self.assertIn("the run file's counts are", err)

    def test_refused_without_analysis(self):
        p = self.path("none.h5")
        write_run(p, analysis=False)
        out = self.path("refused")
        for mod in (fig3, table_s1):
            rc, err = call(mod.main, [p, "--out", out])
            self.assertEqual(rc, 2, mod.__name__)
            self.assertIn("run file has no analysis stage (run the analysis stage first)", err)
            self.assertEqual(len(err.strip().splitlines()), 1, err)
        # familiarity not done yet: table_s1 refuses; fig3 too (it needs both parts)
        r = self.path("running2.h5")
        write_run(r, status="running")
        for mod in (fig3, table_s1):
            rc, err = call(mod.main, [r, "--out", out])
            self.assertEqual(rc, 2, mod.__name__)
            self.assertIn("no familiarity environment done yet", err)
        self.assertFalse(os.path.exists(out))

    def test_table_without_stored_table_is_recomputed(self):
        p = self.path("notable.h5")
        write_run(p, table=False)
        text, rows, notes = table_s1.render(p)
        self.assertIn("recomputed here from the counts", text)
        self.assertEqual(notes, [])
        self.assertEqual([r[0] for r in rows], NOVEL)


class ClaimsTest(Base):
    def verdicts(self, path):
        return {c.id: (number, v) for c, number, v, _ in claims.claims(path)}

    def by_start(self, got, cid):
        return got[cid]

    def test_claims_follow_the_numbers_and_flip(self):
        flipped = self.path("flipped.h5")
        write_run(flipped, flip=True)
        got, flip = self.verdicts(self.full), self.verdicts(flipped)
        # C19 worse agents changed more, C17 disrupted more, C21 more familiar, C22 more novel-only states, C24 wind
        for start in ("C19", "C17", "C21", "C22", "C24"):
            self.assertEqual(self.by_start(got, start)[1], "held", start)
            self.assertEqual(self.by_start(flip, start)[1], "did not hold", start)
        # independent of the flip: worse agents altered more (C18); better agents comparable within ±0.005 u (C20:
        # the same verdict either way)
        for g in (got, flip):
            self.assertEqual(self.by_start(g, "C18")[1], "held")
        self.assertEqual(self.by_start(got, "C20")[1], self.by_start(flip, "C20")[1])
        number, _ = self.by_start(got, "C19")
        self.assertIn("(***)", number)
        self.assertIn("in 2 of 2 novel environments", self.by_start(got, "C21")[0])

    def test_not_measured_without_a_complete_analysis(self):
        p = self.path("running3.h5")
        write_run(p, status="running")
        got = self.verdicts(p)
        number, v = self.by_start(got, "C18")
        self.assertEqual(v, "not measured")
        self.assertIn("status 'running'", number)
        text = summary.summarize(p)
        self.assertIn("| analysis | running |", text)
        self.assertIn("not summarized", text)
        self.assertIn("**Adversity** (Fig. 3A", summary.summarize(self.full))


class ReportTest(Base):
    def setUp(self):
        self.saved = report.FIGURES
        report.FIGURES = [("fig3.py", [])]  # the other figure scripts have their own tests

    def tearDown(self):
        report.FIGURES = self.saved

    def test_report_has_fig3_and_table_s1_or_skips_them_with_a_note(self):
        out = self.path("report")
        path, n, v = report.write_report(self.full, out, "divcoll")
        page = read(path)
        self.assertEqual(n, 1)
        self.assertIn("figures/fig3_adversity_familiarity.png", page)
        self.assertIn("## Table S1", page)
        self.assertIn("| ice |", page)
        self.assertTrue(os.path.isfile(os.path.join(out, "table_s1.md")))
        run2 = self.path("running4.h5")
        write_run(run2, status="running")
        out2 = self.path("report2")
        path, n, v = report.write_report(run2, out2, "divcoll")
        page = read(path)
        self.assertEqual(n, 0)
        self.assertIn("`fig3.py` skipped: analysis stage status 'running'", page)
        self.assertIn("Skipped: analysis stage status 'running'", page)
        none = self.path("none2.h5")
        write_run(none, analysis=False)
        path, _, _ = report.write_report(none, self.path("report3"), "divcoll")
        self.assertIn("the run file has no analysis stage", read(path))


if __name__ == "__main__":
    unittest.main()
