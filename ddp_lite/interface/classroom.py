"""The classroom kit's notebooks: student copies, solution copies and the exercise table.

The notebooks in ``notebooks/`` are the *source* (instructor) version in nbgrader's format: solution
code between ``### BEGIN SOLUTION`` / ``### END SOLUTION`` in solution cells, checks in read-only
autograder test cells (``assert check_x(...)``, with points), open questions in manually graded
answer cells. An nbgrader course can take them as they are; this module and the grader
(:mod:`ddp_lite.interface.grading`, :mod:`ddp_lite.interface.grades`) do the same jobs without a course
database, with nbgrader's own preprocessors:

- :func:`student_copy`: what a student gets (solutions → ``raise NotImplementedError()``, answers
  → "YOUR ANSWER HERE", outputs cleared, test cells locked, checksums recorded);
- :func:`execute`: run a notebook top to bottom under a profile (``DDP_PROFILE``);
- :func:`build_student` / :func:`build_solutions`: every notebook's student copy, or its executed
  solution copy;
- :func:`exercise_table`: the table of every exercise that ``docs/exercises.md`` shows.

Notes that would give an open exercise's answer away are kept from the student copy: a cell tagged
``student-omit`` is left out, and in a Markdown cell the text between ``<!-- answer -->`` and
``<!-- /answer -->`` (invisible when rendered) is cut.
"""
from __future__ import annotations

import contextlib
import copy
import os
import re
from pathlib import Path

import nbformat

from ..core.files import read_regular_bytes, replace_between_markers, write_bytes_atomic
from ..core.outpaths import check_not_overlapping, check_output_folder
from ..method.kit.recipes import get_recipe
from .source_rules import check_no_answer_left, check_numbering, check_source, read_source

__all__ = ["student_copy", "execute", "exercises", "open_answers", "exercise_table", "update_readme_table",
           "build_student", "build_solutions"]

OMIT_TAG = "student-omit"  # a source cell with this tag is not in the student copy
ANSWER_SPAN = re.compile(r"<!-- answer -->.*?<!-- /answer -->", flags=re.S)  # cut from the student copy


def nbgrader_meta(cell) -> dict:
    return cell.get("metadata", {}).get("nbgrader", {})


def read_notebook(path) -> nbformat.NotebookNode:
    path = Path(path)
    if not path.exists():
        raise ValueError(f"notebook {str(path)!r} does not exist")
    return nbformat.reads(read_regular_bytes(path, "notebook").decode("utf-8"), as_version=4)  # never a FIFO


def write_notebook(nb, path) -> None:
    """Write ``nb`` as the repository stores notebooks (indent 1, UTF-8, trailing newline), atomically."""
    text = nbformat.writes(nb)
    write_bytes_atomic(path, (text if text.endswith("\n") else text + "\n").encode("utf-8"))


def source_notebooks(source_dir) -> list[Path]:
    source_dir = Path(source_dir)
    found = sorted(source_dir.glob("[0-9][0-9]_*.ipynb"))
    if not found:
        raise ValueError(f"source_dir {str(source_dir)!r} holds no numbered notebooks (01_*.ipynb ...)")
    check_numbering(found)
    return found


def read_sources(paths) -> dict:
    """``{file name: notebook}`` of the source notebooks ``paths``, each read and checked
    (:func:`ddp_lite.interface.source_rules.read_source`); every one that is malformed is named in one
    ValueError, before anything is written or run."""
    notebooks, problems = {}, []
    for path in paths:
        try:
            notebooks[Path(path).name] = read_source(path)
        except ValueError as error:
            problems.append(str(error))
    if problems:
        raise ValueError("source notebook(s) refused:\n  " + "\n  ".join(problems) if len(problems) > 1
                         else f"source notebook refused: {problems[0]}")
    return notebooks


