"""The classroom kit: student copies, solution copies and a grader for the notebooks' exercises.

The notebooks in ``notebooks/`` are the *source* (instructor) version in nbgrader's format: solution
code between ``### BEGIN SOLUTION`` / ``### END SOLUTION`` in solution cells, checks in read-only
autograder test cells (``assert check_x(...)``, with points), open questions in manually graded
answer cells. An nbgrader course can take them as they are; this module does the same jobs without
a course database, with nbgrader's own preprocessors:

- :func:`student_copy`: what a student gets (solutions → ``raise NotImplementedError()``, answers
  → "YOUR ANSWER HERE", outputs cleared, test cells locked, checksums recorded);
- :func:`execute`: run a notebook top to bottom under a profile (``DDP_PROFILE``);
- :func:`grade_notebook` / :func:`grade`: run submissions at ``ci`` and score each test cell; a
  submission's cells run in a kernel of its own, each check in the grader, calling the student's
  functions in that kernel with data in and data out (:mod:`ddp_lite.interface.grading_kernel`).

A test cell scores its points when it ran without an error and printed nothing on stderr
(nbgrader's rule), and 0 when it failed, timed out, or never ran because the kernel died first.
What is not the student's doing (no kernel starts, the feedback cannot be written) stops the
grading with an error (:class:`GradingStopped`) instead of scoring anyone 0.

Notes that would give an open exercise's answer away are kept from the student copy: a cell tagged
``student-omit`` is left out, and in a Markdown cell the text between ``<!-- answer -->`` and
``<!-- /answer -->`` (invisible when rendered) is cut.
"""
from __future__ import annotations

import contextlib
import copy
import csv
import hashlib
import io
import os
import re
import shutil
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import nbformat

from ..core.files import regular_file, write_bytes_atomic

from ..core.outpaths import check_not_overlapping, check_output_folder
from ..method.recipes import get_recipe
from .grading_kernel import check_imports, run_graded

__all__ = ["GradingStopped", "student_copy", "execute", "exercises", "grade_notebook", "grade", "format_grades", "write_csv",
           "build_student", "build_solutions", "Score", "match_submissions", "read_hand_points",
           "merge_hand_points", "write_feedback", "open_answers", "exercise_table", "update_readme_table"]

STATUSES = ("pass", "fail", "not run", "missing", "unreadable", "answered", "blank", "graded")
OMIT_TAG = "student-omit"  # a source cell with this tag is not in the student copy
ANSWER_SPAN = re.compile(r"<!-- answer -->.*?<!-- /answer -->", flags=re.S)  # cut from the student copy


class GradingStopped(RuntimeError):
    """What stops the grading instead of scoring a student 0: it is not the student's doing (no kernel
    starts, the grader's own copy of a hand-in changed)."""


@dataclass
class Score:
    """One exercise of one student: an autograded check or a hand-graded answer."""
    student: str
    notebook: str  # file stem, e.g. "01_deep_image_prior"
    exercise: str  # "01.2": notebook number, exercise number
    grade_id: str
    kind: str  # "auto" or "manual"
    points: float  # scored (autograded) or 0 until a person grades it (manual)
    max_points: float
    status: str  # one of STATUSES


def _nbgrader_meta(cell) -> dict:
    return cell.get("metadata", {}).get("nbgrader", {})


def _read(path) -> nbformat.NotebookNode:
    path = Path(path)
    if not path.exists():
        raise ValueError(f"notebook {str(path)!r} does not exist")
    return nbformat.read(regular_file(path, "notebook"), as_version=4)  # a FIFO would block the read


def _write(nb, path) -> None:
    """Write ``nb`` as the repository stores notebooks (indent 1, UTF-8, trailing newline), atomically."""
    text = nbformat.writes(nb)
    write_bytes_atomic(path, (text if text.endswith("\n") else text + "\n").encode("utf-8"))


def _source_notebooks(source_dir) -> list[Path]:
    source_dir = Path(source_dir)
    found = sorted(source_dir.glob("[0-9][0-9]_*.ipynb"))
    if not found:
        raise ValueError(f"source_dir {str(source_dir)!r} holds no numbered notebooks (01_*.ipynb ...)")
    return found


