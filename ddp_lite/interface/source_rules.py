"""What a source (instructor) notebook must be before a student copy is built or a hand-in graded from it.

A student copy is the source with its answers cut (:func:`ddp_lite.interface.classroom.student_copy`):
code between ``### BEGIN SOLUTION`` and ``### END SOLUTION`` in solution cells, hidden tests between
``### BEGIN HIDDEN TESTS`` and ``### END HIDDEN TESTS``, Markdown between ``<!-- answer -->`` and
``<!-- /answer -->``. A marker that is misspelt, missing or out of place would leave an answer in the
copy, or stop nbgrader with an error that names no notebook. :func:`check_source` refuses such a
notebook first, naming it, the cell (its number, 1 = the first) and what is wrong:

- a region whose closing marker is missing or misspelt (``### END SOLUTON``, ``<!-- /answr -->``), a
  closing marker without its opening one, a region opened twice;
- a solution region in a cell that is not a solution cell (nbgrader leaves it in the copy);
- a marker written almost right (another case, a letter missing, no spaces): written exactly, or it
  is not a marker;
- nbgrader metadata that is not a mapping; a graded cell without a ``grade_id`` of the form
  ``ex<N>_...`` or without ``points`` (a number ≥ 0); a ``grade_id`` that two cells share.

:func:`read_source` reads a notebook file so that a truncated or non-notebook file is named with the
reason, and checks it. :func:`check_numbering` refuses two sources with one number (``01_x.ipynb`` and
``01_x (1).ipynb``): their exercises would carry the same labels (01.1). Standard library and nbformat.
"""
from __future__ import annotations

import difflib
import json
import math
import re
from pathlib import Path

__all__ = ["SourceError", "check_source", "read_source", "check_numbering", "check_no_answer_left"]

# (opening, closing, name in a message, where it may stand)
_REGIONS = (("BEGIN SOLUTION", "END SOLUTION", "solution region", "solution"),
            ("BEGIN HIDDEN TESTS", "END HIDDEN TESTS", "hidden-tests region", "grade"))
_MARKERS = [f"### {m}" for pair in _REGIONS for m in pair[:2]]
_ANSWER_OPEN, _ANSWER_CLOSE = "<!-- answer -->", "<!-- /answer -->"
_GRADE_ID = re.compile(r"ex(\d+)_")


class SourceError(ValueError):
    """A source notebook a student copy cannot be built from safely, or the grader cannot score against."""


def _meta(cell, where: str) -> dict:
    meta = cell.get("metadata", {}).get("nbgrader", {})
    if not isinstance(meta, dict):
        raise SourceError(f"{where}: its nbgrader metadata is {type(meta).__name__} {meta!r}, not a mapping")
    return meta


def _near(text: str, targets, cutoff: float = 0.8) -> str | None:
    """The target ``text`` is nearly but not exactly (another case, a letter off, spaces), if any."""
    squeezed = " ".join(text.split())
    for target in targets:
        if squeezed != target and (squeezed.upper() == target.upper() or
                                   difflib.SequenceMatcher(None, squeezed.upper(), target.upper()).ratio() >= cutoff):
            return target
    return None


def _code_regions(source: str, meta: dict, where: str) -> None:
    for begin, end, what, allowed in _REGIONS:
        opened = None
        for number, line in enumerate(source.split("\n"), 1):
            if begin in line:  # nbgrader's own test: the phrase anywhere in the line
                if opened is not None:
                    raise SourceError(f"{where}: a {what} opened at line {number} is already open (line {opened}); "
                                      f"close it with '### {end}' first")
                if not meta.get(allowed):
                    kind = "a solution cell" if allowed == "solution" else "a graded (autograder test) cell"
                    raise SourceError(f"{where}: line {number} opens a {what} in a cell that is not {kind} "
                                      f"(nbgrader metadata {allowed}: true): nothing would cut it from the student copy")
                opened = number
            elif end in line:
                if opened is None:
                    raise SourceError(f"{where}: line {number} closes a {what} that was never opened "
                                      f"('### {begin}' first)")
                opened = None
        if opened is not None:
            raise SourceError(f"{where}: the {what} opened at line {opened} is never closed: no '### {end}' "
                              f"after it (misspelt?); its answer would be left in the student copy")
    for number, line in enumerate(source.split("\n"), 1):
        stripped = line.strip()
        if stripped.startswith("#") and not any(m[4:] in line for m in _MARKERS):
            target = _near(stripped, _MARKERS)
            if target:
                raise SourceError(f"{where}: line {number} {stripped!r} looks like {target!r} written wrong; "
                                  f"write the marker exactly (or it is no marker and the answer stays in)")


