"""A run's arrays: what the protocol's claims read from a run file, per connector and environment.

`extract(run.h5)` reads them (stages that are not complete are left out); `write_arrays` keeps them as
`<run>.arrays.json` beside the run's summary, so a study folder kept without its run files still gives every number;
`read_arrays` reads such a file back.
"""

from __future__ import annotations

import json
import os
import tomllib

import numpy as np

from ..reader import complete, list_attr, open_file, text as _s
from ..results import ok_means

ARRAYS_FORMAT = "divcoll-verdict-arrays"
ARRAYS_VERSION = 1


def _lists(a):
    return np.asarray(a, float).tolist()


def _agents(f, cfg) -> dict:
    fit = f["agents/final/fitness"][()]
    out = {"fitness_mean": float(np.mean(fit)), "fitness_sd": float(np.std(fit))}
    if "agents/gen_000/curve_u" in f:
        c = f["agents/gen_000/curve_u"][()][:, 0]
        fit, tu = f["agents/gen_000/fitness"][()], f["agents/gen_000/travel_u"][()]
        bl = np.where(fit != 0, tu / np.where(fit == 0, 1, fit), np.nan)
        out["gen0_mean"] = float(np.nanmean(c / bl))
    return out


def _connectors(f, cfg) -> dict:
    kinds = list_attr(f["connectors"], "kinds")
    out = {"untrained_bl": {k: _lists(f[f"connectors/{k}/curve_bl"][()][0]) for k in kinds
                            if f"connectors/{k}/curve_bl" in f}}
    # learning curves (iteration, replicate): the training batch's travel and, with keep_best, the
    # validation batch's and the iteration whose weights were kept
    curves = {}
    for k in kinds:
        g = f"connectors/{k}"
        if f"{g}/curve_bl" not in f:
            continue
        curves[k] = {"train_bl": _lists(f[f"{g}/curve_bl"][()])}
        if f"{g}/val_bl" in f:
            curves[k]["val_bl"] = _lists(f[f"{g}/val_bl"][()])
        if f"{g}/best_iteration" in f:
            curves[k]["best_iteration"] = _lists(f[f"{g}/best_iteration"][()])
    out["curves"] = curves
    out["wall_s"] = float(f["connectors"].attrs.get("wall_s", float("nan")))
    return out


def _deploy(f, cfg) -> dict:
    d = f["deploy"]
    envs, types = list_attr(d, "environments"), list_attr(d, "types")
    alone, _ = ok_means(d["agents/travel_bl"][()], d["agents/status"][()], 1)
    coll, nok = ok_means(d["collectives/travel_bl"][()], d["collectives/status"][()], 3)  # (E, T, R)
    dep = {"environments": envs, "types": types, "alone_bl": _lists(alone), "collectives_bl": _lists(coll),
           "collectives_ok": np.asarray(nok).tolist()}
    if "agents/travel_bl_early" in d and cfg.get("deploy", {}).get("early_step", 0) > 0:
        dep["alone_bl_early"] = _lists(ok_means(d["agents/travel_bl_early"][()], d["agents/status"][()], 1)[0])
        dep["early_step"] = cfg["deploy"]["early_step"]
    if "references/travel_bl" in d:  # deploy.references: free, passive, follower on uniform and diverse pairs
        ref, rok = ok_means(d["references/travel_bl"][()], d["references/status"][()], 2)  # (E, RT)
        dep["references"] = list_attr(d, "references")
        dep["references_bl"] = _lists(ref)
        dep["references_ok"] = np.asarray(rok).tolist()
        if "references/travel_bl_early" in d and "early_step" in dep:
            dep["references_bl_early"] = _lists(
                ok_means(d["references/travel_bl_early"][()], d["references/status"][()], 2)[0])
    return dep


