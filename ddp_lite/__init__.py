"""ddp-lite: Depth completion with a view-constrained Deep Depth Prior (Ghosh et al., 3DV 2020).

    >>> import ddp_lite as ddp
    >>> result = ddp.complete_depth(rgb, depth_with_nans, camera, neighbors, variant="rgbd+warp")
    >>> result.depth  # (H, W) metres, holes filled

Units and conventions: images float32 (H, W, 3) in [0, 1]; depth float32 (H, W) metres with NaN
holes; cameras in the OpenCV convention (x right, y down, z forward), pixel (0, 0) = centre of the
top-left pixel. ``DDP_PROFILE`` (ci / class / paper) sets sizes and schedules.
"""
# What a notebook or a user calls: completion, its config and profiles, scenes and cameras, the
# transform DDP fits in, SGM input. ``from ddp_lite import *`` gives exactly these.
__all__ = ["complete_depth", "DepthResult", "merge", "FitConfig", "VARIANTS", "fit_image", "ImageResult",
           "get_profile", "Profile", "PROFILES", "make_scene", "list_scenes", "Scene", "View", "Camera", "look_at",
           "DisparityTransform", "sgm_depth", "random_holes"]

__version__ = "0.1.0"

# Names are imported on first use (PEP 562), not with the package: torch and the rest of the stack take
# seconds to import, and `ddp-lite --help` (whose module lives in this package) must not wait for them.
# Building blocks stay importable from here as before; new code imports them from their modules
# (ddp_lite.losses, ddp_lite.nets, ddp_lite.warp, ...), where their documentation lives.
_HOMES = {
    "camera": ("Camera", "look_at", "backproject", "pixel_grid", "project", "relative_pose"),
    "config": ("FitConfig",),
    "dip": ("ImageResult", "fit_image"),
    "disparity": ("DisparityTransform",),
    "fit": ("DepthResult", "complete_depth", "merge"),
    "holes": ("random_holes", "edge_band_holes", "kinect_noise"),
    "profiles": ("PROFILES", "Profile", "get_profile"),
    "scenes": ("list_scenes", "make_scene", "register_scene"),
    "stereo": ("sgm_depth", "sgm_disparity"),
    "variants": ("VARIANTS",),
    "views": ("Scene", "View"),
    "coarse_to_fine": ("complete_depth_coarse_to_fine",),
    "losses": ("disparity_loss", "masked_l1", "rgb_loss", "ssim", "warp_loss"),
    "nets": ("SkipNet", "UNet", "build_net", "make_noise"),
    "neighbors": ("select_neighbors",),
    "warp": ("Warper", "warp_to_reference"),
}
_HOME_OF = {name: module for module, names in _HOMES.items() for name in names}
_SUBMODULES = ("baselines", "datasets", "fusion", "metrics", "organic")


def __getattr__(name: str):
    import importlib
    import importlib.util
    if name in _HOME_OF:
        value = getattr(importlib.import_module(f".{_HOME_OF[name]}", __name__), name)
    elif name in _SUBMODULES or (not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}")):
        value = importlib.import_module(f".{name}", __name__)  # any submodule, as when the package imported them all
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # once: later look-ups do not come here
    return value


def __dir__():
    return sorted(set(globals()) | set(_HOME_OF) | set(_SUBMODULES))
