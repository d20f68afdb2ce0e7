"""Feedback and scores keyed by notebook and exercise: the grade ids of open answers repeat in every notebook
(ex3_answer in 01 and in 02), so a question, an answer or a point is never looked up by its grade id alone.
Hand-made scores and tiny notebooks: nothing runs a kernel here."""
import nbformat

from ddp_lite.interface import classroom, grades
from ddp_lite.interface.grading import Score


def _notebook(folder, name, question, expected):
    def graded(source, **nbgrader):
        meta = {"grade": True, "locked": False, "solution": True, "schema_version": 3, "task": False, **nbgrader}
        return nbformat.v4.new_markdown_cell(source, metadata={"nbgrader": meta})
    nb = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_markdown_cell(f"# {name}\n## Exercises\n1. {question}"),
        graded(f"*Expected answer*: {expected}", grade_id="ex1_answer", points=1)])
    folder.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, folder / f"{name}.ipynb")
    return nb


def _hand_in(tmp_path, student, name, nb, answer):
    copy = classroom.student_copy(nb)
    next(c for c in copy.cells if c.metadata.get("nbgrader", {}).get("grade_id") == "ex1_answer").source = answer
    (tmp_path / "hand-in" / student).mkdir(parents=True, exist_ok=True)
    nbformat.write(copy, tmp_path / "hand-in" / student / f"{name}.ipynb")


def test_open_answers_are_read_under_their_own_notebooks_question(tmp_path):
    source = tmp_path / "source"
    first = _notebook(source, "01_first", "Why is the sky blue?", "scattering")
    second = _notebook(source, "02_second", "Why is grass green?", "chlorophyll")
    _notebook(source, "03_third", "Why is snow white?", "many facets")
    _hand_in(tmp_path, "ada", "01_first", first, "Rayleigh scattering.")
    _hand_in(tmp_path, "ada", "02_second", second, "Chlorophyll absorbs red.")
    _hand_in(tmp_path, "ben", "02_second", second, "Ben's answer on grass.")
    (tmp_path / "hand-in" / "ben" / "01_first.ipynb").write_text("{not json")  # handed in, unreadable
    scores = []
    for student, statuses in (("ada", ("answered", "answered", "missing")),
                              ("ben", ("unreadable", "answered", "missing"))):
        scores += [Score(student, name, f"{name[:2]}.1", "ex1_answer", "manual", 0.0, 1.0, status)
                   for name, status in zip(("01_first", "02_second", "03_third"), statuses)]
    scores = grades.merge_hand_points(scores, {("ada", "02.1"): 1.0})
    grades.write_feedback(scores, tmp_path / "open", tmp_path / "hand-in", source)
    ada = (tmp_path / "open" / "ada.md").read_text().split("## ")[1:]
    ben = (tmp_path / "open" / "ben.md").read_text().split("## ")[1:]
    assert [part.split(" ", 1)[0] for part in ada] == ["01.1", "02.1", "03.1"]
    assert "sky" in ada[0] and "Rayleigh" in ada[0] and "grass" not in ada[0] and "Chlorophyll" not in ada[0]
    assert "grass" in ada[1] and "Chlorophyll" in ada[1] and "Rayleigh" not in ada[1] and "points: 1" in ada[1]
    assert "snow" in ada[2] and "Rayleigh" not in ada[2] and "Chlorophyll" not in ada[2]
    assert "03_third was not handed in" in ada[2]
    assert "could not be read" in ben[0] and "Ben's" not in ben[0] and "Ben's answer" in ben[1]
    assert "03_third was not handed in" in ben[2] and "Ben's" not in ben[2]
    for text in ada + ben:  # the expected answers never reach a student's feedback
        assert "Expected answer" not in text and "facets" not in text


def test_names_with_control_characters_show_escaped_and_still_take_hand_points(tmp_path):
    import csv

    name = "ada\x1b[31m\u202e"
    scores = [Score(name, "01_first", "01.1", "ex1_answer", "manual", 0.0, 1.0, "answered"),
              Score("=cmd", "01_first", "01.1", "ex1_answer", "manual", 0.0, 1.0, "answered")]
    grades.write_csv(scores, tmp_path / "grades.csv")
    text = (tmp_path / "grades.csv").read_text(encoding="utf-8")
    assert "\x1b" not in text and "\u202e" not in text and "ada\\x1b[31m\\u202e" in text
    shown_names = [row["student"] for row in csv.DictReader(open(tmp_path / "grades.csv", encoding="utf-8"))]
    merged = grades.merge_hand_points(scores, {(shown_names[0], "01.1"): 1.0, (shown_names[1], "01.1"): 0.5})
    assert [(s.student, s.points, s.status) for s in merged] == [(name, 1.0, "graded"), ("=cmd", 0.5, "graded")]
    table = grades.format_grades(merged)
    assert "\x1b" not in table and "ada\\x1b[31m\\u202e" in table
