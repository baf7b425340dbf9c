#!/usr/bin/python3
"""One self-contained Markdown page for a run file: provenance, the paper's claims beside this run's
numbers with a verdict each, the summary tables, and every figure the postprocess scripts can draw.

    /usr/bin/python3 postprocess/report.py RUN.h5 [--out DIR] [--divcoll build/divcoll]

Writes DIR/report.md, DIR/table_s1.md and DIR/figures/*. A figure script that fails (for example because its
stage is missing from the run file) is listed with its message instead of its figure; the page is still written.
Fig. 3 and Table S1 (the analysis stage) are skipped with a note unless the analysis stage is complete.
"""
import argparse
import glob
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import claims  # noqa: E402
import summary  # noqa: E402
from divcoll_post import analysis as A  # noqa: E402

# figure scripts, in the paper's order, with the arguments they take besides the run file and --out
FIGURES = [("fig_s1.py", []), ("fig2.py", []), ("fig3.py", []), ("fig4.py", []), ("fig_s2.py", []),
           ("fig_s3.py", []), ("contact_sheet.py", ["--divcoll"])]
# outputs of the analysis stage: drawn only when it is complete
ANALYSIS_SCRIPTS = {"fig3.py", "table_s1.py"}


def analysis_skip(run):
    """None when the analysis stage is complete, else why Fig. 3 and Table S1 are skipped"""
    try:
        st, desc = A.analysis_status(run)
    except OSError as e:
        return f"cannot read the run file: {e}"
    if st == "complete":
        return None
    return desc if st is None else f"{desc}: run the analysis stage to the end first"


def table_s1_section(run, out_dir, skip):
    """Table S1 (table_s1.py, written to out_dir/table_s1.md) as a section of the page, or a note"""
    head = ["## Table S1: familiarity of the connectors' hidden states", ""]
    if skip:
        return head + [f"Skipped: {skip}.", ""]
    p = subprocess.run([sys.executable, os.path.join(HERE, "table_s1.py"), run, "--out", out_dir],
                       capture_output=True, text=True)
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
        path = os.path.join(HERE, script)
        if not os.path.exists(path):
            notes.append(f"- `{script}`: not available in this version")
            continue
        args = [sys.executable, path, run, "--out", fig_dir]
        if "--divcoll" in extra:
            args += ["--divcoll", divcoll]
        p = subprocess.run(args, capture_output=True, text=True)
        if p.returncode != 0:
            msg = (p.stderr.strip() or p.stdout.strip()).splitlines()
            notes.append(f"- `{script}` drew nothing: {msg[-1] if msg else 'exit ' + str(p.returncode)}")
    return notes


def motion_section(fig_dir, out_dir):
    """two animations (the uniform and the diverse weak pair in one novel environment) from the episode
    files contact_sheet.py exported, and links to the contact sheet and every exported episode"""
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
    lines = head + [f"Animations of pair 0 of replicate 0 in **{pick}** (springs coloured by strain, blue "
                    "shortened, red stretched; the camera follows the centre of mass):", ""]
    import animate  # noqa: E402 (matplotlib animation; only needed here)
    for sc in scenes:
        if not os.path.basename(sc).startswith(pick + "_weak_"):
            continue
        traj = sc.replace("_scene.h5", "_traj.h5")
        gif = sc.replace("_scene.h5", ".gif")
        try:
            animate.animate(sc, traj, gif, every=20)
            rel = os.path.relpath(gif, out_dir)
            lines.append(f"- [{os.path.basename(gif)}]({rel})")
        except Exception as e:  # a broken episode file is reported, the page is still written
            lines.append(f"- {os.path.basename(sc)}: not animated ({e})")
    lines += ["", f"The contact sheet (last step of every environment) is `figures/contact_sheet.png`; the scene and "
              f"trajectory files of all its episodes are in `{os.path.relpath(ep_dir, out_dir)}/`. Any other "
              "episode: `divcoll export RUN.h5 --what pair --env ENV --type TYPE --pair Q --out S.h5`, "
              "`divcoll simulate --scene S.h5 --steps T --out T.h5`, "
              "`/usr/bin/python3 postprocess/animate.py S.h5 T.h5 --out episode.gif`.", ""]
    return lines


def write_report(run, out_dir, divcoll):
    fig_dir = os.path.join(out_dir, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    skip = analysis_skip(run)
    notes = draw_figures(run, fig_dir, divcoll, skip)
    lines = [summary.summarize(run).replace("# divcoll run summary", "# divcoll report", 1), ""]
    table = ["## The paper's claims beside this run", "",
             "| claim | this run | verdict |", "|---|---|---|"]
    verdicts = {"held": 0, "did not hold": 0, "not measured": 0}
    for text, number, v in claims.claims(run):
        verdicts[v] += 1
        table.append(f"| {text} | {number} | **{v}** |")
    table += ["", f"{verdicts['held']} held, {verdicts['did not hold']} did not hold, "
                  f"{verdicts['not measured']} not measured.", ""]
    # the claims go first, after the provenance paragraph
    head, _, rest = lines[0].partition("\n\n| stage")
    page = [head, "", *table, "## Stages and numbers", "", "| stage" + rest]
    page += table_s1_section(run, out_dir, skip)
    page += motion_section(fig_dir, out_dir)
    page += ["## Figures", ""]
    pngs = sorted(glob.glob(os.path.join(fig_dir, "*.png")))
    for png in pngs:
        rel = os.path.relpath(png, out_dir)
        page.append(f"### {os.path.splitext(os.path.basename(png))[0]}\n\n![{rel}]({rel})\n")
    if notes:
        page += ["Figures not drawn:", "", *notes, ""]
    path = os.path.join(out_dir, "report.md")
    with open(path, "w") as fh:
        fh.write("\n".join(page) + "\n")
    return path, len(pngs), verdicts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="divcoll run file")
    ap.add_argument("--out", default="out/report", help="output folder")
    ap.add_argument("--divcoll", default=os.path.join(HERE, "..", "build", "divcoll"), help="the divcoll binary")
    a = ap.parse_args(argv)
    if not os.path.exists(a.run):
        print(f"report: no such run file: {a.run}", file=sys.stderr)
        return 2
    try:
        import h5py
        with h5py.File(a.run, "r") as f:
            fmt = f.attrs.get("format", b"")
            fmt = fmt.decode() if isinstance(fmt, bytes) else str(fmt)
        if fmt != "divcoll-run":
            print(f"report: {a.run} is not a divcoll run file (its format attribute is {fmt or 'missing'!r}; "
                  "a scene or trajectory file, or a foreign HDF5 file?)", file=sys.stderr)
            return 2
    except OSError as e:
        print(f"report: cannot read {a.run}: {e}", file=sys.stderr)
        return 2
    try:
        path, n, v = write_report(a.run, a.out, a.divcoll)
    except (OSError, KeyError) as e:
        print(f"report: cannot read {a.run}: {e}", file=sys.stderr)
        return 2
    print(f"report: wrote {path} ({n} figures; claims: {v['held']} held, {v['did not hold']} did not hold, "
          f"{v['not measured']} not measured)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
