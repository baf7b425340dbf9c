"""Post-processing of divcoll run files (read-only): readers and the paper's figures.

Run everything with /usr/bin/python3 (Debian's python3-h5py, numpy, matplotlib)."""

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
