"""The folder ``DDP_CACHE`` names, where the kit keeps what it computed once, and the digest of its own source.

Two caches share the folder: fits (:mod:`ddp_lite.method.fit_cache`) and rendered scenes
(:mod:`ddp_lite.world.scene_cache`). Each keys its entries by a hash that includes :func:`source_digest`,
so an edited library never reads an entry an older one wrote. ``make lab`` sets ``DDP_CACHE`` to
``.cache/fits`` in the checkout; unset or empty, nothing is kept.

    >>> import os
    >>> os.environ.pop(ENV_VAR, None) and None
    >>> cache_folder() is None
    True
"""
from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

from .files import describe_kind

__all__ = ["ENV_VAR", "cache_folder", "source_digest"]

ENV_VAR = "DDP_CACHE"


def cache_folder() -> Path | None:
    """The folder ``DDP_CACHE`` names (``~`` expanded), or None when it is unset or empty.

    A name that exists but is not a folder is refused here, before any work runs (``ValueError``):
    otherwise the first store, after the whole fit or render, would fail."""
    folder = os.environ.get(ENV_VAR, "").strip()
    if not folder:
        return None
    path = Path(folder).expanduser()
    if path.exists() and not path.is_dir():
        raise ValueError(f"{ENV_VAR}={folder!r} names {path}, which is {describe_kind(path.stat().st_mode)}; "
                         f"{ENV_VAR} must name a folder for the fit and scene caches (or be unset)")
    return path


@functools.lru_cache(maxsize=None)
def source_digest(*packages: str) -> str:
    """SHA-256 (hex) over the source files of ``ddp_lite``'s sub-``packages`` ("world", "core", ...), in path
    order; none named: every file of the package."""
    digest = hashlib.sha256()
    root = Path(__file__).resolve().parents[1]  # ddp_lite/
    folders = [root / package for package in packages] or [root]
    for path in sorted(p for folder in folders for p in folder.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()
