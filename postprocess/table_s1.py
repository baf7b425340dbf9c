#!/usr/bin/python3
"""Table S1: "familiarity" of the weak connectors' hidden states in the novel environments, as Markdown.

The command line of divcoll_post.figures.table_s1 (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.table_s1 import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
