"""Scenes rendered once: with ``DDP_CACHE`` set to a folder, :func:`~ddp_lite.world.scenes.make_scene` reads a
scene it rendered before back from there.

A notebook renders its scenes on every run, and the stereo matcher's input at three times the size below 96
rows (``evaluation.experiments.sgm_depth_at_scale``): 2-3 s a notebook at ``ci``, more at ``class``, again
after every kernel restart, and again in every notebook that uses the same scene. Reading one back takes
milliseconds. Each scene is stored as ``make_scene-<key>.npz`` (:meth:`Scene.save`) in the folder the fit
cache uses (:mod:`ddp_lite.core.disk_cache`), keyed by a SHA-256 of the call's arguments, the source of
the code that renders (``ddp_lite/world``, ``ddp_lite/core``) and the NumPy and scikit-image versions (a
photo texture is a scikit-image sample). Rendering is deterministic, so a scene read back is the scene
the call would render now (``tests/world/test_scene_cache.py`` compares them array by array).

An entry is read with ``allow_pickle=False`` and used only if it holds the call's key, scene name, view
count and size, with finite depth everywhere; anything else (a foreign, swapped or truncated file) is
ignored with a warning and the scene rendered again. A store that fails (a full disk, a read-only
folder) warns and returns the rendered scene. As with fits: share a ``DDP_CACHE`` only with people you
trust. Unset (the default): every call renders.
"""
from __future__ import annotations

import hashlib
import json
import os
import warnings
import zipfile

import numpy as np

from ..core.disk_cache import ENV_VAR, cache_folder, source_digest
from ..core.views import Scene

__all__ = ["cached_scene"]


def _key(arguments: dict) -> str:
    import skimage

    environment = {"source": source_digest("world", "core"), "numpy": np.__version__, "skimage": skimage.__version__}
    text = json.dumps({"arguments": arguments, "environment": environment}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _check(scene: Scene, name: str, n_views: int, size: tuple[int, int]) -> None:
    """Raise ``ValueError`` unless ``scene`` is what ``make_scene(name, size, n_views)`` renders."""
    if scene.name != name or len(scene.views) != n_views or len(scene.right) != n_views or len(scene.labels) != n_views:
        raise ValueError(f"it holds {scene.name!r} with {len(scene.views)} views, not {name!r} with {n_views}")
    for view in scene.views + scene.right:
        if view.depth.shape != size or not np.isfinite(view.depth).all():
            raise ValueError(f"a view is {view.depth.shape[0]}×{view.depth.shape[1]} or has unknown depth, "
                             f"not a full {size[0]}×{size[1]} render")
    if any(np.shape(label) != size for label in scene.labels):
        raise ValueError("a label map has another size than its view")


def cached_scene(render, name: str, size: tuple[int, int], n_views: int, seed: int, fov_x_deg, supersample: int
                 ) -> Scene:
    """``render()`` → Scene, or the scene an identical earlier call stored in ``DDP_CACHE`` (see the module
    docstring). The other arguments are ``make_scene``'s, checked by it: they make the key."""
    folder = cache_folder()
    if folder is None:
        return render()
    arguments = {"name": name, "size": list(size), "n_views": int(n_views), "seed": int(seed),
                 "fov_x_deg": None if fov_x_deg is None else float(fov_x_deg), "supersample": int(supersample)}
    key = _key(arguments)
    path = folder / f"make_scene-{key}.npz"
    if os.path.lexists(path):
        try:
            if not path.is_file():
                raise ValueError("it is not a regular file")
            scene = Scene.load(path, tag=key)
            _check(scene, name, int(n_views), tuple(size))
            return scene
        except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile) as error:  # never fatal: render again
            warnings.warn(f"{ENV_VAR}: ignoring the cached scene {path}: {error}; rendering it again",
                          RuntimeWarning, stacklevel=3)
    scene = render()
    try:
        scene.save(path, tag=key)
    except OSError as error:
        warnings.warn(f"{ENV_VAR}: could not store the scene in {path} ({error}); it is returned but not cached",
                      RuntimeWarning, stacklevel=3)
    return scene
