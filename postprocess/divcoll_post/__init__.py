"""Post-processing of divcoll run files (read-only): readers and the paper's figures.

Run everything with /usr/bin/python3 (Debian's python3-h5py, numpy, matplotlib). `divcoll_post.open(RUN.h5)`
gives labelled access to every dataset (xarray, Debian's python3-xarray; see reader.py); install the package
offline with `pip install --no-build-isolation --no-index ./postprocess` (postprocess/README.md)."""

from .runfile import (  # noqa: F401
    FORMAT,
    RunFileError,
    RunMeta,
    Population,
    read_meta,
    read_final,
    read_generation,
    list_generations,
)
from .reader import Run, open  # noqa: F401,E402,A001
