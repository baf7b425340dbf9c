"""End-to-end tests of what a user sees, on a real run file of the tiny preset (made once, ~20 s):
`divcoll demo --run` (the run's trained agents and connector, travel equal to the run file's, no stale text),
how `divcoll report` picks its Python, `divcoll movie`, and report.html opened in headless Chromium (every
image and video loads, no console error; skipped with the reason where Chromium cannot start).

    DIVCOLL_BINARY=build/divcoll /usr/bin/python3 -m unittest postprocess/tests/e2e_report_test.py -v

Run by ctest as postprocess.e2e_report (its own test: it takes minutes, not seconds). Not named test_*.py, so
the quick `unittest discover` of postprocess.unittest leaves it out.
"""
import html
import os
import re
import shlex
import shutil
import stat
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
POST = os.path.dirname(HERE)
REPO = os.path.dirname(POST)
sys.path.insert(0, POST)

from divcoll_post import html_check  # noqa: E402

BIN = os.path.abspath(os.environ.get("DIVCOLL_BINARY", os.path.join(REPO, "build", "divcoll")))


def run(args, env=None, check=True):
    p = subprocess.run(args, capture_output=True, text=True, env=env)
    if check and p.returncode != 0:
        raise AssertionError(f"{' '.join(args)} exited {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p


def probe(mp4):
    """(width, height, frames) of an MP4's video stream"""
    out = run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
               "stream=width,height,nb_read_frames", "-of", "csv=p=0", mp4]).stdout.strip()
    w, h, n = out.split(",")[:3]
    return int(w), int(h), int(n)


