"""The one reader of divcoll run files: every module and command line of divcoll_post reads a run file here.

Two ways in, over the same checked file (root attribute format = "divcoll-run", clear errors otherwise):

- **labelled**: `divcoll_post.open(RUN.h5)` gives every dataset as an xarray.DataArray named by the file's own
  schema attributes:

    import divcoll_post
    with divcoll_post.open("runs/quick.h5") as run:
        t = run.deploy.collectives.travel_bl            # xarray.DataArray, dims (env, type, replicate, pair)
        t.sel(env="ice", type="weak_diverse@diverse")   # (replicate, pair), in BL
        t.attrs["unit"], t.attrs["doc"]                 # "BL", "travel of the pair; NaN unless status is 0"
        run["deploy/hidden/weak_diverse@diverse/states"]
        print(run.deploy)                               # what the group holds, with each dataset's doc

  `labelled(run, name, dims)` reads one dataset that way, refusing it unless its dimensions are `dims`. The pages
  that pick cells by environment, type, replicate or pair read through it: Fig. 2 and the deploy numbers of
  Figs. 4, S2 and S3 (results.load_deploy), the report's Fig. 2A per environment and its episode links
  (report_episodes.py), and Table S1.

- **raw** (numpy, what the other figures, pages and tables compute with): `open_file(RUN.h5)` is the checked
  h5py file for a `with` block; `dataset(f, path, name, shape, axes)` reads one dataset as numpy, refusing it when
  its shape or (where the file names them) its axes are not the expected ones; `list_attr` reads a list attribute
  (`environments`, `types`, ...: comma-joined strings as every stage writes them, or HDF5 string arrays);
  `stage_status`, `complete`, `require_stage` and `envs_done` say what a stage holds (these and `list_attr` take
  a file or group of either reader); `text` decodes an attribute. `STAGES` is the pipeline's stage list, read
  from its one home, src/config/pipeline.hpp.

Every dataset of a run file carries the attributes the run-file schema gives it (src/io/run_file.cpp,
mpi/README.md "Run-file layout"): `axes` (its dimension names, comma separated), `unit`, `doc` and, for each
labelled axis, `labels_<axis>` (comma separated). The labelled reader turns those into an xarray.DataArray with
named dimensions and label coordinates; nothing about shapes, counts or names is written here. A dataset without
`axes` (a file written before the schema, or a test's synthetic file) is refused by the labelled reader with a
message pointing to the raw one, which reads it and checks its axes only where the file names them. Data is
read when a dataset is first accessed. Files are opened read-only; `open()` stays open until close() (or the end of
a `with` block), `open_file()` until the end of its `with` block.

Why xarray (Debian's python3-xarray): it is the standard labelled-array library over numpy, so `sel` by
environment or type name, reductions over named dimensions (`.mean("pair")`) and alignment come for free
instead of a home-made index layer.
"""

from __future__ import annotations

import builtins
import contextlib
import os
import re
from typing import Dict, Iterator, List, Optional, Sequence, Tuple

import numpy as np

try:  # h5py is needed by the whole package; xarray only by the labelled reader
    import h5py
except ImportError as e:  # pragma: no cover - depends on the interpreter
    raise ImportError(
        "h5py is missing: run the post-processing with /usr/bin/python3 (Debian's python3-h5py)"
    ) from e

FORMAT = "divcoll-run"
PIPELINE_HPP = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "src", "config", "pipeline.hpp")


def pipeline_stages(path: str = PIPELINE_HPP) -> List[str]:
    """the pipeline's stages in run order, read from their one home: the stage list DIVCOLL_STAGES of
    src/config/pipeline.hpp, one line `X(name, stream, "reads")` per stage (this package lives in the repository
    beside it)"""
    try:
        with builtins.open(path, encoding="utf-8") as f:  # this module defines its own open()
            text = f.read()
    except OSError as e:
        raise RuntimeError(f"cannot read the pipeline's stage list from {os.path.normpath(path)}: {e.strerror} "
                           "(postprocess/ reads it from the repository's src/config/pipeline.hpp)") from e
    start = text.find("#define DIVCOLL_STAGES(X)")
    body = text[start:].split("\n\n", 1)[0] if start >= 0 else ""
    names = re.findall(r"^\s*X\((\w+),", body, re.M)
    if not names:
        raise RuntimeError(f"no stage list (#define DIVCOLL_STAGES(X) ...) in {os.path.normpath(path)}")
    return names


