"""A contact sheet of one uniform and one diverse pair in every environment of a run file.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.contact_sheet RUN.h5 [--divcoll build/divcoll]
        [--out DIR] [--gifs]

For every deployment environment it exports (`divcoll export`) pair --pair of replicate --replicate of
weak_uniform@uniform and of weak_diverse@diverse, simulates it (`divcoll simulate`) for the run's episode
length, checks that the simulated travel equals the run file's, and draws its last step with the path of
its centre of mass. With --gifs it also writes one animation per episode (divcoll_post.animate). Writes
DIR/contact_sheet.png and DIR/episodes/*.h5 (scene and trajectory files, to look at exactly these
episodes again).
"""
import argparse
import os
import re
import subprocess
import sys
import tomllib

import h5py
import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .. import animate  # noqa: E402

CHECKOUT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

TYPES = [("weak_uniform@uniform", "uniform pair, weak uniform-trained"),
         ("weak_diverse@diverse", "diverse pair, weak diverse-trained")]


from ..reader import RunFileError, list_attr, open_file, text as _s  # noqa: E402


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip() or p.stdout.strip()}")
    return p.stdout


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="divcoll run file with a complete deploy stage")
    ap.add_argument("--divcoll", default=os.path.join(CHECKOUT, "build", "divcoll"), help="the divcoll binary")
    ap.add_argument("--out", default="out/figures", help="output folder")
    ap.add_argument("--pair", type=int, default=0, help="pair index")
    ap.add_argument("--replicate", type=int, default=0, help="connector replicate")
    ap.add_argument("--gifs", action="store_true", help="also write an animation per episode")
    a = ap.parse_args(argv)
    try:
        with open_file(a.run) as f:
            if "deploy/collectives/travel_u" not in f:
                print(f"contact_sheet: {a.run} has no deploy stage (run it first)", file=sys.stderr)
                return 2
            envs, types = list_attr(f["deploy"], "environments"), list_attr(f["deploy"], "types")
            steps = int(tomllib.loads(_s(f.attrs["config"]))["deploy"]["episode_steps"])
    except RunFileError as e:
        print(f"contact_sheet: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"contact_sheet: cannot read {a.run}: {e}", file=sys.stderr)
        return 2
    missing = [t for t, _ in TYPES if t not in types]
    if missing:
        print(f"contact_sheet: {a.run} has no {', '.join(missing)} deployment", file=sys.stderr)
        return 2
    ep_dir = os.path.join(a.out, "episodes")
    os.makedirs(ep_dir, exist_ok=True)
    fig, axes = plt.subplots(len(envs), 2, figsize=(9, 2.1 * len(envs)), dpi=80, squeeze=False)
    for e, env in enumerate(envs):
        for c, (typ, label) in enumerate(TYPES):
            stem = os.path.join(ep_dir, f"{env}_{typ.replace('@', '_at_')}_r{a.replicate}_p{a.pair}")
            out = run([a.divcoll, "export", a.run, "--what", "pair", "--env", env, "--type", typ, "--replicate",
                       str(a.replicate), "--pair", str(a.pair), "--out", stem + "_scene.h5", "--force"])
            stored = float(re.search(r"records travel (\S+) u", out).group(1))
            sim = subprocess.run([a.divcoll, "simulate", "--scene", stem + "_scene.h5", "--steps", str(steps),
                                  "--out", stem + "_traj.h5", "--force"], capture_output=True, text=True)
            if sim.returncode not in (0, 3):  # 3: the episode ended nan/unstable, the file is written
                raise RuntimeError(sim.stderr)
            ep = animate.Episode(stem + "_scene.h5", stem + "_traj.h5")
            with h5py.File(stem + "_traj.h5", "r") as t:
                travel = float(t.attrs["travel"])
            same = (np.isnan(stored) and np.isnan(travel)) or stored == travel
            ax = axes[e, c]
            last = ep.x.shape[0] - 1
            animate.draw_frame(ax, ep, last, half_width=0.9,
                               title=f"{env.replace('_', ' ')}: {label}" + ("" if same else "  (differs from the run file!)"))
            com = ep.x.mean(1)
            ax.plot(com[:, 0], com[:, 1], color="0.4", lw=0.6, zorder=1)
            ax.set_xlabel("")
            if a.gifs:
                animate.animate(stem + "_scene.h5", stem + "_traj.h5", stem + ".gif", every=20)
            print(f"{env:12s} {typ:22s} travel {travel:+.4f} u (run file {stored:+.4f}){'' if same else '  DIFFERS'}")
    fig.tight_layout()
    path = os.path.join(a.out, "contact_sheet.png")
    fig.savefig(path)
    plt.close(fig)
    print(f"contact_sheet: wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
