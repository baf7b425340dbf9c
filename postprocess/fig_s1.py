#!/usr/bin/python3
"""Fig. S1: the morphologies of the final evolved population, one panel per agent.

The command line of divcoll_post.figures.fig_s1 (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.fig_s1 import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