def __getattr__(name):
    """`STAGES`, the pipeline's stages in order (every stage group a run file can hold), read on first use: the
    labelled reader of an installed copy, which has no src/ beside it, never needs it"""
    if name == "STAGES":
        global STAGES
        STAGES = pipeline_stages()
        return STAGES
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class RunFileError(Exception):
    """The file is not a readable divcoll run file, or lacks what was asked for."""


class NotARunFile(RunFileError):
    """An HDF5 file whose root attribute `format` is missing or not "divcoll-run" (`fmt`: what it is, or None)."""

    def __init__(self, message: str, fmt: Optional[str]):
        super().__init__(message)
        self.fmt = fmt


class StageMissing(RunFileError):
    """The run file lacks the stage (or the part of it) a figure, table or page needs."""


# ---- attributes ---------------------------------------------------------------------------------------------------

def _decode(v):
    if isinstance(v, (bytes, np.bytes_)):
        return v.decode("utf-8", "replace")
    if isinstance(v, np.ndarray) and v.shape == ():
        return _decode(v[()])
    if isinstance(v, np.generic):
        return v.item()
    return v


def text(v) -> str:
    """an HDF5 attribute or string value as text (bytes decoded, 0-d arrays and numpy scalars unwrapped)"""
    v = _decode(v)
    return v if isinstance(v, str) else str(v)


_MISSING = object()


def list_attr(g, name: str, where: Optional[str] = None, default=_MISSING) -> List[str]:
    """The list attribute `name` of a group (or file): a comma-joined string, as every stage writes its lists, or
    an HDF5 string array; items stripped, empty ones dropped. Missing: `default` when given, else RunFileError
    naming `where` (default: the group's path)."""
    if name not in g.attrs:
        if default is not _MISSING:
            return default
        raise RunFileError(f"{where if where is not None else g.name}: attribute '{name}' missing")
    v = g.attrs[name]
    if isinstance(v, np.ndarray) and v.ndim == 1:
        return [text(x).strip() for x in v if text(x).strip()]
    return [x.strip() for x in text(v).split(",") if x.strip()]


def int_attr(g, name: str, default: int) -> int:
    """an integer attribute, or `default` when missing or not a number"""
    if name not in g.attrs:
        return default
    try:
        return int(_decode(g.attrs[name]))
    except (TypeError, ValueError):
        return default


# ---- the raw file ---------------------------------------------------------------------------------------------------

def _checked_file(path) -> "h5py.File":
    """the run file open read-only after checking it is one; RunFileError (a message for the user) otherwise"""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise RunFileError(f"{path}: no such file")
    if not os.path.isfile(path):
        raise RunFileError(f"{path}: not a regular file")
    try:
        is_h5 = h5py.is_hdf5(path)
    except OSError as e:
        raise RunFileError(f"{path}: cannot read ({e})") from e
    if not is_h5:
        raise RunFileError(
            f"{path}: not an HDF5 file (expected a divcoll run file, format \"{FORMAT}\")"
        )
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        msg = str(e)
        low = msg.lower()
        if "truncated" in low:
            hint = "truncated file: copied or written only in part?"
        elif "unable to lock" in low or "file locking" in low:
            hint = "locked: is divcoll still writing it?"
        else:
            hint = "damaged or truncated file"
        raise RunFileError(f"{path}: cannot open as HDF5 ({hint}): {msg}") from e
    try:
        fmt = _decode(f.attrs.get("format")) if "format" in f.attrs else None
    except OSError as e:
        f.close()
        raise RunFileError(f"{path}: read error (truncated or damaged file?): {e}") from e
    if fmt is None:
        f.close()
        raise NotARunFile(
            f"{path}: HDF5 file without a 'format' attribute: not a divcoll run file "
            f"(expected format \"{FORMAT}\")", None
        )
    if fmt != FORMAT:
        f.close()
        raise NotARunFile(
            f"{path}: format is \"{fmt}\", not \"{FORMAT}\": not a divcoll run file"
            + (" (scene and trajectory files are read by `divcoll simulate`)" if "divcoll" in str(fmt) else ""),
            str(fmt),
        )
    return f


