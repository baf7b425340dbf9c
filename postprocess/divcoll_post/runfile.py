"""Read-only access to a divcoll run file (HDF5, root attribute format = "divcoll-run").

Layout read here (agents stage; mpi/README.md "Run-file layout", SPEC §9):

    /                 attributes format, version, git_commit, ranks, seed, config (resolved TOML), ...
    /agents           attributes status ("complete" | "running"), generations_done
    /agents/final     the final population, one row per agent
    /agents/gen_NNN   every candidate of generation NNN, same datasets plus `survived`

Every function opens the file with the reader (reader.open_file), reads what it needs into numpy arrays
and closes it again; nothing is ever written. Problems with the file (missing, not HDF5, truncated, another format, a stage that is
not there, a dataset of the wrong shape) raise RunFileError with a message meant for the user.
"""

from __future__ import annotations

import dataclasses
import os
import re
from typing import Dict, List, Optional

import h5py
import numpy as np

# the reader's basics, also reachable from here
from .reader import (  # noqa: F401
    FORMAT,
    RunFileError,
    _decode,
    open_file,
    text,
)

STATUS_NAMES = {0: "ok", 1: "nan", 2: "unstable"}

# name -> (dtype kind, the axes after the row axis `agent`; None = any). The lengths of those axes are the
# file's (the same in every dataset that has the axis), and a dataset that names its axes (the run-file
# schema's `axes` attribute) must name these.
_AGENT_DATASETS = {
    "id": ("i", ()),
    "parent": ("i", ()),
    "cells": ("i", ()),
    "springs": ("i", ()),
    "rest_pos": ("f", ("mass", "xy")),
    "spring_i": ("i", ("spring",)),
    "spring_j": ("i", ("spring",)),
    "amplitude": ("f", ("spring",)),
    "params": ("f", ("agent_weight",)),
    "fitness": ("f", ()),
    "travel_u": ("f", ()),
    "descriptor": ("f", ("descriptor",)),
    "uniqueness": ("f", ()),
    "status": ("iu", ()),
}
_GEN_RE = re.compile(r"^gen_(\d+)$")


@dataclasses.dataclass
class RunMeta:
    path: str
    format: str
    version: Optional[int]
    git_commit: Optional[str]
    ranks: Optional[int]
    seed: Optional[int]
    config: Optional[str]
    name: str  # run.name from the stored config, else the file's stem
    agents_status: Optional[str]  # None when there is no agents group
    generations_done: Optional[int]
    attrs: Dict[str, object]  # every root attribute, strings decoded


@dataclasses.dataclass
class Population:
    """One row per agent. Arrays as stored (int64 / int32 / float64 / uint8)."""

    id: np.ndarray  # (M,)
    parent: np.ndarray  # (M,), -1 = none
    cells: np.ndarray  # (M,) 28-bit body genotype
    springs: np.ndarray  # (M,) 21-bit spring genotype
    rest_pos: np.ndarray  # (M, 11, 2), u
    spring_i: np.ndarray  # (M, 21), local mass index
    spring_j: np.ndarray  # (M, 21)
    amplitude: np.ndarray  # (M, 21), 0 = passive
    params: Optional[np.ndarray]  # (M, agent weights); None when read with params=False
    fitness: np.ndarray  # (M,), BL on flat ground
    travel_u: np.ndarray  # (M,), u
    descriptor: np.ndarray  # (M, 9)
    uniqueness: np.ndarray  # (M,)
    status: np.ndarray  # (M,) 0 ok, 1 nan, 2 unstable
    survived: Optional[np.ndarray] = None  # (M,) generations only
    extra: Dict[str, np.ndarray] = dataclasses.field(default_factory=dict)  # any other dataset
    group: str = ""

    def __len__(self) -> int:
        return int(self.fitness.shape[0])

    @property
    def active(self) -> np.ndarray:
        """(M, 21) bool: spring is actuated."""
        return self.amplitude > 0

    def body_length(self) -> np.ndarray:
        """(M,) max x − min x of the rest positions (SPEC §1), u."""
        x = self.rest_pos[:, :, 0]
        return x.max(axis=1) - x.min(axis=1)


def _int_or_none(v) -> Optional[int]:
    try:
        return None if v is None else int(v)
    except (TypeError, ValueError):
        return None


def _run_name(config: Optional[str]) -> Optional[str]:
    if not config:
        return None
    try:
        import tomllib  # Python >= 3.11

        name = tomllib.loads(config).get("run", {}).get("name")
        if isinstance(name, str) and name:
            return name
    except Exception:
        pass
    # fallback: the first `name = "..."` after a [run] header
    m = re.search(r"^\[run\]\s*$(.*?)(?=^\[|\Z)", config, re.M | re.S)
    if m:
        n = re.search(r'^\s*name\s*=\s*"([^"]*)"', m.group(1), re.M)
        if n and n.group(1):
            return n.group(1)
    return None


