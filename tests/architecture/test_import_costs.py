"""What reading a notebook imports: every process that grades, builds student copies or runs the tests reads
notebooks (nbformat, which validates with jsonschema). From jsonschema 4.24 on, its format checkers pull in
rfc3987-syntax, which builds a Lark grammar at import (2.2 s of CPU here, per process); environment.txt pins
4.23.0, which checks the same formats without it."""
import subprocess
import sys


def test_reading_a_notebook_builds_no_grammar():
    code = ("import sys, nbformat, jsonschema\n"
            "nbformat.validate(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell('x = 1')]))\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('lark', 'rfc3987_syntax')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout
