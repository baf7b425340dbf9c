"""The verdict page of a study judged by the pre-registered protocol (configs/studies/verdicts_protocol.md).

    /usr/bin/python3 postprocess/verdicts.py STUDY_DIR [--out DIR] [--resamples B]

STUDY_DIR is a study folder (`divcoll study --out`) or its kept copy (postprocess/gallery/studies/NAME): the page
reads the `*.arrays.json` beside the run summaries, which `divcoll report STUDY_DIR` writes from the run files.
Writes DIR/verdicts.md (default STUDY_DIR/verdicts) with its figures."""
import argparse
import os
import sys
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post import verdict_page, verdicts  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", help="study folder or its kept copy")
    ap.add_argument("--out", help="output folder (default STUDY/verdicts)")
    ap.add_argument("--resamples", type=int, default=verdicts.B_DEFAULT, help="bootstrap resamples (protocol: 20000)")
    a = ap.parse_args(argv)
    try:
        path = verdict_page.write(a.study, a.out or os.path.join(a.study, "verdicts"), B=a.resamples)
    except (OSError, ValueError, KeyError, tomllib.TOMLDecodeError) as e:
        print(f"verdicts: {e}", file=sys.stderr)
        return 2
    print(f"verdicts: wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
