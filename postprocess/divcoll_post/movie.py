"""The paper's Supplementary Movie, rendered from a run file as MP4 (H.264, Debian's ffmpeg).

    divcoll movie RUN.h5 [--out DIR] [--quick]
    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.movie RUN.h5 [--out DIR] [--divcoll build/divcoll] [--quick]
    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.movie --episode S1.h5 T1.h5 [S2.h5 T2.h5 ...] --out X.mp4

Three parts, each written as its own MP4 in DIR and joined into DIR/supplementary_movie.mp4:

1. agent_optimisation.mp4: a random, untrained agent (`divcoll scene --kind agent`) beside the run's fittest
   evolved agent (`divcoll export --what alone`), 1000 steps on flat, under the run's fitness per generation.
2. connector_optimisation.mp4: the same diverse pair (the deployment's pair 0) with a passive connector
   (every connector weight 0) beside the run's weak diverse-trained connector (replicate 0), on flat, under
   the connector's training curve.
3. deployment.mp4: a uniform pair with its weak uniform-trained connector beside a diverse pair with its weak
   diverse-trained connector (pair 0 of replicate 0 of weak_uniform@uniform and weak_diverse@diverse), in
   each environment of the run (at most six: flat first, then wind, ice, treadmill, step up, sand, gap,
   in that order of preference), for the run's deployment length.

Every episode is the scene file `divcoll export` writes and the trajectory `divcoll simulate` computes from
it; the travel drawn is checked against the run file's. On each frame: the environment's name and its cue
(a wind arrow whose length follows the wind, ice / sand / sticky ground as texture and label, the treadmill's
belt as moving marks), springs coloured by strain with a colour bar, the time stamp, travel so far in BL.
Frames are 1280 × 720 (--quick: fewer frames and environments, for tests).

Exit status: 0 done; 2 bad input (not a run file, a missing stage, no ffmpeg) with a message.
"""
import argparse
import functools
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib

import h5py
import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.patches import FancyArrow  # noqa: E402

CHECKOUT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from . import animate  # noqa: E402

STRAIN = 0.3  # colour scale of spring strain, ±
PREFERRED = ["flat", "wind", "ice", "treadmill", "step_up", "sand", "gap", "obstacle", "sticky", "low_gravity",
             "incline", "decline", "step_down"]
ENVIRONMENTS_TOML = os.path.join(CHECKOUT, "configs", "environments.toml")
UNITS = {"gravity": "u/s²", "damping": "1/s", "belt_speed": "u/s", "wind_amp": "u/s²", "wind_period": "s",
         "adhesion": "u/s²", "adhesion_band": "u"}


def cue(env, path=ENVIRONMENTS_TOML):
    """the caption of environment `env`, written from its table in configs/environments.toml: what differs from the
    [defaults] table (a terrain as its first feature), so that an environment added to the file is captioned too"""
    try:
        with open(path, "rb") as fh:
            table = tomllib.load(fh)
    except OSError:
        return env
    if env not in table:
        return env
    d, e = table.get("defaults", {}), table[env]
    bits = []
    for k, v in e.items():
        if k == "terrain" or v == d.get(k):
            continue
        bits.append(f"{k.replace('_', ' ')} {v:.3g}{(' ' + UNITS[k]) if k in UNITS else ''}")
    segs = e.get("terrain", [])
    if segs:
        dx, y, slope = segs[0]
        if slope:
            bits.append(f"slope {slope:+g}")
        elif len(segs) > 1:
            bits.append(f"feature {segs[1][0] - dx:g} u long at height {y:+g} u")
        elif y:
            bits.append(f"step {y:+g} u")
    name = env.replace("_", " ") + (" (training)" if env == "flat" else "")
    return name + (": " + ", ".join(bits) if bits else "")


GROUND = {"ice": "#cfe8f7", "sand": "#ecd9a0", "sticky": "#b9d3a0", "treadmill": "#c9c9c9"}


class InputError(Exception):
    pass


from .reader import RunFileError, complete, list_attr, open_file, text as _s  # noqa: E402


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in (0, 3):  # simulate exits 3 when an episode ended nan/unstable (its file is written)
        raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip() or p.stdout.strip()}")
    return p.stdout


