"""`python3 -m divcoll_post.verdicts STUDY_DIR [...]`: the verdict page's command line (divcoll_post.verdict_page, the
same arguments; `--help` for them), as `postprocess/verdicts.py` runs it."""
import sys

from ..verdict_page import main

if __name__ == "__main__":
    sys.exit(main())
