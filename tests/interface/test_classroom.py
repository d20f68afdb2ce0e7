"""The classroom kit: nbgrader-format source notebooks, student copies, and the grader.

The grader tests on tiny hand-made notebooks run in seconds; the solutions of two real notebooks (01
and 08; set DDP_GRADE_ALL=1 to grade all ten) run at `ci`; every untouched student copy runs in
test_student_copies.py. Both read the notebooks' fits from the session's fit cache (conftest.py).
nbval already runs every source notebook, where each check cell is an ``assert``, so the solutions
of all ten pass their checks in every `make test`.
"""
import csv
import json
import os
import re
import shutil
from pathlib import Path

import nbformat
import pytest

from ddp_lite.interface import classroom, grades, grading

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"
SOURCES = sorted(NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))


def _meta(cell):
    return cell.metadata.get("nbgrader", {})


def _checks(nb) -> list:
    """The autograded check cells of a notebook (graded, not a solution)."""
    return [c for c in nb.cells if _meta(c).get("grade") and not _meta(c).get("solution")]


def _exercise_list(nb) -> list[str]:
    """Numbers of the exercises listed under the notebook's '## Exercises' heading."""
    text = next(c.source for c in nb.cells if c.cell_type == "markdown" and "## Exercises" in c.source)
    return re.findall(r"^(\d+)\. ", text.split("## Exercises", 1)[1], flags=re.M)


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: p.stem[:2])
def test_every_listed_exercise_has_one_graded_cell_and_every_check_a_solution(path):
    nb = nbformat.read(path, as_version=4)
    graded = classroom.exercises(nb)
    assert [n for n, _ in graded] == _exercise_list(nb)
    for number, meta in graded:
        if meta["solution"]:  # an open exercise: a hand-graded answer with the expected answer
            cell = next(c for c in nb.cells if _meta(c).get("grade_id") == meta["grade_id"])
            assert cell.cell_type == "markdown" and cell.source.startswith("*Expected answer*")
        else:  # a coded exercise: a solution cell before its locked check
            assert meta["locked"] and meta["points"] > 0
            solution = [c for c in nb.cells if _meta(c).get("grade_id", "").startswith(f"ex{number}_")
                        and _meta(c).get("solution")]
            assert len(solution) == 1 and "### BEGIN SOLUTION" in solution[0].source


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: p.stem[:2])
def test_source_notebooks_are_stored_without_outputs_in_the_repository_format(path):
    text = path.read_text(encoding="utf-8")
    nb = json.loads(text)
    assert json.dumps(nb, indent=1, ensure_ascii=False) + "\n" == text
    assert all(not c.get("outputs") and c.get("execution_count") is None for c in nb["cells"] if c["cell_type"] == "code")


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: p.stem[:2])
def test_student_copy_has_stubs_no_solutions_and_the_same_checks(path):
    source = nbformat.read(path, as_version=4)
    student = classroom.student_copy(source)
    assert nbformat.read(path, as_version=4) == source  # the source is not modified
    assert "BEGIN SOLUTION" not in json.dumps(student) and "Expected answer" not in json.dumps(student)
    checks = {_meta(c)["grade_id"]: c.source for c in source.cells if _meta(c).get("locked")}
    for cell in student.cells:
        meta = _meta(cell)
        if meta.get("solution") and cell.cell_type == "code":
            assert "raise NotImplementedError()" in cell.source
        elif meta.get("solution"):
            assert cell.source == "YOUR ANSWER HERE"
        elif meta.get("locked"):
            assert cell.source == checks[meta["grade_id"]] and cell.metadata["editable"] is False
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None


def test_build_student_writes_every_notebook(tmp_path):
    written = classroom.build_student(NOTEBOOKS, tmp_path / "student")
    assert [p.name for p in written] == [p.name for p in SOURCES]
    assert all(json.loads(p.read_text(encoding="utf-8"))["cells"] for p in written)


# --- the grader on tiny notebooks: fast, and every way a submission can go wrong ---------------

