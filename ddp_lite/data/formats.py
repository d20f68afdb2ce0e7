"""Your own captures → the kit's ``Scene``: one entry point over TUM RGB-D, COLMAP and saved scenes.

Three formats people already have, read into the kit's conventions (float32 (H, W, 3) images in
[0, 1]; float32 (H, W) depth in metres, or the reconstruction's own units, NaN = no value;
``Camera`` in the OpenCV convention with pixel (0, 0) the *centre* of the top-left pixel; poses
``cam_from_world``). Each has a writer, so tests and notebooks can make a fixture from a
synthetic scene and read it back. Every reader refuses a malformed file with its path and line
number before anything runs.

* **TUM RGB-D** folders: ``ddp_lite.data.tum`` (``read_tum``, ``write_tum``, ``associate``).
* **COLMAP** text models with per-image depth: ``ddp_lite.data.colmap`` (``read_colmap``, ``write_colmap``).
* **The kit's own** ``Scene.save`` files (``.npz``), or a folder holding exactly one: ``read_scene`` here.

``load_sequence(path, format)`` picks the reader by name.
"""
from __future__ import annotations

import zipfile
import zlib
from pathlib import Path

from ..core.files import regular_file
from .colmap import read_colmap
from .resample import resize_scene
from .tum import read_tum
from ..core.views import Scene

__all__ = ["read_scene", "load_sequence", "FORMATS"]


def read_scene(path, size=None) -> Scene:
    """A ``Scene.save`` file (``.npz``), or a folder holding exactly one, → ``Scene`` (``size`` resamples)."""
    path = Path(path)
    if path.is_dir():
        found = sorted(path.glob("*.npz"))
        if len(found) != 1:
            raise ValueError(f"path: {path} must hold exactly one saved scene (.npz), found {len(found)}")
        path = found[0]
    regular_file(path, "path")
    try:
        scene = Scene.load(path)
    except (KeyError, ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error) as error:
        raise ValueError(f"path: {path} is not a scene written by Scene.save, or is truncated "
                         f"({type(error).__name__}: {error})") from None
    if size is not None:
        scene = resize_scene(scene, size)
    scene.sources = [path.absolute()]
    return scene


FORMATS = {"tum": read_tum, "colmap": read_colmap, "scene": read_scene}


def load_sequence(path, format: str, **options) -> Scene:
    """Read a sequence in ``format`` ('tum', 'colmap' or 'scene'); ``options`` go to that reader."""
    if format not in FORMATS:
        raise ValueError(f"format must be one of {sorted(FORMATS)}, got {format!r}")
    return FORMATS[format](path, **options)
