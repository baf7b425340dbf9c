#!/usr/bin/python3
"""Fig. 2: internal diversity and loose coupling confer resilience (travel of the eight collective types).

The command line of divcoll_post.figures.fig2 (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.fig2 import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