def _tiny_source(tmp_path) -> Path:
    def cell(kind, source, **nbgrader):
        meta = {"nbgrader": {"grade": False, "locked": False, "solution": False, "schema_version": 3, "task": False,
                             **nbgrader}} if nbgrader else {}
        make = nbformat.v4.new_code_cell if kind == "code" else nbformat.v4.new_markdown_cell
        return make(source, metadata=meta)
    nb = nbformat.v4.new_notebook(cells=[
        cell("markdown", "# 01 · tiny\n## Exercises\n1. square\n2. cube\n3. why?"),
        cell("code", "import time"),
        cell("code", "def square(x):\n    ### BEGIN SOLUTION\n    return x * x\n    ### END SOLUTION",
             grade_id="ex1_square", solution=True),
        cell("code", "assert square(3) == 9", grade_id="ex1_square_check", grade=True, locked=True, points=2),
        cell("code", "def cube(x):\n    ### BEGIN SOLUTION\n    return x ** 3\n    ### END SOLUTION",
             grade_id="ex2_cube", solution=True),
        cell("code", "assert cube(2) == 8", grade_id="ex2_cube_check", grade=True, locked=True, points=3),
        cell("markdown", "*Expected answer*: because.", grade_id="ex3_answer", grade=True, solution=True, points=1),
    ])
    folder = tmp_path / "source"
    folder.mkdir()
    path = folder / "01_tiny.ipynb"
    nbformat.write(nb, path)
    return path


def _submit(tmp_path, student: str, nb) -> None:
    folder = tmp_path / "submissions" / student
    folder.mkdir(parents=True)
    nbformat.write(nb, folder / "01_tiny.ipynb")


def _edit(nb, grade_id, source):
    nb = nbformat.from_dict(json.loads(json.dumps(nb)))
    next(c for c in nb.cells if _meta(c).get("grade_id") == grade_id).source = source
    return nb


def test_grader_scores_right_wrong_crashing_tampered_slow_and_missing_work(tmp_path, monkeypatch):
    source_path = _tiny_source(tmp_path)
    source = nbformat.read(source_path, as_version=4)
    student = classroom.student_copy(source)
    # the grader's shell names a recipe: each notebook still runs its own, as a student's make lab does (ada's
    # square is right only in a kernel where DDP_RECIPE is unset)
    monkeypatch.setenv("DDP_RECIPE", "paper")
    _submit(tmp_path, "ada", _edit(source, "ex1_square", "import os\ndef square(x):\n"
                                   "    return x * x if 'DDP_RECIPE' not in os.environ else -1"))  # the solutions
    _submit(tmp_path, "ben", student)  # untouched
    _submit(tmp_path, "cy", _edit(_edit(student, "ex1_square", "def square(x):\n    return x + x"),
                                  "ex3_answer", "Because it is quick."))
    _submit(tmp_path, "dee", _edit(source, "ex2_cube", "import os\nos._exit(1)  # the kernel dies"))
    _submit(tmp_path, "eve", _edit(student, "ex1_square_check", "assert True  # edited check"))
    _submit(tmp_path, "fay", _edit(source, "ex1_square", "import time\ntime.sleep(60)\ndef square(x):\n    return x * x"))
    (tmp_path / "submissions" / "gus").mkdir()  # handed in nothing
    log = []
    scores = grading.grade(tmp_path / "submissions", source_path.parent, timeout=2, log=log.append)  # fay's wait
    table = {(s.student, s.exercise): (s.points, s.status) for s in scores}
    assert table[("ada", "01.1")] == (2, "pass") and table[("ada", "01.2")] == (3, "pass")
    assert table[("ben", "01.1")] == (0, "fail") and table[("ben", "01.2")] == (0, "fail")
    assert table[("ben", "01.3")] == (0, "blank") and table[("cy", "01.3")] == (0, "answered")
    assert table[("cy", "01.1")] == (0, "fail")
    assert table[("dee", "01.1")] == (2, "pass") and table[("dee", "01.2")] == (0, "not run")
    assert table[("eve", "01.1")] == (0, "fail")  # the check came back from the source
    assert table[("fay", "01.1")] == (0, "fail") and table[("fay", "01.2")] == (3, "pass")  # timed out, went on
    assert table[("gus", "01.1")] == (0, "missing")
    text = grades.format_grades(scores)
    assert re.search(r"^ada\s+2\s+3\s+5/5\s+1/1$", text, flags=re.M), text
    assert re.search(r"^ben\s+0\s+0\s+0/5\s+0/1$", text, flags=re.M), text
    grades.write_csv(scores, tmp_path / "out" / "grades.csv")
    rows = list(csv.DictReader(open(tmp_path / "out" / "grades.csv", encoding="utf-8")))
    assert len(rows) == 7 * 3 and rows[0] == {"student": "ada", "notebook": "01_tiny", "exercise": "01.1",
                                              "grade_id": "ex1_square_check", "kind": "auto", "points": "2",
                                              "max_points": "2", "status": "pass"}


