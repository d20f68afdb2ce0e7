"""Parsing text files line by line, with errors that name the file and the line.

The readers of TUM lists and trajectories, COLMAP models and the kit's ``intrinsics.txt`` share
these: ``#`` starts a comment; lines are numbered from 1; a fault raises ``ValueError`` with
``"<path>, line <n>: <what was wrong>"`` (``parse_error``), before anything runs. Quaternions are
(x, y, z, w) here; a reader whose file writes w first reorders before calling ``quaternion_rotation``.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ..core.files import NotTextError, read_text, regular_file


def parse_error(path, line: int | None, message: str) -> ValueError:
    """A ``ValueError`` naming the file and, when known, the 1-based line of a parse problem."""
    where = f"{path}, line {line}" if line is not None else f"{path}"
    return ValueError(f"{where}: {message}")


def text_lines(path, keep_blank: bool = False) -> list[tuple[int, str]]:
    """(1-based line number, stripped text) of a text file, ``#`` comments dropped (blank lines too unless asked)."""
    path = regular_file(path, "path")
    try:
        text = read_text(path, "path")  # a byte-order mark dropped, CRLF → LF: an editor's copy reads the same
    except NotTextError as error:
        raise parse_error(path, None, str(error).split(f"{path} ", 1)[-1]) from None
    lines = []
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if line.startswith("#") or (not line and not keep_blank):
            continue
        lines.append((number, line))
    return lines


def parse_floats(tokens, path, line: int, what: str) -> np.ndarray:
    """Text tokens → a float64 array; a token that is not a number → :func:`parse_error` naming ``what``."""
    try:
        values = np.array([float(t) for t in tokens], dtype=np.float64)
    except ValueError:
        raise parse_error(path, line, f"{what} must be numbers, got {' '.join(tokens)!r}") from None
    if not np.all(np.isfinite(values)):
        raise parse_error(path, line, f"{what} must be finite numbers, got {' '.join(tokens)!r}")
    return values


def quaternion_rotation(quat_xyzw: np.ndarray, path, line: int) -> np.ndarray:
    """A (nearly) unit quaternion (x, y, z, w) → 3×3 rotation; refuse zero or far-from-unit ones."""
    norm = float(np.linalg.norm(quat_xyzw))
    if not abs(norm - 1.0) < 1e-3:
        raise parse_error(path, line, f"the quaternion must have unit length, got length {norm:.6g}")
    return Rotation.from_quat(quat_xyzw / norm).as_matrix()