def exercises(nb) -> list[tuple[str, dict]]:
    """The graded cells of a notebook, in order: [(exercise label "01.2", nbgrader metadata)]."""
    out = []
    for cell in nb.cells:
        meta = nbgrader_meta(cell)
        if meta.get("grade"):
            number = re.match(r"ex(\d+)_", meta["grade_id"])
            if number is None:
                raise ValueError(f"grade_id {meta['grade_id']!r} must start with ex<N>_ (the exercise number)")
            out.append((number.group(1), meta))
    return out


def student_copy(nb, name: str = "notebook") -> nbformat.NotebookNode:
    """The student version of a source notebook (a new object; ``nb`` is not modified). A source whose copy
    could keep an answer is refused first, and a copy that holds a line of an answer is never returned
    (:mod:`ddp_lite.interface.source_rules`; ValueError naming ``name``, the cell and what is wrong)."""
    from nbgrader.preprocessors import (CheckCellMetadata, ClearHiddenTests, ClearMarkScheme, ClearOutput,
                                        ClearSolutions, ComputeChecksums, LockCells)
    check_source(nb, name)
    source, nb = nb, copy.deepcopy(nb)
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
        try:
            nb, resources = step.preprocess(nb, resources)
        except Exception as error:  # what the rules above did not foresee: still named
            raise ValueError(f"{name}: nbgrader's {type(step).__name__} refuses it ({type(error).__name__}: "
                             f"{error})") from None
    check_no_answer_left(source, nb, name)
    return nb


@contextlib.contextmanager
def _environment(**values):
    """Set environment variables for a kernel started inside the block (it inherits them), then restore;
    a value of None removes the variable for the block."""
    saved = {name: os.environ.get(name) for name in values}
    for name, value in values.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = str(value)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def execute(nb, profile: str = "ci", timeout: int = 600, workdir=None, allow_errors: bool = True,
            figures: bool = False, recipe: str | None = None):
    """Run ``nb`` (modified in place) top to bottom in a fresh kernel with ``DDP_PROFILE=profile`` and
    ``DDP_RECIPE=recipe``; ``recipe=None`` unsets ``DDP_RECIPE``, so that the notebook runs its own recipe,
    as in a student's ``make lab`` (``kit``; notebook 09, on real photographs, ``photo``).

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
    if recipe is not None:
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


def build_student(source_dir="notebooks", out_dir="build/student") -> list[Path]:
    """Write the student copy of every source notebook to ``out_dir``; returns the paths. Refused
    (ValueError, before anything is written) when ``out_dir`` is, contains or lies inside ``source_dir``."""
    check_not_overlapping(out_dir, "out_dir (--out)", source_dir, "source_dir (--source)")
    check_output_folder(out_dir, "out_dir (--out)")
    sources = read_sources(source_notebooks(source_dir))
    copies = {name: student_copy(nb, name) for name, nb in sources.items()}  # all built before one is written
    written = []
    for name, nb in copies.items():
        target = Path(out_dir) / name
        write_notebook(nb, target)
        written.append(target)
    return written


def build_solutions(source_dir="notebooks", out_dir="build/solutions", profile: str = "class",
                    timeout: int = 3600, names=None, log=print, recipe: str | None = None) -> list[Path]:
    """Execute every source notebook (solutions in place) under ``profile`` and ``recipe`` (None: each notebook's
    own, as a student runs it) and write it with its outputs to ``out_dir``: the copy a teacher projects. Stops at
    the first failing cell. Refused (ValueError, before anything runs) when ``out_dir`` is, contains or lies inside
    ``source_dir``."""
    check_not_overlapping(out_dir, "out_dir (--out)", source_dir, "source_dir (--source)")
    check_output_folder(out_dir, "out_dir (--out)")
    if recipe is not None:
        get_recipe(recipe)  # an unknown name is refused here, before any notebook runs
    chosen = [path for path in source_notebooks(source_dir)
              if not names or path.stem[:2] in names or path.stem in names]
    sources = read_sources(chosen)  # a malformed one is named before the first runs
    written = []
    for path in chosen:
        log(f"executing {path.name} at {profile} ({f'{recipe} recipe' if recipe else 'its own recipe'}) ...")
        nb = sources[path.name]
        try:
            execute(nb, profile=profile, timeout=timeout, workdir=path.parent, allow_errors=False, figures=True,
                    recipe=recipe)
        except Exception as error:  # nbclient's CellExecutionError carries the cell's own error name and value
            what = f"{getattr(error, 'ename', type(error).__name__)}: {getattr(error, 'evalue', error)}"
            raise RuntimeError(f"{path.name}: a cell failed at {profile} ({what}); it was not written, "
                               f"the {len(written)} before it were") from error
        target = Path(out_dir) / path.name
        write_notebook(nb, target)
        written.append(target)
    return written


def open_answers(nb) -> dict:
    """``{grade_id: answer text}`` of a notebook's open (hand-graded) answer cells."""
    return {nbgrader_meta(c)["grade_id"]: c.source for c in nb.cells
            if nbgrader_meta(c).get("grade") and nbgrader_meta(c).get("solution")}