def exercises(nb) -> list[tuple[str, dict]]:
    """The graded cells of a notebook, in order: [(exercise label "01.2", nbgrader metadata)]."""
    out = []
    for cell in nb.cells:
        meta = _nbgrader_meta(cell)
        if meta.get("grade"):
            number = re.match(r"ex(\d+)_", meta["grade_id"])
            if number is None:
                raise ValueError(f"grade_id {meta['grade_id']!r} must start with ex<N>_ (the exercise number)")
            out.append((number.group(1), meta))
    return out


def student_copy(nb) -> nbformat.NotebookNode:
    """The student version of a source notebook (a new object; ``nb`` is not modified)."""
    from nbgrader.preprocessors import (CheckCellMetadata, ClearHiddenTests, ClearMarkScheme, ClearOutput,
                                        ClearSolutions, ComputeChecksums, LockCells)
    nb = copy.deepcopy(nb)
    cells = []
    for cell in nb.cells:
        if OMIT_TAG in cell.get("metadata", {}).get("tags", []):
            continue
        if cell.cell_type == "markdown":
            cell.source = ANSWER_SPAN.sub("", cell.source)
        cells.append(cell)
    nb.cells = cells
    resources: dict = {}
    # nbgrader's own order for `generate_assignment`, less the database steps (SaveCells).
    for step in (LockCells(), ClearSolutions(), ClearOutput(), CheckCellMetadata(), ClearHiddenTests(),
                 ClearMarkScheme(), ComputeChecksums()):
        nb, resources = step.preprocess(nb, resources)
    return nb


@contextlib.contextmanager
def _environment(**values):
    """Set environment variables for a kernel started inside the block (it inherits them), then restore."""
    saved = {name: os.environ.get(name) for name in values}
    os.environ.update({name: str(value) for name, value in values.items()})
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def execute(nb, profile: str = "ci", timeout: int = 600, workdir=None, allow_errors: bool = True,
            figures: bool = False, recipe: str = "kit"):
    """Run ``nb`` (modified in place) top to bottom in a fresh kernel with ``DDP_PROFILE=profile`` and
    ``DDP_RECIPE=recipe`` (grading keeps the default ``kit``, which the checks expect).

    Args:
        timeout: seconds one cell may take; a cell over it is interrupted and gets an error output.
        workdir: the kernel's working folder (default: the current one).
        allow_errors: go on after a failing cell (grading) or raise at the first one (solutions).
        figures: keep the figures as outputs (Jupyter's inline backend) or draw none (Agg, faster).

    Returns the exception that stopped the run early (the kernel died, ...) or None. Cells after
    that point keep ``execution_count`` None.
    """
    from nbgrader.preprocessors import Execute
    if profile not in ("ci", "class", "paper"):
        raise ValueError(f"profile must be 'ci', 'class' or 'paper', got {profile!r}")
    get_recipe(recipe)  # an unknown name is refused here, before any notebook runs
    if not (isinstance(timeout, int) and timeout > 0):
        raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
    for cell in nb.cells:  # so that "did not run" is visible afterwards
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    runner = Execute(timeout=timeout, allow_errors=allow_errors, interrupt_on_timeout=True)
    resources = {"metadata": {"path": str(workdir or os.getcwd())}}
    backend = "module://matplotlib_inline.backend_inline" if figures else "Agg"
    with _environment(DDP_PROFILE=profile, DDP_RECIPE=recipe, MPLBACKEND=backend):
        try:
            runner.preprocess(nb, resources)
        except Exception as error:  # a dead kernel, or the first error when allow_errors is False
            if not allow_errors:
                raise
            return error
    return None


def _check_ids(source) -> set:
    """grade_ids of the source's autograded check cells (locked, graded, not a solution)."""
    return {_nbgrader_meta(c)["grade_id"] for c in source.cells
            if _nbgrader_meta(c).get("grade") and not _nbgrader_meta(c).get("solution") and c.cell_type == "code"}


