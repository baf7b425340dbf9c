"""Tests of postprocess/gallery/claims_side_by_side.py (two report pages' claims tables side by side) on two
small pages whose verdicts are known.

    cd <repo> && /usr/bin/python3 -m unittest postprocess/tests/test_claims_side_by_side.py -v
"""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(os.path.dirname(HERE), "gallery", "claims_side_by_side.py")

HEAD = "# divcoll report\n\n## The paper's claims beside this run\n\n" \
       "| claim | this run | verdict | counts the test needs | episodes |\n|---|---|---|---|---|\n"
TAIL = "\n12 held.\n\n## Fig. 2A per environment\n\n| environment | agents alone |\n|---|---|\n| flat | 15.6 |\n"


def page(folder, name, rows):
    path = os.path.join(folder, name)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(HEAD + "".join(f"| {c} | {n} | **{v}** | has agents ≥ 50 | [flat](#ep) |\n" for c, n, v in rows) + TAIL)
    return path


def run(a, b):
    return subprocess.run([sys.executable, SCRIPT, a, b, "--names", "double", "float"], capture_output=True, text=True)


class ClaimsSideBySide(unittest.TestCase):
    def test_counts_the_claims_that_keep_their_verdict(self):
        with tempfile.TemporaryDirectory() as d:
            a = page(d, "a.md", [("Agents travel", "5.1 BL", "held"), ("Collectives beat agents", "8 vs 15", "did not hold"),
                                 ("Wind unfamiliar", "44 vs 36", "held")])
            b = page(d, "b.md", [("Agents travel", "4.9 BL", "held"), ("Collectives beat agents", "9 vs 14", "did not hold"),
                                 ("Wind unfamiliar", "30 vs 36", "did not hold")])
            r = run(a, b)
            self.assertEqual(r.returncode, 0, r.stderr)
            lines = r.stdout.splitlines()
            self.assertEqual(lines[0], "| claim | double: this run | double | float: this run | float | same verdict |")
            self.assertIn("| Wind unfamiliar | 44 vs 36 | held | 30 vs 36 | did not hold | **no** |", lines)
            self.assertIn("| Agents travel | 5.1 BL | held | 4.9 BL | held | yes |", lines)
            self.assertEqual(lines[-1], "2 of 3 claims keep their verdict")
            # the Fig. 2A table after the claims is not read as claims
            self.assertNotIn("flat", r.stdout)

    def test_a_claim_in_one_page_only_fails(self):
        with tempfile.TemporaryDirectory() as d:
            a = page(d, "a.md", [("Agents travel", "5.1 BL", "held"), ("Only here", "1", "held")])
            b = page(d, "b.md", [("Agents travel", "4.9 BL", "held")])
            r = run(a, b)
            self.assertEqual(r.returncode, 1)
            self.assertIn("Only here", r.stderr)

    def test_a_page_without_claims_is_refused(self):
        with tempfile.TemporaryDirectory() as d:
            a = os.path.join(d, "a.md")
            with open(a, "w") as fh:
                fh.write("# not a report\n")
            r = run(a, a)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("no claims table", r.stderr)


if __name__ == "__main__":
    unittest.main()
