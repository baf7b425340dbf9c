#!/usr/bin/env python3
"""No C++ function in src/ or mpi/ is longer than 120 lines, outside a few declarative tables.

    python3 .ci/function_length.py [ROOT]      (ROOT: the source tree; by default the checkout holding .ci/)

Reads every src/**/*.{cpp,hpp} and mpi/**/*.{cpp,hpp} below ROOT. A function's length is its lines from the one
holding its opening brace to the one holding its closing brace, both counted. Comments, string and character
literals and preprocessor lines are blanked first, so that braces in them do not count. Functions are found at
namespace and class scope: free functions, member functions defined in or out of their class, lambdas that
initialise a variable there. Whatever a function's body holds (lambdas, local classes) is part of that function.

Exits 0 when no function is too long; 1 naming each one that is (file:line: name, its length); 2 when a file
cannot be scanned (a brace left open) or an entry of ALLOWED no longer names a function of the tree.
"""

import pathlib
import re
import sys

LIMIT = 120

# functions that are declarative tables, a row an entry, whatever their length (path, name): such a table
# grows by a row for every new key, dataset or command, and cutting it in pieces would only scatter it
ALLOWED = {
    # every key of the run configuration: section, name, type, default, bounds, unit, description, field
    ("src/config/config.cpp", "schema"),
    # every group and dataset of the run file: path, type, axes, unit, description
    ("src/io/run_file.cpp", "base_entries"),
    # every subcommand: name, help line, the options it registers, what it runs. Its rows hold code, not only
    # data: each registers its options with CLI11 calls, one a line, without branches or loops
    ("src/cli/main.cpp", "commands"),
}

DIRS = ("src", "mpi")
SUFFIXES = (".cpp", ".hpp")
ME = pathlib.Path(__file__).resolve()


def blank(text):
    """text with comments, string and character literals and preprocessor lines turned into spaces (newlines
    kept, so that line numbers stay); a literal keeps its quotes"""
    out = list(text)
    n = len(text)

    def wipe(a, b):
        for k in range(a, min(b, n)):
            if out[k] != "\n":
                out[k] = " "

    def line_end(j):  # the end of the line at j, with its continuation lines (a backslash before the newline)
        while j < n and text[j] != "\n":
            j += 2 if text[j] == "\\" else 1
        return j

    def literal_end(j, quote):  # just past the closing quote of a literal whose text starts at j
        while j < n and text[j] != quote and text[j] != "\n":
            j += 2 if text[j] == "\\" else 1
        return j + 1

    i, line_start = 0, True  # line_start: only white space since the last newline
    while i < n:
        c = text[i]
        if c == "\n" or c.isspace():
            line_start = line_start or c == "\n"
            i += 1
        elif line_start and c == "#":  # a directive
            j = line_end(i)
            wipe(i, j)
            i = j
        elif text.startswith("//", i):
            j = line_end(i)
            wipe(i, j)
            i = j
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            j = n if end < 0 else end + 2
            wipe(i, j)
            i, line_start = j, False
        elif c == '"':
            prefix = re.search(r"(?<!\w)(u8|u|U|L)?R$", text[max(0, i - 4) : i])
            if prefix:  # a raw string: R"delim( ... )delim"
                open_paren = text.find("(", i + 1)
                delim = text[i + 1 : open_paren]
                end = text.find(")" + delim + '"', open_paren + 1)
                j = n if end < 0 else end + len(delim) + 1
            else:
                j = literal_end(i + 1, '"') - 1
            wipe(i + 1, j)
            i, line_start = j + 1, False
        elif c == "'" and not re.search(r"\b[0-9][0-9A-Za-z_']*$", text[max(0, i - 64) : i]):
            j = literal_end(i + 1, "'") - 1  # a character literal; a ' inside a number (1'000) is a digit separator
            wipe(i + 1, j)
            i, line_start = j + 1, False
        else:
            i, line_start = i + 1, False
    return "".join(out)


