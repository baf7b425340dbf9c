"""Paired float − double table of the precision studies, from their kept run summaries (postprocess/RESULTS.md,
"Double against float"):

    /usr/bin/python3 postprocess/gallery/study_claims_reduced_precision_paired.py STUDY_DIR [STUDY_DIR ...]

per seed with both variants, each type's travel on flat and in the novel environments (mean of them), float − double.
The summaries are read and the intervals computed as on the robustness page (divcoll_post.robustness)."""
import glob
import os
import sys

import numpy as np
from scipy import stats

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from divcoll_post.robustness import SummaryRun, t_interval  # noqa: E402

VARIANTS = ("baseline", "float_networks")


def load(folder):
    """{seed: {variant: SummaryRun}} of one study folder"""
    out = {}
    for var in VARIANTS:
        for p in glob.glob(os.path.join(folder, var, "seed*.summary.json")):
            seed = int(os.path.basename(p)[4:].split(".")[0])
            out.setdefault(seed, {})[var] = SummaryRun(p)
    return out


runs = {}
for folder in sys.argv[1:]:
    more = load(folder)
    if runs.keys() & more.keys():
        sys.exit(f"{folder}: seeds {sorted(runs.keys() & more.keys())} are in an earlier folder too")
    runs.update(more)
seeds = sorted(s for s in runs if len(runs[s]) == len(VARIANTS))
first = runs[seeds[0]]["baseline"]


def series(run, key):
    """travel per environment: agents alone or collective type `key`"""
    return run.alone if key == "alone" else run.coll[key]


def where(run, arr, novel):
    return run.novel_mean(arr) if novel else float(arr[run.flat])


print(f"seeds: {', '.join(map(str, seeds))} ({len(seeds)} paired runs)\n")
print("| travel, BL (3000 steps) | where | double mean | float mean | float − double, mean [95% t interval] | paired t p | float lower in |")
print("|---|---|---|---|---|---|---|")
mean_row = f"mean of the {len(first.types)} collective types"
for key in ["alone"] + first.types + [mean_row]:
    for label, novel in (("flat", False), (f"novel (mean of {len(first.novel)})", True)):
        side = {}
        for var in VARIANTS:
            keys = first.types if key == mean_row else [key]
            side[var] = np.array([np.mean([where(runs[s][var], series(runs[s][var], k), novel) for k in keys])
                                  for s in seeds])
        d = side["float_networks"] - side["baseline"]
        m, lo, hi, _ = t_interval(d)
        name = "agents alone" if key == "alone" else key
        print(f"| {name} | {label} | {side['baseline'].mean():.2f} | {side['float_networks'].mean():.2f} | {m:+.2f} [{lo:+.2f}, {hi:+.2f}] | "
              f"{stats.ttest_1samp(d, 0).pvalue:.2f} | {int((d < 0).sum())}/{len(seeds)} |")
