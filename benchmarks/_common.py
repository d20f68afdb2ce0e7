"""What the benchmark scripts share: their command line checked before any work, and their rows files.

Arguments: :func:`parse_args` adds ``--check-args`` to every script (check the arguments, print
``arguments OK`` and exit 0 before any work: what the test of the documented commands runs) and turns a
``check(args)`` that raises ``ValueError`` into a usage error naming the option (exit 2). The argument types
(:func:`positive_int`, :func:`seed_int`, :func:`lane`, :func:`data_root`, ...) do the same inside argparse.

Rows: one JSON line per fill or fit, appended as each finishes (:class:`RowsFile`). A row is reused on a
resumed run only when every field that changes its numbers (:func:`row_key`: size, profile, recipe and its
overrides, seed, case, hole kind, variant, ...) matches, so a run at another size or profile never reports
another run's rows as its own; a last line cut short by a stopped run is moved aside to ``FILE.torn``
with a word, and the rest resumed.
"""
from __future__ import annotations

import argparse
import ast
import dataclasses
import json
import os
from pathlib import Path


# ------------------------------------------------------------------ the command line

def add_profile_args(parser: argparse.ArgumentParser, profile: str = "class") -> None:
    """``--size H W``, ``--profile`` and ``--threads``."""
    from ddp_lite.method.profiles import PROFILES

    parser.add_argument("--size", type=positive_int, nargs=2, metavar=("H", "W"), help="image size (default: the profile's)")
    parser.add_argument("--profile", default=profile, choices=sorted(PROFILES))
    parser.add_argument("--threads", type=positive_int, default=1)


def profile_from_args(args):
    """Set torch's thread count and return the chosen profile, resized by ``--size``."""
    import torch  # here, not above: a script held to AVX2 (isa.py) starts again before torch is imported

    from ddp_lite.method.profiles import get_profile

    torch.set_num_threads(args.threads)
    profile = get_profile(args.profile)
    return dataclasses.replace(profile, size=tuple(args.size)) if args.size else profile


def parse_args(parser: argparse.ArgumentParser, argv=None, check=None) -> argparse.Namespace:
    """``parser``'s arguments, checked before any work. ``--check-args`` (added here) exits 0 after the checks;
    ``check(args)`` may raise ``ValueError`` (its message, which names the option, becomes a usage error,
    exit 2) or return nothing."""
    parser.add_argument("--check-args", action="store_true",
                        help="check the arguments and exit (0: they are good) before any work")
    args = parser.parse_args(argv)
    if check is not None:
        try:
            check(args)
        except ValueError as error:
            parser.error(str(error))
    if args.check_args:
        print("arguments OK")
        parser.exit(0)
    return args


def _number(kind, minimum, what: str):
    def convert(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return value
    convert.__name__ = what  # argparse names the type in its message
    return convert


positive_int = _number(int, 1, "a whole number ≥ 1")
seed_int = _number(int, 0, "a seed, a whole number ≥ 0")
nonnegative_float = _number(float, 0.0, "a number ≥ 0")


def positive_float(text: str) -> float:
    """A float > 0 (seconds, a budget)."""
    value = nonnegative_float(text)
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def lane(text: str) -> tuple[int, int]:
    """``i/n``: every n-th case from the i-th, 0 ≤ i < n."""
    try:
        index, lanes = (int(v) for v in text.split("/"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected i/n (lane i of n, 0 ≤ i < n), got {text!r}") from None
    if lanes < 1 or not 0 <= index < lanes:
        raise argparse.ArgumentTypeError(f"expected i/n with n ≥ 1 and 0 ≤ i < n, got {text!r}")
    return index, lanes


def existing_folder(text: str) -> Path:
    """A folder that exists."""
    path = Path(text)
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"no such folder {text!r}" if not path.exists() else f"{text!r} is a file, not a folder")
    return path


def existing_file(text: str) -> Path:
    """A regular file that exists."""
    path = Path(text)
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"no such file {text!r}" if not path.exists() else f"{text!r} is not a file")
    return path


def data_root(text: str) -> Path:
    """A folder of Middlebury scenes with ground truth, one folder per scene (``real_suite.find_scenes``)."""
    from ddp_lite.studies.real_suite import find_scenes

    path = existing_folder(text)
    try:
        find_scenes(path)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error).replace("root: ", "", 1)) from None
    return path


def check_rows_out(path, flag: str = "--out") -> None:
    """A rows file a run appends to: ``ValueError`` naming ``flag`` unless it can be written (and, if it exists,
    read back to resume)."""
    from ddp_lite.core.outpaths import check_output_file

    check_output_file(path, flag, example="rows.jsonl")
    if os.path.exists(path) and not os.access(path, os.R_OK):
        raise ValueError(f"{flag} {os.fspath(path)!r} cannot be read (its rows are what a run resumes from)")


def check_output_folder(path, flag: str) -> None:
    """An output folder: ``ValueError`` naming ``flag`` unless it can be created or written."""
    from ddp_lite.core.outpaths import check_output_folder as check

    check(path, flag)


def check_rows_in(path, flag: str) -> None:
    """A rows file to report: it must exist and hold at least one row."""
    if not os.path.isfile(path):
        raise ValueError(f"{flag}: no such file {os.fspath(path)!r}" if not os.path.exists(path)
                         else f"{flag} {os.fspath(path)!r} is not a file")


