"""Every untouched student copy runs to the end at `ci`: each check fails cleanly (it prints FAIL and the
stub's NotImplementedError, then its assert fails) and no other cell errors, so a student who has
done nothing yet can still run the whole notebook, and the grader scores it 0.

Ten notebook runs: kept out of test_classroom.py so that `make test` (pytest-xdist, one file per
worker) runs them beside the other tests. They read their fits back from the session's fit cache
(``fit_cache``, see conftest.py), which the notebooks' own nbval runs fill: what is tested here is
the flow of a student copy and its checks; the fits themselves are the notebooks' (same inputs,
same numbers).
"""
import json
import re

import nbformat
import pytest
from test_classroom import README, SOURCES, _checks, _meta  # this file's folder is on sys.path (see conftest.py)

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


# --- a source a student copy could leak from is refused, named, before anything is written ---------------

def _graded(kind, source, **nbgrader):
    meta = {"grade": False, "locked": False, "solution": False, "schema_version": 3, "task": False, **nbgrader}
    make = nbformat.v4.new_code_cell if kind == "code" else nbformat.v4.new_markdown_cell
    return make(source, metadata={"nbgrader": meta})


SOLVED = "def f():\n    ### BEGIN SOLUTION\n    return 'the secret answer 42'\n    ### END SOLUTION"
MALFORMED = {  # name: (cells after the heading, what the refusal says besides the cell)
    "closing marker misspelt": ([_graded("code", SOLVED.replace("END SOLUTION", "END SOLUTON"), grade_id="ex1_f",
                                         solution=True)], "never closed"),
    "closing marker missing": ([_graded("code", SOLVED.rsplit("\n", 1)[0], grade_id="ex1_f", solution=True)],
                               "never closed"),
    "closing marker in lower case": ([_graded("code", SOLVED.replace("### END SOLUTION", "### end solution"),
                                              grade_id="ex1_f", solution=True)], "never closed"),
    "opening marker misspelt": ([_graded("code", SOLVED.replace("BEGIN SOLUTION", "BEGIN SOLUTON"), grade_id="ex1_f",
                                         solution=True)], "never opened"),
    "region opened twice": ([_graded("code", SOLVED.replace("    return", "    ### BEGIN SOLUTION\n    return"),
                                     grade_id="ex1_f", solution=True)], "already open"),
    "region outside a solution cell": ([nbformat.v4.new_code_cell(SOLVED)], "not a solution cell"),
    "region in a markdown note": ([nbformat.v4.new_markdown_cell("### BEGIN SOLUTION\nthe secret answer 42\n"
                                                                 "### END SOLUTION")], "not a solution cell"),
    "hidden tests never closed": ([_graded("code", "### BEGIN HIDDEN TESTS\nassert 'the secret answer 42'",
                                           grade_id="ex1_c", grade=True, locked=True, points=1)], "never closed"),
    "marker almost right": ([_graded("code", SOLVED.replace("### END SOLUTION", "### END SOLUTION\n# ## BEGIN SOLUTON"),
                                     grade_id="ex1_f", solution=True)], "written wrong"),
    "answer span misspelt": ([nbformat.v4.new_markdown_cell("Note <!-- answer -->the secret answer 42<!-- /answr -->")],
                             "not <!-- answer -->"),
    "answer span never closed": ([nbformat.v4.new_markdown_cell("Note <!-- answer -->the secret answer 42")],
                                 "never closed"),
    "answer comment never closed": ([nbformat.v4.new_markdown_cell("Note <!-- answer the secret answer 42")],
                                    "never closed"),
    "answer span closed first": ([nbformat.v4.new_markdown_cell("<!-- /answer -->the secret answer 42"
                                                                "<!-- answer -->")], "never opened"),
    "answer span in another case": ([nbformat.v4.new_markdown_cell("<!-- ANSWER -->the secret answer 42"
                                                                   "<!-- /ANSWER -->")], "not <!-- answer -->"),
    "check without points": ([_graded("code", "assert f()", grade_id="ex1_c", grade=True, locked=True)], "points"),
    "check with points as text": ([_graded("code", "assert f()", grade_id="ex1_c", grade=True, locked=True,
                                           points="two")], "points"),
    "check with negative points": ([_graded("code", "assert f()", grade_id="ex1_c", grade=True, locked=True,
                                            points=-1)], "points"),
    "check without grade_id": ([_graded("code", "assert f()", grade=True, locked=True, points=1)], "grade_id"),
    "check with an empty grade_id": ([_graded("code", "assert f()", grade_id="", grade=True, locked=True, points=1)],
                                     "grade_id"),
    "grade_id without an exercise number": ([_graded("code", "assert f()", grade_id="check", grade=True,
                                                     locked=True, points=1)], "ex<N>_"),
    "grade_id twice": ([_graded("code", "assert f()", grade_id="ex1_c", grade=True, locked=True, points=1),
                        _graded("code", "assert f()", grade_id="ex1_c", grade=True, locked=True, points=1)],
                       "also cell"),
    "nbgrader metadata not a mapping": ([nbformat.v4.new_code_cell("x = 1", metadata={"nbgrader": "yes"})],
                                        "not a mapping"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_a_source_that_could_leak_an_answer_is_refused_naming_notebook_and_cell(case, tmp_path, capsys):
    from ddp_lite.interface.cli import main
    cells, says = MALFORMED[case]
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell("# 01 · tiny\n## Exercises\n1. f")] + cells)
    (tmp_path / "source").mkdir()
    with open(tmp_path / "source" / "01_tiny.ipynb", "w", encoding="utf-8") as handle:
        handle.write(json.dumps(nb))  # as an editor saves it: nbformat.write would refuse some of these
    with pytest.raises(ValueError, match=rf"01_tiny\.ipynb, cell {len(cells) + 1 if case != 'grade_id twice' else 3}.*"
                                         rf"{re.escape(says)}"):
        classroom.build_student(tmp_path / "source", tmp_path / "student")
    assert not (tmp_path / "student").exists() or not any((tmp_path / "student").iterdir())
    assert main(["student", "--source", str(tmp_path / "source"), "--out", str(tmp_path / "student")]) == 2
    err = capsys.readouterr().err
    assert "01_tiny.ipynb, cell" in err and says in err and "unexpected" not in err, err
    with pytest.raises(ValueError, match=r"01_tiny\.ipynb, cell"):  # and the grader scores nobody against it
        (tmp_path / "hand-in" / "ada").mkdir(parents=True)
        grading.grade(tmp_path / "hand-in", tmp_path / "source", log=lambda *_: None)


