"""The numbers behind the paper's claims, from a divcoll run file alone, as Markdown.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.summary RUN.h5 [--out SUMMARY.md]

Every mean is over the episodes whose status is ok (0); episodes that ended nan or unstable are counted
and reported, never averaged. "Novel" is the mean over the novel environments of each environment's mean
(every environment weighs the same, as in the paper's Fig. 2A).
"""
import argparse
import sys

import numpy as np

from .reader import STAGES, RunFileError, complete, list_attr, open_file, text as _s  # noqa: E402
from .results import env_means, ok_mean  # noqa: E402


def fmt(x):
    return "—" if not np.isfinite(x) else f"{x:.3f}"


def busy_text(attrs):
    """a stage's last session as its timing attributes give it: ranks, the share of rank-time computing items,
    rank 0's share, and max / mean busy seconds over ranks"""
    busy = [float(x) for x in _s(attrs.get("busy_s_per_rank_last_session", "")).split(",") if x.strip()]
    wall = float(attrs.get("wall_s_last_session", float("nan")))
    if not busy or not wall > 0:
        return "–"
    n = len(busy)
    return (f"{n}, {100 * sum(busy) / (n * wall):.0f}%, {100 * busy[0] / wall:.0f}%, "
            f"{max(busy) / np.mean(busy):.2f}" if np.mean(busy) > 0 else f"{n}, 0%, 0%, –")


def summarize(path):
    lines = []
    w = lines.append
    with open_file(path) as f:
        w(f"# divcoll run summary: `{path}`\n")
        w(f"commit {_s(f.attrs.get('git_commit', '?'))}, seed {_s(f.attrs.get('seed', '?'))}, "
          f"ranks {_s(f.attrs.get('ranks', '?'))}, started {_s(f.attrs.get('start_time', '?'))}, "
          f"ended {_s(f.attrs.get('end_time', '(not finished)'))}"
          + (f"; kernels {_s(f.attrs['kernels'])} on {_s(f.attrs.get('cpu', '?'))}, "
             f"built for {_s(f.attrs.get('build_target', '?'))}" if "kernels" in f.attrs else "") + "\n")
        w("| stage | status | wall time (s, summed over sessions) | last session: ranks, busy share, master busy, "
          "imbalance (max / mean busy) |\n|---|---|---|---|")
        for st in STAGES:
            if st in f:
                g = f[st]
                wall = g.attrs.get("wall_s", g.attrs.get("wall_s_last_session", float("nan")))
                wall = float(wall)
                w(f"| {st} | {_s(g.attrs.get('status', '?'))} | {wall:{'.0f' if wall >= 100 else '.1f'}} | "
                  f"{busy_text(g.attrs)} |")
        w("")
        if "agents/final" in f:
            fit = f["agents/final/fitness"][()]
            w(f"**Agents** (final population of {len(fit)}): fitness {fit.mean():.3f} ± {fit.std():.3f} BL "
              f"(min {fit.min():.3f}, max {fit.max():.3f}); {len(set(f['agents/final/cells'][()]))} body placements.\n")
        if "connectors" in f:
            w("**Connector training** (mean pair travel of the batch, BL, mean over replicates):\n")
            w("| kind | iteration 1 | last iteration | best iteration |\n|---|---|---|---|")
            for kind in list_attr(f["connectors"], "kinds"):
                if f"connectors/{kind}/curve_bl" not in f:
                    continue
                c = f[f"connectors/{kind}/curve_bl"][()]
                m = np.nanmean(c, axis=1)
                done = int(f["connectors"].attrs.get("iterations_done", len(m)))
                m = m[:done]
                if len(m):
                    w(f"| {kind} | {fmt(m[0])} | {fmt(m[-1])} (iteration {len(m)}) | {fmt(np.nanmax(m))} |")
            w("")
        if "deploy/collectives/travel_bl" in f:
            d = f["deploy"]
            envs, types = list_attr(d, "environments"), list_attr(d, "types")
            done = int(d.attrs.get("envs_done", len(envs)))
            novel = [i for i, e in enumerate(envs[:done]) if e != "flat"]
            fl = envs.index("flat")
            at, ast = d["agents/travel_bl"][()], d["agents/status"][()]
            ct, cst = d["collectives/travel_bl"][()], d["collectives/status"][()]
            w(f"**Deployment** (Fig. 2A; {done} of {len(envs)} environments done; BL in {int(ct.shape[-1])} pairs × "
              f"{int(ct.shape[2])} replicates per type):\n")
            w("| | flat | novel (mean of env means) | not ok |\n|---|---|---|---|")
            am, ab = env_means(at[:done], ast[:done])
            alone_flat, alone_novel = am[fl], np.mean(am[novel]) if novel else float("nan")
            w(f"| independent agents | {fmt(alone_flat)} | {fmt(alone_novel)} | {ab} |")
            rows = {}
            for t, name in enumerate(types):
                m, b = env_means(ct[:done, t], cst[:done, t])
                rows[name] = (m[fl], np.mean(m[novel]) if novel else float("nan"))
                w(f"| {name} | {fmt(m[fl])} | {fmt(rows[name][1])} | {b} |")
            w("")
            beats = [n for n, (fv, _) in rows.items() if fv > alone_flat]
            w(f"- collective types beating independent agents on flat: {len(beats)} of {len(rows)}")
            if novel:
                best = max(rows, key=lambda n: rows[n][1])
                w(f"- best type in the novel environments: {best} ({fmt(rows[best][1])} BL)")
            w("- transplant on flat (Fig. 2B): " + "; ".join(
                f"{k} deployed uniform {fmt(rows[k + '@uniform'][0])} / diverse {fmt(rows[k + '@diverse'][0])}"
                for k in sorted({n.split('@')[0] for n in rows})))
            w("")
            w("Per environment (BL):\n")
            w("| environment | agents | " + " | ".join(types) + " |\n|---|---|" + "---|" * len(types))
            for e in range(done):
                cells = [fmt(ok_mean(ct[e, t], cst[e, t])[0]) for t in range(len(types))]
                w(f"| {envs[e]} | {fmt(am[e])} | " + " | ".join(cells) + " |")
            w("")
        if "specialists/travel_bl" in f and complete(f, "specialists"):
            envs = list_attr(f["specialists"], "environments")
            t, s = f["specialists/travel_bl"][()], f["specialists/status"][()]
            w("**Specialists** (Fig. S2; best replicate in its own environment, BL):\n")
            w("| environment | best specialist | mean of specialists |\n|---|---|---|")
            for e, env in enumerate(envs):
                reps = [ok_mean(t[e, r], s[e, r])[0] for r in range(t.shape[1])]
                w(f"| {env} | {fmt(np.nanmax(reps))} | {fmt(np.nanmean(reps))} |")
            w("")
        if "scaling/travel_bl" in f and complete(f, "scaling"):
            envs = list_attr(f["scaling"], "environments")
            sizes = f["scaling/sizes"][()]
            t, s = f["scaling/travel_bl"][()], f["scaling/status"][()]
            novel = [i for i, e in enumerate(envs) if e != "flat"]
            w("**Scaling** (Fig. 4; chains, mean over novel environments of env means, BL):\n")
            w("| N | uniform | diverse |\n|---|---|---|")
            for si, n in enumerate(sizes):
                vals = []
                for v in range(2):
                    m, _ = env_means(t[:, si, v], s[:, si, v])
                    vals.append(np.mean(m[novel]))
                w(f"| {n} | {fmt(vals[0])} | {fmt(vals[1])} |")
            w("")
        if complete(f, "graded"):
            envs = list_attr(f["graded"], "environments")
            novel = [i for i, e in enumerate(envs) if e != "flat"]
            w("**Graded diversity** (Fig. S3; novel environments, mean of env means, BL):\n")
            w("| population | diversity sources | agents alone | weak diverse pairs |\n|---|---|---|---|")
            if "deploy/collectives/travel_bl" in f:
                d = f["deploy"]
                types = list_attr(d, "types")
                am, _ = env_means(d["agents/travel_bl"][()], d["agents/status"][()])
                if "weak_diverse@diverse" in types:
                    t = types.index("weak_diverse@diverse")
                    pm, _ = env_means(d["collectives/travel_bl"][()][:, t], d["collectives/status"][()][:, t])
                    w(f"| main | behaviour,springs,shape,pairing | {fmt(np.mean(am[novel]))} | {fmt(np.mean(pm[novel]))} |")
            for pop in list_attr(f["graded"], "populations"):
                g = f[f"graded/{pop}"]
                am, _ = env_means(g["deploy/agents/travel_bl"][()], g["deploy/agents/status"][()])
                pm, _ = env_means(g["deploy/pairs/travel_bl"][()], g["deploy/pairs/status"][()])
                w(f"| {pop} | {_s(g.attrs.get('diversity_sources', '?'))} | {fmt(np.mean(am[novel]))} | "
                  f"{fmt(np.mean(pm[novel]))} |")
            w("")
    lines += analysis_lines(path)
    return "\n".join(lines)


