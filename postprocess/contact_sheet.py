#!/usr/bin/python3
"""A contact sheet of one uniform and one diverse pair in every environment of a run file.

The command line of divcoll_post.figures.contact_sheet (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.contact_sheet import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
