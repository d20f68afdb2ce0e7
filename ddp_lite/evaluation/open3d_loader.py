"""Open3D, imported on first use by the point-cloud code (fusion, the P/R/F metrics), without what the kit
never uses:

- Open3D-ML (``open3d.ml``), which ``import open3d`` loads in full: its datasets import scikit-learn, 2.5 s of
  the 3.5 s the import takes on a 2-core laptop, in every notebook that fuses a cloud. It is loaded lazily
  instead (``importlib.util.LazyLoader``): ``open3d.ml`` is still there and loads on its first use;
- ``open3d.visualization``, which imports Plotly and Dash for its ``draw_plotly`` (0.9 s): lazy too, for the
  kit draws its clouds itself (``evaluation.fusion.render_point_cloud``);
- the web visualizer, which Open3D enables in any Jupyter kernel with three lines of log in the cell's
  output: off (``OPEN3D_DISABLE_WEB_VISUALIZER=true``) unless the environment says otherwise.

An ``open3d`` imported before (by the caller, or a test) is returned as it is.

    >>> o3d = import_open3d()
    >>> o3d.geometry.PointCloud().is_empty()
    True
"""
from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import os
import sys
import threading

__all__ = ["import_open3d"]

_LOCK = threading.Lock()
WEB_VISUALIZER = "OPEN3D_DISABLE_WEB_VISUALIZER"


LAZY = ("open3d.ml", "open3d.visualization")


class _LazyOpen3DParts(importlib.abc.MetaPathFinder):
    """Finds the ``LAZY`` sub-packages as the other finders do, with their loaders made lazy; every other
    name: not mine."""

    def find_spec(self, name, path=None, target=None):
        if name not in LAZY:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path, target)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec  # not a package on disk (an external OPEN3D_ML_ROOT, ...): imported as usual
        spec.loader = importlib.util.LazyLoader(spec.loader)
        return spec


def import_open3d():
    """The ``open3d`` module (see the module docstring): its first import here loads ``LAZY`` lazily."""
    if "open3d" in sys.modules:
        return sys.modules["open3d"]
    with _LOCK:
        saved = os.environ.get(WEB_VISUALIZER)  # read by open3d's import only: set for it, then as it was
        os.environ.setdefault(WEB_VISUALIZER, "true")
        finder = _LazyOpen3DParts()
        sys.meta_path.insert(0, finder)
        try:
            import open3d
        finally:
            sys.meta_path.remove(finder)
            if saved is None:
                os.environ.pop(WEB_VISUALIZER, None)
    return open3d
