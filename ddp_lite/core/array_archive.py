"""Values as an ``.npz`` archive that loads without pickle: the arrays as members ``a0``, ``a1``, ...,
and the structure that names them as JSON in one more member.

The fit cache (``ddp_lite.method.runtime.cache_entry``) and the grader (``ddp_lite.interface.grading_kernel``)
each turn their own values into a structure, and store the arrays in it through :func:`array_node`;
:func:`write_archive` writes the two atomically. What each may hold, and how it is read back, stays
theirs. Standard library and NumPy only: the grader's kernel imports this for every call.

Example:
    >>> import os, tempfile
    >>> arrays = []
    >>> structure = {"depth": array_node(np.zeros((2, 3), np.float32), arrays, TypeError)}
    >>> path = os.path.join(tempfile.mkdtemp(), "value.npz")
    >>> write_archive(path, "structure", structure, arrays)
    >>> with np.load(path, allow_pickle=False) as archive:
    ...     archive["a0"].shape, json.loads(archive["structure"].tobytes())
    ((2, 3), {'depth': {'array': 0}})
"""
from __future__ import annotations

import io
import json

import numpy as np

from .files import write_bytes_atomic

__all__ = ["ARRAY_KINDS", "array_node", "archive_bytes", "write_archive"]

ARRAY_KINDS = "biufc"  # bool, integers, floats, complex: what NumPy stores without pickling


def array_node(value, arrays: list, refuse) -> dict:
    """``value`` (an ndarray or a NumPy scalar) appended to ``arrays``; returns its node in the structure,
    ``{"array": i}`` or ``{"scalar": i}``. ``refuse(what)`` makes the exception raised for a dtype that
    only a pickle could hold (``what``: "an array of dtype object")."""
    array = np.asarray(value)
    if array.dtype.kind not in ARRAY_KINDS:
        raise refuse(f"an array of dtype {array.dtype}")
    arrays.append(array)
    return {"array" if isinstance(value, np.ndarray) else "scalar": len(arrays) - 1}


def archive_bytes(member: str, structure, arrays: list) -> bytes:
    """The ``.npz`` bytes: ``structure`` as JSON (UTF-8 bytes as uint8) in ``member``, then ``arrays`` as ``a0``, ``a1``, ..."""
    buffer = io.BytesIO()
    np.savez(buffer, **{member: np.frombuffer(json.dumps(structure).encode(), np.uint8)},
             **{f"a{i}": array for i, array in enumerate(arrays)})
    return buffer.getvalue()


def write_archive(path, member: str, structure, arrays: list) -> None:
    """Write :func:`archive_bytes` to ``path`` atomically (a temporary file, then a rename)."""
    write_bytes_atomic(path, archive_bytes(member, structure, arrays))
