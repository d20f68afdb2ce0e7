"""What is done with the scores of a grading (:mod:`ddp_lite.interface.grading`): points given by
hand to the open exercises, the per-student table, the CSV, and each student's open answers to read.
"""
from __future__ import annotations

import csv
import io
from dataclasses import replace
from pathlib import Path

import nbformat

from ..core.files import read_regular_bytes, write_bytes_atomic
from ..core.printable import printable as shown
from .classroom import exercises, listed_exercises, open_answers, read_sources, source_notebooks
from .grading import Score, match_submissions, notebook_files

__all__ = ["read_hand_points", "merge_hand_points", "format_grades", "write_csv", "write_feedback", "spreadsheet_text"]


def read_hand_points(path) -> dict:
    """An instructor's CSV of hand-given points → ``{(student, exercise): points}``.

    Columns ``student``, ``exercise`` ("07.2") and ``points``; others are ignored. Refused (ValueError
    naming the row) if a column is missing, a value is not a finite number ≥ 0, or a pair repeats.
    """
    path = Path(path)
    if not path.exists():
        raise ValueError(f"points {str(path)!r}: no such file")
    try:
        data = read_regular_bytes(path, "points")  # a folder or a FIFO: said as it is, never blocked on
    except IsADirectoryError as error:
        raise ValueError(str(error)) from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise ValueError(f"points {str(path)!r} is not UTF-8 text ({error.reason} at byte {error.start})") from None
    rows = list(csv.DictReader(io.StringIO(text, newline="")))
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
    # a name as grades.csv or the table shows it (escaped, a formula quoted) names the same student
    by_key = {(name, s.exercise): s for s in scores for name in (spreadsheet_text(s.student), s.student)}
    points = {(by_key[key].student if key in by_key else key[0], key[1]): value for key, value in points.items()}
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


def format_grades(scores: list[Score]) -> str:
    """A per-student, per-exercise table of the autograded checks (points), with totals and the count
    of open answers written (they are graded by hand)."""
    auto = [s for s in scores if s.kind == "auto"]
    columns = list(dict.fromkeys(s.exercise for s in auto))
    students = list(dict.fromkeys(s.student for s in scores))
    width = max([7] + [len(shown(s)) for s in students])
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
        lines.append(f"{shown(student):<{width}} " + " ".join(cells) + f" {f'{total:g}/{maximum:g}':>7}"
                     f" {f'{answered + len(graded)}/{len(manual)}':>6}" + (f" {hand_points:>9}" if hand else ""))
    lines.append("points per autograded check; 'open': answers written to the open exercises (grade by hand)"
                 + ("; 'hand': the points given by hand, of the exercises graded" if hand else ""))
    return "\n".join(lines)


_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def spreadsheet_text(value: str) -> str:
    """A text cell a spreadsheet shows as text: one that starts with ``= + - @``, a tab or a carriage
    return (a student's folder named ``=HYPERLINK(...)``) gets a leading ``'`` (OWASP's advice against
    CSV injection); a line break or any other control character inside it is written as its escape
    (``\\r``, ``\\n``, ``\\x1b``: a row stays one line, and shows as it is); any other text is unchanged."""
    value = str(value)
    value = "'" + value if value.startswith(_FORMULA_START) else value
    return "".join(c if c == "\t" else shown(c) for c in value)  # a tab is text to a CSV reader


def write_csv(scores: list[Score], path) -> None:
    """One row per student and exercise (student, notebook, exercise, grade_id, kind, points,
    max_points, status), written atomically; every text cell through :func:`spreadsheet_text`, so no
    name becomes a formula."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["student", "notebook", "exercise", "grade_id", "kind", "points", "max_points", "status"])
    for s in scores:
        writer.writerow([spreadsheet_text(s.student), spreadsheet_text(s.notebook), spreadsheet_text(s.exercise),
                         spreadsheet_text(s.grade_id), s.kind, f"{s.points:g}", f"{s.max_points:g}", s.status])
    write_bytes_atomic(path, buffer.getvalue().encode("utf-8"))


def write_feedback(scores: list[Score], out_dir, submissions_dir, source_dir="notebooks") -> list[Path]:
    """Write each student's open answers to ``<out_dir>/<student>.md`` (question, answer, points
    field), atomically; returns the paths. The question is the source's exercise list item.

    Questions and answers are looked up by notebook and exercise: the grade ids of open answers repeat
    from notebook to notebook (``ex3_answer``). An exercise of a notebook that was not handed in, could
    not be read or lacks its answer cell says which."""
    out_dir = Path(out_dir)
    questions = {}  # (notebook stem, exercise "01.3"): the exercise list's item
    for name, nb in read_sources(source_notebooks(source_dir)).items():
        stem = Path(name).stem
        items = listed_exercises(nb)
        for number, meta in exercises(nb):
            questions[(stem, f"{stem[:2]}.{number}")] = items.get(number, "")
    written = []
    for student in dict.fromkeys(s.student for s in scores):
        manual = [s for s in scores if s.student == student and s.kind == "manual"]
        handed_in, _, _ = match_submissions(
            notebook_files(Path(submissions_dir) / student),
            list(dict.fromkeys(f"{s.notebook}.ipynb" for s in manual)))
        handed_in = {Path(name).stem: path for name, path in handed_in.items()}
        unreadable = {s.notebook for s in manual if s.status == "unreadable"}  # the grader said why
        answers = {}  # (notebook stem, grade_id): the student's answer
        for notebook, path in handed_in.items():
            if notebook in unreadable:
                continue  # a link to the source, say: never read again here
            try:
                nb = nbformat.reads(read_regular_bytes(path, "notebook").decode("utf-8"), as_version=4)
                answers.update({(notebook, grade_id): text for grade_id, text in open_answers(nb).items()})
            except Exception:  # changed since it was graded: its answers show as not found
                unreadable.add(notebook)
        lines = [f"# Open answers: {shown(student)}", ""]
        for s in manual:
            answer = answers.get((s.notebook, s.grade_id))
            if s.notebook not in handed_in:
                answer = f"*({s.notebook} was not handed in)*"
            elif s.notebook in unreadable:
                answer = f"*({shown(handed_in[s.notebook].name)} could not be read as a notebook: no answer to show)*"
            elif answer is None:
                answer = f"*(the hand-in of {s.notebook} has no answer cell for {s.exercise})*"
            lines += [f"## {s.exercise} ({s.notebook}, {s.max_points:g} points): {s.status}", "",
                      f"> {questions.get((s.notebook, s.exercise), '')}".replace("\n", "\n> "), "",
                      answer.strip(), "",
                      f"points: {s.points:g}" if s.status == "graded" else "points: ", ""]
        target = out_dir / f"{student}.md"
        write_bytes_atomic(target, "\n".join(lines).encode("utf-8"))
        written.append(target)
    return written
