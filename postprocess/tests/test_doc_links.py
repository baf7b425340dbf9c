"""Every link of the repository's Markdown files stays inside the repository and leads somewhere: no URL (no
scheme, no bare http(s) address, which GitHub would link), every relative path exists in the checkout, and every
#anchor names a heading of its target file (GitHub's heading slugs). Files: the Markdown files git tracks (all
*.md under the checkout when git is not available).

    /usr/bin/python3 -m unittest postprocess/tests/test_doc_links.py
"""
import glob
import os
import re
import subprocess
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
URL = re.compile(r"\b(?:https?|ftp)://|\bwww\.\w", re.I)


def markdown_files():
    try:
        out = subprocess.run(["git", "-C", REPO, "ls-files", "*.md"], capture_output=True, text=True, check=True)
        files = [os.path.join(REPO, f) for f in out.stdout.split()]
    except (OSError, subprocess.CalledProcessError):
        files = []
    if not files:
        files = [f for f in glob.glob(os.path.join(REPO, "**", "*.md"), recursive=True)
                 if "/build/" not in f and "/out/" not in f]
    return sorted(f for f in files if os.path.isfile(f))


def slug(title):
    """GitHub's anchor of a heading: lower case, markup and punctuation dropped, spaces to hyphens"""
    t = re.sub(r"`([^`]*)`", r"\1", title)
    t = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", t)
    t = t.strip().lower()
    t = re.sub(r"[^\w\- ]", "", t)
    return t.replace(" ", "-")


def anchors(path):
    seen, out = {}, set()
    in_code = False
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if line.lstrip().startswith("```"):
                in_code = not in_code
                continue
            m = None if in_code else re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
            if m:
                s = slug(m.group(1))
                n = seen.get(s, 0)
                seen[s] = n + 1
                out.add(s if n == 0 else f"{s}-{n}")
            out.update(re.findall(r'<a (?:id|name)="([^"]+)"', line))
    return out


def problems(path, repo=REPO):
    """[(line number, text)] of the links of one Markdown file that leave the repository or lead nowhere"""
    bad = []
    in_code = False
    with open(path, encoding="utf-8") as fh:
        lines = fh.read().splitlines()
    for no, line in enumerate(lines, 1):
        if line.lstrip().startswith("```"):
            in_code = not in_code
            continue
        if in_code:
            continue
        text = re.sub(r"`[^`]*`", "", line)  # code spans are not links
        if URL.search(text):
            bad.append((no, f"address outside the repository: {text.strip()[:100]}"))
        for target in LINK.findall(text):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I) or target.startswith("//"):
                bad.append((no, f"link outside the repository: {target}"))
                continue
            file_part, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
            if not dest.startswith(repo + os.sep) and dest != repo:
                bad.append((no, f"link leaves the checkout: {target}"))
            elif not os.path.exists(dest):
                bad.append((no, f"no such file in the repository: {target}"))
            elif anchor and dest.endswith(".md") and anchor not in anchors(dest):
                bad.append((no, f"no heading for #{anchor} in {os.path.relpath(dest, repo)}"))
    return bad


class DocLinks(unittest.TestCase):
    def test_the_checker_finds_each_kind_of_bad_link(self):
        import tempfile
        with tempfile.TemporaryDirectory() as repo:
            d = os.path.join(repo, "docs")
            os.makedirs(d)
            p = os.path.join(d, "x.md")
            with open(p, "w") as fh:
                fh.write("# Top part\n\n[ok](#top-part) [web](https://example.org) see http://example.org\n"
                         "[gone](no_such.md) [anchor](#nowhere) `https://in.code` [out](../../x.md) [up](../docs/x.md#top-part)\n")
            bad = problems(p, repo)
            got = "\n".join(t for _, t in bad)
        for want in ("link outside the repository: https://example.org", "address outside the repository",
                     "no such file in the repository: no_such.md", "no heading for #nowhere",
                     "link leaves the checkout"):
            self.assertIn(want, got)
        self.assertEqual(len(bad), 5, got)  # the good links, and the address in code, are not among them
        self.assertNotIn("in.code", got)

    def test_every_markdown_link_stays_in_the_repository(self):
        files = markdown_files()
        self.assertIn(os.path.join(REPO, "README.md"), files)
        bad = [f"{os.path.relpath(f, REPO)}:{no}: {t}" for f in files for no, t in problems(f)]
        self.assertEqual(bad, [], "\n" + "\n".join(bad))


if __name__ == "__main__":
    unittest.main()
