"""A Kinect-v1-style (structured light) reading of an exact depth map: where it has holes and how it is noisy.

A structured-light sensor projects a dot pattern from a projector a baseline ``b`` (≈ 7.5 cm) to
the side of its IR camera and measures each dot's disparity against a reference pattern. So:

- **projector shadow**: a surface the projector cannot see gets no dots, hence no depth. With the
  projector at ``+b`` along the camera's x axis (rows are epipolar lines), a point at column u and
  depth z lies on projector column ``x_p = u − f·b / z``; it is hidden from the projector when a
  point to its right (nearer the projector's side) has a projector column at or left of its own:
  ``min_{u' > u} x_p(u') < x_p(u)``. The shadow falls beside depth edges, on the background side
  away from the projector (left of objects for b > 0), ``f·b·(1/z_near − 1/z_far)`` px wide;
- **grazing surfaces**: dots on a surface seen at a grazing angle are smeared and not decoded;
  pixels whose surface normal (from the depth itself) is more than ``grazing_deg`` from the
  viewing ray drop out, depth edges included (there the normal mixes two surfaces);
- **dark surfaces**: too little IR comes back; pixels whose grey level (a stand-in for IR albedo)
  is below ``dark_level`` drop out with probability ``dark_dropout``;
- **range**: no reading nearer than ``depth_range[0]`` or farther than ``depth_range[1]``;
- **disparity quantisation**: the sensor's disparity ``f_s·b / z`` (``f_s`` the IR camera's focal
  length, ≈ 580 px at 480×640, in *its* pixels, not the image's) is measured with noise
  ``disparity_noise`` px and rounded to 1/``subpixel`` px (1/8 for Kinect v1), so the depth
  steps are ``z² / (subpixel·f_s·b)`` and the depth noise grows as z².

Depth in metres (H, W), NaN = no reading; cameras in the OpenCV convention. Inputs are never
modified; randomness only from ``seed``.
"""
from __future__ import annotations

import numpy as np

from ..core.camera import Camera
from ..core.checks import check_depth, check_image, check_int, check_real

__all__ = ["KINECT", "projector_shadow", "grazing_mask", "quantise_depth", "kinect_holes", "kinect_depth"]

KINECT = dict(projector_offset=0.075, sensor_focal=580.0, subpixel=8, disparity_noise=0.05,
              depth_range=(0.5, 4.5), grazing_deg=80.0, dark_level=0.06, dark_dropout=0.7)
"""Kinect v1 figures: baseline 7.5 cm, IR focal 580 px, 1/8-px disparity, 0.5–4.5 m."""

_GREY = np.array([0.2989, 0.5870, 0.1140])


def _depth_and_camera(depth, camera) -> tuple[np.ndarray, Camera]:
    if not isinstance(camera, Camera):
        raise TypeError(f"camera must be a ddp_lite.Camera, got {type(camera).__name__}")
    array = check_depth(depth, "depth", min_valid=0, shape=(camera.height, camera.width), dtype=np.float64)
    return array, camera


def projector_shadow(depth, camera: Camera, projector_offset: float = 0.075, tolerance: float = 0.25) -> np.ndarray:
    """(H, W) bool, True where the projector, ``projector_offset`` metres along the camera's x axis
    (negative: to the left), cannot see the surface of ``depth`` (H, W) metres (NaN: no surface, casts
    no shadow). ``tolerance`` px of projector column keeps round-off on slanted surfaces from counting.

    Example:
        >>> cam = Camera.from_fov(12, 1, 90.0)  # f = 6 px
        >>> depth = np.array([[2.0] * 6 + [1.0] * 3 + [2.0] * 3])  # a near box, columns 6–8
        >>> # background centres within f·b·(1/1 − 1/2) = 3.3 px left of the box's first one (column 6)
        >>> projector_shadow(depth, cam, projector_offset=1.1).astype(int).tolist()
        [[0, 0, 0, 1, 1, 1, 0, 0, 0, 0, 0, 0]]
    """
    depth, camera = _depth_and_camera(depth, camera)
    offset = check_real(projector_offset, "projector_offset")
    if offset == 0.0:
        return np.zeros(depth.shape, bool)
    tolerance = check_real(tolerance, "tolerance", 0.0)
    u = np.arange(depth.shape[1], dtype=np.float64)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        column = u - camera.K[0, 0] * offset / depth  # (H, W) projector column, NaN where no surface
    if offset < 0:  # mirror: a projector on the left sees along the row the other way
        column = -column[:, ::-1]
    blockers = np.where(np.isfinite(column), column, np.inf)
    # the smallest projector column of the points strictly to the right of each pixel
    right_min = np.minimum.accumulate(blockers[:, ::-1], axis=1)[:, ::-1]
    right_min = np.concatenate([right_min[:, 1:], np.full((depth.shape[0], 1), np.inf)], axis=1)
    shadow = np.isfinite(column) & (right_min < column - tolerance)
    return shadow[:, ::-1] if offset < 0 else shadow


