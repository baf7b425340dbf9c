#!/usr/bin/python3
"""Fig. 4: travel of uniform and diverse collectives against collective size, per environment.

The command line of divcoll_post.figures.fig4 (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.fig4 import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