class Clip:
    """one episode to draw: scene, trajectory, title, the travel the run file records (BL) or None"""

    def __init__(self, scene, traj, title, stored_bl=None):
        self.ep = animate.Episode(scene, traj)
        self.title = title
        with h5py.File(scene, "r") as s:
            # the numeric constants (name and contact are strings)
            self.env_attrs = {k: float(v) for k, v in s["env"].attrs.items() if not isinstance(v, (str, bytes))}
        self.bl = self.ep.bl
        self.stored_bl = stored_bl
        with h5py.File(traj, "r") as t:
            self.travel_u = float(t.attrs["travel"])
        self.steps = self.ep.x.shape[0] - 1

    def travel_bl(self, t):
        return (self.ep.x[t].mean(0)[0] - self.ep.x[0].mean(0)[0]) / self.bl


def draw_cues(ax, clip, t, x0, x1, y0, y1):
    """the environment's cue on ax: ground texture, wind arrow, moving belt marks"""
    ep, env = clip.ep, clip.ep.env
    tx, ty = ep.terrain_line(x0 - 1, x1 + 1)
    if env in GROUND:
        ax.fill_between(tx, ty, y0 - 1, color=GROUND[env], zorder=0.5)
    if env == "sand":
        rng = np.random.default_rng(0)
        px = rng.uniform(np.floor(x0) - 2, np.ceil(x1) + 2, 4000)
        py = rng.uniform(-0.06, 0.0, 4000)
        sel = (px > x0) & (px < x1)
        ax.scatter(px[sel], np.interp(px[sel], tx, ty) + py[sel], s=1.5, color="#a88a3c", zorder=0.6, lw=0)
    if env == "treadmill":
        belt = clip.env_attrs.get("belt_speed", 0.05)
        shift = -(belt * t * ep.dt) % 0.05  # marks move backwards with the ground
        for mx in np.arange(np.floor(x0 / 0.05) * 0.05 - 0.05, x1 + 0.05, 0.05) + shift:
            yy = np.interp(mx, tx, ty)
            ax.plot([mx, mx - 0.015], [yy - 0.004, yy - 0.018], color="#555555", lw=1.2, zorder=0.7)
    if env == "ice":
        for mx in np.arange(np.floor(x0 / 0.08) * 0.08, x1, 0.08):
            yy = np.interp(mx, tx, ty)
            ax.plot([mx, mx + 0.03], [yy - 0.01, yy - 0.025], color="white", lw=1.5, zorder=0.7)
    if env == "wind":
        amp, period = clip.env_attrs.get("wind_amp", 2.0), clip.env_attrs.get("wind_period", 4.0)
        w = amp * np.sin(2 * np.pi * t * ep.dt / period)
        cx, cy = (x0 + x1) / 2, y1 - 0.06 * (y1 - y0)
        length = 0.12 * (x1 - x0) * w / max(amp, 1e-9)
        if abs(length) > 1e-4:
            ax.add_patch(FancyArrow(cx, cy, length, 0, width=0.012 * (y1 - y0), head_width=0.04 * (y1 - y0),
                                    head_length=min(abs(length), 0.03 * (x1 - x0)), length_includes_head=True,
                                    color="#1f6fb4", zorder=6))
        shown = round(w, 1) or 0.0  # no "-0.0" where the wind turns
        ax.text(cx, cy - 0.05 * (y1 - y0), f"wind {shown:+.1f} u/s²" if shown else "wind 0 u/s² (turning)",
                ha="center", va="top", fontsize=9,
                color="#1f6fb4", zorder=6)