@contextlib.contextmanager
def open_file(path) -> Iterator["h5py.File"]:
    """The run file as a read-only h5py.File for a `with` block, after checking it is one; RunFileError otherwise
    (also for a read error inside the block: a truncated or damaged file)."""
    f = _checked_file(path)
    try:
        yield f
    except OSError as e:  # a read past the end of a truncated file, a damaged chunk
        raise RunFileError(f"{os.fspath(path)}: read error (truncated or damaged file?): {e}") from e
    finally:
        f.close()


def _is_group(obj) -> bool:
    """an h5py group, or a group of the labelled reader"""
    return isinstance(obj, (h5py.Group, Group))


def stage_status(f, stage: str) -> Optional[str]:
    """the stage's `status` attribute ("complete", "running", ...), "?" when it has none, None without the group
    (`f`: a file open with open_file() or open())"""
    if stage not in f or not _is_group(f[stage]):
        return None
    return text(f[stage].attrs.get("status", "?"))


def complete(f, stage: str) -> bool:
    """the stage is in the file with status complete"""
    return stage_status(f, stage) == "complete"


def require_stage(f, path, stage: str):
    """the stage's group; StageMissing without it (`f`: a file open with open_file() or open())"""
    if stage not in f or not _is_group(f[stage]):
        raise StageMissing(f"{path}: run file has no {stage} stage (run the {stage} stage first)")
    return f[stage]


def dataset(f, path, name: str, shape: Optional[Tuple[int, ...]] = None,
            axes: Optional[Sequence[str]] = None) -> np.ndarray:
    """The dataset `name` as numpy, refused unless it has `shape` and (when the file names its axes: the run-file
    schema's `axes` attribute) the axes `axes`. StageMissing when it is not there."""
    if name not in f or not isinstance(f[name], h5py.Dataset):
        _missing(f, path, name)
    d = f[name]
    if shape is not None and tuple(d.shape) != tuple(shape):
        raise RunFileError(f"{path}: /{name} has shape {d.shape}, expected {tuple(shape)}")
    if axes is not None and "axes" in d.attrs and text(d.attrs["axes"]) != ",".join(axes):
        raise RunFileError(f"{path}: /{name} has axes {text(d.attrs['axes'])}, expected {','.join(axes)}")
    return d[()]


def _missing(f, path, name: str):
    stage = name.split("/")[0]
    st = text(f[stage].attrs.get("status", "?")) if stage in f else "absent"
    raise StageMissing(f"{path}: /{name} missing (the {stage} stage has status '{st}': "
                       f"run the {stage} stage to the end first)")


def labelled(run: "Run", name: str, dims: Sequence[str]):
    """The dataset `name` of a run file open with open(), as the labelled reader gives it (an xarray.DataArray),
    refused unless its dimensions are `dims`. StageMissing when it is not there; RunFileError when the file does
    not name its axes."""
    if name not in run or isinstance(run[name], Group):
        _missing(run, run.path, name)
    a = run[name]
    if tuple(a.dims) != tuple(dims):
        raise RunFileError(f"{run.path}: /{name} has axes {','.join(a.dims)}, expected {','.join(dims)}")
    return a


def envs_done(g, n: int) -> int:
    """how many of a stage's n environments are done: its `envs_done`, else all when complete, else none"""
    if "envs_done" in g.attrs:
        return max(0, min(n, int(_decode(g.attrs["envs_done"]))))
    return n if text(g.attrs.get("status", "")) == "complete" else 0


# ---- the labelled reader ----------------------------------------------------------------------------------------------


def _xarray():
    try:
        import xarray
    except ImportError as e:  # pragma: no cover - depends on the interpreter
        raise ImportError(
            "xarray is missing: install Debian's python3-xarray (jobs/install-deps.sh does)"
        ) from e
    return xarray


def _split(text) -> List[str]:
    text = _decode(text)
    return [x for x in str(text).split(",")] if text != "" else []


def _label_values(labels: List[str]):
    """Labels as numbers where they all are (chain sizes), else as strings."""
    try:
        return np.array([int(x) for x in labels])
    except ValueError:
        return np.array(labels, dtype=object)