def listed_exercises(nb) -> dict:
    """``{"1": text}`` of the numbered items under a notebook's "## Exercises" heading."""
    listed = next((c.source for c in nb.cells if c.cell_type == "markdown" and "## Exercises" in c.source), "")
    listed = ANSWER_SPAN.sub("", listed.split("## Exercises", 1)[-1])  # an open exercise's answer stays hidden
    items = re.findall(r"^(\d+)\. (.+?)(?=^\d+\. |\Z)", listed, flags=re.M | re.S)
    return {number: " ".join(text.split()) for number, text in items}

TABLE_START = "<!-- exercise table: written by ddp_lite.interface.classroom.exercise_table; refresh: python -m ddp_lite.interface.classroom docs/exercises.md -->"
TABLE_END = "<!-- end of the exercise table -->"


def exercise_table(source_dir="notebooks") -> str:
    """The Markdown table of every exercise (number, its whole task as the notebook states it, how it is
    graded, points) and a count, read from the source notebooks: ``docs/exercises.md``'s table, so that
    it cannot drift from them."""
    rows = ["| exercise | task | graded by | points |", "|---|---|---|---|"]
    checked = open_ = checked_points = open_points = 0
    for path, nb in zip(paths := source_notebooks(source_dir), read_sources(paths).values()):
        items = listed_exercises(nb)
        cells = {nbgrader_meta(c).get("grade_id"): c for c in nb.cells}
        for number, meta in exercises(nb):
            task = items.get(number, "").replace("|", "\\|")  # a pipe would end the table's cell
            if meta.get("solution"):
                graded, open_, open_points = "expected answer, by hand", open_ + 1, open_points + meta["points"]
            else:
                names = sorted(set(re.findall(r"\b(check_\w+)\(", cells[meta["grade_id"]].source)))
                graded = ", ".join(f"`{n}`" for n in names) or "its assert"
                checked, checked_points = checked + 1, checked_points + meta["points"]
            rows.append(f"| {path.stem[:2]}.{number} | {task} | {graded} | {meta['points']:g} |")
    rows += ["", f"{checked + open_} exercises: {checked} checked ({checked_points:g} points), {open_} open "
                 f"({open_points:g} points, graded by hand)."]
    return "\n".join(rows)


def update_readme_table(readme, source_dir="notebooks") -> bool:
    """Rewrite the exercise table between ``TABLE_START`` and ``TABLE_END`` in ``readme`` (atomically);
    True if it changed."""
    return replace_between_markers(readme, TABLE_START, TABLE_END, exercise_table(source_dir), "exercise table")


if __name__ == "__main__":  # python -m ddp_lite.interface.classroom docs/exercises.md [notebooks]: refresh the table
    import sys
    if len(sys.argv) not in (2, 3):
        sys.exit("usage: python -m ddp_lite.interface.classroom docs/exercises.md [SOURCE_DIR]")
    changed = update_readme_table(sys.argv[1], *(sys.argv[2:] or ["notebooks"]))
    print(f"{sys.argv[1]}: exercise table {'updated' if changed else 'already up to date'}")
