#!/usr/bin/python3
"""Fig. 2A's numbers from a run file, through the labelled reader (divcoll_post.open).

    /usr/bin/python3 postprocess/examples/fig2a_numbers.py RUN.h5

For flat ground and for the novel environments (the mean of the per-environment means), the mean travel
in body lengths of the agents alone and of each deployment type `<kind>@uniform|diverse`, over the ok
episodes (status 0), with its 95% percentile-bootstrap CI (stratified by environment) and the episodes
left out. Everything about the layout (dimension names, environment and type names, sizes) comes from
the file's own attributes. divcoll_post.figures.fig2 draws the same numbers.
"""

import sys

import numpy as np

try:
    import divcoll_post
except ImportError:  # run from the checkout without `pip install ./postprocess`
    import os

    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    import divcoll_post
from divcoll_post.results import stratified_bootstrap_ci


def ok_episodes(travel, status):
    """The travels of the ok episodes (status 0, finite), in storage order, and the count of the others."""
    ok = (status.values == 0) & np.isfinite(travel.values)
    return travel.values[ok], int((~ok).sum())


def numbers(path, n_boot=1000, seed=0):
    """{(setting, who): (mean, ci_low, ci_high, n_ok, n_not_ok)}, setting "flat" or "novel", who "agents"
    or a deployment type."""
    with divcoll_post.open(path) as run:
        deploy = run.deploy
        alone_t, alone_s = deploy.agents.travel_bl, deploy.agents.status  # (env, agent)
        pair_t, pair_s = deploy.collectives.travel_bl, deploy.collectives.status  # (env, type, replicate, pair)
        envs = list(pair_t.env.values[: int(deploy.attrs.get("envs_done", pair_t.sizes["env"]))])
        settings = {"flat": ["flat"], "novel": [e for e in envs if e != "flat"]}
        who = {"agents": lambda e: (alone_t.sel(env=e), alone_s.sel(env=e))}
        for t in pair_t.type.values:
            who[t] = lambda e, t=t: (pair_t.sel(env=e, type=t), pair_s.sel(env=e, type=t))
        out = {}
        for setting, es in settings.items():
            if not es:
                continue
            for name, select in who.items():
                per_env = [ok_episodes(*select(e)) for e in es]
                groups = [v for v, _ in per_env]
                bad = sum(b for _, b in per_env)
                mean = float(np.mean([g.mean() for g in groups])) if all(g.size for g in groups) else float("nan")
                lo, hi = stratified_bootstrap_ci(groups, n_boot=n_boot, seed=seed)
                out[(setting, name)] = (mean, lo, hi, int(sum(g.size for g in groups)), bad)
        return out


def main(argv):
    if len(argv) != 2:
        print(__doc__.strip().split("\n\n")[1], file=sys.stderr)
        return 2
    try:
        rows = numbers(argv[1])
    except divcoll_post.RunFileError as e:
        print(f"fig2a_numbers: {e}", file=sys.stderr)
        return 2
    print(f"{'setting':<7} {'who':<24} {'mean BL':>9} {'95% CI':>21} {'ok':>6} {'not ok':>6}")
    for (setting, name), (m, lo, hi, n_ok, bad) in rows.items():
        print(f"{setting:<7} {name:<24} {m:9.4f} [{lo:9.4f}, {hi:9.4f}] {n_ok:6d} {bad:6d}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
