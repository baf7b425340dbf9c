#!/usr/bin/python3
"""Fig. 3: internal adversity (DTW, a) and external adversity (familiarity of the connector's states, b-c).

The command line of divcoll_post.figures.fig3 (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.fig3 import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
