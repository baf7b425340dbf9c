#!/usr/bin/python3
"""The numbers behind the paper's claims, from a divcoll run file alone, as Markdown.

The command line of divcoll_post.summary (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.summary import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