def _answer_spans(source: str, where: str) -> None:
    opened = None
    for found in re.finditer(r"<!--(.*?)(-->|\Z)", source, flags=re.S):
        line = source.count("\n", 0, found.start()) + 1
        text, closed = found.group(0), found.group(2) == "-->"
        body = " ".join(found.group(1).split()).lower()
        if closed and text == _ANSWER_OPEN:
            if opened is not None:
                raise SourceError(f"{where}: an answer span opened at line {line} is already open (line {opened}); "
                                  f"close it with {_ANSWER_CLOSE} first")
            opened = line
        elif closed and text == _ANSWER_CLOSE:
            if opened is None:
                raise SourceError(f"{where}: line {line} closes an answer span that was never opened ({_ANSWER_OPEN})")
            opened = None
        elif "answer" in body or _near(body, ("answer", "/answer"), 0.7) or (not closed and len(body) < 20):
            raise SourceError(f"{where}: line {line} {text[:40]!r} is not {_ANSWER_OPEN} or {_ANSWER_CLOSE} written "
                              f"exactly{'' if closed else ' (the comment is never closed)'}: an answer span must be "
                              f"marked exactly, or its text is left in the student copy")
    if opened is not None:
        raise SourceError(f"{where}: the answer span opened at line {opened} is never closed: no {_ANSWER_CLOSE} "
                          f"after it (misspelt?); its text would be left in the student copy")


def check_source(nb, name: str = "notebook") -> None:
    """Refuse (:class:`SourceError`, naming ``name``, the cell and what is wrong) a source notebook whose
    student copy could keep an answer, or whose nbgrader metadata the grader cannot score by (module
    docstring)."""
    seen: dict = {}
    for index, cell in enumerate(nb.get("cells", []), 1):
        where = f"{name}, cell {index}"
        meta = _meta(cell, where)
        source = cell.get("source", "")
        if not isinstance(source, str):
            raise SourceError(f"{where}: its source is {type(source).__name__}, not text")
        if cell.get("cell_type") == "markdown":
            _answer_spans(source, where)
        if cell.get("cell_type") in ("code", "markdown"):
            _code_regions(source, meta, where)
        if not (meta.get("grade") or meta.get("solution") or meta.get("locked") or meta.get("task")):
            continue
        grade_id = meta.get("grade_id")
        if not isinstance(grade_id, str) or not grade_id.strip():
            raise SourceError(f"{where}: an nbgrader cell without a grade_id (got {grade_id!r}); give it one such as "
                              f"'ex1_square'")
        if grade_id in seen:
            raise SourceError(f"{where}: grade_id {grade_id!r} is also cell {seen[grade_id]}'s; each cell needs its own")
        seen[grade_id] = index
        if meta.get("grade"):
            if not _GRADE_ID.match(grade_id):
                raise SourceError(f"{where}: grade_id {grade_id!r} must start with ex<N>_ (the exercise number)")
            points = meta.get("points")
            if isinstance(points, bool) or not isinstance(points, (int, float)) or not (math.isfinite(points)
                                                                                        and points >= 0):
                raise SourceError(f"{where}: graded cell {grade_id!r} needs points, a number ≥ 0 (got {points!r})")


def _unclosed(text: str) -> bool:
    """The JSON ``text`` ends inside a string or with a bracket still open (or holds nothing): cut short."""
    depth, in_string, escaped = 0, False, False
    for char in text:
        if in_string:
            escaped, in_string = (not escaped and char == "\\"), in_string and (escaped or char != '"')
        elif char == '"':
            in_string = True
        elif char in "[{":
            depth += 1
        elif char in "]}":
            depth -= 1
    return in_string or depth > 0 or not text.strip()