# ------------------------------------------------------------------ recipes on the command line

def split_top(body: str) -> list[str]:
    """Split on commas that are not inside brackets: ``channels=(16, 32),lr=0.01``."""
    parts, depth, current = [], 0, ""
    for ch in body:
        depth += ch in "([{"
        depth -= ch in ")]}"
        if ch == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    return parts + [current] if current else parts


def recipe_overrides(text: str, reserved=("seed",)) -> tuple[str, dict]:
    """``name`` or ``name:key=value,key=value`` → (name, {key: value}); values as Python literals, bare
    words as strings (``warp_combine=min``). ``ValueError`` naming the recipe: an item without ``=``, a key that
    is no ``FitConfig`` field (with the nearest), or one the command line sets itself (``reserved``: the seed
    comes from ``--seeds``)."""
    from ddp_lite.method.config import FIELDS, _not_a_field

    name, _, body = text.partition(":")
    if not name.strip():
        raise ValueError(f"--recipes {text!r}: give a recipe's name before ':'")
    overrides = {}
    for item in split_top(body.replace(";", ",")) if body else []:
        key, equals, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not equals or not key or not value:
            raise ValueError(f"--recipes {text!r}: {item!r} is not key=value")
        if key in reserved:
            raise ValueError(f"--recipes {text!r}: {key!r} is set by its own option (--{key}s), not by a recipe")
        if key not in FIELDS:
            raise ValueError(f"--recipes {text!r}: " + _not_a_field(key, f"{key!r} is no FitConfig field"))
        try:
            overrides[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            overrides[key] = value  # a bare word: FitConfig's own check says whether it is one of a field's words
    return name.strip(), overrides


def check_configs(configs) -> None:
    """Build and validate each FitConfig that a run will fit, before any: ``configs`` yields
    ``(what, thunk)`` pairs; a bad one raises ``ValueError`` naming ``what``."""
    for what, thunk in configs:
        try:
            thunk().validate()
        except (TypeError, ValueError) as error:
            raise ValueError(f"{what}: {error}") from None


# ------------------------------------------------------------------ rows files

def row_key(row: dict, fields) -> tuple:
    """The fields of ``row`` that change its numbers, in ``fields`` order (a missing one is None), as a key."""
    return tuple(json.dumps(row.get(name), sort_keys=True) for name in fields)


def read_rows(path, say=print) -> list[dict]:
    """The rows of a JSON-lines file ([] when it does not exist). A last line that is not JSON, a row cut
    short by a stopped run, is moved to ``FILE.torn`` (appended, kept readable) and the file rewritten
    without it, atomically, with a word through ``say``; a bad line before the last raises ``ValueError``
    naming the file and line (that file is not one this kit wrote)."""
    path = Path(path)
    if not path.exists():
        return []
    text = path.read_text()
    lines = text.splitlines()
    rows = []
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
            if not isinstance(row, dict):
                raise ValueError("not an object")
        except ValueError:
            if number == len(lines):
                _set_aside(path, lines, say)
                break
            raise ValueError(f"{path}: line {number} is not a JSON row ({line[:60]!r}); only a last line cut "
                             f"short is set aside") from None
        rows.append(row)
    return rows


def _set_aside(path: Path, lines: list[str], say) -> None:
    from ddp_lite.core.files import atomic_path

    torn = path.with_name(path.name + ".torn")
    with open(torn, "a") as handle:
        handle.write(lines[-1] + "\n")
    with atomic_path(path) as temporary, open(temporary, "w") as handle:
        handle.write("".join(line + "\n" for line in lines[:-1]))
    say(f"{path}: its last line was cut short (a run stopped while writing it): moved to {torn}; the other "
        f"{sum(1 for line in lines[:-1] if line.strip())} rows kept")


class RowsFile:
    """A rows file a run appends to and resumes from: ``done(row)`` says whether a row with the same
    :func:`row_key` (over ``fields``) is already there; ``record(row)`` appends one at once (a stopped run keeps
    what it finished). Rows without every field in ``fields`` (written before they were recorded) are never
    reused, and said so once."""

    def __init__(self, path, fields, say=print):
        self.path, self.fields = (Path(path) if path else None), tuple(fields)
        self.rows = read_rows(self.path, say) if self.path else []
        keyed = [r for r in self.rows if all(name in r for name in self.fields)]
        if len(keyed) < len(self.rows):
            missing = sorted({name for r in self.rows for name in self.fields if name not in r})
            say(f"{self.path}: {len(self.rows) - len(keyed)} rows do not record {', '.join(missing)}: "
                f"not reused (they may come from another size or profile)")
        self.keys = {row_key(r, self.fields) for r in keyed}
        self._handle = None

    def done(self, row: dict) -> bool:
        return row_key(row, self.fields) in self.keys

    def record(self, row: dict) -> None:
        self.rows.append(row)
        self.keys.add(row_key(row, self.fields))
        if self.path is None:
            return
        if self._handle is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._handle = open(self.path, "a")
        self._handle.write(json.dumps(row) + "\n")
        self._handle.flush()

    def close(self) -> None:
        if self._handle is not None:
            self._handle.close()
            self._handle = None

