#!/usr/bin/python3
"""Fig. S2: generalist connectors against environment specialists, per novel environment.

The command line of divcoll_post.figures.fig_s2 (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.fig_s2 import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