@pytest.mark.parametrize("bad, match", [({"profile": "fast"}, "profile"), ({"timeout": 0}, "timeout")])
def test_execute_refuses_bad_arguments(bad, match):
    with pytest.raises(ValueError, match=match):
        classroom.execute(nbformat.v4.new_notebook(), **bad)


def test_grade_refuses_a_folder_without_students(tmp_path):
    with pytest.raises(ValueError, match="submissions_dir"):
        grading.grade(tmp_path / "nowhere")
    with pytest.raises(ValueError, match="no student folders"):
        grading.grade(tmp_path)


# --- the real notebooks at ci: minutes ------------------------------------------------------------

def test_the_notebooks_have_fifteen_autograded_checks():
    assert sum(len(_checks(nbformat.read(p, as_version=4))) for p in SOURCES) == 15


@pytest.mark.fit_cache  # the fits of notebooks 01 and 08 are their nbval runs' (conftest.py)
def test_solutions_get_full_marks(tmp_path):
    chosen = SOURCES if os.environ.get("DDP_GRADE_ALL") else [p for p in SOURCES if p.stem[:2] in ("01", "08")]
    source_dir = tmp_path / "source"
    source_dir.mkdir()
    for path in chosen:
        shutil.copy(path, source_dir / path.name)
    shutil.copytree(source_dir, tmp_path / "submissions" / "teacher")
    scores = grading.grade(tmp_path / "submissions", source_dir, log=print)
    auto = [s for s in scores if s.kind == "auto"]
    assert auto and all(s.points == s.max_points and s.status == "pass" for s in auto), auto


def test_solution_copies_keep_their_figures_and_stop_at_a_failing_cell(tmp_path, monkeypatch):
    source = tmp_path / "source"
    source.mkdir()
    plot = nbformat.v4.new_code_cell("import os\nimport matplotlib.pyplot as plt\nplt.plot([0, 1])\n"
                                     "print('drawn, recipe', os.environ.get('DDP_RECIPE'))")
    nbformat.write(nbformat.v4.new_notebook(cells=[plot]), source / "01_plot.ipynb")
    monkeypatch.setenv("DDP_RECIPE", "paper")  # no recipe asked for: the notebook runs its own, as a student's
    [written] = classroom.build_solutions(source, tmp_path / "solutions", profile="ci", log=lambda *_: None)
    assert os.environ["DDP_RECIPE"] == "paper"  # the caller's environment as it was
    outputs = nbformat.read(written, as_version=4).cells[0].outputs
    assert any("image/png" in o.get("data", {}) for o in outputs)  # the teacher projects these
    assert "drawn, recipe None" in "".join(o.get("text", "") for o in outputs), outputs
    broken = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1 / 0")])
    nbformat.write(broken, source / "02_broken.ipynb")
    with pytest.raises(Exception, match="ZeroDivisionError"):
        classroom.build_solutions(source, tmp_path / "solutions", profile="ci", names=["02"], log=lambda *_: None)
    assert not (tmp_path / "solutions" / "02_broken.ipynb").exists()


# --- the grader's paths, renamed downloads, one row per student, hand-given points ------------------

def test_a_renamed_download_is_graded_and_an_unknown_file_is_named(tmp_path):
    source_path = _tiny_source(tmp_path)
    folder = tmp_path / "submissions" / "ada"
    folder.mkdir(parents=True)
    nbformat.write(nbformat.read(source_path, as_version=4), folder / "01_tiny (1).ipynb")  # a browser's rename
    nbformat.write(nbformat.v4.new_notebook(), folder / "scratch.ipynb")
    log = []
    scores = grading.grade(tmp_path / "submissions", source_path.parent, timeout=30, log=log.append)
    assert {s.exercise: s.status for s in scores} == {"01.1": "pass", "01.2": "pass", "01.3": "answered"}
    assert any("'01_tiny (1).ipynb' as 01_tiny.ipynb" in line for line in log), log
    assert any("scratch.ipynb" in line and "not graded" in line for line in log), log
    assert len([line for line in log if line.startswith("[1/1] ada")]) == 1  # one line per student by default


