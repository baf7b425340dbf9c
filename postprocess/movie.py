#!/usr/bin/python3
"""The paper's Supplementary Movie, rendered from a run file as MP4 (H.264, Debian's ffmpeg).

The command line of divcoll_post.movie (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.movie import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