def matching(code, i):
    """the index of the brace closing the one at code[i], or -1"""
    depth = 0
    for j in range(i, len(code)):
        if code[j] == "{":
            depth += 1
        elif code[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return -1


def paren_groups(head):
    """(start, end) of each outermost ( ... ) of head, or None when a bracket of head is left open"""
    groups, depth, start = [], 0, 0
    for k, c in enumerate(head):
        if c in "([":
            if depth == 0 and c == "(":
                start = k
            depth += 1
        elif c in ")]":
            depth -= 1
            if depth < 0:
                return None
            if depth == 0 and c == ")":
                groups.append((start, k))
    return groups if depth == 0 else None


# what may stand between a function's parameters and its body: qualifiers, a trailing return type (where only
# :: has a colon), a constructor's initialisers after a lone colon
AFTER_PARAMS = re.compile(
    r"^((const|volatile|noexcept|override|final|mutable|constexpr)\b|&&?|\(\s*\w*\s*\)|\s)*"
    r"(->(?:[^:]|::)*)?"
    r"(:(?!:)(?P<init>.*))?$",
    re.S,
)
# an operator's name (operator==, operator(), operator bool), spelt as an identifier while the head is read so
# that its brackets are not taken for the parameters: each sign as _XX, its code in hex
OPERATOR = re.compile(r"\boperator\s*(\(\s*\)|\[\s*\]|[A-Za-z_][\w:<>]*|[^\s(\w]+)")
NAME = re.compile(r"(~?[A-Za-z_]\w*(\s*<[^()]*>)?(\s*::\s*~?[A-Za-z_]\w*(\s*<[^()]*>)?)*)$")
NOT_A_NAME = re.compile(r"^(if|for|while|switch|catch|return|sizeof|decltype|alignas)$")
LAMBDA = re.compile(r"(\w+)\s*=\s*\[[^\]]*\]$")


def spell_operator(m):
    sign = m.group(1)
    return "operator" + ("_20" + sign if sign[0].isalpha() or sign[0] == "_" else re.sub(r"\W", lambda c: "_%02x" % ord(c.group()), sign))


def unspell_operator(name):
    return re.sub(r"operator((_[0-9a-f]{2})+)", lambda m: "operator" + bytes.fromhex(m.group(1).replace("_", "")).decode(), name)


def classify(head):
    """what a brace at namespace or class scope opens, from the code before it: 'namespace', 'class',
    ('function', name), or 'other' (an initialiser, an enum, a brace inside an expression)"""
    h = " ".join(head.split())
    if paren_groups(h) is None:
        return "other"  # inside ( or [: a braced argument, a default argument
    h = re.sub(r"^(template\s*<[^{;]*?>\s*)+(?=[A-Za-z_~\[])", "", h)  # template heads
    h = re.sub(r"\[\[.*?\]\]", "", h).strip()  # attributes
    if re.match(r"^(inline\s+)?namespace\b", h) or re.match(r'^extern\s*"\s*"$', h):
        return "namespace"
    if re.match(r"^(typedef\s+)?(class|struct|union)\b", h) and "(" not in h.split(":")[0]:
        return "class"
    if re.match(r"^(typedef\s+)?enum\b", h):
        return "other"
    h = OPERATOR.sub(spell_operator, h)
    groups = paren_groups(h)
    if not groups:  # a lambda without parameters initialising a variable
        lam = re.search(r"(\w+)\s*=\s*\[[^\]]*\]\s*(mutable\b\s*)?(->[^=]*)?$", h)
        return ("function", lam.group(1)) if lam else "other"
    # the parameters: the first ( ... ) that only qualifiers or initialisers follow (before it there may stand
    # macro calls without a semicolon, inside the initialisers other ( ... ))
    for start, end in groups:
        tail = AFTER_PARAMS.match(h[end + 1 :])
        if not tail:
            continue
        if tail.group("init") is not None and re.search(r"[\w>]$", h):
            return "other"  # a member's or a base's braced initialiser: member{...}
        before = h[:start].rstrip()
        lam = LAMBDA.search(before)
        if lam:
            return ("function", lam.group(1))
        name = NAME.search(before)
        if not name or NOT_A_NAME.match(name.group(1)):
            return "other"
        return ("function", unspell_operator(re.sub(r"\s+", "", name.group(1))))
    return "other"


def functions(code):
    """(name, line of its name, line of its opening brace, length in lines) of every function of blanked code;
    raises ValueError at a brace that is never closed or closes nothing"""
    line_at = [0] * (len(code) + 1)  # the line of each index
    line = 1
    for k, c in enumerate(code):
        line_at[k] = line
        line += c == "\n"
    found = []

    def scan(i, end):
        head, head_start = [], i  # the code since the last ; { or } of this scope, inner braces folded to {}
        while i < end:
            c = code[i]
            if c == "}":
                raise ValueError("line %d: this } closes nothing" % line_at[i])
            if c != "{":
                if c == ";":
                    head, head_start = [], i + 1
                else:
                    head.append(c)
                i += 1
                continue
            close = matching(code, i)
            if close < 0:
                raise ValueError("line %d: this { is never closed" % line_at[i])
            kind = classify("".join(head))
            if kind == "other":
                head.append("{}")
                i = close + 1
                continue
            if kind in ("namespace", "class"):
                scan(i + 1, close)
            else:
                short = kind[1].split("::")[-1]
                at = re.search(r"(?<!\w)%s\s*[(=]" % re.escape(short), code[head_start:i]) if short[:8] != "operator" else None
                name_line = line_at[head_start + at.start()] if at else line_at[i]
                found.append((kind[1], name_line, line_at[i], line_at[close] - line_at[i] + 1))
            head, head_start = [], close + 1
            i = close + 1

    scan(0, len(code))
    return found


def main(argv):
    root = pathlib.Path(argv[1]) if len(argv) > 1 else ME.parent.parent
    files = sorted(p for d in DIRS if (root / d).is_dir() for p in (root / d).rglob("*") if p.suffix in SUFFIXES)
    too_long, broken, seen, count, longest = [], [], set(), 0, None
    for path in files:
        rel = path.relative_to(root).as_posix()
        try:
            found = functions(blank(path.read_text(encoding="utf-8")))
        except ValueError as e:
            broken.append("%s: cannot be scanned: %s" % (rel, e))
            continue
        for name, line, _, length in found:
            count += 1
            if (rel, name) in ALLOWED:
                seen.add((rel, name))
                continue
            if longest is None or length > longest[0]:
                longest = (length, "%s:%d %s" % (rel, line, name))
            if length > LIMIT:
                too_long.append("%s:%d: %s is %d lines long (at most %d)" % (rel, line, name, length, LIMIT))
    # an allowed table that is gone is named, so that the list stays short (not in another tree, a test's)
    stale = [] if root.resolve() != ME.parent.parent else [
        "%s: %s is in ALLOWED of .ci/function_length.py but is no function there" % e for e in sorted(ALLOWED - seen)]
    for msg in too_long + broken + stale:
        print(msg)
    if too_long:
        print("function length: %d function(s) longer than %d lines; cut each into functions of one step each (a "
              "declarative table may be named in ALLOWED of .ci/function_length.py)" % (len(too_long), LIMIT))
        return 1
    if broken or stale:
        return 2
    print("function length: %d functions in %d files, none longer than %d lines but the tables %s; the longest: "
          "%s, %d lines" % (count, len(files), LIMIT, ", ".join(sorted(n for _, n in ALLOWED)),
                            longest[1] if longest else "-", longest[0] if longest else 0))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