def test_match_submissions_prefers_the_exact_name_then_the_newest_copy(tmp_path):
    names = ["01_a.ipynb", "02_b.ipynb", "03_c.ipynb"]
    for i, name in enumerate(["01_a.ipynb", "01_a (1).ipynb", "Copy of 02_b.ipynb", "02_b-Copy1.ipynb", "x.ipynb"]):
        (tmp_path / name).write_text("{}")
        os.utime(tmp_path / name, (1000 + i, 1000 + i))
    matched, notes, unmatched = grading.match_submissions(sorted(tmp_path.iterdir()), names)
    assert {k: v.name for k, v in matched.items()} == {"01_a.ipynb": "01_a.ipynb", "02_b.ipynb": "02_b-Copy1.ipynb"}
    assert sorted(p.name for p in unmatched) == ["01_a (1).ipynb", "Copy of 02_b.ipynb", "x.ipynb"]
    assert notes == ["graded '02_b-Copy1.ipynb' as 02_b.ipynb (the newest of 2 copies)"]


def test_grade_refuses_an_unwritable_feedback_folder_before_any_run(tmp_path):
    source_path = _tiny_source(tmp_path)
    _submit(tmp_path, "ada", nbformat.read(source_path, as_version=4))
    (tmp_path / "feedback").mkdir()
    (tmp_path / "feedback" / "ada").write_text("a file where ada's folder goes")
    log = []
    with pytest.raises(ValueError, match="executed_dir"):
        grading.grade(tmp_path / "submissions", source_path.parent, executed_dir=tmp_path / "feedback", log=log.append)
    assert log == []  # nobody was graded, nobody scored 0


def test_hand_points_merge_into_the_scores_and_open_answers_go_to_one_file_per_student(tmp_path):
    source_path = _tiny_source(tmp_path)
    student = classroom.student_copy(nbformat.read(source_path, as_version=4))
    _submit(tmp_path, "cy", _edit(student, "ex3_answer", "Because it is quick."))
    _submit(tmp_path, "dan", student)
    scores = grading.grade(tmp_path / "submissions", source_path.parent, timeout=30, log=lambda *_: None)
    (tmp_path / "hand.csv").write_text("student,exercise,points,comment\ncy,01.3,0.5,fair\n")
    merged = grades.merge_hand_points(scores, grades.read_hand_points(tmp_path / "hand.csv"))
    assert [(s.points, s.status) for s in merged if (s.student, s.exercise) == ("cy", "01.3")] == [(0.5, "graded")]
    assert [s for s in scores if s.status == "graded"] == []  # a new list; the input is unchanged
    assert re.search(r"^cy\s+0\s+0\s+0/5\s+1/1\s+0.5/1$", grades.format_grades(merged), flags=re.M)
    for bad, match in (("cy,01.1,1\n", "autograded"), ("cy,01.3,2\n", "more than"), ("zed,01.3,1\n", "zed"),
                       ("cy,01.3,-1\n", "line 2")):
        (tmp_path / "bad.csv").write_text("student,exercise,points\n" + bad)
        with pytest.raises(ValueError, match=match):
            grades.merge_hand_points(scores, grades.read_hand_points(tmp_path / "bad.csv"))
    written = grades.write_feedback(merged, tmp_path / "open", tmp_path / "submissions", source_path.parent)
    assert sorted(p.name for p in written) == ["cy.md", "dan.md"]
    text = (tmp_path / "open" / "cy.md").read_text()
    assert "## 01.3" in text and "> why?" in text and "Because it is quick." in text and "points: 0.5" in text
    assert "YOUR ANSWER HERE" in (tmp_path / "open" / "dan.md").read_text()


def test_exercise_11_3s_command_prints_what_its_expected_answer_says(tmp_path, capsys, monkeypatch):
    import functools

    from ddp_lite.interface.cli import main
    from ddp_lite.data.tum import write_tum
    from ddp_lite.sequences import sequence_cost
    from ddp_lite.world.scenes import make_scene
    # the GPU figures come from the convolution FLOPs the warm-up counts; the timed runs give the CPU line only,
    # which this test does not read: the shortest timed runs (1 and 2 iterations instead of 2 and 8)
    monkeypatch.setattr(sequence_cost, "measure_fit_cost", functools.partial(sequence_cost.measure_fit_cost,
                                                                             iterations=(1, 2)))
    nb = nbformat.read(NOTEBOOKS / "11_your_own_data.ipynb", as_version=4)
    listed = next(c.source for c in nb.cells if "## Exercises" in c.source).split("3. Run `", 1)[1]
    command = listed.split("`", 1)[0].split()
    assert command[:2] == ["ddp-lite", "sequence"] and "<DATA>" in command
    data = write_tum(make_scene("desk", size=(24, 32), n_views=4), tmp_path / "capture")
    assert main([str(data) if a == "<DATA>" else a for a in command[1:]]) == 0
    printed = capsys.readouterr().out
    minutes = float(re.search(r"≈ ([0-9.]+) min per view", printed).group(1))
    answer = next(c.source for c in nb.cells if _meta(c).get("grade_id") == "ex3_answer")
    assert f"≈ {minutes} GPU-minutes per view" in answer and "4 jobs" in printed and "512×960" in printed
    claimed = float(re.search(r"≈ (\d+) GPU-hours", answer).group(1))
    assert round(150 * minutes / 60) == claimed  # the answer's arithmetic on the printed figure


