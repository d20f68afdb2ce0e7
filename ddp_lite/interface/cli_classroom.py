"""``ddp-lite student | solutions | grade``: the classroom commands, which call ``classroom``.

Every output path is checked before the first notebook is read or run (a grading run takes
minutes per student; a bad ``--csv`` found at the end would throw it away), and locked for the
command's length: a second command writing the same output is refused at once. Handlers take the
parsed namespace and return the exit code; the parser is in ``cli``.
"""
from __future__ import annotations

import os

from ..core.outpaths import check_not_overlapping, check_output_file, check_output_folder, output_lock
from ..core.printable import printable as shown


def student_command(args) -> int:
    """``ddp-lite student``: the student copies of the notebooks (exercise answers removed)."""
    from .classroom import build_student
    with output_lock([args.out], "--out"):
        written = build_student(args.source, args.out)
    for path in written:
        print(f"wrote {path}")
    return 0


def solutions_command(args) -> int:
    """``ddp-lite solutions``: the notebooks executed with their answers, for the instructor."""
    from .classroom import build_solutions

    def log(message):
        print(message, flush=True)
    from ..method.kit.recipes import ENV_VAR, get_recipe
    # --recipe, else DDP_RECIPE, else each notebook's own (kit; notebook 09 photo), as a student runs it
    named = args.recipe or os.environ.get(ENV_VAR, "").strip()
    recipe = get_recipe(args.recipe).name if named else None
    with output_lock([args.out], "--out"):
        written = build_solutions(args.source, args.out, profile=args.profile, timeout=args.timeout,
                                  names=args.only, log=log, recipe=recipe)
    print(f"{len(written)} executed notebooks in {os.path.abspath(args.out)} "
          f"({args.profile}, {f'recipe {recipe}' if recipe else 'each its own recipe'})")
    return 0


def grade_command(args) -> int:
    """``ddp-lite grade``: score the students' submitted notebooks into a CSV."""
    check_output_file(args.csv, "--csv", suffixes=(".csv",), example="grades.csv")
    for flag, folder in (("--executed", args.executed), ("--feedback", args.feedback)):
        if folder is not None:
            check_output_folder(folder, flag)
            check_not_overlapping(folder, flag, args.submissions, "SUBMISSIONS")
            check_not_overlapping(folder, flag, args.source, "--source")
    from .grades import format_grades, merge_hand_points, read_hand_points, write_csv, write_feedback
    from .grading import grade
    hand = read_hand_points(args.points) if args.points else None  # a bad file is refused before any run

    def log(message):
        print(message, flush=True)
    outputs = [args.csv] + [folder for folder in (args.executed, args.feedback) if folder is not None]
    with output_lock(outputs, "--csv" if len(outputs) == 1 else "--csv/--executed/--feedback"):
        guarded = [path for path in (args.points, args.csv, args.executed, args.feedback) if path is not None]
        scores = grade(args.submissions, args.source, timeout=args.timeout, profile=args.profile,
                       executed_dir=args.executed, log=log, details=args.details, guarded=guarded)
        if hand is not None:
            scores = merge_hand_points(scores, hand, source=args.points)
        print()
        print(format_grades(scores))
        write_csv(scores, args.csv)
        print(f"per-exercise scores written to {os.path.abspath(args.csv)}")
        if args.feedback:
            for path in write_feedback(scores, args.feedback, args.submissions, args.source):
                print(f"open answers: {shown(path)}")
    return 0
