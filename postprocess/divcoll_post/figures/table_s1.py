"""Table S1: "familiarity" of the weak connectors' hidden states in the novel environments, as Markdown.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.table_s1 RUN.h5 [--out DIR]

Reads /analysis/familiarity of a divcoll run file (src/stages/analysis.hpp) and writes DIR/table_s1.md (DIR
defaults to out/figures); prints its path. One row per novel environment. For each connector replicate and
environment one PaCMAP fit embeds the hidden states recorded in flat (training) and in that environment; the
coordinates are rounded half to even into unit cells and every state is counted as lying in a cell that holds
both training and novel states, only training states or only novel states. The columns are these three counts,
each as the mean over replicates of the diverse-trained connector (on diverse pairs) and of the uniform-trained
one (on clones), with Welch's p between them (the run file's familiarity/table; recomputed from the counts when
the table is absent). The larger mean of each pair is bold: for "both" that is the type to which the novel
environment is more familiar. p < 0.05 is marked with stars (* < 0.05, ** < 0.01, *** < 0.001). The last
columns give the states per fit (training + novel, mean over replicates) and which type is more familiar.

Exit status: 0 done; 2 the file is not a divcoll run file, has no analysis stage or no familiarity results yet
(message on stderr).
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from .. import analysis as A  # noqa: E402
from .. import results as R  # noqa: E402
from ..reader import labelled  # noqa: E402
from ..reader import open as open_labelled  # noqa: E402

NAME = "table_s1.md"
TABLE = "analysis/familiarity/table"
TABLE_DIMS = ("novel_env", "cell_class", "table_column")
CLASSES = ("both", "train_only", "novel_only")  # the table's cell classes, in the order of A.COUNT_NAMES
COLUMNS = ("diverse_mean", "uniform_mean", "welch_p")


def _n(x) -> str:
    return "—" if x is None or not np.isfinite(x) else f"{x:.1f}"


def _p(p) -> str:
    if p is None or not np.isfinite(p):
        return "—"
    s = A.stars(p)
    return f"{p:.2g}" + (f" {s}" if s != "n.s." else "")


def _pair(d, u):
    """(diverse cell, uniform cell): the larger one bold"""
    dc, uc = _n(d), _n(u)
    if np.isfinite(d) and np.isfinite(u) and d != u:
        if d > u:
            dc = f"**{dc}**"
        else:
            uc = f"**{uc}**"
    return dc, uc


def consistency(fam: A.Familiarity):
    """messages for stored table means that differ from the means of the stored counts"""
    if fam.table is None:
        return []
    rec = fam.recomputed_table()
    out = []
    for e, env in enumerate(fam.envs):
        if not np.allclose(fam.table[e, :, :2], rec[e, :, :2], rtol=1e-9, atol=1e-9, equal_nan=True):
            out.append(f"{env}: familiarity/table means differ from the means of familiarity/<type>/counts")
    return out


def labelled_numbers(path, fam: A.Familiarity):
    """(the table, dims TABLE_DIMS: the run file's familiarity/table, else recomputed from the counts; the states
    per fit {type: (novel_env, replicate, source)}), both cut to the environments done, as the labelled reader
    gives them"""
    with open_labelled(path) as run:
        ns = {t: labelled(run, f"analysis/familiarity/{t}/n_states", ("novel_env", "replicate", "source"))
              for t in (A.DIVERSE, A.UNIFORM)}
        tab = labelled(run, TABLE, TABLE_DIMS) if fam.table is not None else None
    if tab is None:
        import xarray
        tab = xarray.DataArray(fam.recomputed_table(), dims=TABLE_DIMS, coords={
            "novel_env": fam.envs, "cell_class": list(CLASSES), "table_column": list(COLUMNS)})
    return tab.sel(novel_env=fam.envs).astype(float), {t: a.sel(novel_env=fam.envs) for t, a in ns.items()}


def render(path) -> tuple:
    """(Markdown text, rows) where rows are (env, table (3 × 3), n_states means {type: (train, novel)})"""
    meta = R.load_meta(path)
    an = A.load_analysis(path, need=("familiarity",))
    fam = an.familiarity
    tab, n_states = labelled_numbers(path, fam)
    notes = consistency(fam)
    lines = ["# Table S1 — familiarity of the connectors' hidden states in the novel environments", "",
             f"{R.run_title(meta)}; analysis stage {an.status}; {len(fam.envs)} of {len(an.novel_environments)} novel "
             f"environments; {fam.replicates} connector replicates per type.", ""]
    hdr = ["environment"]
    for k in A.COUNT_NAMES:
        hdr += [f"{k}: diverse", f"{k}: uniform", f"{k}: p"]
    hdr += ["states per fit, diverse (training + novel)", "states per fit, uniform (training + novel)",
            "more familiar to"]
    lines += ["| " + " | ".join(hdr) + " |", "|---|" + "---:|" * (len(hdr) - 2) + "---|"]
    rows = []
    n_div = n_div_sig = n_uni_novel = 0
    for env in fam.envs:
        row = tab.sel(novel_env=env)
        cells = [env.replace("_", " ")]
        for k in CLASSES:
            d, u, p = (row.sel(cell_class=k, table_column=c).item() for c in COLUMNS)
            cells += [*_pair(d, u), _p(p)]
        ns = {}
        for t in (A.DIVERSE, A.UNIFORM):
            m = n_states[t].sel(novel_env=env).astype(float).reduce(np.nanmean, "replicate")
            train, novel = (m.sel(source=s).item() for s in ("training", "novel"))
            ns[t] = (train, novel)
            cells.append(f"{train:g} + {novel:g}")
        both = row.sel(cell_class="both")
        d, u, p = (both.sel(table_column=c).item() for c in COLUMNS)
        more = "diverse" if d > u else "uniform" if u > d else "—"
        if more == "diverse":
            n_div += 1
            n_div_sig += int(np.isfinite(p) and p < 0.05)
        novel_only = row.sel(cell_class="novel_only")
        if novel_only.sel(table_column="uniform_mean") > novel_only.sel(table_column="diverse_mean"):
            n_uni_novel += 1
        cells.append(more)
        lines.append("| " + " | ".join(cells) + " |")
        rows.append((env, row.values, ns))
    E = len(fam.envs)
    lines += ["",
              f"The novel environment is more familiar to the diverse-trained connector (more states in cells shared "
              f"with training) in {n_div} of {E} environments ({n_div_sig} with p < 0.05); the uniform-trained "
              f"connector has more states exclusive to the novel environment in {n_uni_novel} of {E}.", "",
              "Each count is the mean over connector replicates of the number of states (PaCMAP coordinates rounded "
              "half to even into unit cells) whose cell holds states of both environments (both), only of flat, the "
              "training environment (train-only), or only of the novel environment (novel-only). "
              "Diverse: the weak diverse-trained connector on diverse pairs; uniform: the weak uniform-trained one on "
              "clones. Bold: the larger mean of each pair (the paper bolds only the pairs that "
              "agree with its finding). p: Welch's t-test, diverse vs uniform over replicates; * < 0.05, ** < 0.01, "
              "*** < 0.001."]
    if fam.table is None:
        lines += ["", "The run file has no familiarity/table: means and p recomputed here from the counts."]
    for n in notes:
        lines += ["", f"Warning: {n}."]
    return "\n".join(lines) + "\n", rows, notes


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="divcoll run file (HDF5)")
    ap.add_argument("--out", default=os.path.join("out", "figures"), help="output directory (default out/figures)")
    a = ap.parse_args(argv)
    try:
        text, _, notes = render(a.run)
    except R.RunFileError as e:
        print(f"table_s1: {e}", file=sys.stderr)
        return 2
    for n in notes:
        print(f"table_s1: warning: {n}", file=sys.stderr)
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, NAME)
    with open(path, "w") as fh:
        fh.write(text)
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