def _analysis(f, cfg) -> dict:
    a = f["analysis"]
    adv, fam, fam_cal = {}, {}, {}
    for t in list_attr(a, "types"):
        g = a[f"adversity/{t}"]
        dtw, ws = g["dtw"][()], g["worse_slot"][()]  # (E, R, P, 2), (E, R, P)
        worse = np.take_along_axis(dtw, ws[..., None].astype(int), axis=3)[..., 0]
        better = np.take_along_axis(dtw, 1 - ws[..., None].astype(int), axis=3)[..., 0]
        with np.errstate(invalid="ignore"):
            adv[t] = {"all": _lists(np.nanmean(dtw, axis=(0, 2, 3))),
                      "worse": _lists(np.nanmean(worse, axis=(0, 2))),
                      "better": _lists(np.nanmean(better, axis=(0, 2)))}
        c = a[f"familiarity/{t}/counts"][()]  # (E_novel, R, 6)
        fam[t] = _lists(c[..., :3])
        if f"familiarity/{t}/counts_calibrated" in a:  # analysis.calibrated_cell_scale > 0 (A6's C24c)
            fam_cal[t] = _lists(a[f"familiarity/{t}/counts_calibrated"][()][..., :3])
    out = {"novel_environments": list_attr(a, "novel_environments"), "dtw": adv, "familiarity": fam}
    if fam_cal:
        out["familiarity_calibrated"] = fam_cal
        out["calibrated_cell_scale"] = cfg["analysis"]["calibrated_cell_scale"]
    return out


def _specialists(f, cfg) -> dict:
    s = f["specialists"]
    m, _ = ok_means(s["travel_bl"][()], s["status"][()], 2)  # (E_s, R_s)
    return {"environments": list_attr(s, "environments"), "travel_bl": _lists(m)}


def _scaling(f, cfg) -> dict:
    sc = f["scaling"]
    m, _ = ok_means(sc["travel_bl"][()], sc["status"][()], 4)  # (E, S, 2, R)
    return {"environments": list_attr(sc, "environments"), "sizes": [int(x) for x in sc["sizes"][()]],
            "travel_bl": _lists(m)}


def _graded(f, cfg) -> dict:
    g = f["graded"]
    pops = {}
    for pop in list_attr(g, "populations"):
        gp = g[pop]
        al, _ = ok_means(gp["deploy/agents/travel_bl"][()], gp["deploy/agents/status"][()], 1)
        pa, _ = ok_means(gp["deploy/pairs/travel_bl"][()], gp["deploy/pairs/status"][()], 2)  # (E, R)
        pops[pop] = {"alone_bl": _lists(al), "pairs_bl": _lists(pa)}
    return {"environments": list_attr(g, "environments"), "populations": pops}


# the stages whose arrays a run keeps, in run order, each with its reader (the run file, its config)
STAGE_ARRAYS = (("agents", _agents), ("connectors", _connectors), ("deploy", _deploy), ("analysis", _analysis),
                ("specialists", _specialists), ("scaling", _scaling), ("graded", _graded))


def extract(path: str) -> dict:
    """the arrays the protocol reads, from a run file (stages that are not complete are left out)"""
    out = {"format": ARRAYS_FORMAT, "version": ARRAYS_VERSION, "run_file": os.path.basename(path)}
    with open_file(path) as f:
        cfg = tomllib.loads(_s(f.attrs["config"])) if "config" in f.attrs else {}
        out["seed"] = cfg.get("run", {}).get("seed")
        out["git_commit"] = _s(f.attrs.get("git_commit", ""))
        out["episode_steps"] = {"connectors": cfg.get("connectors", {}).get("episode_steps"),
                                "deploy": cfg.get("deploy", {}).get("episode_steps")}
        for stage, read in STAGE_ARRAYS:
            if complete(f, stage):
                out[stage] = read(f, cfg)
    return out


def arrays_path(run_path: str) -> str:
    return os.path.splitext(run_path)[0] + ".arrays.json"


def write_arrays(run_path: str) -> str:
    path = arrays_path(run_path)
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(extract(run_path), fh, sort_keys=True)
        fh.write("\n")
    os.replace(tmp, path)
    return path


def read_arrays(path: str) -> dict:
    with open(path) as fh:
        a = json.load(fh)
    if a.get("format") != ARRAYS_FORMAT or a.get("version") != ARRAYS_VERSION:
        raise ValueError(f"{path} is not a divcoll verdict-arrays file of version {ARRAYS_VERSION}")
    return a
