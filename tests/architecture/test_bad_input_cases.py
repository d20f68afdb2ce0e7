"""The bad-input cases, one list per class of input (``bad_input_harness.CASE_FILES``): every file that holds
cases is listed (the verdict count of ``python tests/bad_input_harness.py`` reads them all), and together they
keep every case ever written."""
from __future__ import annotations

import re
from pathlib import Path

import bad_input_harness

TESTS = Path(__file__).resolve().parents[1]


def test_every_file_of_cases_is_listed():
    takes_the_test = re.compile(r"^test_\w+ = refusal_test\(CASES\)$", re.MULTILINE)
    holding = sorted(str(p.relative_to(TESTS)) for p in TESTS.rglob("test_*.py")
                     if takes_the_test.search(p.read_text(encoding="utf-8")))
    assert holding == sorted(bad_input_harness.CASE_FILES)


def test_the_list_is_long_enough():
    cases = bad_input_harness.all_cases()
    assert len(cases) >= 250 and len({c.id for c in cases}) == len(cases)
