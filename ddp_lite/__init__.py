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
# (ddp_lite.method.paper.losses, ddp_lite.method.paper.nets, ...), where their documentation lives. The modules sit
# in sub-packages by concern: core, world, classical, method (paper, kit, runtime), data, evaluation, studies,
# sequences, interface.
_HOMES = {
    "core.camera": ("Camera", "look_at", "backproject", "pixel_grid", "project", "relative_pose"),
    "method.config": ("FitConfig",),
    "method.dip": ("ImageResult", "fit_image"),
    "method.paper.disparity": ("DisparityTransform",),
    "method.fit": ("DepthResult", "merge"),
    "method.combine": ("complete_depth",),
    "classical.holes": ("random_holes", "stroke_holes", "edge_band_holes", "kinect_noise"),
    "data.middlebury_rail": ("load_middlebury_scene",),
    "method.profiles": ("PROFILES", "Profile", "get_profile"),
    "world.scenes": ("list_scenes", "make_scene", "register_scene"),
    "classical.stereo": ("sgm_depth", "sgm_disparity"),
    "method.paper.variants": ("VARIANTS",),
    "core.views": ("Scene", "View"),
    "method.coarse_to_fine": ("complete_depth_coarse_to_fine",),
    "method.paper.losses": ("disparity_loss", "masked_l1", "rgb_loss", "ssim", "warp_loss"),
    "method.paper.nets": ("SkipNet", "UNet", "build_net", "make_noise"),
    "world.neighbors": ("select_neighbors",),
    "method.paper.warp": ("Warper", "warp_to_reference"),
}
_HOME_OF = {name: module for module, names in _HOMES.items() for name in names}
_PACKAGES = {  # sub-package → its modules, each one concern (the sub-package's docstring says which)
    "core": ('checks', 'camera', 'views', 'progress', 'outpaths', 'files', 'array_archive'),
    "world": ('scenes', 'render', 'textures', 'photo_texture', 'solids', 'terrain', 'organic', 'neighbors'),
    "classical": ('baselines', 'depth_fills', 'guided_fills', 'stereo', 'holes', 'kinect'),
    "method": ('config', 'profiles', 'fit_inputs', 'stopping', 'time_left', 'loop', 'fit', 'fit_cache', 'combine', 'coarse_to_fine',
               'full_resolution', 'dip', 'equation'),
    "method.paper": ('disparity', 'losses', 'warp', 'nets', 'variants', 'total_loss'),
    "method.kit": ('hole_losses', 'hole_terms', 'visibility', 'warp_confidence', 'warp_cost', 'warp_terms', 'net_inputs',
                   'blend', 'ensemble', 'recipes'),
    "method.runtime": ('device', 'tensors', 'memory', 'side_by_side', 'cache_entry'),
    "data": ('datasets', 'fileio', 'file_writers', 'formats', 'colmap', 'tum', 'middlebury', 'middlebury_rail',
             'textparse', 'resample'),
    "data.samples": ('make_samples',),
    "evaluation": ('metrics', 'fusion', 'experiments', 'viz', 'plane_sweep'),
    "studies": ('real_cases', 'real_suite', 'table6', 'additions', 'mvs_kinect_experiments'),
    "sequences": ('sequence', 'sequence_cost', 'sequence_files', 'sequence_jobs', 'runner', 'working_size'),
    "interface": ('cli', 'cli_classroom', 'cli_complete', 'cli_demo', 'cli_sequence', 'classroom', 'grading', 'grades',
                  'grading_kernel', 'own_work',
                  'exercises'),
}
_PACKAGE_OF = {module: package for package, modules in _PACKAGES.items() for module in modules}


def __getattr__(name: str):
    import importlib
    if name in _HOME_OF:
        value = getattr(importlib.import_module(f".{_HOME_OF[name]}", __name__), name)
    elif name in _PACKAGE_OF:  # a module by its own name (ddp.metrics), as when the package was flat
        value = importlib.import_module(f".{_PACKAGE_OF[name]}.{name}", __name__)
    elif name in _PACKAGES:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # once: later look-ups do not come here
    return value


def __dir__():
    return sorted(set(globals()) | set(_HOME_OF) | {p for p in _PACKAGES if "." not in p} | set(_PACKAGE_OF))
