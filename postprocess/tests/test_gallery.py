"""The gallery is the current record: every page and picture in postprocess/gallery/ is listed in its README, every
page states what made it (a command on the page, or in the README's paragraph or table row that names it), and every
command on a page or in the README names only files, modules and divcoll commands that exist in the checkout.

    /usr/bin/python3 -m unittest postprocess/tests/test_gallery.py

A command is a code span (`...`) or an HTML comment (<!-- ... -->) that starts, after environment assignments and
`nice`/`mpirun` with their options, with divcoll, build/divcoll, python3, /usr/bin/python3, bash, ffmpeg or a path of
the checkout's jobs/ or postprocess/, or with a script's name and its arguments (a script beside the page). In it, a repository path (under configs/, jobs/, postprocess/, src/, tests/ or
mpi/, or a script beside the page) must exist, `-m MODULE` must be a module under postprocess/, and `divcoll NAME`
a command of src/cli/main.cpp. Absolute paths, out/ and placeholders (DIR, OUT, NAME, <name>, *) are not checked."""
import fnmatch
import glob
import os
import re
import shlex
import tempfile
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
GALLERY = os.path.join(REPO, "postprocess", "gallery")

CODE = re.compile(r"`([^`]+)`")  # a code span may wrap a line
COMMENT = re.compile(r"<!--(.*?)-->", re.S)
PROGRAMS = ("divcoll", "build/divcoll", "python3", "/usr/bin/python3", "bash", "ffmpeg")
REPO_DIRS = ("configs/", "jobs/", "postprocess/", "src/", "tests/", "mpi/")
SCRIPT = re.compile(r"\.(py|sh|toml|cpp|hpp)$")
PLACEHOLDER = re.compile(r"[*<>{}$]|\b(DIR|OUT|NAME|PAGE|PREFIX|TREE|STUDY|RUN)\b")


def divcoll_commands(repo=REPO):
    """the subcommands of src/cli/main.cpp (`command<...>("name", "about", ...)`)"""
    with open(os.path.join(repo, "src", "cli", "main.cpp"), encoding="utf-8") as fh:
        return set(re.findall(r'^\s*"([a-z][a-z-]*)", "', fh.read(), re.M))


def words(cmd):
    try:
        return shlex.split(cmd)
    except ValueError:  # an unbalanced quote in prose-like code
        return cmd.split()


def program(ws):
    """the index of the program word of a command's words, or None when it is not a command"""
    i = 0
    while i < len(ws) and re.match(r"^[A-Z_][A-Z0-9_]*=", ws[i]):  # VAR=value
        i += 1
    while i < len(ws) and ws[i] in ("nice", "mpirun", "exec"):
        i += 1
        while i < len(ws) and ws[i].startswith("-"):  # nice -n 10, mpirun --bind-to none -np 2 -x VAR
            i += 2 if ws[i] in ("-n", "-np", "--bind-to", "-x") else 1
    if i >= len(ws):
        return None
    w = ws[i]
    if w in PROGRAMS or w.startswith(("jobs/", "postprocess/")):
        return i
    if re.search(r"\.(py|sh)$", w) and "/" not in w and i + 1 < len(ws):  # a script beside the page, with arguments
        return i
    return None


def commands(text):
    """the commands of a Markdown text: code spans and HTML comments that start with a known program"""
    out = []
    for m in COMMENT.finditer(text):
        for line in m.group(1).strip().splitlines():
            ws = words(line.strip())
            if program(ws) is not None:
                out.append(line.strip())
    for m in CODE.finditer(COMMENT.sub("", text)):
        span = " ".join(m.group(1).split())
        ws = words(span)
        if program(ws) is not None:
            out.append(span)
    return out


def problems(cmd, page_dir, repo=REPO, known=None):
    """what a command names that does not exist: [message]"""
    known = divcoll_commands(repo) if known is None else known
    ws = words(cmd)
    i = program(ws)
    bad = []
    prog = ws[i]
    if prog in ("divcoll", "build/divcoll") and i + 1 < len(ws) and not ws[i + 1].startswith("-"):
        if ws[i + 1] not in known:
            bad.append(f"no divcoll command {ws[i + 1]!r}")
    for k, w in enumerate(ws[i:], i):
        if w == "-m" and k + 1 < len(ws):
            mod = ws[k + 1]
            base = os.path.join(repo, "postprocess", *mod.split("."))
            if not (os.path.isfile(base + ".py") or os.path.isfile(os.path.join(base, "__init__.py"))):
                bad.append(f"no module {mod} under postprocess/")
            continue
        w = w.split("=", 1)[1] if re.match(r"^[A-Za-z_.-]+=", w) else w  # key=path
        if w.startswith(("/", "~", "out/", "-")) or PLACEHOLDER.search(w) or "://" in w:
            continue
        if w.startswith(REPO_DIRS):
            if not os.path.exists(os.path.join(repo, w.rstrip("/"))):
                bad.append(f"no such file in the repository: {w}")
        elif SCRIPT.search(w) and "/" not in w and k == i:  # a script named by itself: beside the page
            if not os.path.exists(os.path.join(page_dir, w)):
                bad.append(f"no such script beside the page: {w}")
    return bad


