"""The report of a run file, as a Markdown page and a self-contained HTML page: the preset and its counts
against the paper's, provenance, the paper's claims beside this run's numbers with a verdict each, the
summary tables, every figure of divcoll_post.figures, and movies.

    divcoll report RUN.h5 [--out DIR] [--movie]
    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.report RUN.h5 [--out DIR] [--divcoll build/divcoll]
        [--movie]

Writes DIR/report.md, DIR/report.html (report_html.py: figures embedded, movies as <video controls> beside
it; every number of the claims table and of Fig. 2A per environment, and every single episode a caption
names, linked to the `divcoll export` command of its episode: report_episodes.py), DIR/table_s1.md,
DIR/figures/* (motion_<env>.mp4: a uniform and a diverse pair side by side) and with --movie DIR/movie/*
(movie.py: the paper's Supplementary Movie). A figure script that fails (for example because its
stage is missing from the run file) is listed with its message instead of its figure; the page is still written.
Fig. 3 and Table S1 (the analysis stage) are skipped with a note unless the analysis stage is complete.
"""
import argparse
import glob
import os
import subprocess
import sys

# the folder holding the divcoll_post package (postprocess/ in the checkout) and the checkout
PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CHECKOUT = os.path.dirname(PACKAGE_PARENT)

from . import report_episodes  # noqa: E402
from . import report_html  # noqa: E402
from . import summary  # noqa: E402
from . import analysis as A  # noqa: E402
from . import single_run, verdicts as V  # noqa: E402
from .reader import NotARunFile, RunFileError, open_file  # noqa: E402

# figures (the module file divcoll_post/figures/<name>), in the paper's order, with the arguments they
# take besides the run file and --out
FIGURES = [("fig_s1.py", []), ("fig2.py", []), ("fig3.py", []), ("fig4.py", []), ("fig_s2.py", []),
           ("fig_s3.py", []), ("contact_sheet.py", ["--divcoll"])]
# outputs of the analysis stage: drawn only when it is complete
ANALYSIS_SCRIPTS = {"fig3.py", "table_s1.py"}


def analysis_skip(run):
    """None when the analysis stage is complete, else why Fig. 3 and Table S1 are skipped"""
    try:
        st, desc = A.analysis_status(run)
    except (OSError, RunFileError) as e:
        return f"cannot read the run file: {e}"
    if st == "complete":
        return None
    return desc if st is None else f"{desc}: run the analysis stage to the end first"


def figure_command(script):
    """the command that runs figure `script` ("fig2.py"): its module divcoll_post.figures.fig2 under this Python"""
    return [sys.executable, "-m", f"divcoll_post.figures.{os.path.splitext(script)[0]}"]


