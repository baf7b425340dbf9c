"""Tests of animate.py: the terrain drawn is the scene's, the GIF has the frames asked for, and a
trajectory of another scene is refused. Needs the divcoll binary (DIVCOLL_BINARY, set by ctest)."""

import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from divcoll_post import animate  # noqa: E402

BIN = os.environ.get("DIVCOLL_BINARY", os.path.join(HERE, "..", "..", "build", "divcoll"))


@unittest.skipUnless(os.path.exists(BIN), f"no divcoll binary at {BIN} (set DIVCOLL_BINARY)")
class MotionTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        d = cls.dir.name
        cls.scene = os.path.join(d, "pair.h5")
        cls.traj = os.path.join(d, "traj.h5")
        cls.agent = os.path.join(d, "agent.h5")
        subprocess.run([BIN, "scene", "--kind", "pair", "--env", "step_up", "--out", cls.scene], check=True,
                       capture_output=True)
        subprocess.run([BIN, "simulate", "--scene", cls.scene, "--steps", "60", "--out", cls.traj], check=True,
                       capture_output=True)
        subprocess.run([BIN, "scene", "--kind", "agent", "--env", "flat", "--out", cls.agent], check=True,
                       capture_output=True)

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def test_terrain_line_has_the_step_as_a_wall(self):
        ep = animate.Episode(self.scene, self.traj)
        xs, ys = ep.terrain_line(-1.0, 2.0)
        x_f = ep.terrain[1, 0]
        # left of the step the ground is at 0, right of it at +0.04 (SPEC §3), and the jump is at x_f
        self.assertTrue(np.all(ys[xs < x_f - 1e-12] == 0.0))
        self.assertTrue(np.allclose(ys[xs > x_f + 1e-12], 0.04))
        self.assertIn(x_f, xs)

    def test_gif_has_one_frame_per_drawn_step(self):
        from PIL import Image
        out = os.path.join(self.dir.name, "a.gif")
        n = animate.animate(self.scene, self.traj, out, every=20)
        self.assertEqual(n, 4)  # steps 0, 20, 40, 60 of 61 recorded states
        with Image.open(out) as im:
            self.assertEqual(im.n_frames, 4)

    def test_trajectory_of_another_scene_is_refused(self):
        rc = animate.main([self.agent, self.traj, "--out", os.path.join(self.dir.name, "x.gif")])
        self.assertEqual(rc, 2)
        self.assertFalse(os.path.exists(os.path.join(self.dir.name, "x.gif")))


if __name__ == "__main__":
    unittest.main()