def _meta(f, path) -> RunMeta:
    attrs = {k: _decode(v) for k, v in f.attrs.items()}
    config = attrs.get("config")
    config = config if isinstance(config, str) else None
    name = _run_name(config) or os.path.splitext(os.path.basename(os.fspath(path)))[0]
    status = gens = None
    if "agents" in f and isinstance(f["agents"], h5py.Group):
        ga = f["agents"].attrs
        status = _decode(ga["status"]) if "status" in ga else None
        gens = _int_or_none(_decode(ga["generations_done"])) if "generations_done" in ga else None
    return RunMeta(
        path=os.fspath(path),
        format=attrs.get("format"),
        version=_int_or_none(attrs.get("version")),
        git_commit=attrs.get("git_commit") if isinstance(attrs.get("git_commit"), str) else None,
        ranks=_int_or_none(attrs.get("ranks")),
        seed=_int_or_none(attrs.get("seed")),
        config=config,
        name=name,
        agents_status=status,
        generations_done=gens,
        attrs=attrs,
    )


def read_meta(path) -> RunMeta:
    """Root attributes (provenance, config, seed) and the agents stage's status."""
    with open_file(path) as f:
        return _meta(f, path)


def _read_population(f, path, group: str, params: bool) -> Population:
    where = f"{os.fspath(path)}: /{group}"
    if group not in f or not isinstance(f[group], h5py.Group):
        stage = group.split("/")[0]
        if stage not in f:
            why = f"no '{stage}' group: the {stage} stage has not run (or not been written yet)"
        else:
            st = f[stage].attrs.get("status")
            done = f[stage].attrs.get("generations_done")
            why = (
                f"missing (/{stage} status = {_decode(st) if st is not None else '?'}, "
                f"generations_done = {_decode(done) if done is not None else '?'})"
            )
            if group.endswith("final"):
                why += ": the agents stage has not finished"
        raise RunFileError(f"{where} {why}")
    g = f[group]
    missing = [k for k in _AGENT_DATASETS if k not in g or not isinstance(g[k], h5py.Dataset)]
    if missing:
        raise RunFileError(f"{where}: missing dataset(s) {', '.join(missing)}")
    rows = g["fitness"].shape[0] if g["fitness"].ndim >= 1 else None
    out = {}
    lengths = {}  # axis name -> its length in this file
    for k, (kind, tail) in _AGENT_DATASETS.items():
        d = g[k]
        if d.ndim < 1 or d.shape[0] != rows:
            raise RunFileError(f"{where}/{k}: shape {d.shape}, expected {rows} rows (one per agent)")
        if d.ndim != 1 + len(tail):
            raise RunFileError(f"{where}/{k}: shape {d.shape}, expected axes (agent, {', '.join(tail)})")
        if "axes" in d.attrs and _decode(d.attrs["axes"]) != ",".join(("agent",) + tail):
            raise RunFileError(f"{where}/{k}: axes {_decode(d.attrs['axes'])}, expected {','.join(('agent',) + tail)}")
        for name, n in zip(tail, d.shape[1:]):
            if lengths.setdefault(name, n) != n:
                raise RunFileError(f"{where}/{k}: shape {d.shape}: axis {name} has length {n}, elsewhere {lengths[name]}")
        if d.dtype.kind not in kind and not (kind == "f" and d.dtype.kind in "iu"):
            raise RunFileError(f"{where}/{k}: dtype {d.dtype}, expected {'float' if kind == 'f' else 'integer'}")
        out[k] = None if (k == "params" and not params) else d[()]
    n_masses = lengths["mass"]
    for k in ("spring_i", "spring_j"):
        a = out[k]
        if a.size and (a.min() < 0 or a.max() >= n_masses):
            raise RunFileError(f"{where}/{k}: mass index out of range 0..{n_masses - 1}")
    survived = None
    if "survived" in g and isinstance(g["survived"], h5py.Dataset):
        survived = g["survived"][()]
    extra = {
        k: g[k][()]
        for k in g
        if k not in _AGENT_DATASETS and k != "survived" and isinstance(g[k], h5py.Dataset)
    }
    return Population(survived=survived, extra=extra, group="/" + group, **out)


def read_final(path, params: bool = True) -> Population:
    """The final population (/agents/final). params=False skips the (M × weights) controller weights."""
    with open_file(path) as f:
        return _read_population(f, path, "agents/final", params)


def list_generations(path) -> List[int]:
    """Indices of the stored generations (/agents/gen_NNN), ascending; [] if none."""
    with open_file(path) as f:
        if "agents" not in f or not isinstance(f["agents"], h5py.Group):
            return []
        gens = []
        for k, v in f["agents"].items():
            m = _GEN_RE.match(k)
            if m and isinstance(v, h5py.Group):
                gens.append(int(m.group(1)))
        return sorted(gens)


def read_generation(path, gen: int, params: bool = True) -> Population:
    """Every candidate of generation `gen` (/agents/gen_NNN), with `survived`."""
    gen = int(gen)
    with open_file(path) as f:
        name = f"gen_{gen:03d}"
        if "agents" in f and isinstance(f["agents"], h5py.Group) and name not in f["agents"]:
            for k in f["agents"]:  # tolerate another zero padding
                m = _GEN_RE.match(k)
                if m and int(m.group(1)) == gen:
                    name = k
                    break
        return _read_population(f, path, f"agents/{name}", params)
