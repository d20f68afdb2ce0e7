"""Resampling loaded views and scenes, undistorting RGB-D pairs, and a loaded scene's depth range.

What every loader does after reading its files: colour is resampled by area (linear when
enlarging), depth and labels by the nearest pixel *centre* (OpenCV ``INTER_NEAREST_EXACT``: no
invented depths, no shift against K), cameras by ``Camera.resized``. ``size`` is (H, W). A loaded
scene gets ``meta`` d_min/d_max from its depths, rounded as ``make_scene`` sets them. Inputs are
never modified.
"""
from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from ..core.camera import Camera
from ..core.checks import check_size
from ..core.views import Scene, View


def check_optional_size(size):
    """``size`` checked as (H, W) positive ints, or None (keep the size)."""
    return None if size is None else check_size(size)


def resize_view(rgb, depth, camera: Camera, size):
    """Resample a view to ``size`` (H, W): colour by area/linear, depth by nearest (no invented depths).

    Nearest is OpenCV's ``INTER_NEAREST_EXACT``: a new pixel takes the old pixel under its *centre*
    ((u + 0.5)·s − 0.5), the convention ``Camera.resized`` uses. Plain ``INTER_NEAREST`` takes the
    top-left one of each block, which shifts depth against colour and K by (s − 1)/2 old pixels."""
    if size is None or tuple(size) == depth.shape:
        return rgb, depth, camera
    H, W = size
    shrink = H < depth.shape[0] and W < depth.shape[1]
    rgb = cv2.resize(rgb, (W, H), interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
    depth = cv2.resize(depth, (W, H), interpolation=cv2.INTER_NEAREST_EXACT)
    return rgb, depth, camera.resized(W, H)


_PIXEL_META = ("doffs", "ndisp", "focal")  # meta entries in pixels: they scale with the image width


def resize_scene(scene: Scene, size) -> Scene:
    """A copy of ``scene`` with every view (and right view) resampled to ``size`` (H, W): colour by
    area (linear when enlarging), depth and labels by the nearest pixel centre (no invented depths),
    cameras by ``Camera.resized``; pixel-unit ``meta`` (doffs, ndisp, focal) scaled by the x factor,
    metre-unit ``meta`` (baseline, d_min, d_max, ...) kept. The input scene is not modified."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a ddp_lite.Scene, got {type(scene).__name__}")
    if not scene.views:
        raise ValueError("scene has no views to resize")
    H, W = check_optional_size(size)
    sx = W / scene.views[0].camera.width

    def view(v: View) -> View:
        rgb, depth, camera = resize_view(v.rgb, v.depth, v.camera, (H, W))
        return View(rgb.copy(), depth.copy(), camera, v.name)
    labels = [cv2.resize(np.asarray(l), (W, H), interpolation=cv2.INTER_NEAREST_EXACT) for l in scene.labels]
    meta = {k: (float(v) * sx if k in _PIXEL_META else v) for k, v in scene.meta.items()}
    return Scene(scene.name, [view(v) for v in scene.views], [view(v) for v in scene.right], meta, labels,
                 list(scene.sources))


def scene_depth_range(depths) -> dict:
    """``d_min``/``d_max`` for DDP's disparity transform, as ``make_scene`` sets them (empty if no depth)."""
    finite = np.concatenate([d[np.isfinite(d)] for d in depths])
    if finite.size == 0:
        return {}
    return {"d_min": float(np.floor(0.9 * finite.min() * 100.0)) / 100.0,
            "d_max": float(np.ceil(finite.max() * 100.0)) / 100.0}


def undistort_rgbd(rgb: np.ndarray, depth: np.ndarray, K: np.ndarray, dist) -> tuple[np.ndarray, np.ndarray]:
    """Remove OpenCV lens distortion (k1, k2, p1, p2[, k3]) from an RGB-D pair, keeping K.

    Colour is resampled bilinearly, depth by the nearest pixel (no invented depths); a point's z
    does not change when only its pixel moves, so depth values are kept as they are. Pixels that
    map outside the original image become black / NaN."""
    H, W = depth.shape
    map_x, map_y = cv2.initUndistortRectifyMap(K, np.asarray(dist, np.float64), None, K, (W, H), cv2.CV_32FC1)
    rgb = cv2.remap(rgb, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    raw = cv2.remap(np.nan_to_num(depth, nan=0.0), map_x, map_y, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT,
                    borderValue=0)
    return rgb, np.where(raw > 0, raw, np.nan).astype(np.float32)


def finish_scene(name: str, views: list[View], size, sources=()) -> Scene:
    """Resample the views to ``size`` (H, W) if given; d_min/d_max from the depths (as make_scene sets them);
    ``sources``: the folders and files the views were read from (``Scene.sources``)."""
    if size is not None:
        resized = [(resize_view(v.rgb, v.depth, v.camera, check_size(size)), v.name) for v in views]
        views = [View(rgb.copy(), depth.copy(), camera, name) for (rgb, depth, camera), name in resized]
    return Scene(name, views, [], scene_depth_range([v.depth for v in views]), [], _unique_paths(sources))


def _unique_paths(paths) -> list:
    """Absolute paths, each once, in order: what ``Scene.sources`` holds."""
    seen = []
    for path in paths:
        path = Path(path).absolute()
        if path not in seen:
            seen.append(path)
    return seen