def blocks(text):
    """paragraphs and table rows of a Markdown text"""
    out = []
    for para in re.split(r"\n\s*\n", text):
        lines = para.splitlines()
        if lines and all(line.lstrip().startswith("|") for line in lines):
            out += lines
        else:
            out.append(para)
    return out


def gallery_entries(gallery=GALLERY):
    """the files and folders of the gallery a reader meets: its top level, and the pages in its folders (the kept
    studies' data and the pages' figure folders excepted)"""
    top = [e for e in sorted(os.listdir(gallery)) if e != "README.md" and not e.startswith(".")]
    pages = [os.path.relpath(p, gallery) for p in glob.glob(os.path.join(gallery, "*", "*.md"))
             if not os.path.relpath(p, gallery).startswith("studies" + os.sep)]
    return top, sorted(pages)


def listed(name, readme):
    """is this gallery entry named in the README (by name, as name/, or by a `glob` there)"""
    if re.search(r"(?<![\w.-])" + re.escape(name) + r"(?![\w.-])", readme):
        return True
    return any(fnmatch.fnmatch(name, g.rstrip("/")) for g in CODE.findall(readme) if "*" in g)


class Gallery(unittest.TestCase):
    def setUp(self):
        with open(os.path.join(GALLERY, "README.md"), encoding="utf-8") as fh:
            self.readme = fh.read()

    def test_the_checker_finds_what_does_not_exist(self):
        known = {"report", "study"}
        with tempfile.TemporaryDirectory() as repo:
            os.makedirs(os.path.join(repo, "postprocess", "pkg"))
            os.makedirs(os.path.join(repo, "jobs"))
            open(os.path.join(repo, "postprocess", "pkg", "__init__.py"), "w").close()
            open(os.path.join(repo, "postprocess", "pkg", "tool.py"), "w").close()
            open(os.path.join(repo, "jobs", "run.sh"), "w").close()
            page = ("<!-- divcoll grad-diag RUN.h5 --kind weak -->\n"
                    "made by `PYTHONPATH=postprocess /usr/bin/python3 -m pkg.tool out/x.h5`, "
                    "`/usr/bin/python3 postprocess/gone.py DIR`, `python3 -m pkg.gone X`, "
                    "`nice -n 10 build/divcoll study configs/studies/none.toml --out out/s`, "
                    "`bash jobs/run.sh OUT`, `divcoll report postprocess/gallery/studies/NAME --out PAGE`, "
                    "`mpirun --bind-to none -np 2 build/divcoll report out/x.h5` and `plot.py A B`; "
                    "`connectors.kinds=weak` is not a command.")
            cmds = commands(page)
            self.assertEqual(len(cmds), 9, cmds)
            bad = [b for c in cmds for b in problems(c, repo, repo, known)]
        for want in ("no divcoll command 'grad-diag'", "no such file in the repository: postprocess/gone.py",
                     "no module pkg.gone under postprocess/", "no such file in the repository: configs/studies/none.toml",
                     "no such script beside the page: plot.py"):
            self.assertIn(want, bad)
        self.assertEqual(len(bad), 5, bad)  # the good commands, the placeholders and out/ are not among them

    def test_every_gallery_file_is_listed_in_its_readme(self):
        top, pages = gallery_entries()
        missing = [e for e in top + pages if not listed(e, self.readme)]
        self.assertEqual(missing, [], "not in postprocess/gallery/README.md: " + ", ".join(missing))

    def test_every_page_states_what_made_it(self):
        _, pages = gallery_entries()
        pages += [e for e in os.listdir(GALLERY) if e.endswith(".md") and e != "README.md"]
        silent = []
        for rel in sorted(pages):
            with open(os.path.join(GALLERY, rel), encoding="utf-8") as fh:
                own = commands(fh.read())
            near = [c for b in blocks(self.readme) if listed(rel, b) for c in commands(b)]
            if not own and not near:
                silent.append(rel)
        self.assertEqual(silent, [], "no command on the page nor beside it in the README: " + ", ".join(silent))

    def test_every_command_names_what_exists(self):
        known = divcoll_commands()
        self.assertIn("report", known)
        files = [os.path.join(GALLERY, "README.md")]
        files += [p for p in glob.glob(os.path.join(GALLERY, "**", "*.md"), recursive=True)
                  if os.sep + "studies" + os.sep not in p and not p.endswith(os.sep + "README.md")]
        bad, n = [], 0
        for path in sorted(files):
            with open(path, encoding="utf-8") as fh:
                cmds = commands(fh.read())
            n += len(cmds)
            bad += [f"{os.path.relpath(path, REPO)}: `{c[:80]}`: {b}" for c in cmds
                    for b in problems(c, os.path.dirname(path), known=known)]
        self.assertGreater(n, 10)
        self.assertEqual(bad, [], "\n" + "\n".join(bad))


if __name__ == "__main__":
    unittest.main()