def data_array(dataset: "h5py.Dataset"):
    """One dataset of a run file as an xarray.DataArray named by its attributes."""
    xr = _xarray()
    attrs = {k: _decode(v) for k, v in dataset.attrs.items()}
    if "axes" not in attrs:
        raise RunFileError(
            f"{dataset.file.filename}: {dataset.name} has no 'axes' attribute (a run file written before the "
            "run-file schema, or a synthetic file): read it with divcoll_post.reader.open_file and dataset"
        )
    dims = _split(attrs["axes"])
    if len(dims) != dataset.ndim:
        raise RunFileError(
            f"{dataset.file.filename}: {dataset.name} has {dataset.ndim} dimension(s) but axes = {attrs['axes']!r}"
        )
    coords = {}
    for k, name in enumerate(dims):
        key = f"labels_{name}"
        if key in attrs:
            labels = _split(attrs[key])
            if len(labels) != dataset.shape[k]:
                raise RunFileError(
                    f"{dataset.file.filename}: {dataset.name}: {len(labels)} labels for axis {name} of length "
                    f"{dataset.shape[k]}"
                )
            coords[name] = _label_values(labels)
    attrs = {k: v for k, v in attrs.items() if not k.startswith("labels_")}
    attrs["path"] = dataset.name
    return xr.DataArray(dataset[()], dims=dims, coords=coords, name=dataset.name.rsplit("/", 1)[-1], attrs=attrs)


class Group:
    """A group of the run file: child groups and datasets as attributes (`run.deploy.collectives`) or by
    path (`run["deploy/collectives/travel_bl"]`); `attrs` holds the group's own attributes, decoded."""

    def __init__(self, h5group: "h5py.Group"):
        self._g = h5group
        self._cache: Dict[str, object] = {}

    @property
    def name(self) -> str:
        return self._g.name

    @property
    def attrs(self) -> Dict[str, object]:
        return {k: _decode(v) for k, v in self._g.attrs.items()}

    def keys(self) -> List[str]:
        return list(self._g.keys())

    def __contains__(self, path: str) -> bool:
        return path in self._g

    def __iter__(self) -> Iterator[str]:
        return iter(self.keys())

    def __getitem__(self, path: str):
        path = path.strip("/")
        if path in self._cache:
            return self._cache[path]
        if path not in self._g:
            where = self._g.name.rstrip("/") + "/" + path
            raise KeyError(f"{self._g.file.filename}: no {where} (this group holds: {', '.join(self.keys())})")
        obj = self._g[path]
        out = Group(obj) if isinstance(obj, h5py.Group) else data_array(obj)
        self._cache[path] = out
        return out

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self[name]
        except KeyError as e:
            raise AttributeError(str(e)) from None

    def __dir__(self):
        return sorted(set(super().__dir__()) | {k for k in self.keys() if k.isidentifier()})

    def __repr__(self) -> str:
        lines = [f"<divcoll run-file group {self._g.name}>"]
        for k, v in self.attrs.items():
            if k != "config":
                lines.append(f"  @{k} = {v}")
        for k, obj in self._g.items():
            if isinstance(obj, h5py.Group):
                lines.append(f"  {k}/")
            else:
                axes = _decode(obj.attrs.get("axes", "?"))
                unit = _decode(obj.attrs.get("unit", "?"))
                doc = _decode(obj.attrs.get("doc", ""))
                dims = ", ".join(f"{a}={n}" for a, n in zip(str(axes).split(","), obj.shape))
                lines.append(f"  {k} ({dims}) [{unit}] {doc}")
        return "\n".join(lines)


class Run(Group):
    """An open run file (see the module's doc)."""

    def __init__(self, path):
        self.path = os.fspath(path)
        f = _checked_file(self.path)
        super().__init__(f)
        self._file = f

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def datasets(self) -> List[str]:
        """Paths of every dataset, in name order."""
        out: List[str] = []
        self._file.visititems(lambda name, obj: out.append(name) if isinstance(obj, h5py.Dataset) else None)
        return out

    def config(self) -> Optional[dict]:
        """The run's resolved config (every key), parsed from the root attribute `config`."""
        text = self.attrs.get("config")
        if not isinstance(text, str):
            return None
        import tomllib  # Python >= 3.11

        return tomllib.loads(text)


def open(path) -> Run:  # noqa: A001 - the reader's entry point, as h5py.File / xarray.open_dataset
    """Open a run file for labelled reading (see the module's doc)."""
    return Run(path)