def read_source(path):
    """The source notebook at ``path``, read and checked (:func:`check_source`); a file that is not a whole
    notebook (truncated, not JSON, not nbformat 4) is refused with the reason, naming it."""
    import nbformat

    from ..core.files import read_regular_bytes
    path = Path(path)
    if not path.exists():
        raise SourceError(f"notebook {str(path)!r} does not exist")
    try:
        data = read_regular_bytes(path, "notebook")
    except IsADirectoryError as error:
        raise SourceError(str(error)) from None
    try:
        text = data.decode("utf-8")
        raw = json.loads(text)
        if not isinstance(raw, dict) or not isinstance(raw.get("nbformat"), int) or not isinstance(raw.get("cells"),
                                                                                                  list):
            raise SourceError(f"{path.name}: not a notebook: JSON without an 'nbformat' version and a list of 'cells'")
        nb = nbformat.reads(text, as_version=4)
    except SourceError:
        raise
    except UnicodeDecodeError as error:
        raise SourceError(f"{path.name}: not a notebook: not UTF-8 text ({error.reason} at byte {error.start})") from None
    except json.JSONDecodeError as error:
        cut = "; the file ends early (truncated?)" if _unclosed(text) else ""
        raise SourceError(f"{path.name}: not a notebook: not JSON at line {error.lineno} column {error.colno} "
                          f"({error.msg}){cut}") from None
    except Exception as error:  # nbformat's own: no 'nbformat' key, a version it does not read
        raise SourceError(f"{path.name}: not a notebook nbformat reads ({type(error).__name__}: {error})") from None
    try:
        nbformat.validate(nb)
    except nbformat.ValidationError as error:
        raise SourceError(f"{path.name}: not a valid notebook: {error.message}") from None
    check_source(nb, path.name)
    return nb


def check_numbering(paths) -> None:
    """Refuse two source notebooks with one number (``01_x.ipynb`` and ``01_x (1).ipynb``), naming both."""
    numbers: dict = {}
    for path in paths:
        number = Path(path).name[:2]
        if number in numbers:
            raise SourceError(f"{numbers[number].name!r} and {Path(path).name!r} are both notebook {number}: their "
                              f"exercises would carry the same labels ({number}.1, ...); keep one of them")
        numbers[number] = Path(path)


def _answer_lines(nb) -> dict:
    """``{line: cell number}`` of the source's answers: lines inside solution and hidden-test regions, in
    answer spans, and of hand-graded answer cells (Markdown solution cells), stripped, 12 characters or more."""
    found: dict = {}
    for index, cell in enumerate(nb.cells, 1):
        meta = cell.get("metadata", {}).get("nbgrader", {})
        lines = []
        if cell.cell_type == "markdown" and meta.get("solution") and "BEGIN SOLUTION" not in cell.source:
            lines = cell.source.split("\n")
        else:
            inside = False
            for line in cell.source.split("\n"):
                if "BEGIN SOLUTION" in line or "BEGIN HIDDEN TESTS" in line:
                    inside = True
                elif "END SOLUTION" in line or "END HIDDEN TESTS" in line:
                    inside = False
                elif inside:
                    lines.append(line)
            if cell.cell_type == "markdown":
                for span in re.findall(r"<!-- answer -->(.*?)<!-- /answer -->", cell.source, flags=re.S):
                    lines += span.split("\n")
        for line in lines:
            if len(line.strip()) >= 12:
                found.setdefault(line.strip(), index)
    return found


def check_no_answer_left(source, copy, name: str = "notebook") -> None:
    """Refuse a student ``copy`` that still holds a line of one of the ``source``'s answers, or a marker: the
    last guard, whatever let it through."""
    answers = _answer_lines(source)
    for index, cell in enumerate(copy.cells, 1):
        for marker in _MARKERS + [_ANSWER_OPEN, _ANSWER_CLOSE]:
            if (marker[4:] if marker.startswith("###") else marker) in cell.source:
                raise SourceError(f"{name}: the student copy's cell {index} still holds {marker!r}; not written")
        for line in cell.source.split("\n"):
            if line.strip() in answers:
                raise SourceError(f"{name}: the student copy's cell {index} holds {line.strip()[:60]!r}, a line of "
                                  f"the answer in the source's cell {answers[line.strip()]}; not written (the same "
                                  f"line outside the answer gives it away: reword one of them)")
