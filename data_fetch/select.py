"""Which of a dataset's files ``--only`` picks: a glob, a folder, or a scene's name.

``--only`` (repeatable) selects a file (its name relative to the dataset folder) when one of its values

* matches the whole name as a glob: ``HalfSize/Plastic/*``, ``Adirondack-*``;
* names a folder the file is in: ``HalfSize/Plastic``, ``MiddEval3/trainingQ/Piano``, ``HalfSize``;
* names a scene: a folder on the file's path (``Plastic``: every size of Plastic) or the scene of an
  archive named ``<Scene>-<variant>.zip`` (``Adirondack``: ``Adirondack-perfect.zip`` and ``-imperfect.zip``).
"""
from __future__ import annotations

import fnmatch

__all__ = ["matches", "select_names"]


def matches(name: str, pattern: str) -> bool:
    """Whether the file ``name`` (``'HalfSize/Plastic/view1.png'``) is selected by ``pattern`` (see the module).

    Example:
        >>> [matches("HalfSize/Plastic/view1.png", p) for p in ("Plastic", "HalfSize/Plastic", "HalfSize/P*", "Baby1")]
        [True, True, False, False]
    """
    if fnmatch.fnmatchcase(name, pattern):
        return True
    folder = pattern.strip("/")
    if not folder:
        return False
    if name.startswith(folder + "/"):
        return True
    parts = name.split("/")
    if "/" not in folder and folder in parts[:-1]:
        return True
    last = parts[-1]
    return last.endswith(".zip") and "-" in last and last[:-4].rsplit("-", 1)[0] == folder


def select_names(names, only) -> list[str]:
    """The names among ``names`` that any of ``only`` (a pattern or a list of them) selects, in order."""
    patterns = [only] if isinstance(only, str) else list(only)
    return [name for name in names if any(matches(name, p) for p in patterns)]