def grade_notebook(submission, source, student: str = "", timeout: int = 600, profile: str = "ci",
                   workdir=None, name: str | None = None, executed=None) -> list[Score]:
    """Score one submitted notebook against its source notebook (both NotebookNodes or paths;
    ``name``, the notebook's file stem such as "01_deep_image_prior", defaults to the source's).
    ``executed``: where to write the executed notebook with its outputs (feedback), if given.
    ``workdir``: the kernel's working folder (default: a new temporary folder, removed afterwards).

    The test cells are taken from the source (matched by ``grade_id``), so an edited or deleted check
    cannot pass; a missing solution cell just fails its check. The student's cells run in a fresh
    kernel; each check cell runs in this process and calls the student's functions in that kernel
    (:mod:`ddp_lite.interface.grading_kernel`), so nothing the submission does in its kernel changes a
    check. ``submission=None`` scores a notebook that was not handed in: every exercise 0, status "missing".
    """
    if not isinstance(source, nbformat.NotebookNode):
        name = name or Path(source).stem
        source = _read(source)
    if not name:
        raise ValueError("name: give the notebook's file stem when source is a NotebookNode")
    expected = exercises(source)
    if submission is None:
        return [Score(student, name, f"{name[:2]}.{n}", m["grade_id"], "manual" if m.get("solution") else "auto",
                      0.0, float(m["points"]), "missing") for n, m in expected]
    if profile not in ("ci", "class", "paper"):
        raise ValueError(f"profile must be 'ci', 'class' or 'paper', got {profile!r}")
    if not (isinstance(timeout, int) and timeout > 0):
        raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
    nb = _read(submission) if not isinstance(submission, nbformat.NotebookNode) else copy.deepcopy(submission)
    locked = {_nbgrader_meta(c)["grade_id"]: c for c in student_copy(source).cells
              if _nbgrader_meta(c).get("locked") and _nbgrader_meta(c).get("grade_id")}
    for index, cell in enumerate(nb.cells):
        grade_id = _nbgrader_meta(cell).get("grade_id")
        if grade_id in locked:  # nbgrader's OverwriteCells, from the source instead of a database
            nb.cells[index] = copy.deepcopy(locked[grade_id])
    checks = _check_ids(source)
    for cell in nb.cells:  # "not run" stays visible afterwards
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    env = {**os.environ, "DDP_PROFILE": profile, "DDP_RECIPE": "kit", "MPLBACKEND": "Agg"}
    for variable in ("PWD", "OLDPWD"):  # no path to the grader's folder handed to the submission
        env.pop(variable, None)
    with contextlib.ExitStack() as stack:
        if workdir is None:
            workdir = stack.enter_context(tempfile.TemporaryDirectory(prefix="ddp-grade-"))
        stopped, started = run_graded(nb, lambda c: _nbgrader_meta(c).get("grade_id") in checks, workdir, env, timeout)
    if not started:
        # the kernel did not start: the machine's doing, not the student's (whatever the notebook names
        # as its kernel, the grader starts its own python3)
        raise GradingStopped(f"no cell of {name} ran: the kernel did not start ({type(stopped).__name__}: "
                           f"{stopped}); fix the environment and grade again") from stopped
    if executed is not None:
        _write(nb, executed)

    from nbgrader.utils import determine_grade
    graded = {_nbgrader_meta(c)["grade_id"]: c for c in nb.cells if _nbgrader_meta(c).get("grade")}
    scores = []
    for number, meta in expected:
        kind = "manual" if meta.get("solution") else "auto"
        label = f"{name[:2]}.{number}"
        cell = graded.get(meta["grade_id"])
        if cell is None:
            scores.append(Score(student, name, label, meta["grade_id"], kind, 0.0, float(meta["points"]), "missing"))
            continue
        if kind == "manual":
            points, maximum = determine_grade(cell)  # 0 if unchanged from the student copy, None if answered
            status = "blank" if points == 0 else "answered"
            scores.append(Score(student, name, label, meta["grade_id"], kind, 0.0, maximum, status))
        elif cell.execution_count is None:
            scores.append(Score(student, name, label, meta["grade_id"], kind, 0.0, float(meta["points"]), "not run"))
        else:
            points, maximum = determine_grade(cell)
            scores.append(Score(student, name, label, meta["grade_id"], kind, float(points), maximum,
                                "pass" if points == maximum else "fail"))
    return scores


# What a browser, a file manager or Jupyter makes of a file name on a second download or a duplicate:
# "01_x (1).ipynb", "01_x(1).ipynb", "Copy of 01_x.ipynb", "01_x-Copy1.ipynb", "01_x - Copy (2).ipynb"
# (Windows), "01_x.ipynb.ipynb", and any of them in another case ("01_X.IPYNB").
_RENAMED = re.compile(r"^(?:Copy of )?(?P<stem>.+?)(?:\.ipynb)?(?: ?\(\d+\)|-Copy\d*| - Copy(?: \(\d+\))?)?\.ipynb$",
                      re.IGNORECASE)


