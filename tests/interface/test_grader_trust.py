"""The grader does not trust a submission: checks run where its code cannot reach, each student in a folder of
their own, and one student's broken notebook stops nobody else's grading. A tiny one-exercise source (the real
check_fscore), graded at `ci`: a kernel start per student."""
import json
from pathlib import Path

import nbformat

from ddp_lite.interface import classroom, grading

RIGHT = "def fscore(precision, recall):\n    ### BEGIN SOLUTION\n    return 0.0 if precision + recall == 0 else " \
        "2 * precision * recall / (precision + recall)\n    ### END SOLUTION"


def _source(tmp_path) -> Path:
    def graded(source, **nbgrader):
        meta = {"grade": False, "locked": False, "solution": False, "schema_version": 3, "task": False, **nbgrader}
        return nbformat.v4.new_code_cell(source, metadata={"nbgrader": meta})
    nb = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_markdown_cell("# 01 · f-score\n## Exercises\n1. the F-score"),
        nbformat.v4.new_code_cell("import numpy as np"),
        graded(RIGHT, grade_id="ex1_fscore", solution=True),
        graded("from ddp_lite.interface.exercises import check_fscore\n\nassert check_fscore(fscore)",
               grade_id="ex1_fscore_check", grade=True, locked=True, points=2),
    ])
    path = tmp_path / "source" / "01_fs.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    return path


def _hand_in(tmp_path, student, nb=None, solution=RIGHT, text=None) -> Path:
    path = tmp_path / "hand-in" / student / "01_fs.ipynb"
    path.parent.mkdir(parents=True)
    if text is not None:
        path.write_text(text)
        return path
    nb = nbformat.from_dict(json.loads(json.dumps(nb)))
    next(c for c in nb.cells if c.metadata.get("nbgrader", {}).get("grade_id") == "ex1_fscore").source = solution
    nbformat.write(nb, path)
    return path


def test_no_submission_can_pass_a_check_it_fails_or_touch_other_files(tmp_path):
    source_path = _source(tmp_path)
    source_bytes = source_path.read_bytes()
    student = classroom.student_copy(nbformat.read(source_path, as_version=4))
    honest = tmp_path / "hand-in" / "c_honest" / "01_fs.ipynb"
    # a wrong answer plus every way its kernel could make the check pass: the check's name rebound, the
    # module's function patched, an input transformer that empties every later cell, a handler that swallows errors
    _hand_in(tmp_path, "b_cheat", student, (
        "def fscore(precision, recall):\n    return 0.0\n"
        "check_fscore = lambda f: True\n"
        "import ddp_lite.interface.exercises as e\ne.check_fscore = lambda f: True\ne._report = lambda *a: True\n"
        "get_ipython().set_custom_exc((BaseException,), lambda *a, **k: None)\n"
        "get_ipython().input_transformers_cleanup.append(lambda lines: ['pass\\n'])"))
    # a right answer that rewrites another student's hand-in and the instructor's source and writes beside
    # itself, in a notebook naming a kernel that does not exist (the grader starts its own python3)
    broken = nbformat.from_dict(json.loads(json.dumps(student)))
    broken.metadata["kernelspec"] = {"name": "no-such-kernel", "display_name": "gone", "language": "python"}
    _hand_in(tmp_path, "a_vandal", broken, RIGHT + (
        f"\nopen({str(honest)!r}, 'w').write('{{}}')\nopen({str(source_path)!r}, 'w').write('gone')\n"
        "open('beside.txt', 'w').write('x')"))
    _hand_in(tmp_path, "c_honest", student)
    _hand_in(tmp_path, "e_not_a_notebook", text='{"cells": 3, "metadata": {}, "nbformat": 4, "nbformat_minor": 5}')
    (tmp_path / "hand-in" / "f_link").mkdir()
    (tmp_path / "hand-in" / "f_link" / "01_fs.ipynb").symlink_to(source_path)  # the instructor's solutions
    log = []
    scores = grading.grade(tmp_path / "hand-in", source_path.parent, timeout=60, log=log.append)
    table = {s.student: (s.points, s.status) for s in scores}
    assert table == {"a_vandal": (2, "pass"), "b_cheat": (0, "fail"), "c_honest": (2, "pass"),
                     "e_not_a_notebook": (0, "unreadable"), "f_link": (0, "unreadable")}, log
    assert source_path.read_bytes() == source_bytes  # written back, and the vandal named
    assert json.loads(honest.read_text())["cells"]
    assert any(line.startswith("a_vandal:") and str(source_path) in line for line in log), log
    assert any(line.startswith("e_not_a_notebook/01_fs.ipynb: unreadable") for line in log), log
    assert any(line.startswith("f_link/01_fs.ipynb: unreadable") and "symbolic link" in line for line in log), log
    assert not (tmp_path / "hand-in" / "a_vandal" / "beside.txt").exists()  # ran in a folder of its own


def test_answers_cross_as_data_only():
    import numpy as np
    import pytest

    from ddp_lite.core.camera import Camera
    from ddp_lite.interface.grading_kernel import decode, encode
    camera = Camera.from_fov(8, 6, 60.0)
    value = decode(encode([1, 2.5, float("nan"), "s", None, (np.arange(3), {"k": np.float32(1.5)}), camera]))
    assert value[:2] == [1, 2.5] and np.isnan(value[2]) and value[3:5] == ["s", None]
    np.testing.assert_array_equal(value[5][0], np.arange(3))
    assert value[5][1]["k"] == np.float32(1.5) and isinstance(value[5][1]["k"], np.float32)
    np.testing.assert_array_equal(value[6].K, camera.K)
    with pytest.raises(TypeError, match="not an answer"):
        encode(object())
    with pytest.raises(TypeError, match="dtype object"):
        encode(np.array([object()]))
