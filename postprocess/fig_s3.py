#!/usr/bin/python3
"""Fig. S3: graded diversity among agents — agents alone vs. pairs joined by weak diverse-trained connectors.

The command line of divcoll_post.figures.fig_s3 (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.fig_s3 import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