def _notebook_files(folder: Path) -> list[Path]:
    """A student's notebooks: every ``.ipynb`` under ``folder`` whatever the suffix's case, checkpoints left out."""
    return sorted(p for p in folder.rglob("*") if p.suffix.lower() == ".ipynb" and ".ipynb_checkpoints" not in p.parts)


def match_submissions(files, names) -> tuple[dict, list[str], list]:
    """Match handed-in notebook files to source notebook names.

    Args:
        files: the student's ``.ipynb`` paths.
        names: the source notebooks' file names ("01_deep_image_prior.ipynb", ...).

    Returns:
        (``{name: path}``, notes on renamed files taken for a source, the files matched to nothing).
        The exact name wins; else a renamed copy ("01_x (1).ipynb", "Copy of 01_x.ipynb",
        "01_x-Copy1.ipynb", "01_x - Copy.ipynb", another case), the most recently modified one when
        there are several.
    """
    files = [Path(f) for f in files]
    matched, notes = {}, []
    for name in names:
        exact = [f for f in files if f.name == name]
        if exact:
            matched[name] = exact[0]
            continue
        renamed = [f for f in files if (m := _RENAMED.match(f.name)) and (m.group("stem") + ".ipynb").lower() == name.lower()]
        if renamed:
            matched[name] = max(renamed, key=lambda f: (f.stat().st_mtime, f.name))
            notes.append(f"graded {matched[name].name!r} as {name}"
                         + (f" (the newest of {len(renamed)} copies)" if len(renamed) > 1 else ""))
    used = set(matched.values())
    return matched, notes, [f for f in files if f not in used]


def _inside(path: Path, folder: Path) -> bool:
    """``path`` resolves to a place inside ``folder`` (no link out of it on the way)."""
    real, home = os.path.realpath(path), os.path.realpath(folder)
    return os.path.commonpath([real, home]) == home


class _Snapshot:
    """The hand-ins and source notebooks as read before any submission runs: each copied into a private
    folder (mode 0700, removed at the end), its SHA-256 kept in memory. ``bytes(path)`` reads the copy
    back and checks it against its hash; :meth:`restore` writes a changed original back from it."""

    def __init__(self, paths, folder: str):
        self.folder, self.digests, self.copies = Path(folder), {}, {}
        for number, path in enumerate(paths):
            if os.path.islink(path):  # no hand-in, and writing back would put a file in its place
                continue
            try:
                data = regular_file(path, "notebook").read_bytes()
            except (OSError, ValueError):
                continue  # a FIFO, a folder: scored as unreadable, never read
            copy_path = self.folder / f"{number}.ipynb"
            write_bytes_atomic(copy_path, data)
            self.copies[Path(path)], self.digests[Path(path)] = copy_path, hashlib.sha256(data).hexdigest()

    def __contains__(self, path) -> bool:
        return Path(path) in self.copies

    def bytes(self, path) -> bytes:
        data = self.copies[Path(path)].read_bytes()
        if hashlib.sha256(data).hexdigest() != self.digests[Path(path)]:
            raise GradingStopped(f"the grader's own copy of {path} changed during grading (a submission reached "
                               f"it); grade again, in an account of its own")
        return data

    def restore(self) -> list[str]:
        """Write back every original whose bytes differ from what was read (or that is gone, or was replaced
        by a link or a folder); what was done, one line per file."""
        done = []
        for path, digest in self.digests.items():
            try:
                if path.is_file() and not path.is_symlink() and hashlib.sha256(path.read_bytes()).hexdigest() == digest:
                    continue
            except OSError:
                pass
            try:
                data = self.bytes(path)
                if path.is_symlink():
                    path.unlink()
                elif path.is_dir():
                    shutil.rmtree(path)
                write_bytes_atomic(path, data, overwrite_readonly=True)
                done.append(f"changed {path} while they ran; it was written back as read before grading")
            except OSError as error:
                done.append(f"changed {path} while they ran and it could not be written back ({error})")
        return done