def figure_env():
    """the environment of a figure's process: this package importable"""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([PACKAGE_PARENT] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    return env


def table_s1_section(run, out_dir, skip):
    """Table S1 (table_s1.py, written to out_dir/table_s1.md) as a section of the page, or a note"""
    head = ["## Table S1: familiarity of the connectors' hidden states", ""]
    if skip:
        return head + [f"Skipped: {skip}.", ""]
    p = subprocess.run(figure_command("table_s1.py") + [run, "--out", out_dir], capture_output=True, text=True,
                       env=figure_env())
    if p.returncode != 0:
        msg = (p.stderr.strip() or p.stdout.strip()).splitlines()
        return head + [f"Not written: {msg[-1] if msg else 'exit ' + str(p.returncode)}", ""]
    with open(p.stdout.strip().splitlines()[-1]) as fh:
        body = fh.read().splitlines()
    if body and body[0].startswith("# "):
        body = body[1:]
    while body and not body[0].strip():
        body = body[1:]
    return head + body + [""]


def draw_figures(run, fig_dir, divcoll, skip=None):
    notes = []
    for script, extra in FIGURES:
        if script in ANALYSIS_SCRIPTS and skip:
            notes.append(f"- `{script}` skipped: {skip}")
            continue
        if not os.path.exists(os.path.join(PACKAGE_PARENT, "divcoll_post", "figures", script)):
            notes.append(f"- `{script}`: not available in this version")
            continue
        args = figure_command(script) + [run, "--out", fig_dir]
        if "--divcoll" in extra:
            args += ["--divcoll", divcoll]
        p = subprocess.run(args, capture_output=True, text=True, env=figure_env())
        if p.returncode != 0:
            msg = (p.stderr.strip() or p.stdout.strip()).splitlines()
            notes.append(f"- `{script}` drew nothing: {msg[-1] if msg else 'exit ' + str(p.returncode)}")
    return notes


def motion_section(fig_dir, out_dir, quick=False, eps=None):
    """a movie of the uniform and the diverse weak pair side by side in one novel environment (MP4, movie.py),
    from the episode files contact_sheet.py exported, and where every exported episode is"""
    head = ["## Motion", ""]
    ep_dir = os.path.join(fig_dir, "episodes")
    scenes = sorted(glob.glob(os.path.join(ep_dir, "*_scene.h5")))
    if not scenes:
        return head + ["No episodes were exported (the contact sheet was not drawn).", ""]
    envs = []
    for sc in scenes:
        env = os.path.basename(sc).split("_weak_")[0]
        if env not in envs:
            envs.append(env)
    pick = "wind" if "wind" in envs else next((e for e in envs if e != "flat"), envs[0])
    lines = head + [f"Pair 0 of replicate 0 in **{pick}**, the uniform pair (weak uniform-trained connector) beside "
                    "the diverse pair (weak diverse-trained connector); springs coloured by strain, travel in BL, "
                    "the camera follows each centre of mass" + episode_refs(eps, pick, 0) + ":", ""]
    from . import movie  # noqa: E402 (matplotlib and ffmpeg; only needed here)
    mine = [sc for sc in scenes if os.path.basename(sc).startswith(pick + "_weak_")]
    mp4 = os.path.join(fig_dir, f"motion_{pick}.mp4")
    try:
        clips = []
        for sc in sorted(mine, key=lambda p: "diverse_at_diverse" in p):  # uniform first
            c = movie.Clip(sc, sc.replace("_scene.h5", "_traj.h5"), "")
            c.title = ("uniform pair, weak uniform-trained" if "uniform_at_uniform" in sc
                       else "diverse pair, weak diverse-trained")
            clips.append(c)
        movie.render(mp4, clips, f"{pick.replace('_', ' ')}: uniform vs diverse pair", quick=quick,
                     every=60 if quick else 30)
        lines.append(f"[{os.path.basename(mp4)}]({os.path.relpath(mp4, out_dir)})")
    except Exception as e:  # a broken episode file or no ffmpeg is reported, the page is still written
        lines.append(f"Not rendered: {e}")
    lines += ["", f"The contact sheet (last step of every environment; pair 0 of replicate 0, e.g. in flat"
              f"{episode_refs(eps, 'flat', 0)}) is `figures/contact_sheet.png`; the scene and "
              f"trajectory files of all its episodes are in `{os.path.relpath(ep_dir, out_dir)}/`. Any other "
              "episode: `divcoll export RUN.h5 --what pair --env ENV --type TYPE --pair Q --out S.h5`, "
              "`divcoll simulate --scene S.h5 --steps T --out T.h5`, "
              "`PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.movie --episode S.h5 T.h5 --out "
              "episode.mp4`.", ""]
    return lines


def episode_refs(eps, env, pair, types=("weak_uniform@uniform", "weak_diverse@diverse")):
    """' (episodes: [uniform](#..), [diverse](#..))': pair `pair` of replicate 0 in env of each type, or ''"""
    if eps is None:
        return ""
    got = [f"[{t}](#{a})" for t in types if (a := eps.pair(env, t, pair=pair))]
    return f" (episodes: {', '.join(got)})" if got else ""


def movie_section(run, out_dir, divcoll, eps=None):
    """the paper's Supplementary Movie (movie.py) in out_dir/movie"""
    head = ["## Supplementary Movie", ""]
    from . import movie  # noqa: E402
    try:
        paths = movie.supplementary(run, os.path.join(out_dir, "movie"), divcoll)
    except Exception as e:
        return head + [f"Not rendered: {e}", ""]
    names = ["the whole movie", "agent optimisation", "connector optimisation", "deployment, uniform vs diverse"]
    refs = ["", " (the fittest agent alone on flat, `--what alone --env flat --agent I`)",
            ", the trained pair is pair 0 of replicate 0 on flat" + episode_refs(eps, "flat", 0, ["weak_diverse@diverse"]),
            ", pair 0 of replicate 0 in each environment, e.g. wind" + episode_refs(eps, "wind", 0)]
    return head + [f"- {n}{r}: [{os.path.basename(p)}]({os.path.relpath(p, out_dir)})"
                   for n, r, p in zip(names, refs, paths)] + [""]


def scale_section(run):
    """the preset and its counts against the paper's"""
    name, rows = single_run.scale(run)
    small = [r for r in rows if isinstance(r[2], (int, float)) and isinstance(r[3], (int, float)) and r[2] < r[3]]
    if small:
        verdict = (f"**Preset `{name}`: smaller than the paper in {len(small)} of {len(rows)} counts.** This page reports "
                   f"the run file `{os.path.basename(run)}` only; it is not a paper-scale report. Claims are judged "
                   "only where the run has the counts their tests need; the others read *too small to judge*, with "
                   "the count that is short. The paper's claims judged over independent populations at the paper's "
                   "per-connector scale are in the repository at `postprocess/gallery/verdicts/verdicts.md`; "
                   "postprocess/RESULTS.md summarises every run and study.")
    else:
        verdict = f"**Preset `{name}`: the paper's counts or more.**"
    out = [verdict, "", precision_line(run), "", "| count | config key | this run | paper |", "|---|---|---|---|"]
    out += [f"| {what} | `{k}` | {v} | {p} |" for what, k, v, p in rows]
    return out + [""]


def precision_line(run):
    """the run's arithmetic (run.precision): two runs in different precisions are different runs, never bit-equal"""
    prec = single_run.key(single_run.config(run), "run.precision") or "double"
    if prec == "float_networks":
        return ("Arithmetic: `run.precision = float_networks`: the controllers' networks in float, the physics and every "
                "optimizer in double (jobs/BENCHMARKS.md, \"The float path\"); its numbers are not bit-comparable with a double run's.")
    return f"Arithmetic: `run.precision = {prec}` (the spec's)."


def write_report(run, out_dir, divcoll, movie=False, quick=False):
    fig_dir = os.path.join(out_dir, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    skip = analysis_skip(run)
    notes = draw_figures(run, fig_dir, divcoll, skip)
    lines = [summary.summarize(run).replace("# divcoll run summary", "# divcoll report", 1), ""]
    eps = report_episodes.Episodes(run, os.path.abspath(run))
    table = ["## The paper's claims beside this run", "",
             f"The pre-registered claims (configs/studies/verdicts_protocol.md, the verdict page's "
             f"{V.CLAIMS[0].id}–{V.CLAIMS[-1].id}), each "
             "judged on this run alone: its effect at all of the run's connectors against the claim's own margin "
             "(held when it lies in the region the claim names); the verdict page judges the same effects over "
             "populations.", "",
             "| claim | this run | verdict | counts the test needs | episodes |", "|---|---|---|---|---|"]
    verdicts = {v: 0 for v in single_run.VERDICTS}
    for c, number, v, needs in single_run.claims(run):
        verdicts[v] += 1
        table.append(f"| **{c.id}** {c.text} | {number} | **{v}** | {needs} | {eps.claim_cell(c, number)} |")
    table += ["", ", ".join(f"{n} {v}" for v, n in verdicts.items()) + ". Episodes: each link leads to the "
              "`divcoll export` command of the median ok episode of one cell the number averages over (an environment "
              "and an agent alone, a collective type, a specialist or a chain; replicate 0 for connectors), listed "
              "under [Episodes behind the numbers](#episodes-behind-the-numbers).", ""]
    # the preset and the claims go first, after the provenance paragraph
    head, _, rest = lines[0].partition("\n\n| stage")
    page = [head, "", *scale_section(run), *table, *eps.fig2a_table(), "## Stages and numbers", "", "| stage" + rest]
    page += table_s1_section(run, out_dir, skip)
    page += motion_section(fig_dir, out_dir, quick, eps)
    if movie:
        page += movie_section(run, out_dir, divcoll, eps)
    page += ["## Figures", ""]
    pngs = sorted(glob.glob(os.path.join(fig_dir, "*.png")))
    for png in pngs:
        rel = os.path.relpath(png, out_dir)
        page.append(f"### {os.path.splitext(os.path.basename(png))[0]}\n\n![{rel}]({rel})\n")
    if notes:
        page += ["Figures not drawn:", "", *notes, ""]
    page += eps.listing()
    path = os.path.join(out_dir, "report.md")
    with open(path, "w") as fh:
        fh.write("\n".join(page) + "\n")
    report_html.write(run, out_dir, "\n".join(page))
    return path, len(pngs), verdicts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="divcoll run file")
    ap.add_argument("--out", default="out/report", help="output folder")
    ap.add_argument("--divcoll", default=os.path.join(CHECKOUT, "build", "divcoll"), help="the divcoll binary")
    ap.add_argument("--movie", action="store_true", help="also render the Supplementary Movie (movie.py)")
    ap.add_argument("--quick", action="store_true", help="smaller, fewer movie frames (tests)")
    a = ap.parse_args(argv)
    if not os.path.exists(a.run):
        print(f"report: no such run file: {a.run}", file=sys.stderr)
        return 2
    try:
        with open_file(a.run):
            pass
    except NotARunFile as e:
        print(f"report: {a.run} is not a divcoll run file (its format attribute is {e.fmt or 'missing'!r}; "
              "a scene or trajectory file, or a foreign HDF5 file?)", file=sys.stderr)
        return 2
    except RunFileError as e:
        print(f"report: cannot read {a.run}: {e}", file=sys.stderr)
        return 2
    try:
        path, n, v = write_report(a.run, a.out, a.divcoll, a.movie, a.quick)
    except (OSError, KeyError, RunFileError) as e:
        print(f"report: cannot read {a.run}: {e}", file=sys.stderr)
        return 2
    print(f"report: wrote {path} and {os.path.join(a.out, 'report.html')} ({n} figures; claims: "
          + ", ".join(f"{k} {x}" for x, k in v.items()) + ")")
    return 0


if __name__ == "__main__":
    sys.exit(main())
