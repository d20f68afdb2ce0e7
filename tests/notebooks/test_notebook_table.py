"""The README's notebook table is rendered from the times bench_laptop.py records (notebook_table.py), never typed."""
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import notebook_table  # noqa: E402

TABLE = """# A kit

| notebook | what it shows | time `ci` | time `class`, AVX2 | `class`, another CPU |
|---|---|---|---|---|
| `01_first` | one thing | 9 s | 9.9 min | 0.6 min |
| `02_second` | another | 8 s (Xeon) | 2.0 min | — |

Text after the table: 12 s.
"""


def _rows(path, *rows):
    path.write_text("".join(json.dumps(dict(threads=2, cpu="c", when="d", **row)) + "\n" for row in rows))
    return path


def test_the_readme_table_says_what_the_recorded_times_say():
    wrong = notebook_table.differences(notebook_table.README.read_text(),
                                       notebook_table.rendered(notebook_table.read_rows()))
    assert not wrong, "README.md's notebook table differs from benchmarks/results/notebook_times.jsonl: " + "; ".join(wrong)
    assert set(notebook_table.table_lines(notebook_table.README.read_text())) == {
        p.stem for p in (notebook_table.HERE.parent / "notebooks").glob("[0-9][0-9]_*.ipynb")}


def test_the_latest_time_of_each_column_is_written_and_nothing_else_changes(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(TABLE)
    results = _rows(tmp_path / "times.jsonl",
                    dict(notebook="01_first", profile="class", isa="avx2", seconds=600.0, note=""),
                    dict(notebook="01_first", profile="class", isa="avx2", seconds=294.0, note=""),  # the later run wins
                    dict(notebook="01_first", profile="class", isa="native", seconds=30.0, note=""),  # no column: ignored
                    dict(notebook="02_second", profile="ci", isa="avx2", seconds=12.4, note="EPYC"))
    changed = notebook_table.write_readme(readme, results)
    assert readme.read_text() == TABLE.replace("| 9.9 min |", "| 4.9 min |").replace("| 8 s (Xeon) |", "| 12 s (EPYC) |")
    assert len(changed) == 2 and all("the table says" in line for line in changed)
    assert notebook_table.differences(readme.read_text(), notebook_table.rendered(notebook_table.read_rows(results))) == []


def test_a_measured_notebook_missing_from_the_table_is_reported(tmp_path):
    results = _rows(tmp_path / "times.jsonl", dict(notebook="03_third", profile="ci", isa="avx2", seconds=5.0, note=""))
    assert notebook_table.differences(TABLE, notebook_table.rendered(notebook_table.read_rows(results))) == [
        "03_third: measured, but not in the table"]