# --- the README's instructor section, from the notebooks and the Makefile --------------------------

README = NOTEBOOKS.parent / "README.md"
EXERCISE_TABLE = NOTEBOOKS.parent / "docs" / "exercises.md"  # written from the notebooks


def test_the_exercise_table_is_the_notebooks(tmp_path):
    text = EXERCISE_TABLE.read_text(encoding="utf-8")
    block = text.split(classroom.TABLE_START, 1)[1].split(classroom.TABLE_END, 1)[0].strip()
    assert block == classroom.exercise_table(NOTEBOOKS)
    listed = sum(len(classroom.exercises(nbformat.read(p, as_version=4))) for p in SOURCES)
    assert f"{listed} exercises:" in block and "| 11.3 |" in block  # every notebook's, 11's too
    for number, (path, task) in {f"{p.stem[:2]}.{n}": (p, t) for p in SOURCES
                                 for n, t in classroom.listed_exercises(nbformat.read(p, as_version=4)).items()}.items():
        row = next(r for r in block.splitlines() if r.startswith(f"| {number} |"))
        assert f"| {task.replace('|', chr(92) + '|')} |" in row, (number, path.name)  # whole, never cut
        assert "<!-- answer -->" not in row and row.count("`") % 2 == 0, row
    copy = tmp_path / "exercises.md"  # and the refresh rewrites only the table
    copy.write_text(text.replace("| 01.1 |", "| 01.9 |"), encoding="utf-8")
    assert classroom.update_readme_table(copy, NOTEBOOKS) and copy.read_text(encoding="utf-8") == text


def test_notebook_09s_exercises_are_its_own():
    def checks(path):
        return {re.search(r"check_\w+", c.source).group(0) for c in _checks(nbformat.read(path, as_version=4))}
    nine = checks(NOTEBOOKS / "09_real_data.ipynb")
    others = set().union(*(checks(p) for p in SOURCES if not p.name.startswith("09")))
    assert nine and not nine & others, nine & others


@pytest.mark.parametrize("target", ["student", "solutions", "grade"])
def test_make_classroom_targets_use_an_existing_environment_without_installing(target, tmp_path):
    import subprocess
    def dry(*extra):
        return subprocess.run(["make", "-n", target, *extra], cwd=NOTEBOOKS.parent, capture_output=True,
                              text=True, env={**os.environ, "MAKEFLAGS": ""}).stdout
    own = dry(f"VENV={tmp_path}")
    assert f"{tmp_path}/bin/ddp-lite {target}" in own and "pip install --" not in own and "-m venv" not in own, own
    assert "pip install --" in dry("-B")  # the kit's own .venv: (re)installed when asked to remake everything
    assert f"ddp-lite grade submissions --source notebooks --csv grades.csv --details" in dry(
        "VENV=/x", "GRADE_ARGS=--details") or target != "grade"


