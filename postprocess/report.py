#!/usr/bin/python3
"""The report of a run file, as a Markdown page and a self-contained HTML page: the preset and its counts

The command line of divcoll_post.report (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.report import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