@pytest.mark.parametrize("text, says", [(None, "ends early"), ("", "ends early"), ("[1, 2]", "not a notebook"),
                                        ('{"cells": []}', "not a notebook"), ("\xff\xfe", "not UTF-8")])
def test_a_truncated_or_foreign_source_is_named_with_the_reason(text, says, tmp_path, capsys):
    from ddp_lite.interface.cli import main
    (tmp_path / "source").mkdir()
    good = json.dumps(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("x = 1")]))
    (tmp_path / "source" / "01_fine.ipynb").write_text(good)
    (tmp_path / "source" / "02_bad.ipynb").write_bytes((good[:len(good) // 2] if text is None else text)
                                                       .encode("latin-1" if text == "\xff\xfe" else "utf-8"))
    assert main(["student", "--source", str(tmp_path / "source"), "--out", str(tmp_path / "student")]) == 2
    err = capsys.readouterr().err
    assert "02_bad.ipynb" in err and says in err and "unexpected" not in err and "01_fine" not in err, err
    assert not (tmp_path / "student" / "01_fine.ipynb").exists()  # nothing written: the set is not whole


def test_two_sources_with_one_number_are_refused_naming_both(tmp_path, capsys):
    from ddp_lite.interface.cli import main
    (tmp_path / "source").mkdir()
    for name in ("01_x.ipynb", "01_x (1).ipynb"):
        nbformat.write(nbformat.v4.new_notebook(), tmp_path / "source" / name)
    assert main(["student", "--source", str(tmp_path / "source"), "--out", str(tmp_path / "student")]) == 2
    err = capsys.readouterr().err
    assert "'01_x (1).ipynb'" in err and "'01_x.ipynb'" in err and "notebook 01" in err, err
    assert not (tmp_path / "student").exists() or not any((tmp_path / "student").iterdir())
