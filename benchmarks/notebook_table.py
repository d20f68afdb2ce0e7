"""The README's notebook table, from measurements: its `ci` and `class`, AVX2 columns are rendered from
``results/notebook_times.jsonl``, the rows ``bench_laptop.py --notebooks`` appends, never typed by hand.

    python benchmarks/notebook_table.py           # the two columns as the results give them
    python benchmarks/notebook_table.py --write   # put them into README.md's table (bench_laptop does this)
    python benchmarks/notebook_table.py --check   # exit 1 if README.md's table says otherwise (tests do this)

A row of the results: ``{"notebook": "06_classical_baselines", "profile": "class", "isa": "avx2",
"seconds": 290.0, "threads": 2, "cpu": "...", "when": "2026-12-07", "note": ""}``; the latest row of a
(notebook, column) wins. ``note`` (the machine, when it is not the run's) is printed in brackets after the
figure. The table's other columns (what a notebook shows; `class` on an earlier CPU) are left as they are.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results" / "notebook_times.jsonl"
sys.path.insert(0, str(HERE))  # _common, as every benchmark takes it
from _common import parse_args  # noqa: E402
README = HERE.parent / "README.md"

# README column (its index among a row's cells, 0 = the notebook's name) → which rows fill it, and how a
# figure is written there: seconds at `ci`, minutes at `class`
COLUMNS = {2: dict(profile="ci", isa=None), 3: dict(profile="class", isa="avx2")}


def _cell(row: dict) -> str:
    """A row's figure as the README writes it: '21 s' at ci, '1.6 min' at class, with its note in brackets."""
    seconds = float(row["seconds"])
    figure = f"{seconds:.0f} s" if row["profile"] == "ci" else f"{seconds / 60:.1f} min"
    return figure + (f" ({row['note']})" if row.get("note") else "")


def read_rows(path: Path = RESULTS) -> list[dict]:
    """The results' rows, in the order they were written (an empty list where there is no file)."""
    if not Path(path).is_file():
        return []
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def rendered(rows: list[dict]) -> dict[str, dict[int, str]]:
    """{notebook stem: {README column index: cell text}} from the latest row of each (notebook, column)."""
    cells: dict[str, dict[int, str]] = {}
    for row in rows:
        for column, wanted in COLUMNS.items():
            if row["profile"] == wanted["profile"] and wanted["isa"] in (None, row["isa"]):
                cells.setdefault(row["notebook"], {})[column] = _cell(row)
    return cells


def _split(line: str) -> list[str]:
    return [cell.strip() for cell in line.strip().strip("|").split(" | ")]


def table_lines(text: str) -> dict[str, int]:
    """{notebook stem: line index} of the README's notebook table rows (``| `NN_name` | ... |``)."""
    found = {}
    for index, line in enumerate(text.splitlines()):
        cells = _split(line) if line.startswith("| `") else []
        if cells and cells[0].strip("`")[:2].isdigit() and cells[0].strip("`")[2:3] == "_":
            found[cells[0].strip("`")] = index
    return found


def differences(text: str, cells: dict[str, dict[int, str]]) -> list[str]:
    """Where ``text``'s table differs from ``cells``: one line each (a notebook the results have and the table
    lacks counts too)."""
    lines, rows = text.splitlines(), table_lines(text)
    out = []
    for notebook, columns in sorted(cells.items()):
        if notebook not in rows:
            out.append(f"{notebook}: measured, but not in the table")
            continue
        have = _split(lines[rows[notebook]])
        out += [f"{notebook}, column {column}: the table says {have[column]!r}, the results {want!r}"
                for column, want in sorted(columns.items()) if have[column] != want]
    return out


def written(text: str, cells: dict[str, dict[int, str]]) -> str:
    """``text`` with its table's measured columns replaced by ``cells``; every other character kept."""
    lines, rows = text.splitlines(keepends=True), table_lines(text)
    for notebook, columns in cells.items():
        if notebook in rows:
            index = rows[notebook]
            have = _split(lines[index])
            for column, want in columns.items():
                have[column] = want
            ending = lines[index][len(lines[index].rstrip("\r\n")):]
            lines[index] = "| " + " | ".join(have) + " |" + ending
    return "".join(lines)


def write_readme(readme: Path = README, results: Path = RESULTS) -> list[str]:
    """Put the results into ``readme``'s table (written atomically); returns what changed."""
    text = readme.read_text()
    changed = differences(text, rendered(read_rows(results)))
    new = written(text, rendered(read_rows(results)))
    if new != text:
        from ddp_lite.core.files import write_bytes_atomic
        write_bytes_atomic(readme, new.encode())
    return changed


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="put the results into README.md's table")
    parser.add_argument("--check", action="store_true", help="exit 1 where README.md's table differs from them")
    def check(args):
        if args.write and args.check:
            raise ValueError("--write and --check: give one (--write changes README.md, --check only reads it)")
    args = parse_args(parser, argv, check)
    cells = rendered(read_rows())
    if args.write:
        for line in write_readme():
            print("written:", line)
        return 0
    if args.check:
        wrong = differences(README.read_text(), cells)
        for line in wrong:
            print(line)
        return 1 if wrong else 0
    for notebook, columns in sorted(cells.items()):
        print(f"{notebook:<28}" + "".join(f"{columns.get(c, '—'):>22}" for c in COLUMNS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