def draw_panel(ax, clip, t, half_width):
    ep = clip.ep
    ax.clear()
    com = ep.x[t].mean(0)
    x0, x1 = com[0] - half_width, com[0] + half_width
    tx, ty = ep.terrain_line(x0 - 1, x1 + 1)
    y0 = min(float(ty[(tx >= x0 - 0.1) & (tx <= x1 + 0.1)].min(initial=0.0)), com[1] - 0.2) - 0.06
    y1 = y0 + (x1 - x0) * 0.62
    ax.fill_between(tx, ty, y0 - 1, color="#d9cfc1", zorder=0)
    draw_cues(ax, clip, t, x0, x1, y0, y1)
    ax.plot(tx, ty, color="#6b5a45", lw=1.5, zorder=1)
    seg = np.stack([ep.x[t, ep.si], ep.x[t, ep.sj]], axis=1)
    width = np.full(len(ep.si), 1.6)
    width[ep.conn] = 3.4
    lc = LineCollection(seg, cmap="coolwarm", norm=plt.Normalize(-STRAIN, STRAIN), linewidths=width, zorder=2)
    lc.set_array(np.clip(ep.strain(t), -STRAIN, STRAIN))
    ax.add_collection(lc)
    colours = plt.cm.tab10(ep.agent_of % 10)
    touching = ep.touch[t].astype(bool)
    ax.scatter(ep.x[t, :, 0], ep.x[t, :, 1], s=22, c=np.where(touching[:, None], colours, 1.0), edgecolors=colours,
               linewidths=1.2, zorder=3)
    ax.plot(com[0], com[1], "k+", ms=10, zorder=4)
    ax.axvline(ep.x[0].mean(0)[0], color="#777777", lw=0.8, ls=":", zorder=0.8)  # where the centre of mass started
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(clip.title, fontsize=11, loc="left")
    done = f"   (run file: {clip.stored_bl:+.2f} BL)" if clip.stored_bl is not None and t == clip.steps else ""
    ax.text(0.01, 0.02, f"travel {clip.travel_bl(t):+.2f} BL{done}", transform=ax.transAxes, fontsize=11,
            fontweight="bold", va="bottom", zorder=7,
            bbox=dict(facecolor="white", alpha=0.8, edgecolor="none", pad=2))
    ax.text(0.99, 0.98, cue(ep.env), transform=ax.transAxes, fontsize=10, ha="right", va="top", zorder=7,
            bbox=dict(facecolor="white", alpha=0.8, edgecolor="none", pad=2))
    return lc


class Writer:
    """frames of a matplotlib figure piped into ffmpeg as H.264"""

    def __init__(self, path, fig, fps):
        if shutil.which("ffmpeg") is None:
            raise InputError("ffmpeg is not installed (apt-get install ffmpeg; jobs/install-deps.sh does)")
        self.fig = fig
        w, h = fig.canvas.get_width_height()
        self.size = (w - w % 2, h - h % 2)
        self.path = path
        self.p = subprocess.Popen(["ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgba", "-s",
                                   f"{w}x{h}", "-r", str(fps), "-i", "-", "-vf", f"crop={self.size[0]}:{self.size[1]}:0:0",
                                   "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "23", "-preset", "veryfast",
                                   "-movflags", "+faststart", path], stdin=subprocess.PIPE, stderr=subprocess.PIPE)
        self.frames = 0

    def frame(self):
        self.fig.canvas.draw()
        self.p.stdin.write(self.fig.canvas.buffer_rgba())
        self.frames += 1

    def close(self):
        self.p.stdin.close()
        err = self.p.stderr.read().decode()
        if self.p.wait() != 0:
            raise RuntimeError(f"ffmpeg failed writing {self.path}: {err.strip()}")


