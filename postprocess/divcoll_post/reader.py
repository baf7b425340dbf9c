"""Labelled access to a divcoll run file, with the layout taken from the file itself.

    import divcoll_post
    with divcoll_post.open("runs/quick.h5") as run:
        t = run.deploy.collectives.travel_bl            # xarray.DataArray, dims (env, type, replicate, pair)
        t.sel(env="ice", type="weak_diverse@diverse")   # (replicate, pair), in BL
        t.attrs["unit"], t.attrs["doc"]                 # "BL", "travel of the pair; NaN unless status is 0"
        run["deploy/hidden/weak_diverse@diverse/states"]
        print(run.deploy)                               # what the group holds, with each dataset's doc

Every dataset of a run file carries the attributes the run-file schema gives it (src/io/run_file.cpp,
mpi/README.md "Run-file layout"): `axes` (its dimension names, comma separated), `unit`, `doc` and, for each
labelled axis, `labels_<axis>` (comma separated). The reader turns those into an xarray.DataArray with
named dimensions and label coordinates; nothing about shapes, counts or names is written here. Data is
read when a dataset is first accessed. The file is opened read-only and stays open until close() (or the
end of a `with` block).

Why xarray (Debian's python3-xarray): it is the standard labelled-array library over numpy, so `sel` by
environment or type name, reductions over named dimensions (`.mean("pair")`) and alignment come for free
instead of a home-made index layer.
"""

from __future__ import annotations

import os
from typing import Dict, Iterator, List, Optional

import numpy as np

from .runfile import FORMAT, RunFileError, _decode

try:  # h5py is needed by the whole package; xarray only here
    import h5py
except ImportError as e:  # pragma: no cover - depends on the interpreter
    raise ImportError("h5py is missing: install Debian's python3-h5py") from e


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
            "run-file schema, or not a divcoll run file): read it with h5py or divcoll_post.results"
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
        if not os.path.isfile(self.path):
            raise RunFileError(f"{self.path}: no such file")
        if not h5py.is_hdf5(self.path):
            raise RunFileError(f"{self.path}: not an HDF5 file (expected a divcoll run file)")
        f = h5py.File(self.path, "r")
        fmt = _decode(f.attrs.get("format", ""))
        if fmt != FORMAT:
            f.close()
            raise RunFileError(f"{self.path}: format is {fmt!r}, not {FORMAT!r}: not a divcoll run file")
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
