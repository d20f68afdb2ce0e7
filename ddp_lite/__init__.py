"""ddp-lite: Depth completion with a view-constrained Deep Depth Prior (Ghosh et al., 3DV 2020).

    >>> import ddp_lite as ddp
    >>> result = ddp.complete_depth(rgb, depth_with_nans, camera, neighbors, variant="rgbd+warp")
    >>> result.depth  # (H, W) metres, holes filled

Units and conventions: images float32 (H, W, 3) in [0, 1]; depth float32 (H, W) metres with NaN
holes; cameras in the OpenCV convention (x right, y down, z forward), pixel (0, 0) = centre of the
top-left pixel. ``DDP_PROFILE`` (ci / class / paper) sets sizes and schedules, ``DDP_RECIPE`` (kit /
paper / photo) the method.

The modules sit in sub-packages by concern, each docstring naming its modules and what it may
import: ``core`` (the data model and shared checks), ``world`` (synthetic scenes), ``classical``
(stereo, hole models, classical fills), ``method`` (DDP: ``paper``, ``kit``, ``runtime`` and the fit),
``data`` (readers and writers of real data), ``evaluation`` (metrics, fusion, experiments, figures),
``studies`` (the paper's tables and the kit's studies), ``sequences`` (whole captures) and
``interface`` (the command line and the classroom).
"""
# The front door: what a notebook user or a script calls, each name with the module that defines (and
# documents) it. ``from ddp_lite import *`` gives exactly these; every other name is imported from its
# own module (``from ddp_lite.method.paper.losses import ssim``).
_FRONT_DOOR = {
    "complete_depth": "method.complete", "DepthResult": "method.result", "merge": "method.result",
    "FitConfig": "method.config", "RunOptions": "method.runtime.options", "VARIANTS": "method.paper.variants",
    "fit_image": "method.dip", "ImageResult": "method.dip",
    "get_profile": "method.profiles", "Profile": "method.profiles", "PROFILES": "method.profiles",
    "get_recipe": "method.kit.recipes",
    "make_scene": "world.scenes", "list_scenes": "world.scenes", "select_neighbors": "world.neighbors",
    "Scene": "core.views", "View": "core.views", "Camera": "core.camera", "look_at": "core.camera",
    "DisparityTransform": "method.paper.disparity", "sgm_depth": "classical.stereo", "random_holes": "classical.holes",
}
__all__ = list(_FRONT_DOOR)

__version__ = "0.1.0"


# Imported on first use (PEP 562), not with the package: torch and the rest of the stack take seconds to
# import, and `ddp-lite --help` (whose module lives in this package) must not wait for them.
def __getattr__(name: str):
    if name not in _FRONT_DOOR:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib
    value = getattr(importlib.import_module(f".{_FRONT_DOOR[name]}", __name__), name)
    globals()[name] = value  # once: later look-ups do not come here
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