def grade(submissions_dir, source_dir="notebooks", timeout: int = 600, profile: str = "ci", log=print,
          executed_dir=None, details: bool = False) -> list[Score]:
    """Grade every student folder in ``submissions_dir`` (``<dir>/<student>/**/NN_name.ipynb``).

    A notebook is matched to its source by file name (a renamed download such as "01_x (1).ipynb"
    too, see :func:`match_submissions`); a notebook that is missing scores 0, one that crashes or
    times out scores 0 for what did not run, an unreadable file scores 0 ("unreadable", the log says
    why), and none stops the others. What is not the student's doing (no kernel, an unwritable
    ``executed_dir``) raises instead: every output path is checked before the first notebook runs.
    ``executed_dir``: write each executed notebook to ``<executed_dir>/<student>/`` (feedback).
    ``details``: log a line per student and notebook; else one line per student.

    Every hand-in and source notebook is copied (a private folder) and hashed before the first submission
    runs, and graded from that copy; each student's notebooks run in a temporary folder of their own holding copies of them, and
    each check runs in this process (:func:`grade_notebook`). After each student, a hand-in or source
    notebook that changed on disk is written back and the student named in the log.
    """
    submissions_dir = Path(submissions_dir)
    if not submissions_dir.is_dir():
        raise ValueError(f"submissions_dir {str(submissions_dir)!r} is not a folder")
    students = sorted(p for p in submissions_dir.iterdir() if p.is_dir() and not p.name.startswith("."))
    if not students:
        raise ValueError(f"submissions_dir {str(submissions_dir)!r} has no student folders (<dir>/<student>/*.ipynb)")
    sources = _source_notebooks(source_dir)
    if executed_dir is not None:
        check_output_folder(executed_dir, "executed_dir (--executed)")
        for student in students:
            check_output_folder(Path(executed_dir) / student.name, "executed_dir (--executed)")
    source_nbs = {path.name: _read(path) for path in sources}
    # the checks' modules are loaded now, before a submission could edit their files
    for module in check_imports(c.source for nb in source_nbs.values() for c in nb.cells
                                if _nbgrader_meta(c).get("grade") and not _nbgrader_meta(c).get("solution")):
        with contextlib.suppress(ImportError):
            __import__(module)
    matched = {}
    for student in students:
        handed_in, notes, unmatched = match_submissions(_notebook_files(student), list(source_nbs))
        matched[student] = (handed_in, notes, unmatched)
    private = tempfile.mkdtemp(prefix="ddp-grade-copies-")  # mode 0700
    try:
        kept = _Snapshot(list(sources) + [p for handed_in, _, _ in matched.values() for p in handed_in.values()],
                         private)
        return _grade_students(students, sources, source_nbs, matched, kept, timeout, profile, log, executed_dir,
                               details)
    finally:
        shutil.rmtree(private, ignore_errors=True)


def _grade_students(students, sources, source_nbs, matched, kept, timeout, profile, log, executed_dir,
                    details) -> list[Score]:
    scores = []
    for number, student in enumerate(students, 1):
        handed_in, notes, unmatched = matched[student]
        for note in notes:
            log(f"{student.name}: {note}")
        if unmatched:
            log(f"{student.name}: not graded, no notebook of that name: "
                + ", ".join(repr(str(p.relative_to(student))) for p in unmatched))
        mine = []
        with tempfile.TemporaryDirectory(prefix="ddp-grade-") as workdir:
            for source_path in sources:
                source = source_nbs[source_path.name]
                path = handed_in.get(source_path.name)
                result = None
                if path is not None:
                    try:
                        if os.path.islink(path) or not _inside(path, student):  # the source's solutions, say
                            raise ValueError(f"{path.name} is a symbolic link to {os.path.realpath(path)}; a hand-in "
                                             f"must be the student's own file")
                        if path not in kept:  # a FIFO, a folder, a vanished file: scored, not read
                            regular_file(path, "notebook")
                            raise OSError(f"{path} could not be read")
                        data = kept.bytes(path)
                        submission = nbformat.reads(data.decode("utf-8"), as_version=4)
                        nbformat.validate(submission)
                        write_bytes_atomic(Path(workdir) / source_path.name, data)
                        executed = Path(executed_dir) / student.name / source_path.name if executed_dir else None
                        result = grade_notebook(submission, source, student.name, timeout, profile, workdir=workdir,
                                                name=source_path.stem, executed=executed)
                    except GradingStopped:
                        raise  # not the student's doing: stop, score nobody 0
                    except Exception as error:  # the student's file is not a gradable notebook: 0, go on
                        why = f"{type(error).__name__}: {error}"
                    if result is None:
                        log(f"{student.name}/{path.name}: unreadable, scored 0 ({why.splitlines()[0][:300]})")
                        mine.extend(replace(s, status="unreadable")
                                    for s in grade_notebook(None, source, student.name, name=source_path.stem))
                        continue
                else:
                    result = grade_notebook(None, source, student.name, name=source_path.stem)
                if details:
                    auto = [s for s in result if s.kind == "auto"]
                    log(f"{student.name:<16} {source_path.stem:<26} {sum(s.points for s in auto):g}/"
                        f"{sum(s.max_points for s in auto):g}" + ("  (not handed in)" if path is None else ""))
                mine.extend(result)
        for line in kept.restore():
            log(f"{student.name}: their notebooks {line}")
        auto = [s for s in mine if s.kind == "auto"]
        log(f"[{number}/{len(students)}] {student.name}: {sum(s.points for s in auto):g}/"
            f"{sum(s.max_points for s in auto):g} autograded points, {len(handed_in)}/{len(sources)} notebooks handed in")
        scores.extend(mine)
    return scores


