"""The verdict page of a study judged by the pre-registered protocol (configs/studies/verdicts_protocol.md).

    /usr/bin/python3 postprocess/verdicts.py STUDY_DIR [--out DIR] [--resamples B] [--readings | --states] [--readme README.md]

The one script left in postprocess/, kept because the protocol names it: the command line of
divcoll_post.verdict_page (`python3 -m divcoll_post.verdict_page`, the same arguments; `--help` for them)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.verdict_page import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
