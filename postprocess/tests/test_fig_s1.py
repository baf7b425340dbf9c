"""Tests of the run-file reader and divcoll_post.figures.fig_s1 on a synthetic run file.

    cd <repo> && /usr/bin/python3 -m unittest discover -s postprocess/tests -v
"""

import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import h5py

HERE = os.path.dirname(os.path.abspath(__file__))
POST = os.path.dirname(HERE)
sys.path.insert(0, POST)

from divcoll_post import runfile  # noqa: E402
from divcoll_post.figures import fig_s1  # noqa: E402

ROWS, COLS = 4, 7
M = 12


def lattice_pos(r, c):
    """SPEC §4.1: cell (r, c) at (0.05c + 0.025(r mod 2), 0.05 r √3/2)."""
    return 0.05 * c + 0.025 * (r % 2), 0.05 * r * np.sqrt(3) / 2


def neighbours(r, c):
    out = [(r, c - 1), (r, c + 1)]
    dc = (-1, 0) if r % 2 == 0 else (0, 1)
    for dr in (-1, 1):
        for d in dc:
            out.append((r + dr, c + d))
    return [(a, b) for a, b in out if 0 <= a < ROWS and 0 <= b < COLS]


def random_bodies(n, rng):
    """n distinct 11-cell connected lattice shapes with exactly 21 neighbour edges, found by random
    compact growth (enough for a test; the program's generator also checks holes)."""
    shapes, seen = [], set()
    for _ in range(20000):
        start = (int(rng.integers(ROWS)), int(rng.integers(COLS)))
        cells = {start}
        while len(cells) < 11:
            front = sorted({q for p in cells for q in neighbours(*p)} - cells)
            w = np.array([sum(q in cells for q in neighbours(*f)) for f in front], float) ** 3
            cells.add(front[rng.choice(len(front), p=w / w.sum())])
        order = sorted(cells)  # row-major
        idx = {p: k for k, p in enumerate(order)}
        edges = sorted({tuple(sorted((idx[p], idx[q]))) for p in order for q in neighbours(*p) if q in cells})
        if len(edges) != 21:
            continue
        key = frozenset(order)  # distinct placements (shapes may repeat shifted; fine here)
        if key in seen:
            continue
        seen.add(key)
        shapes.append((order, edges))
        if len(shapes) == n:
            return shapes
    raise RuntimeError("could not grow enough shapes")


def agent_rows(n, rng, id0=0):
    shapes = random_bodies(n, rng)
    d = {k: [] for k in ("cells", "springs", "rest_pos", "spring_i", "spring_j", "amplitude")}
    for order, edges in shapes:
        pos = np.array([lattice_pos(r, c) for r, c in order])
        pos -= pos.min(axis=0)
        bits = rng.random(21) < 0.5
        bits[0] = True
        d["cells"].append(sum(1 << (r * COLS + c) for r, c in order))
        d["springs"].append(sum(1 << k for k in range(21) if bits[k]))
        d["rest_pos"].append(pos)
        d["spring_i"].append([e[0] for e in edges])
        d["spring_j"].append([e[1] for e in edges])
        d["amplitude"].append(np.where(bits, 0.15, 0.0))
    out = {
        "id": np.arange(id0, id0 + n, dtype=np.int64),
        "parent": np.full(n, -1, np.int64),
        "cells": np.array(d["cells"], np.int64),
        "springs": np.array(d["springs"], np.int64),
        "rest_pos": np.array(d["rest_pos"], np.float64),
        "spring_i": np.array(d["spring_i"], np.int32),
        "spring_j": np.array(d["spring_j"], np.int32),
        "amplitude": np.array(d["amplitude"], np.float64),
        "params": rng.normal(size=(n, 3509)),
        "fitness": rng.uniform(0.2, 4.0, n),
        "descriptor": rng.normal(size=(n, 9)),
        "uniqueness": rng.uniform(0, 1, n),
        "status": np.zeros(n, np.uint8),
    }
    out["travel_u"] = out["fitness"] * 0.3
    return out