def read_hand_points(path) -> dict:
    """An instructor's CSV of hand-given points → ``{(student, exercise): points}``.

    Columns ``student``, ``exercise`` ("07.2") and ``points``; others are ignored. Refused (ValueError
    naming the row) if a column is missing, a value is not a finite number ≥ 0, or a pair repeats.
    """
    path = Path(path)
    if not path.exists():
        raise ValueError(f"points {str(path)!r}: no such file")
    try:
        regular_file(path, "points")  # a folder or a FIFO: said as it is, before anything is opened
    except IsADirectoryError as error:
        raise ValueError(str(error)) from None
    with open(path, newline="", encoding="utf-8-sig") as handle:
        rows = list(csv.DictReader(handle))
    if not rows:
        raise ValueError(f"points {str(path)!r} has no rows (columns: student, exercise, points)")
    missing = {"student", "exercise", "points"} - set(rows[0])
    if missing:
        raise ValueError(f"points {str(path)!r} lacks the column(s) {', '.join(sorted(missing))}")
    points = {}
    for line, row in enumerate(rows, 2):
        key = (row["student"].strip(), row["exercise"].strip())
        try:
            value = float(row["points"])
        except ValueError:
            value = float("nan")
        if not (value >= 0 and value < float("inf")):
            raise ValueError(f"points {str(path)!r} line {line}: points must be a number ≥ 0, got {row['points']!r}")
        if key in points:
            raise ValueError(f"points {str(path)!r} line {line}: {key[0]} {key[1]} is given twice")
        points[key] = value
    return points


def merge_hand_points(scores: list[Score], points: dict, source="points") -> list[Score]:
    """The scores with hand-given points on the open exercises (status "graded"); a new list.

    Refused (ValueError) if a row names a student or exercise that was not graded, an exercise that
    is autograded, or more points than the exercise's maximum.
    """
    by_key = {(s.student, s.exercise): s for s in scores}
    for (student, exercise), value in points.items():
        score = by_key.get((student, exercise))
        if score is None:
            raise ValueError(f"{source}: no {exercise} of {student!r} among the graded exercises")
        if score.kind != "manual":
            raise ValueError(f"{source}: {exercise} is autograded; give points only for open exercises")
        if value > score.max_points:
            raise ValueError(f"{source}: {value:g} points for {student} {exercise}, more than its {score.max_points:g}")
    return [replace(s, points=points[(s.student, s.exercise)], status="graded")
            if (s.student, s.exercise) in points else s for s in scores]


def open_answers(nb) -> dict:
    """``{grade_id: answer text}`` of a notebook's open (hand-graded) answer cells."""
    return {_nbgrader_meta(c)["grade_id"]: c.source for c in nb.cells
            if _nbgrader_meta(c).get("grade") and _nbgrader_meta(c).get("solution")}


def _listed_exercises(nb) -> dict:
    """``{"1": text}`` of the numbered items under a notebook's "## Exercises" heading."""
    listed = next((c.source for c in nb.cells if c.cell_type == "markdown" and "## Exercises" in c.source), "")
    items = re.findall(r"^(\d+)\. (.+?)(?=^\d+\. |\Z)", listed.split("## Exercises", 1)[-1], flags=re.M | re.S)
    return {number: " ".join(text.split()) for number, text in items}


TABLE_START = "<!-- exercise table: written by ddp_lite.interface.classroom.exercise_table; refresh: python -m ddp_lite.interface.classroom docs/exercises.md -->"
TABLE_END = "<!-- end of the exercise table -->"