def grazing_mask(depth, camera: Camera, grazing_deg: float = 80.0) -> np.ndarray:
    """(H, W) bool, True where the surface normal of ``depth`` (H, W) metres (central differences of the
    back-projected points; one-sided at the image border) is more than ``grazing_deg`` from the viewing
    ray; False where it cannot be computed (a NaN neighbour: no evidence either way)."""
    depth, camera = _depth_and_camera(depth, camera)
    limit = check_real(grazing_deg, "grazing_deg", 0.0, 90.0)
    H, W = depth.shape
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    points = np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(camera.K).T * depth[..., None]  # (H, W, 3)
    dv, du = np.gradient(points, axis=(0, 1))  # central differences, one-sided at the border
    normal = np.cross(du, dv)
    with np.errstate(invalid="ignore", divide="ignore"):
        cosine = np.abs(np.sum(normal * points, -1)) / (np.linalg.norm(normal, axis=-1) * np.linalg.norm(points, axis=-1))
        return cosine < np.cos(np.radians(limit))  # NaN (an unknown neighbour): no evidence, not grazing


def quantise_depth(depth, sensor_focal: float = 580.0, baseline: float = 0.075, subpixel: int = 8,
                   disparity_noise: float = 0.0, seed: int = 0) -> np.ndarray:
    """(H, W) metres → (H, W) float32 metres as a structured-light sensor reads them: disparity
    ``sensor_focal·baseline / z`` (px of the sensor) plus Gaussian noise ``disparity_noise`` px, rounded
    to 1/``subpixel`` px, turned back into depth. NaN stays NaN, and so does a disparity rounded to 0.

    Example:
        >>> quantise_depth(np.array([[2.0]]), sensor_focal=100.0, baseline=0.1, subpixel=1).tolist()  # d = 5 px
        [[2.0]]
    """
    clean = check_depth(depth, "depth", min_valid=0, dtype=np.float64)
    focal = check_real(sensor_focal, "sensor_focal", 0.0, None, low_open=True)
    baseline = check_real(baseline, "baseline", 0.0, None, low_open=True)
    subpixel = check_int(subpixel, "subpixel", minimum=1)
    noise = check_real(disparity_noise, "disparity_noise", 0.0)
    rng = np.random.default_rng(check_int(seed, "seed", minimum=0))
    fb = focal * baseline
    disparity = fb / clean + noise * rng.standard_normal(clean.shape)
    levels = np.round(disparity * subpixel) / subpixel
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(levels > 0, fb / levels, np.nan)
    return out.astype(np.float32)


def kinect_holes(depth, camera: Camera, rgb=None, seed: int = 0, projector_offset: float = KINECT["projector_offset"],
                 depth_range=KINECT["depth_range"], grazing_deg: float = KINECT["grazing_deg"],
                 dark_level: float = KINECT["dark_level"], dark_dropout: float = KINECT["dark_dropout"]) -> dict:
    """Why a Kinect gives no reading at each pixel of exact ``depth`` (H, W) metres seen by ``camera``:
    ``{"shadow", "grazing", "dark", "range"}`` → (H, W) bool masks (they overlap). ``rgb`` (H, W, 3) in
    [0, 1] drives the dark-surface dropouts (without it there are none)."""
    clean, camera = _depth_and_camera(depth, camera)
    near, far = (check_real(x, "depth_range", 0.0) for x in depth_range)
    if not 0 < near < far:
        raise ValueError(f"depth_range must be (near, far) metres with 0 < near < far, got {depth_range!r}")
    level = check_real(dark_level, "dark_level", 0.0, 1.0)
    dropout = check_real(dark_dropout, "dark_dropout", 0.0, 1.0)
    rng = np.random.default_rng(check_int(seed, "seed", minimum=0))
    dark = np.zeros(clean.shape, bool)
    if rgb is not None:
        grey = check_image(rgb, "rgb", clean.shape).astype(np.float64) @ _GREY
        dark = (grey < level) & (rng.random(clean.shape) < dropout)
    with np.errstate(invalid="ignore"):
        out_of_range = ~((clean >= near) & (clean <= far))
    return {"shadow": projector_shadow(clean, camera, projector_offset),
            "grazing": grazing_mask(clean, camera, grazing_deg),
            "dark": dark, "range": out_of_range}


def kinect_depth(depth, camera: Camera, rgb=None, seed: int = 0, **options):
    """A Kinect-v1-style reading of exact ``depth`` (H, W) metres seen by ``camera`` → ``(depth, mask)``:
    float32 metres with NaN where ``kinect_holes`` finds no reading, the rest quantised as
    ``quantise_depth`` does, and the valid mask (H, W) bool. ``options`` override ``KINECT``'s entries.

    Example:
        >>> from ddp_lite.world.scenes import make_scene
        >>> view = make_scene("desk", size=(48, 64), n_views=1)[0]
        >>> reading, mask = kinect_depth(view.depth, view.camera, view.rgb)
    """
    unknown = set(options) - set(KINECT)
    if unknown:
        raise ValueError(f"unknown options {sorted(unknown)}; known: {sorted(KINECT)}")
    settings = {**KINECT, **options}
    if check_real(settings["projector_offset"], "projector_offset") == 0.0:
        raise ValueError("projector_offset must be non-zero: it is also the baseline the disparity is measured on")
    causes = kinect_holes(depth, camera, rgb, seed, settings["projector_offset"], settings["depth_range"],
                          settings["grazing_deg"], settings["dark_level"], settings["dark_dropout"])
    reading = quantise_depth(depth, settings["sensor_focal"], abs(settings["projector_offset"]),
                             settings["subpixel"], settings["disparity_noise"], seed + 1)
    missing = np.logical_or.reduce(list(causes.values()))
    reading[missing] = np.nan
    return reading, np.isfinite(reading)