def write_run(path, rng, final=True, n=M):
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "divcoll-run"
        f.attrs["version"] = 1
        f.attrs["git_commit"] = "0123456789ab"
        f.attrs["ranks"] = 2
        f.attrs["seed"] = 7
        f.attrs["config"] = '[run]\nseed = 7\nname = "synthetic"\n\n[agents]\npopulation = 12\n'
        a = f.create_group("agents")
        a.attrs["status"] = "complete" if final else "running"
        a.attrs["generations_done"] = 2 if final else 1
        for g in range(2 if final else 1):
            rows = agent_rows(2 * n, rng, id0=100 * g)
            grp = a.create_group(f"gen_{g:03d}")
            for k, v in rows.items():
                grp.create_dataset(k, data=v)
            grp.create_dataset("survived", data=(np.arange(2 * n) % 2).astype(np.uint8))
        if final:
            rows = agent_rows(n, rng, id0=1000)
            rows["status"][-1] = 2  # one unstable agent
            rows["fitness"][-1] = np.nan
            grp = a.create_group("final")
            for k, v in rows.items():
                grp.create_dataset(k, data=v)
    return path


def png_size(path):
    with open(path, "rb") as fh:
        head = fh.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG signature"
    assert head[12:16] == b"IHDR"
    return struct.unpack(">II", head[16:24])


