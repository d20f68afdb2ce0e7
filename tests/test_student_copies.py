"""Every untouched student copy runs to the end at `ci`: each check fails cleanly (it prints FAIL and the
stub's NotImplementedError, then its assert fails) and no other cell errors, so a student who has
done nothing yet can still run the whole notebook, and the grader scores it 0.

Ten notebook runs: kept out of test_classroom.py so that `make test` (pytest-xdist, one file per
worker) runs them beside the other tests. They read their fits back from the session's fit cache
(``fit_cache``, see conftest.py), which the notebooks' own nbval runs fill: what is tested here is
the flow of a student copy and its checks; the fits themselves are the notebooks' (same inputs,
same numbers).
"""
import re

import nbformat
import pytest
from test_classroom import README, SOURCES, _checks, _meta  # tests/ is on sys.path (see conftest.py)

from ddp_lite.interface import classroom, grading

# What a course must give nbgrader's autograder per cell (README, "For instructors"); the student
# copies below run with exactly this limit.
NBGRADER_TIMEOUT = int(re.search(r"`c\.Execute\.timeout = (\d+)`", README.read_text(encoding="utf-8")).group(1))

# The key figures and findings of open exercises' expected answers that the source's notes also state: the student
# copy must not (they are cut with <!-- answer --> spans).
KEY_NUMBERS = {"02_depth_only_prior": {"ex4_answer": ["within 5 %"]},
               "07_fusion_and_views": {"ex2_answer": ["Table 1's direction"]}}


def test_the_readme_tells_a_course_to_raise_nbgraders_cell_timeout():
    from nbgrader.preprocessors import Execute
    assert Execute().timeout == 30  # nbgrader's default: too short for a fit cell
    assert NBGRADER_TIMEOUT >= 600


@pytest.mark.parametrize("name", sorted(KEY_NUMBERS))
def test_no_expected_answers_key_number_is_in_the_student_copy(name):
    source = nbformat.read(SOURCES[0].parent / f"{name}.ipynb", as_version=4)
    notes = "\n".join(c.source for c in source.cells if c.cell_type == "markdown" and not _meta(c).get("solution"))
    student = "\n".join(c.source for c in classroom.student_copy(source).cells if c.cell_type == "markdown")
    for grade_id, keys in KEY_NUMBERS[name].items():
        answer = next(c.source for c in source.cells if _meta(c).get("grade_id") == grade_id)
        for key in keys:
            flat = " ".join(answer.split())
            assert key in flat and key in " ".join(notes.split()), (grade_id, key)  # a real leak, guarded
            assert key not in " ".join(student.split()), (name, grade_id, key)
    assert "<!-- answer -->" not in student and "<!-- /answer -->" not in student


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.stem[:2])
@pytest.mark.fit_cache
def test_untouched_student_copy_runs_to_the_end_fails_every_check_cleanly_and_scores_zero(source, tmp_path):
    handed_in = tmp_path / "untouched" / source.name
    handed_in.parent.mkdir()
    nbformat.write(classroom.student_copy(nbformat.read(source, as_version=4)), handed_in)
    executed = tmp_path / "executed.ipynb"
    scores = grading.grade_notebook(handed_in, source, "untouched", workdir=handed_in.parent, executed=executed,
                                      timeout=NBGRADER_TIMEOUT)  # every cell within what the README tells a course
    auto = [s for s in scores if s.kind == "auto"]
    assert len(auto) == len(_checks(nbformat.read(source, as_version=4))) and all(s.points == 0 and s.status == "fail" for s in auto)
    assert all(s.status == "blank" for s in scores if s.kind == "manual")
    nb = nbformat.read(executed, as_version=4)
    for cell in (c for c in nb.cells if c.cell_type == "code"):
        errors = [o for o in cell.outputs if o.output_type == "error"]
        assert cell.execution_count is not None, f"{source.name}: a cell did not run"
        if _meta(cell).get("grade"):  # the check printed why, then its assert failed
            printed = "".join(o.get("text", "") for o in cell.outputs if o.output_type == "stream")
            assert printed.startswith("FAIL") and "NotImplementedError" in printed, (source.name, printed)
            assert [e.ename for e in errors] == ["AssertionError"], (source.name, errors)
        else:
            assert not errors, (source.name, cell.source[:80], errors)
