#!/usr/bin/env python3
"""The function-length check on small trees written here: it names a function one line too long with its file,
line and length, and is not misled by braces in comments and literals, initialisers or tables of data.

    python3 .ci/function_length_test.py
"""

import pathlib
import subprocess
import sys
import tempfile
import unittest

CHECK = pathlib.Path(__file__).resolve().parent / "function_length.py"


def body(lines):
    """a function body of that many lines, its braces' lines counted"""
    return "{\n" + "".join("  x += %d;\n" % k for k in range(lines - 2)) + "}\n"


def check(files):
    """exit code and output of the check on a tree holding files {path: text}"""
    with tempfile.TemporaryDirectory() as root:
        for path, text in files.items():
            (pathlib.Path(root) / path).parent.mkdir(parents=True, exist_ok=True)
            (pathlib.Path(root) / path).write_text(text)
        run = subprocess.run([sys.executable, str(CHECK), root], capture_output=True, text=True)
        return run.returncode, run.stdout + run.stderr


class FunctionLength(unittest.TestCase):
    def test_a_function_of_121_lines_is_named_with_its_line_and_length(self):
        code, out = check({"src/a/long.cpp": "namespace a {\n\nint too_long(int x) " + body(121) + "}\n"})
        self.assertEqual(code, 1, out)
        self.assertIn("src/a/long.cpp:3: too_long is 121 lines long (at most 120)", out)

    def test_functions_of_120_lines_pass_wherever_they_stand(self):
        text = ("namespace a {\nstruct S {\n  int inside(int x) const " + body(120) + "};\n"
                "int S::outside(int x) const " + body(120) + "auto lambda = [](int x) " + body(120) + ";\n}\n")
        code, out = check({"mpi/fit.hpp": text})
        self.assertEqual(code, 0, out)
        self.assertIn("3 functions in 1 files", out)

    def test_braces_in_comments_literals_and_directives_do_not_count(self):
        noise = ('  // {\n  /* { */\n  const char* s = "{";\n  char c = \'{\';\n  int big = 1\'000;\n'
                 '  const char* r = R"x({)x";\n#define OPEN {\n')
        code, out = check({"src/b.cpp": "int f(int x) {\n" + noise * 10 + "}\nint g(int x) " + body(121)})
        self.assertEqual(code, 1, out)
        self.assertIn("src/b.cpp:73: g is 121 lines long", out)
        self.assertNotIn(": f is", out)

    def test_a_long_table_of_data_or_initialisers_is_no_function(self):
        rows = "".join('    {"key%d", %d},\n' % (k, k) for k in range(200))
        text = ("const std::vector<Row> kRows = {\n" + rows + "};\n"
                "S::S(int a) : a_{a}, rows_{\n" + rows + "} " + body(5))
        code, out = check({"src/c.cpp": text})
        self.assertEqual(code, 0, out)
        self.assertIn("1 functions in 1 files", out)

    def test_a_brace_left_open_is_an_error_not_a_pass(self):
        code, out = check({"src/d.cpp": "int f() {\n  return 0;\n"})
        self.assertEqual(code, 2, out)
        self.assertIn("src/d.cpp: cannot be scanned: line 1: this { is never closed", out)


if __name__ == "__main__":
    unittest.main()
