"""The verdict page of a study judged by the pre-registered protocol (configs/studies/verdicts_protocol.md).

    /usr/bin/python3 postprocess/verdicts.py STUDY_DIR [--out DIR] [--resamples B] [--readings | --states | --dev] [--readme README.md]

STUDY_DIR is a study folder (`divcoll study --out`) or its kept copy (postprocess/gallery/studies/NAME): the page
reads the `*.arrays.json` beside the run summaries, which `divcoll report STUDY_DIR` writes from the run files.
Writes DIR/verdicts.md (default STUDY_DIR/verdicts) with its figures; with --readings, DIR/readings.md (default
STUDY_DIR/readings): each variant of the study judged as its own family beside its baseline on the same populations
(configs/studies/verdicts_readings.toml); with --states, DIR/states.md (default STUDY_DIR/states): the analysis
claims of one population at each variant's state count (configs/studies/verdicts_states.toml); with --dev,
DIR/connector_dev.md (default STUDY_DIR/connector_dev): the development grid of connector training and the
candidate amendment A5 chooses (configs/studies/connector_dev.toml)."""
import argparse
import os
import sys
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post import connector_dev, verdict_page, verdicts  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", help="study folder or its kept copy")
    ap.add_argument("--out", help="output folder (default STUDY/verdicts)")
    ap.add_argument("--resamples", type=int, default=verdicts.B_DEFAULT, help="bootstrap resamples (protocol: 20000)")
    ap.add_argument("--readme", metavar="README",
                    help="also rewrite README's block between <!-- verdict table --> and <!-- /verdict table -->")
    ap.add_argument("--readings", action="store_true",
                    help="the readings page: every variant against the study's baseline on the same populations")
    ap.add_argument("--states", action="store_true",
                    help="the state-count page: one population's analysis claims at each variant's state count")
    ap.add_argument("--dev", action="store_true",
                    help="the development page of connector training: every candidate, its cost and A5's choice")
    a = ap.parse_args(argv)
    try:
        if a.dev:
            path = connector_dev.write(a.study, a.out or os.path.join(a.study, "connector_dev"))
        elif a.states:
            path = verdict_page.states_page(a.study, a.out or os.path.join(a.study, "states"))
        elif a.readings:
            path = verdict_page.readings_page(a.study, a.out or os.path.join(a.study, "readings"), B=a.resamples)
        else:
            path = verdict_page.write(a.study, a.out or os.path.join(a.study, "verdicts"), B=a.resamples,
                                      readme=a.readme or "")
    except (OSError, ValueError, KeyError, tomllib.TOMLDecodeError) as e:
        print(f"verdicts: {e}", file=sys.stderr)
        return 2
    print(f"verdicts: wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