def test_a_submission_that_is_a_fifo_is_scored_unreadable_without_blocking(tmp_path):
    """A named pipe where a notebook should be: reading it would wait for a writer for ever. It is scored
    0 as unreadable, said as a FIFO, and the next student is graded."""
    import contextlib
    import threading
    import time
    source_path = _tiny_source(tmp_path)
    (tmp_path / "submissions" / "ada").mkdir(parents=True)
    fifo = tmp_path / "submissions" / "ada" / "01_tiny.ipynb"
    os.mkfifo(fifo)
    _submit(tmp_path, "ben", nbformat.read(source_path, as_version=4))

    def unblock():  # a reader stuck on the FIFO is let go after 20 s, so that a failure is a failure, not a hang
        time.sleep(20)
        with contextlib.suppress(OSError):
            fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
            os.close(fd)
    threading.Thread(target=unblock, daemon=True).start()
    log, start = [], time.monotonic()
    scores = grading.grade(tmp_path / "submissions", source_path.parent, timeout=30, log=log.append)
    assert time.monotonic() - start < 20, "the grader waited on the FIFO"
    assert any("ada/01_tiny.ipynb: unreadable" in line and "FIFO" in line for line in log), log
    assert {s.exercise: s.status for s in scores if s.student == "ada"} == {e: "unreadable" for e in ("01.1", "01.2", "01.3")}
    assert {s.exercise: s.status for s in scores if s.student == "ben"} == {"01.1": "pass", "01.2": "pass", "01.3": "answered"}
    points = tmp_path / "points.csv"
    os.mkfifo(points)
    with pytest.raises(ValueError, match=r"points: .*FIFO"):
        grades.read_hand_points(points)
    with pytest.raises(ValueError, match=r"points: .*folder"):
        grades.read_hand_points(tmp_path / "submissions")


@pytest.mark.parametrize("handed_in", ["01_a - Copy.ipynb", "01_a - Copy (2).ipynb", "01_a(1).ipynb", "01_A.ipynb",
                                       "01_a (2).IPYNB", "01_a.ipynb.ipynb", "copy of 01_a.ipynb"])
def test_renamed_copies_of_every_kind_are_matched(tmp_path, handed_in):
    """Windows' " - Copy", no space before "(1)", another case, a doubled suffix: all the student's notebook."""
    (tmp_path / handed_in).write_text("{}")
    matched, notes, unmatched = grading.match_submissions([tmp_path / handed_in], ["01_a.ipynb", "02_b.ipynb"])
    assert {k: v.name for k, v in matched.items()} == {"01_a.ipynb": handed_in} and not unmatched
    assert notes == [f"graded {handed_in!r} as 01_a.ipynb"]
    assert grading.notebook_files(tmp_path) == [tmp_path / handed_in]  # found, whatever the suffix's case


def test_a_kernel_that_does_not_start_stops_the_grading_and_scores_nobody_0(tmp_path, monkeypatch, capsys):
    """The machine's fault (no kernel starts) is an error with exit 1, never a student's 0 in grades.csv."""
    from jupyter_client.manager import AsyncKernelManager

    from ddp_lite.interface.cli import main
    source_path = _tiny_source(tmp_path)
    _submit(tmp_path, "ada", nbformat.read(source_path, as_version=4))

    async def no_kernel(self, **kwargs):
        raise RuntimeError("Kernel died before replying to kernel_info")
    monkeypatch.setattr(AsyncKernelManager, "start_kernel", no_kernel)
    log = []
    with pytest.raises(RuntimeError, match="kernel did not start"):
        grading.grade(tmp_path / "submissions", source_path.parent, timeout=30, log=log.append)
    assert not any("ada:" in line and "0/" in line for line in log), log
    csv_path = tmp_path / "grades.csv"
    assert main(["grade", str(tmp_path / "submissions"), "--source", str(source_path.parent),
                 "--csv", str(csv_path)]) == 1
    assert "kernel did not start" in capsys.readouterr().err and not csv_path.exists()


def test_a_kernel_whose_first_start_fails_is_started_again_and_the_work_graded(tmp_path, monkeypatch):
    """A start that fails for a moment's reason (its ports taken before it binds them: "Kernel died before
    replying to kernel_info") is the machine's, once: the grader starts the kernel again and grades."""
    from jupyter_client.manager import AsyncKernelManager

    source_path = _tiny_source(tmp_path)
    _submit(tmp_path, "ada", nbformat.read(source_path, as_version=4))
    start, failed = AsyncKernelManager.start_kernel, []

    async def fails_once(self, **kwargs):  # once in each process that grades (the supervised child)
        if not failed:
            failed.append(True)
            raise RuntimeError("Kernel died before replying to kernel_info")
        return await start(self, **kwargs)
    monkeypatch.setattr(AsyncKernelManager, "start_kernel", fails_once)
    scores = grading.grade(tmp_path / "submissions", source_path.parent, timeout=30, log=lambda *_: None)
    table = {(s.student, s.exercise): (s.points, s.status) for s in scores}
    assert table[("ada", "01.1")] == (2, "pass") and table[("ada", "01.2")] == (3, "pass"), table
