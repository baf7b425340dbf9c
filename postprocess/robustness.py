#!/usr/bin/python3
"""The robustness page of a study folder (`divcoll study STUDY.toml --out DIR`): the pre-registered claims

The command line of divcoll_post.robustness (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.robustness import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