def render(path, clips, heading, quick=False, every=20, fps=25, below=None, hold=1.0):
    """clips side by side, one frame every `every` steps of the longest; `below(ax, frame_step)` draws a strip
    under them (a curve with a moving marker); the last frame is held `hold` seconds"""
    fig = plt.figure(figsize=(12.8, 7.2), dpi=100)
    n = len(clips)
    top = 0.86
    bottom = 0.30 if below else 0.12
    gs = fig.add_gridspec(1, n, left=0.02, right=0.92, top=top, bottom=bottom, wspace=0.05)
    axes = [fig.add_subplot(gs[0, i]) for i in range(n)]
    cax = fig.add_axes([0.935, bottom + 0.05, 0.012, top - bottom - 0.1])
    sm = plt.cm.ScalarMappable(cmap="coolwarm", norm=plt.Normalize(-STRAIN, STRAIN))
    cb = fig.colorbar(sm, cax=cax)
    cb.set_label("spring strain ℓ/L − 1 (blue shortened, red stretched)", fontsize=9)
    cb.ax.tick_params(labelsize=8)
    bax = fig.add_axes([0.07, 0.07, 0.83, 0.15]) if below else None
    fig.suptitle(heading, fontsize=14, x=0.02, ha="left", y=0.975)
    clock = fig.text(0.02, 0.905, "", fontsize=11, family="monospace")
    fig.text(0.92, 0.905, "filled dot: mass touching the ground   +: centre of mass   dotted: start",
             fontsize=8.5, ha="right", color="#444444")
    steps = max(c.steps for c in clips)
    frames = list(range(0, steps + 1, every))
    if frames[-1] != steps:
        frames.append(steps)
    half = 0.55 if n <= 2 else 0.45
    w = Writer(path, fig, fps)
    try:
        for k, t in enumerate(frames):
            for ax, c in zip(axes, clips):
                draw_panel(ax, c, min(t, c.steps), half)
            clock.set_text(f"t = {t * clips[0].ep.dt:5.2f} s   step {t:5d} / {steps}")
            if bax is not None:
                below(bax, t / max(steps, 1))
            reps = int(hold * fps) if k == len(frames) - 1 else 1
            for _ in range(reps):
                w.frame()
    finally:
        w.close()
        plt.close(fig)
    return w.frames


def title_card(path, lines, quick=False, seconds=2.5, fps=25):
    fig = plt.figure(figsize=(12.8, 7.2), dpi=100)
    seconds = 0.5 if quick else seconds
    fig.text(0.5, 0.62, lines[0], ha="center", va="center", fontsize=24, fontweight="bold")
    for i, ln in enumerate(lines[1:]):
        fig.text(0.5, 0.48 - 0.07 * i, ln, ha="center", va="center", fontsize=13, color="#333333")
    w = Writer(path, fig, fps)
    try:
        for _ in range(int(seconds * fps)):
            w.frame()
    finally:
        w.close()
        plt.close(fig)


def concat(parts, out):
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as fh:
        for p in parts:
            fh.write(f"file '{os.path.abspath(p)}'\n")
        lst = fh.name
    try:
        p = subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-f", "concat", "-safe", "0", "-i", lst, "-c", "copy",
                            "-movflags", "+faststart", out], capture_output=True, text=True)
        if p.returncode != 0:
            raise RuntimeError(f"ffmpeg could not join the parts: {p.stderr.strip()}")
    finally:
        os.unlink(lst)


def curve_strip(values, xlabel, ylabel, label=None):
    """a below() function: the curve (per x = 1..len) with a marker moving along it as the clip plays"""
    values = np.asarray(values, float)

    def below(ax, frac):
        ax.clear()
        x = np.arange(len(values))
        ax.plot(x, values, color="#1f4e79", lw=1.8, marker="o" if len(values) < 30 else None, ms=3)
        k = int(round(frac * (len(values) - 1)))
        ax.plot(x[: k + 1], values[: k + 1], color="#d62728", lw=2.6)
        ax.set_xlabel(xlabel, fontsize=9)
        ax.set_ylabel(ylabel, fontsize=9)
        ax.tick_params(labelsize=8)
        ax.grid(color="#e5e5e5", lw=0.6)
        if label:
            ax.text(0.01, 0.92, label, transform=ax.transAxes, fontsize=9, va="top")
    return below