def analysis_lines(path):
    """Fig. 3A's numbers and Table S1's gist when the analysis stage is complete; a note when it is not."""
    from . import analysis as A

    st, desc = A.analysis_status(path)
    if st is None:
        return []
    if st != "complete":
        return [f"**Adversity and familiarity** (Fig. 3, Table S1): not summarized, {desc}.\n"]
    try:
        an = A.load_analysis(path)
    except RunFileError as e:
        return [f"**Adversity and familiarity** (Fig. 3, Table S1): cannot read: {e}\n"]
    adv, fam = an.adversity, an.familiarity
    out = [f"**Adversity** (Fig. 3A; DTW distance per step, u; mean over {adv.replicates} replicates, 95% bootstrap "
           f"CI):\n", "| agent | uniform-trained | diverse-trained | Welch p |", "|---|---|---|---|"]
    for k, name in ((A.WORSE, "worse-performing"), (A.BETTER, "better-performing")):
        cells = []
        for t in A.TYPES:
            lo, hi = adv.ci(t, k)
            cells.append(f"{fmt(adv.mean(t, k))} [{fmt(lo)}, {fmt(hi)}]")
        out.append(f"| {name} | " + " | ".join(cells) + f" | {adv.p(k):.3g} {A.stars(adv.p(k))} |")
    tab = fam.best_table()
    wins = sum(1 for e in range(len(fam.envs)) if tab[e, 0, 0] > tab[e, 0, 1])
    out += ["", f"**Familiarity** (Table S1): the novel environment is more familiar (more states in cells shared with "
                f"training) to the diverse-trained connector in {wins} of {len(fam.envs)} novel environments.", ""]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="divcoll run file (HDF5)")
    ap.add_argument("--out", help="write the Markdown here instead of printing it")
    a = ap.parse_args(argv)
    try:
        text = summarize(a.run)
    except RunFileError as e:
        print(f"summary: {e}", file=sys.stderr)
        return 2
    except (OSError, KeyError) as e:
        print(f"summary: cannot read {a.run}: {e}", file=sys.stderr)
        return 2
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text + "\n")
        print(f"summary: wrote {a.out}")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
