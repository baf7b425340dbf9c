"""Animate one episode from its scene file and trajectory file (SPEC §9) as a GIF.

    divcoll export RUN.h5 --what pair --env step_up --type weak_diverse@diverse --pair 3 --out S.h5
    divcoll simulate --scene S.h5 --steps 3000 --out T.h5
    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.animate S.h5 T.h5 --out episode.gif

Drawn: the terrain (segments of env/terrain, walls where heights jump), every spring coloured by its
strain ℓ/L − 1 (blue shortened, red stretched; the actuation shows as strain), connector springs thicker,
masses as dots in one colour per agent (filled when touching the ground), the collective's centre of
mass as a cross, time and travel so far (BL) in the corner. For MP4 at 1280×720 with environment cues and a
colour bar, use movie.py --episode. The camera follows the centre of mass.
"""
import argparse
import sys

import h5py
import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import animation  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402


class Episode:
    """a scene and its trajectory, as numpy arrays"""

    def __init__(self, scene_path, traj_path):
        with h5py.File(scene_path, "r") as s:
            if s.attrs.get("format", b"") not in (b"divcoll-scene", "divcoll-scene"):
                raise ValueError(f"{scene_path} is not a divcoll scene file")
            self.si = s["springs/i"][()]
            self.sj = s["springs/j"][()]
            self.rest = s["springs/rest_length"][()]
            self.mass_index = s["agents/mass_index"][()]
            self.conn = s["connectors/spring_index"][()].ravel() if "connectors/spring_index" in s else np.array([], int)
            self.terrain = s["env/terrain"][()]
            self.env = s["env"].attrs["name"]
            self.env = self.env.decode() if isinstance(self.env, bytes) else str(self.env)
            self.dt = float(s.attrs["dt"])
            n_masses = s["masses/m"].shape[0]
        with h5py.File(traj_path, "r") as t:
            self.x = t["x"][()]
            self.touch = t["touch"][()]
        if self.x.shape[1] != n_masses:
            raise ValueError(f"{traj_path} ({self.x.shape[1]} masses) does not belong to {scene_path} "
                             f"({n_masses} masses)")
        self.agent_of = np.zeros(self.x.shape[1], int)
        for a, row in enumerate(self.mass_index):
            self.agent_of[row] = a
        # body length (SPEC §1): the mean over agents of the x extent at step 0 (the rest positions as placed)
        self.bl = float(np.mean([np.ptp(self.x[0, row, 0]) for row in self.mass_index]))

    def strain(self, t):
        d = self.x[t, self.si] - self.x[t, self.sj]
        return np.sqrt((d * d).sum(1)) / self.rest - 1.0

    def terrain_line(self, x0, x1):
        """polyline of the ground between x0 and x1 (vertical jumps become walls)"""
        xs, ys = [], []
        k = len(self.terrain)
        starts = np.concatenate([[-np.inf], self.terrain[1:, 0]])
        for q in range(k):
            a = max(starts[q], x0)
            b = min(self.terrain[q + 1, 0] if q + 1 < k else np.inf, x1)
            if a >= b:
                continue
            xq, yq, s = self.terrain[q]
            xq = a if q == 0 else xq
            xs += [a, b]
            ys += [yq + s * (a - xq), yq + s * (b - xq)]
        return np.array(xs), np.array(ys)


def draw_frame(ax, ep, t, half_width=0.6, title=None):
    """draws step t of the episode on ax (cleared first); returns the artists"""
    ax.clear()
    com = ep.x[t].mean(0)
    x0, x1 = com[0] - half_width, com[0] + half_width
    tx, ty = ep.terrain_line(x0 - 1, x1 + 1)
    ax.fill_between(tx, ty, -1.0, color="#d9cfc1", zorder=0)
    ax.plot(tx, ty, color="#6b5a45", lw=1.2, zorder=1)
    seg = np.stack([ep.x[t, ep.si], ep.x[t, ep.sj]], axis=1)
    strain = np.clip(ep.strain(t), -0.3, 0.3)
    width = np.full(len(ep.si), 1.2)
    width[ep.conn] = 2.6
    lc = LineCollection(seg, cmap="coolwarm", norm=plt.Normalize(-0.3, 0.3), linewidths=width, zorder=2)
    lc.set_array(strain)
    ax.add_collection(lc)
    colours = plt.cm.tab10(ep.agent_of % 10)
    touching = ep.touch[t].astype(bool)
    ax.scatter(ep.x[t, :, 0], ep.x[t, :, 1], s=14, c=np.where(touching[:, None], colours, 1.0),
               edgecolors=colours, linewidths=1.0, zorder=3)
    ax.plot(com[0], com[1], "k+", ms=8, zorder=4)
    travel = com[0] - ep.x[0].mean(0)[0]
    ax.text(0.02, 0.95, f"t = {t * ep.dt:.2f} s   travel {travel / ep.bl:+.2f} BL", transform=ax.transAxes,
            va="top", fontsize=8)
    ax.set_xlim(x0, x1)
    ax.set_ylim(min(ty.min(), com[1] - 0.2) - 0.05, com[1] + 0.35)
    ax.set_aspect("equal")
    ax.set_xlabel("x (u)")
    ax.set_ylabel("y (u)")
    if title:
        ax.set_title(title, fontsize=9)
    return lc


def animate(scene, traj, out, every=10, fps=25):
    ep = Episode(scene, traj)
    frames = list(range(0, ep.x.shape[0], every))
    fig, ax = plt.subplots(figsize=(6, 3.4), dpi=90)
    title = f"{ep.env.replace('_', ' ')}: {ep.x.shape[1] // 11} agent(s), {ep.x.shape[0] - 1} steps"

    def update(k):
        draw_frame(ax, ep, frames[k], title=title)
        return []

    anim = animation.FuncAnimation(fig, update, frames=len(frames), blit=False)
    anim.save(out, writer=animation.PillowWriter(fps=fps))
    plt.close(fig)
    return len(frames)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", help="scene file (divcoll export / divcoll scene)")
    ap.add_argument("trajectory", help="its trajectory file (divcoll simulate)")
    ap.add_argument("--out", default="episode.gif", help="GIF to write")
    ap.add_argument("--every", type=int, default=10, help="draw every this many steps")
    ap.add_argument("--fps", type=int, default=25, help="frames per second of the GIF")
    a = ap.parse_args(argv)
    if a.every < 1 or a.fps < 1:
        print("animate: --every and --fps must be at least 1", file=sys.stderr)
        return 2
    try:
        n = animate(a.scene, a.trajectory, a.out, a.every, a.fps)
    except (OSError, KeyError, ValueError) as e:
        print(f"animate: {e}", file=sys.stderr)
        return 2
    print(f"animate: wrote {a.out} ({n} frames)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