class RunFile:
    def __init__(self, path, divcoll, work):
        self.path, self.divcoll, self.work = path, divcoll, work
        try:
            with open_file(path) as f:
                self.cfg = tomllib.loads(_s(f.attrs["config"]))
                for st in ("agents", "connectors", "deploy"):
                    if not complete(f, st):
                        raise InputError(f"{path} has no complete {st} stage (the movie needs agents, connectors "
                                         "and deploy)")
                gens = sorted(k for k in f["agents"] if k.startswith("gen_"))
                self.gen_best = [float(np.nanmax(f[f"agents/{g}/fitness"][()])) for g in gens]
                self.gen_mean = [float(np.nanmean(f[f"agents/{g}/fitness"][()])) for g in gens]
                self.final_fitness = f["agents/final/fitness"][()]
                self.curve = np.nanmean(f["connectors/weak_diverse/curve_bl"][()], axis=1)
                d = f["deploy"]
                self.envs, self.types = list_attr(d, "environments"), list_attr(d, "types")
                self.coll_bl = d["collectives/travel_bl"][()]
                self.alone_bl = d["agents/travel_bl"][()]
        except RunFileError as e:
            raise InputError(str(e))
        except OSError as e:
            raise InputError(f"cannot read {path}: {e}")

    def export(self, stem, *args):
        scene = os.path.join(self.work, stem + "_scene.h5")
        out = run([self.divcoll, "export", self.path, *args, "--out", scene, "--force"])
        m = re.search(r"records travel (\S+) u \((\S+) BL\)", out)
        return scene, (float(m.group(2)) if m else None)

    def simulate(self, scene, steps):
        traj = scene.replace("_scene.h5", "_traj.h5")
        run([self.divcoll, "simulate", "--scene", scene, "--steps", str(steps), "--out", traj, "--force"])
        return traj


_JOBS = []  # the renders run_parallel hands to its forked workers (closures need no pickling after a fork)


def _run_job(i):
    _JOBS[i]()
    return i


def run_parallel(jobs, workers=None):
    """runs zero-argument render jobs, each writing its own file, on `workers` forked processes (default: every
    core, at most the job count); one core or one job runs them in this process"""
    global _JOBS
    workers = min(len(jobs), workers or os.cpu_count() or 1)
    if workers <= 1:
        for j in jobs:
            j()
        return
    import multiprocessing
    _JOBS = list(jobs)
    try:
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            pool.map(_run_job, range(len(_JOBS)), chunksize=1)
    finally:
        _JOBS = []