@unittest.skipUnless(os.path.exists(BIN), f"no divcoll binary at {BIN} (set DIVCOLL_BINARY)")
class EndToEnd(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.run_file = os.path.join(cls.dir, "tiny.h5")
        run([BIN, "run", os.path.join(REPO, "configs", "tiny.toml"), "--out", cls.run_file])

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def script(self, name, body):
        d = os.path.join(self.dir, name)
        os.makedirs(d, exist_ok=True)
        p = os.path.join(d, "python3")
        with open(p, "w") as fh:
            fh.write("#!/bin/sh\n" + body + "\n")
        os.chmod(p, os.stat(p).st_mode | stat.S_IEXEC)
        return d, p

    # item 3: the demo walks the run's trained agents with its trained connector
    def test_demo_uses_the_runs_trained_agents_and_connector(self):
        out = os.path.join(self.dir, "demo")
        p = run([BIN, "demo", "--run", self.run_file, "--out", out, "--env", "ice"])
        self.assertIn("trained agents of", p.stdout)
        self.assertIn("weak diverse-trained connector", p.stdout)
        self.assertNotIn("untrained", p.stdout)
        self.assertNotIn("until the agents stage", p.stdout)
        self.assertNotIn("differs from the run file", p.stdout)
        rows = {m.group(1): (float(m.group(2)), float(m.group(3)))
                for m in re.finditer(r"^(flat|ice)\s+\S+\s+(\S+)\s+ok\s+(\S+)", p.stdout, re.M)}
        self.assertEqual(set(rows), {"flat", "ice"})
        for env, (got, stored) in rows.items():
            self.assertAlmostEqual(got, stored, places=4, msg=env)  # the episode the run file records
        # the median pair of replicate 0 on flat, read back from the run file
        import h5py
        import numpy as np
        with h5py.File(self.run_file, "r") as f:
            types = f["deploy"].attrs["types"]
            types = (types.decode() if isinstance(types, bytes) else types).split(",")
            v = f["deploy/collectives/travel_bl"][0, types.index("weak_diverse@diverse"), 0]
        self.assertAlmostEqual(rows["flat"][1], float(np.sort(v)[(len(v) - 1) // 2]), places=4)
        for f in ("pair_flat_scene.h5", "pair_flat_traj.h5", "pair_ice_scene.h5", "pair_ice_traj.h5"):
            self.assertTrue(os.path.isfile(os.path.join(out, f)), f)

    def test_demo_without_a_run_says_its_agents_are_untrained(self):
        p = run([BIN, "demo", "--out", os.path.join(self.dir, "demo0"), "--steps", "50"])
        self.assertIn("random, untrained agents", p.stdout)
        self.assertIn("--run RUN.h5", p.stdout)

    def test_demo_movie_is_1280_wide(self):
        out = os.path.join(self.dir, "demo_movie")
        run([BIN, "demo", "--run", self.run_file, "--out", out, "--movie"])
        w, h, n = probe(os.path.join(out, "demo.mp4"))
        self.assertEqual((w, h), (1280, 720))
        self.assertGreater(n, 5)

    # item 6: which Python `divcoll report` runs under, and that it says so
    def test_report_python_from_divcoll_python(self):
        log = os.path.join(self.dir, "argv.txt")
        _, fake = self.script("fake_env", f'echo "$@" > {log}')
        env = dict(os.environ, DIVCOLL_PYTHON=fake)
        p = run([BIN, "report", self.run_file, "--out", os.path.join(self.dir, "r0")], env=env)
        self.assertIn(f"divcoll: Python {fake} (from DIVCOLL_PYTHON)", p.stdout)
        with open(log) as fh:
            argv = fh.read()
        self.assertIn("-m divcoll_post.report", argv)
        self.assertIn(self.run_file, argv)
        env["DIVCOLL_PYTHON"] = os.path.join(self.dir, "no_such_python")
        p = run([BIN, "report", self.run_file], env=env, check=False)
        self.assertEqual(p.returncode, 2)
        self.assertIn("DIVCOLL_PYTHON", p.stderr)

    def test_report_python_first_on_path_with_the_modules_else_usr_bin(self):
        not_a_run = os.path.join(self.dir, "not_a_run.txt")
        with open(not_a_run, "w") as fh:
            fh.write("text\n")
        env = {k: v for k, v in os.environ.items() if k != "DIVCOLL_PYTHON"}
        bare, _ = self.script("bare", "exit 1")  # a python3 without numpy, h5py, matplotlib
        good, _ = self.script("good", 'exec /usr/bin/python3 "$@"')
        env["PATH"] = f"{bare}:{good}:/usr/bin:/bin"
        p = run([BIN, "report", not_a_run], env=env, check=False)
        self.assertIn(f"divcoll: Python {good}/python3 (the first python3 on PATH that has numpy, h5py and "
                      "matplotlib)", p.stdout)
        self.assertEqual(p.returncode, 2)  # divcoll_post.report ran under it and refused the file
        self.assertRegex(p.stderr, r"^report: ")  # divcoll_post.report itself refused the file
        env["PATH"] = bare
        p = run([BIN, "report", not_a_run], env=env, check=False)
        self.assertIn(f"divcoll: Python /usr/bin/python3 (Debian's; no python3 on PATH has numpy, h5py and "
                      f"matplotlib (tried {bare}/python3))", p.stdout)
        self.assertEqual(p.returncode, 2)

    # items 4 and 5: the movie, and the report page in a browser
    def test_movie_has_three_parts_at_1280_by_720(self):
        out = os.path.join(self.dir, "movie")
        run([BIN, "movie", self.run_file, "--out", out, "--quick"])
        for name in ("supplementary_movie.mp4", "agent_optimisation.mp4", "connector_optimisation.mp4",
                     "deployment.mp4"):
            w, h, n = probe(os.path.join(out, name))
            self.assertEqual((w, h), (1280, 720), name)
            self.assertGreater(n, 2, name)
        parts = sum(probe(os.path.join(out, p))[2] for p in ("agent_optimisation.mp4", "connector_optimisation.mp4",
                                                             "deployment.mp4"))
        self.assertGreater(probe(os.path.join(out, "supplementary_movie.mp4"))[2], parts)  # plus the title cards

    @classmethod
    def report_page(cls):
        """`divcoll report` of the tiny run, made once: (stdout, report.html's path, its text)"""
        if not hasattr(cls, "_page"):
            out = os.path.join(cls.dir, "report")
            p = run([BIN, "report", cls.run_file, "--out", out])
            page = os.path.join(out, "report.html")
            with open(page) as fh:
                cls._page = (p.stdout, page, fh.read())
        return cls._page

    def test_report_html_loads_in_chromium(self):
        stdout, page, text = self.report_page()
        self.assertIn("report.html", stdout)
        self.assertIn("Preset <code>tiny</code>", text)
        self.assertIn("Arithmetic: <code>run.precision = double</code> (the spec's).", text)
        self.assertIn("too small to judge", text)
        self.assertIn("claims judged over independent populations", text)
        self.assertIn("postprocess/gallery/verdicts/verdicts.md", text)
        self.assertIn("<video controls", text)
        self.assertNotRegex(text, r'src="https?://')  # nothing from the network
        try:
            problems, facts = html_check.check(page, os.path.join(self.dir, "shot.png"))
        except html_check.CannotStart as e:
            self.skipTest(f"Chromium cannot start here: {e}")
        self.assertEqual(problems, [])
        self.assertGreaterEqual(len(facts["imgs"]), 6)  # the figures
        self.assertGreaterEqual(len(facts["vids"]), 1)
        self.assertTrue(all(v["width"] >= 1280 for v in facts["vids"]), facts["vids"])

    # item 5: every number links to the `divcoll export` command of its episode, and the commands run
    def test_report_links_numbers_to_export_commands_that_run(self):
        _, _, text = self.report_page()
        ids = set(re.findall(r'<li id="(ep-[^"]+)"', text))
        hrefs = re.findall(r'href="#(ep-[^"]+)"', text)
        self.assertTrue(hrefs)
        self.assertEqual(sorted(set(hrefs) - ids), [])  # every link has its episode
        self.assertEqual(sorted(ids - set(hrefs)), [])  # and every listed episode is linked from a number
        # the claims table: one row per claim, its episodes column linking wherever the claim has episodes
        claims_table = text[text.index('id="the-paper-s-claims-beside-this-run"'):]
        claims_table = claims_table[:claims_table.index("</table>")]
        rows = re.findall(r"<tr>(.*?)</tr>", claims_table)[1:]
        from divcoll_post import verdicts as V
        self.assertEqual(len(rows), len(V.CLAIMS))
        unlinked = [r for r in rows if 'href="#ep-' not in r]
        # only the claims whose episodes are not exported (connector-training batches, generation 0's training)
        no_links = [c for c in V.CLAIMS if c.episodes.envs == "none"]
        self.assertEqual(len(unlinked), len(no_links), [r[:80] for r in unlinked])
        for r in unlinked:
            self.assertIn("are not exported", r)
        for kind in ("alone", "weak_diverse-at-diverse", "spec-", "chain-"):
            self.assertTrue(any(kind in h for h in hrefs), kind)
        # Fig. 2A per environment and the movie caption link single episodes
        self.assertIn('href="#ep-flat-weak_diverse-at-diverse"', text)
        self.assertRegex(text, r'href="#ep-\w+-weak_uniform-at-uniform-r0-p0"')
        # run one listed command pair as printed: the exported scene's travel is the page's, and simulate
        # reproduces the run file's travel bit for bit
        item = re.search(r'<li id="ep-ice-weak_diverse-at-diverse">(.*?)</li>', text).group(1)
        shown = float(re.search(r", (-?[0-9.]+) BL", item).group(1))
        cmds = [html.unescape(c) for c in re.findall(r"<code>(divcoll [^<]+)</code>", item)]
        self.assertEqual([c.split()[1] for c in cmds], ["export", "simulate"])
        work = os.path.join(self.dir, "from_page")
        os.makedirs(work, exist_ok=True)
        outs = [subprocess.run([BIN] + shlex.split(c)[1:], capture_output=True, text=True, cwd=work) for c in cmds]
        self.assertEqual([o.returncode for o in outs], [0, 0], [o.stderr for o in outs])
        stored = re.search(r"records travel (\S+) u \((\S+) BL\), status ok", outs[0].stdout)
        self.assertIsNotNone(stored, outs[0].stdout)
        self.assertAlmostEqual(float(stored.group(2)), shown, places=3)
        import h5py
        traj = shlex.split(cmds[1])[shlex.split(cmds[1]).index("--out") + 1]
        with h5py.File(os.path.join(work, traj), "r") as f:
            self.assertEqual(float(f.attrs["travel"]), float(stored.group(1)))

    def test_chromium_check_finds_a_broken_image_a_missing_video_and_a_console_error(self):
        page = os.path.join(self.dir, "broken.html")
        with open(page, "w") as fh:
            fh.write('<!DOCTYPE html><html><head><meta charset="utf-8"><title>x</title></head><body>'
                     '<img src="missing.png"><video controls src="missing.mp4"></video>'
                     '<script>console.error("boom")</script></body></html>')
        try:
            problems, _ = html_check.check(page)
        except html_check.CannotStart as e:
            self.skipTest(f"Chromium cannot start here: {e}")
        text = "\n".join(problems)
        self.assertIn("image did not load", text)
        self.assertIn("video did not load", text)
        self.assertIn("boom", text)
        # the console is read live and again from Chromium's replay: the error is still listed once
        self.assertEqual(sum("boom" in p for p in problems), 1, problems)


if __name__ == "__main__":
    unittest.main()
