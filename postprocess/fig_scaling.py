#!/usr/bin/python3
"""Table and plot of a scaling benchmark (jobs/bench-scaling.sh): wall time per stage against ranks,

The command line of divcoll_post.figures.fig_scaling (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.fig_scaling import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