def supplementary(runpath, out_dir, divcoll, quick=False):
    """the paper's Supplementary Movie from a run file: its episodes are exported and simulated first, then every
    title card and clip is rendered, on every core at once (run_parallel), and the parts are joined"""
    os.makedirs(out_dir, exist_ok=True)
    jobs = []
    work = os.path.join(out_dir, "episodes")
    os.makedirs(work, exist_ok=True)
    r = RunFile(runpath, divcoll, work)
    every = 100 if quick else 20
    name = r.cfg.get("run", {}).get("name", "?")
    parts = []

    # 1. agent optimisation
    train_steps = int(r.cfg["agents"]["episode_steps"])
    rnd = os.path.join(work, "random_agent_scene.h5")
    run([divcoll, "scene", "--kind", "agent", "--env", "flat", "--seed", "1", "--out", rnd, "--force"])
    best = int(np.nanargmax(r.final_fitness))
    evo, _ = r.export("evolved_agent", "--what", "alone", "--env", "flat", "--agent", str(best))
    clips = [Clip(rnd, r.simulate(rnd, train_steps), "a random agent, untrained"),
             Clip(evo, r.simulate(evo, train_steps), f"the fittest evolved agent (agent {best})",
                  stored_bl=float(r.final_fitness[best]))]
    def part(k, card_lines, stem, heading, strip):
        """a title card and the clips under a curve strip: [card path, part path]"""
        card = os.path.join(out_dir, f"card{k}.mp4")
        jobs.append(functools.partial(title_card, card, card_lines, quick))
        path = os.path.join(out_dir, stem + ".mp4")
        jobs.append(functools.partial(render, path, clips, heading, quick, every, below=curve_strip(*strip)))
        return [card, path]

    parts += part(1, ["1. Agent optimisation", "evolution of bodies + gradient descent on controllers",
                      f"{len(r.gen_best)} generations of {len(r.final_fitness)} agents ({name} preset)"],
                  "agent_optimisation", f"Agent optimisation: before and after ({train_steps} steps on flat)",
                  (r.gen_best, "generation", "best fitness (BL)", "best fitness of each generation (red: played so far)"))
    p1 = parts[-1]

    # 2. connector optimisation
    conn_steps = int(r.cfg["connectors"]["episode_steps"])
    trained, stored = r.export("trained_pair", "--what", "pair", "--env", "flat", "--type", "weak_diverse@diverse",
                               "--pair", "0", "--replicate", "0")
    passive = os.path.join(work, "passive_pair_scene.h5")
    shutil.copyfile(trained, passive)
    with h5py.File(passive, "r+") as f:
        f["connector_params"][...] = 0.0
    clips = [Clip(passive, r.simulate(passive, conn_steps), "diverse pair 0, passive connector (all weights 0)"),
             Clip(trained, r.simulate(trained, conn_steps), "the same pair, weak diverse-trained connector")]
    parts += part(2, ["2. Connector optimisation", "gradient descent through the simulator on the connector's weights",
                      f"{len(r.curve)} iterations, agents frozen"],
                  "connector_optimisation", f"Connector optimisation: untrained vs trained ({conn_steps} steps on flat)",
                  (r.curve, "training iteration", "mean batch travel (BL)",
                   "weak diverse-trained connector: mean travel of the training batch"))
    p2 = parts[-1]

    # 3. deployment
    dep_steps = int(r.cfg["deploy"]["episode_steps"])
    envs = [e for e in PREFERRED if e in r.envs][: (2 if quick else 6)]
    card = os.path.join(out_dir, "card3.mp4")
    jobs.append(functools.partial(title_card, card, ["3. Deployment: uniform vs diverse",
                                                     "no learning; flat is the training environment",
                                                     ", ".join(e.replace("_", " ") for e in envs)], quick))
    parts.append(card)
    p3s = []
    for env in envs:
        clips = []
        for typ, label in (("weak_uniform@uniform", "uniform pair (clones), weak uniform-trained"),
                           ("weak_diverse@diverse", "diverse pair, weak diverse-trained")):
            sc, st = r.export(f"{env}_{typ.replace('@', '_at_')}", "--what", "pair", "--env", env, "--type", typ,
                              "--pair", "0", "--replicate", "0")
            clips.append(Clip(sc, r.simulate(sc, dep_steps), label, stored_bl=st))
        p = os.path.join(out_dir, f"deployment_{env}.mp4")
        jobs.append(functools.partial(render, p, clips,
                                      f"Deployment in {env.replace('_', ' ')}: uniform vs diverse ({dep_steps} steps)",
                                      quick, every * 2))
        p3s.append(p)
    run_parallel(jobs)
    p3 = os.path.join(out_dir, "deployment.mp4")
    concat(p3s, p3)
    parts += p3s
    full = os.path.join(out_dir, "supplementary_movie.mp4")
    concat(parts, full)
    for p in p3s + [os.path.join(out_dir, f"card{i}.mp4") for i in (1, 2, 3)]:
        os.remove(p)
    return [full, p1, p2, p3]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", nargs="?", help="divcoll run file with complete agents, connectors and deploy stages")
    ap.add_argument("--out", default=None, help="output folder (run mode, default out/movie) or MP4 (--episode)")
    ap.add_argument("--divcoll", default=os.path.join(CHECKOUT, "build", "divcoll"), help="the divcoll binary")
    ap.add_argument("--quick", action="store_true", help="fewer frames and environments (tests)")
    ap.add_argument("--episode", nargs="+", metavar="FILE", help="scene and trajectory files, in pairs: render "
                    "these episodes side by side into --out")
    a = ap.parse_args(argv)
    try:
        if a.episode:
            if len(a.episode) % 2:
                raise InputError("--episode takes scene and trajectory files in pairs")
            out = a.out or "episode.mp4"
            clips = []
            for sc, tr in zip(a.episode[::2], a.episode[1::2]):
                c = Clip(sc, tr, "")
                c.title = f"{c.ep.env.replace('_', ' ')}"
                clips.append(c)
            n = render(out, clips, "demo: " + ", ".join(c.title for c in clips), a.quick, every=40 if a.quick else 20)
            print(f"movie: wrote {out} ({n} frames)")
            return 0
        if not a.run:
            raise InputError("give a run file, or --episode SCENE TRAJ ...")
        if not os.path.exists(a.run):
            raise InputError(f"no such run file: {a.run}")
        paths = supplementary(a.run, a.out or "out/movie", a.divcoll, a.quick)
        print(f"movie: wrote {paths[0]} (parts: {', '.join(os.path.basename(p) for p in paths[1:])})")
        return 0
    except (InputError, KeyError, ValueError) as e:
        print(f"movie: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
