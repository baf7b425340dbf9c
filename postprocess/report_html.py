#!/usr/bin/python3
"""report.html: the report page (report.py's Markdown) as one self-contained HTML file.

The command line of divcoll_post.report_html (`--help` for its arguments)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.report_html import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
