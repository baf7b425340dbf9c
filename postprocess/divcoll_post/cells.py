"""The familiarity cell scale of statistic C24c, calibrated on a run file's stored embeddings.

The analysis stage stores every PaCMAP fit's 2-D coordinates (analysis/familiarity/<type>/embedding, training
states first, then the novel environment's; NaN padding). At cell scale s a state's cell is round(s × coordinate)
on each axis (round half to even, as the stage's std::nearbyint), and a state is *exclusive* when its cell holds
states of one source only. m(s) is the exclusive share of a fit, averaged over every novel environment, both
analysed types and every connector; the calibrated scale is the root of m(s) = target, found by bisection on ln s
(configs/studies/verdicts_cells.toml fixes the rule: target 0.275, bracket [1, 1000], two significant digits).

The embeddings are stored as float32, the stage classifies the float64 coordinates: a state within float32
rounding of a cell border can fall on the other side. The check at the stage's own scale (the stored counts
against the counts recomputed here) says how often that happens.

    PYTHONPATH=postprocess python3 -m divcoll_post.cells RUN.h5 [--target 0.275] [--json OUT.json]
"""
from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from .reader import list_attr, open_file, text


def classify(y: np.ndarray, n_train: int, scale: float) -> tuple[int, int, int]:
    """states in cells holding both sources, training only, novel only (y: (n, 2) coordinates, training first)"""
    cells = np.rint(np.asarray(y, dtype=np.float64) * scale).astype(np.int64)
    label = np.zeros(len(cells), dtype=np.int64)
    label[n_train:] = 1
    _, cell, = np.unique(cells, axis=0, return_inverse=True)[:2]
    cell = cell.reshape(-1)
    seen = np.zeros(cell.max() + 1, dtype=np.int64)
    np.bitwise_or.at(seen, cell, 1 << label)
    kind = seen[cell]
    return int((kind == 3).sum()), int((kind == 1).sum()), int((kind == 2).sum())


def fits(f) -> list[tuple[str, str, int, np.ndarray, int]]:
    """every fit of the run file: (type, novel environment, replicate, coordinates, training states)"""
    a = f["analysis"]
    out = []
    for t in list_attr(a, "types"):
        g = a[f"familiarity/{t}"]
        emb, ns = g["embedding"][()], g["n_states"][()]  # (E, R, 2·max, 2), (E, R, 2)
        for e, env in enumerate(list_attr(a, "novel_environments")):
            for r in range(emb.shape[1]):
                n_train, n_novel = int(ns[e, r, 0]), int(ns[e, r, 1])
                if n_train < 1 or n_novel < 1:
                    continue
                out.append((t, env, r, emb[e, r, :n_train + n_novel], n_train))
    return out


def exclusive_share(all_fits, scale: float) -> float:
    shares = []
    for _, _, _, y, n_train in all_fits:
        both, tr, nov = classify(y, n_train, scale)
        shares.append((tr + nov) / (both + tr + nov))
    return float(np.mean(shares))


def calibrate(all_fits, target: float, lo: float = 1.0, hi: float = 1000.0, digits: int = 2):
    """the scale in [lo, hi] where the mean exclusive share crosses target, by bisection on ln(scale), rounded to
    `digits` significant digits; with the shares at both ends and the path taken"""
    m_lo, m_hi = exclusive_share(all_fits, lo), exclusive_share(all_fits, hi)
    path = [(lo, m_lo), (hi, m_hi)]
    if not (m_lo <= target <= m_hi):
        raise ValueError(f"the mean exclusive share runs from {m_lo:.4f} (scale {lo}) to {m_hi:.4f} (scale {hi}); "
                         f"the target {target} is outside it")
    a, b = math.log(lo), math.log(hi)
    while b - a > 1e-4:
        c = 0.5 * (a + b)
        m = exclusive_share(all_fits, math.exp(c))
        path.append((math.exp(c), m))
        a, b = (c, b) if m < target else (a, c)
    s = math.exp(0.5 * (a + b))
    rounded = float(f"{s:.{digits - 1}e}")
    return rounded, s, path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run_file")
    ap.add_argument("--target", type=float, default=0.275, help="mean exclusive share to reach (default 0.275)")
    ap.add_argument("--json", help="write the calibration (scale, shares along the way, check) here")
    args = ap.parse_args(argv)
    with open_file(args.run_file) as f:
        all_fits = fits(f)
        a = f["analysis"]
        # the check: the stage's stored counts against the counts recomputed here at the stage's scale
        stored, mism = 0, 0
        scale0 = _cell_scale(f.attrs["config"])
        for t, env, r, y, n_train in all_fits:
            e = list_attr(a, "novel_environments").index(env)
            want = tuple(int(x) for x in a[f"familiarity/{t}/counts"][e, r, :3])
            stored += 1
            mism += classify(y, n_train, scale0) != want
    if not all_fits:
        print(f"{args.run_file}: no familiarity fits", file=sys.stderr)
        return 2
    scale, raw, path = calibrate(all_fits, args.target)
    m = exclusive_share(all_fits, scale)
    print(f"{len(all_fits)} fits; at the stage's cell scale {scale0:g} the recomputed counts differ from the "
          f"stored ones in {mism} of {stored} fits (float32 coordinates)")
    print(f"mean exclusive share {path[0][1]:.4f} at scale {path[0][0]:g}, {path[1][1]:.4f} at {path[1][0]:g}")
    print(f"calibrated cell scale {scale:g} (bisection {raw:.4f}); mean exclusive share there {m:.4f} "
          f"(target {args.target})")
    if args.json:
        with open(args.json, "w") as out:
            json.dump({"run_file": args.run_file, "target": args.target, "fits": len(all_fits),
                       "check_scale": scale0, "check_fits_differing": mism, "scale": scale, "bisection": raw,
                       "share_at_scale": m, "path": path}, out, indent=1)
    return 0


def _cell_scale(cfg) -> float:
    import tomllib
    return float(tomllib.loads(text(cfg))["analysis"]["cell_scale"])


if __name__ == "__main__":
    sys.exit(main())
