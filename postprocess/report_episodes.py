#!/usr/bin/python3
"""The episodes behind the report's numbers: for every cell a number averages over (an environment and an agent

The command line of divcoll_post.report_episodes (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.report_episodes import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
