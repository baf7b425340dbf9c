"""Paired float − double table of the precision studies, from their kept run summaries (README, float path):
    /usr/bin/python3 postprocess/gallery/study_claims_reduced_precision_paired.py STUDY_DIR [STUDY_DIR ...]
per seed with both variants, each type's travel on flat and in the novel environments (mean of 12), float − double."""
import glob, json, math, os, sys
import numpy as np
from scipy import stats

def load(folder):
    out = {}
    for var in ("baseline", "float_networks"):
        for p in glob.glob(os.path.join(folder, var, "seed*.summary.json")):
            seed = int(os.path.basename(p)[4:].split(".")[0])
            out.setdefault(seed, {})[var] = json.load(open(p))["fig2a"]
    return out

runs = {}
for f in sys.argv[1:]:
    runs.update(load(f))
seeds = sorted(s for s in runs if len(runs[s]) == 2)
first = runs[seeds[0]]["baseline"]
types = first["types"]
envs = first["environments"]
fl = envs.index("flat")
def val(f, key):
    if key == "alone":
        return f["alone"]["as_run"][fl], float(np.mean([v for i, v in enumerate(f["alone"]["as_run"]) if i != fl]))
    c = f["collectives"][key]
    return c[fl], float(np.mean([v for i, v in enumerate(c) if i != fl]))
def ci(d):
    d = np.asarray(d); m = d.mean(); se = d.std(ddof=1) / math.sqrt(len(d)); t = stats.t.ppf(0.975, len(d) - 1)
    return m, m - t * se, m + t * se, stats.ttest_1samp(d, 0).pvalue, int((d < 0).sum())
print(f"seeds: {', '.join(map(str, seeds))} ({len(seeds)} paired runs)\n")
print("| travel, BL (3000 steps) | where | double mean | float mean | float − double, mean [95% t interval] | paired t p | float lower in |")
print("|---|---|---|---|---|---|---|")
rows = ["alone"] + types + ["mean of the 8 collective types"]
for key in rows:
    for w, wi in (("flat", 0), ("novel (mean of 12)", 1)):
        if key.startswith("mean of"):
            b = [np.mean([val(runs[s]["baseline"], t)[wi] for t in types]) for s in seeds]
            f = [np.mean([val(runs[s]["float_networks"], t)[wi] for t in types]) for s in seeds]
        else:
            b = [val(runs[s]["baseline"], key)[wi] for s in seeds]
            f = [val(runs[s]["float_networks"], key)[wi] for s in seeds]
        m, lo, hi, p, nl = ci(np.array(f) - np.array(b))
        name = "agents alone" if key == "alone" else key
        print(f"| {name} | {w} | {np.mean(b):.2f} | {np.mean(f):.2f} | {m:+.2f} [{lo:+.2f}, {hi:+.2f}] | {p:.2f} | {nl}/{len(seeds)} |")