def exercise_table(source_dir="notebooks", width: int = 80) -> str:
    """The Markdown table of every exercise (number, task, how it is graded, points) and a count,
    read from the source notebooks: the README's table, so that it cannot drift from them."""
    rows = ["| exercise | task | graded by | points |", "|---|---|---|---|"]
    checked = open_ = checked_points = open_points = 0
    for path in _source_notebooks(source_dir):
        nb = _read(path)
        items = _listed_exercises(nb)
        cells = {_nbgrader_meta(c).get("grade_id"): c for c in nb.cells}
        for number, meta in exercises(nb):
            task = items.get(number, "")
            first = task if len(task) <= width else task[:width - 1].rsplit(" ", 1)[0] + " …"
            if first.count("`") % 2:  # cut inside a code span: close it
                first = first[:-2] + "` …"
            if meta.get("solution"):
                graded, open_, open_points = "expected answer, by hand", open_ + 1, open_points + meta["points"]
            else:
                names = sorted(set(re.findall(r"\b(check_\w+)\(", cells[meta["grade_id"]].source)))
                graded = ", ".join(f"`{n}`" for n in names) or "its assert"
                checked, checked_points = checked + 1, checked_points + meta["points"]
            rows.append(f"| {path.stem[:2]}.{number} | {first.replace('|', '/')} | {graded} | {meta['points']:g} |")
    rows += ["", f"{checked + open_} exercises: {checked} checked ({checked_points:g} points), {open_} open "
                 f"({open_points:g} points, graded by hand)."]
    return "\n".join(rows)


def update_readme_table(readme, source_dir="notebooks") -> bool:
    """Rewrite the exercise table between ``TABLE_START`` and ``TABLE_END`` in ``readme`` (atomically);
    True if it changed."""
    text = Path(readme).read_text(encoding="utf-8")
    if TABLE_START not in text or TABLE_END not in text:
        raise ValueError(f"readme {str(readme)!r} has no exercise table markers ({TABLE_START} ... {TABLE_END})")
    head, rest = text.split(TABLE_START, 1)
    _, tail = rest.split(TABLE_END, 1)
    new = f"{head}{TABLE_START}\n{exercise_table(source_dir)}\n{TABLE_END}{tail}"
    if new != text:
        write_bytes_atomic(readme, new.encode("utf-8"))
    return new != text


def write_feedback(scores: list[Score], out_dir, submissions_dir, source_dir="notebooks") -> list[Path]:
    """Write each student's open answers to ``<out_dir>/<student>.md`` (question, answer, points
    field), atomically; returns the paths. The question is the source's exercise list item."""
    out_dir = Path(out_dir)
    questions = {}
    for path in _source_notebooks(source_dir):
        nb = _read(path)
        items = _listed_exercises(nb)
        for number, meta in exercises(nb):
            questions[meta["grade_id"]] = items.get(number, "")
    written = []
    for student in dict.fromkeys(s.student for s in scores):
        manual = [s for s in scores if s.student == student and s.kind == "manual"]
        handed_in, _, _ = match_submissions(
            _notebook_files(Path(submissions_dir) / student),
            list(dict.fromkeys(f"{s.notebook}.ipynb" for s in manual)))
        answers = {}
        for name, path in handed_in.items():
            try:
                answers.update(open_answers(nbformat.read(regular_file(path, "notebook"), as_version=4)))
            except Exception:  # unreadable: already reported by grade(); its answers show as missing
                pass
        lines = [f"# Open answers: {student}", ""]
        for s in manual:
            answer = answers.get(s.grade_id)
            lines += [f"## {s.exercise} ({s.notebook}, {s.max_points:g} points): {s.status}", "",
                      f"> {questions.get(s.grade_id, '')}".replace("\n", "\n> "), "",
                      (answer if answer is not None else "*(not handed in)*").strip(), "",
                      f"points: {s.points:g}" if s.status == "graded" else "points: ", ""]
        target = out_dir / f"{student}.md"
        write_bytes_atomic(target, "\n".join(lines).encode("utf-8"))
        written.append(target)
    return written


