#!/usr/bin/python3
"""Animate one episode from its scene file and trajectory file (SPEC §9) as a GIF.

The command line of divcoll_post.animate (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.animate import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