class FigS1Test(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="fig_s1_test_")
        cls.run_path = write_run(os.path.join(cls.tmp, "run.h5"), np.random.default_rng(1))

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def fig(self, path, out=None):
        out = out or os.path.join(self.tmp, "figs")
        return subprocess.run([sys.executable, "-m", "divcoll_post.figures.fig_s1", path, "--out", out],
                              capture_output=True, text=True, timeout=300, env=dict(os.environ, PYTHONPATH=POST))

    # --- reader -----------------------------------------------------------------------------------
    def test_reader_final_shapes(self):
        p = runfile.read_final(self.run_path)
        self.assertEqual(len(p), M)
        self.assertEqual(p.rest_pos.shape, (M, 11, 2))
        self.assertEqual(p.spring_i.shape, (M, 21))
        self.assertEqual(p.spring_j.shape, (M, 21))
        self.assertEqual(p.amplitude.shape, (M, 21))
        self.assertEqual(p.params.shape, (M, 3509))
        self.assertEqual(p.descriptor.shape, (M, 9))
        for k in ("id", "parent", "cells", "springs", "fitness", "travel_u", "uniqueness", "status"):
            self.assertEqual(getattr(p, k).shape, (M,), k)
        self.assertEqual(p.status.dtype, np.uint8)
        self.assertEqual(p.spring_i.dtype, np.int32)
        self.assertTrue(np.all(p.spring_i < p.spring_j))
        self.assertIsNone(p.survived)
        self.assertIsNone(runfile.read_final(self.run_path, params=False).params)
        np.testing.assert_allclose(p.rest_pos.min(axis=1), 0.0, atol=1e-12)

    def test_reader_meta_and_generations(self):
        m = runfile.read_meta(self.run_path)
        self.assertEqual(m.format, "divcoll-run")
        self.assertEqual(m.name, "synthetic")
        self.assertEqual(m.seed, 7)
        self.assertEqual(m.ranks, 2)
        self.assertEqual(m.agents_status, "complete")
        self.assertEqual(m.generations_done, 2)
        self.assertEqual(runfile.list_generations(self.run_path), [0, 1])
        g = runfile.read_generation(self.run_path, 1)
        self.assertEqual(len(g), 2 * M)
        self.assertEqual(g.survived.shape, (2 * M,))
        self.assertEqual(int(g.id[0]), 100)
        with self.assertRaises(runfile.RunFileError):
            runfile.read_generation(self.run_path, 5)

    def test_reader_refuses_foreign(self):
        foreign = os.path.join(self.tmp, "foreign_r.h5")
        with h5py.File(foreign, "w") as f:
            f.create_dataset("x", data=np.zeros(3))
        with self.assertRaisesRegex(runfile.RunFileError, "format"):
            runfile.read_final(foreign)
        scene = os.path.join(self.tmp, "scene_r.h5")
        with h5py.File(scene, "w") as f:
            f.attrs["format"] = "divcoll-scene"
        with self.assertRaisesRegex(runfile.RunFileError, "divcoll-scene"):
            runfile.read_meta(scene)
        with self.assertRaisesRegex(runfile.RunFileError, "no such file"):
            runfile.read_meta(os.path.join(self.tmp, "missing.h5"))

    # --- figure helpers ---------------------------------------------------------------------------
    def test_order_and_titles(self):
        f = np.array([1.0, 3.9, np.nan, 2.5, 3.9])
        s = np.array([0, 0, 1, 2, 0], np.uint8)
        self.assertEqual(fig_s1.fitness_order(f, s).tolist(), [1, 4, 0, 2, 3])
        self.assertEqual(fig_s1.panel_title(3, 3.912, 0), "#3  3.9 BL")
        self.assertEqual(fig_s1.panel_title(5, np.nan, 2), "#5  unstable")
        self.assertEqual(fig_s1.grid_shape(100), (10, 10))
        self.assertEqual(fig_s1.grid_shape(12), (3, 4))

    # --- the script -------------------------------------------------------------------------------
    def test_figure_written(self):
        out = os.path.join(self.tmp, "figs")
        r = self.fig(self.run_path, out)
        self.assertEqual(r.returncode, 0, r.stderr)
        png = os.path.join(out, "fig_s1_morphologies.png")
        pdf = os.path.join(out, "fig_s1_morphologies.pdf")
        self.assertIn(png, r.stdout)
        self.assertIn(pdf, r.stdout)
        w, h = png_size(png)
        self.assertTrue(600 <= w <= 4000 and 300 <= h <= 4000, (w, h))
        self.assertGreater(os.path.getsize(png), 20_000)
        with open(pdf, "rb") as fh:
            self.assertEqual(fh.read(5), b"%PDF-")
        import matplotlib.image as mimg

        im = mimg.imread(png)
        self.assertEqual(im.shape[:2], (h, w))
        rgb = im[:, :, :3]
        # some dark-red active-spring pixels and some light-grey passive-spring pixels
        red = (rgb[:, :, 0] > 0.55) & (rgb[:, :, 1] < 0.25) & (rgb[:, :, 2] < 0.3)
        grey = (np.abs(rgb[:, :, 0] - 0.74) < 0.04) & (np.abs(rgb[:, :, 1] - rgb[:, :, 0]) < 0.02) \
            & (np.abs(rgb[:, :, 2] - rgb[:, :, 0]) < 0.02)
        self.assertGreater(int(red.sum()), 500)
        self.assertGreater(int(grey.sum()), 500)

    def assert_refused(self, path, *needles):
        r = self.fig(path, os.path.join(self.tmp, "refused"))
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        for n in needles:
            self.assertIn(n, r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "refused", "fig_s1_morphologies.png")))

    def test_refuses_foreign_hdf5(self):
        path = os.path.join(self.tmp, "foreign.h5")
        with h5py.File(path, "w") as f:
            f.create_dataset("x", data=np.zeros(3))
        self.assert_refused(path, "format")

    def test_refuses_text_file(self):
        path = os.path.join(self.tmp, "notes.txt")
        with open(path, "w") as fh:
            fh.write("this is not a run file\n")
        self.assert_refused(path, "not an HDF5 file")

    def test_refuses_truncated_file(self):
        path = os.path.join(self.tmp, "truncated.h5")
        with open(self.run_path, "rb") as src, open(path, "wb") as dst:
            dst.write(src.read(os.path.getsize(self.run_path) // 2))
        self.assert_refused(path, "truncated")

    def test_refuses_missing_final(self):
        path = write_run(os.path.join(self.tmp, "running.h5"), np.random.default_rng(2), final=False)
        self.assert_refused(path, "agents/final", "running")


if __name__ == "__main__":
    unittest.main()