def format_grades(scores: list[Score]) -> str:
    """A per-student, per-exercise table of the autograded checks (points), with totals and the count
    of open answers written (they are graded by hand)."""
    auto = [s for s in scores if s.kind == "auto"]
    columns = list(dict.fromkeys(s.exercise for s in auto))
    students = list(dict.fromkeys(s.student for s in scores))
    width = max([7] + [len(s) for s in students])
    hand = any(s.status == "graded" for s in scores)
    lines = [f"{'student':<{width}} " + " ".join(f"{c:>5}" for c in columns) + f" {'auto':>7} {'open':>6}"
             + (f" {'hand':>9}" if hand else "")]
    for student in students:
        mine = {s.exercise: s for s in auto if s.student == student}
        cells = [f"{mine[c].points:>5g}" if c in mine else f"{'-':>5}" for c in columns]
        total = sum(s.points for s in mine.values())
        maximum = sum(s.max_points for s in mine.values())
        manual = [s for s in scores if s.student == student and s.kind == "manual"]
        answered = sum(s.status == "answered" for s in manual)
        graded = [s for s in manual if s.status == "graded"]
        hand_points = f"{sum(s.points for s in graded):g}/{sum(s.max_points for s in graded):g}"
        lines.append(f"{student:<{width}} " + " ".join(cells) + f" {f'{total:g}/{maximum:g}':>7}"
                     f" {f'{answered + len(graded)}/{len(manual)}':>6}" + (f" {hand_points:>9}" if hand else ""))
    lines.append("points per autograded check; 'open': answers written to the open exercises (grade by hand)"
                 + ("; 'hand': the points given by hand, of the exercises graded" if hand else ""))
    return "\n".join(lines)


def write_csv(scores: list[Score], path) -> None:
    """One row per student and exercise (student, notebook, exercise, grade_id, kind, points,
    max_points, status), written atomically."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["student", "notebook", "exercise", "grade_id", "kind", "points", "max_points", "status"])
    for s in scores:
        writer.writerow([s.student, s.notebook, s.exercise, s.grade_id, s.kind, f"{s.points:g}",
                         f"{s.max_points:g}", s.status])
    write_bytes_atomic(path, buffer.getvalue().encode("utf-8"))


def build_student(source_dir="notebooks", out_dir="build/student") -> list[Path]:
    """Write the student copy of every source notebook to ``out_dir``; returns the paths. Refused
    (ValueError, before anything is written) when ``out_dir`` is, contains or lies inside ``source_dir``."""
    check_not_overlapping(out_dir, "out_dir (--out)", source_dir, "source_dir (--source)")
    check_output_folder(out_dir, "out_dir (--out)")
    written = []
    for path in _source_notebooks(source_dir):
        target = Path(out_dir) / path.name
        _write(student_copy(_read(path)), target)
        written.append(target)
    return written


def build_solutions(source_dir="notebooks", out_dir="build/solutions", profile: str = "class",
                    timeout: int = 3600, names=None, log=print, recipe: str = "kit") -> list[Path]:
    """Execute every source notebook (solutions in place) under ``profile`` and ``recipe`` and write it with its
    outputs to ``out_dir``: the copy a teacher projects. Stops at the first failing cell. Refused
    (ValueError, before anything runs) when ``out_dir`` is, contains or lies inside ``source_dir``."""
    check_not_overlapping(out_dir, "out_dir (--out)", source_dir, "source_dir (--source)")
    check_output_folder(out_dir, "out_dir (--out)")
    get_recipe(recipe)  # an unknown name is refused here, before any notebook runs
    written = []
    for path in _source_notebooks(source_dir):
        if names and path.stem[:2] not in names and path.stem not in names:
            continue
        log(f"executing {path.name} at {profile} ({recipe} recipe) ...")
        nb = _read(path)
        try:
            execute(nb, profile=profile, timeout=timeout, workdir=path.parent, allow_errors=False, figures=True,
                    recipe=recipe)
        except Exception as error:  # nbclient's CellExecutionError carries the cell's own error name and value
            what = f"{getattr(error, 'ename', type(error).__name__)}: {getattr(error, 'evalue', error)}"
            raise RuntimeError(f"{path.name}: a cell failed at {profile} ({what}); it was not written, "
                               f"the {len(written)} before it were") from error
        target = Path(out_dir) / path.name
        _write(nb, target)
        written.append(target)
    return written


if __name__ == "__main__":  # python -m ddp_lite.interface.classroom docs/exercises.md [notebooks]: refresh the table
    import sys
    if len(sys.argv) not in (2, 3):
        sys.exit("usage: python -m ddp_lite.interface.classroom docs/exercises.md [SOURCE_DIR]")
    changed = update_readme_table(sys.argv[1], *(sys.argv[2:] or ["notebooks"]))
    print(f"{sys.argv[1]}: exercise table {'updated' if changed else 'already up to date'}")
