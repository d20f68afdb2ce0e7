"""Middlebury 2005/2006 scenes as calibrated multi-view scenes: seven views on a rail, and the truth.

Each 2005/2006 scene was photographed from seven positions on one horizontal rail, equally spaced and
rectified: ``view0.png`` … ``view6.png``, left to right. ``disp1.png`` is the ground truth of view1 (for
the pair view1–view5), ``disp5.png`` that of view5, ``dmin.txt`` the disparity offset of the crop at
full size. The dataset comes in three sizes, FullSize (≈ 1300 px wide), HalfSize and ThirdSize; a copy
reduced further (the kit ships Plastic, Baby1, Bowling1 and Art at a quarter) follows the same rule:

* disparity PNG: intensity = ``scale`` × the disparity at this size (``scale`` = 1, 2, 3, 4 for full,
  half, third, quarter), so intensity ≈ the full-size disparity; 0 = unknown → NaN depth;
* camera (the dataset's figures at full size): f = 3740 px, view1–view5 baseline 160 mm, one rail step
  40 mm. At a size: f = 3740 / scale, ``doffs`` = dmin / scale, and Z = f · 0.160 / (d + doffs)
  = 3740 · 0.160 / (intensity + dmin) metres, the same at every size;
* as pinhole cameras (OpenCV convention, x right, z forward; the world frame is view1's): view k sits at
  x = (k − 1) · 0.040 m with the same f and a principal point shifted by (k − 1) · doffs / 4, so that a
  pixel (x, y) of view1 with disparity d appears in view k at (x − (k − 1) · d / 4, y). View1's principal
  point is taken at the image centre (pixel (0, 0) is the centre of the top-left pixel); only the
  shifts between views matter for warping.

``load_rail_scene`` returns view1 as the reference ``scene[0]`` (ground-truth depth), the requested rail
neighbours after it (``neighbors=(0, 2)``: the paper's N = 2 nearest calibrated views), and view5 in
``scene.right`` (the stereo partner, with its own truth) for SGBM. ``load_middlebury_scene`` reads a
2005/2006 folder or a 2014 one (``calib.txt``; ``middlebury.load_middlebury``) alike;
``ground_truth_occlusion`` gives the reference pixels its stereo partner does not see.

Cite the dataset when you use or ship it: D. Scharstein and C. Pal, *Learning conditional random fields
for stereo*, CVPR 2007; H. Hirschmüller and D. Scharstein, *Evaluation of cost functions for stereo
matching*, CVPR 2007 (2005/2006); D. Scharstein et al., *High-resolution stereo datasets with
subpixel-accurate ground truth*, GCPR 2014 (2014).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.camera import Camera
from ..core.views import Scene, View
from .fileio import existing_path, read_image_file, read_rgb, read_text_file
from .installed import is_2014_folder, is_rail_folder
from .middlebury import check_scene_depth, load_middlebury, require_valid_depth
from .resample import check_optional_size, resize_scene, scene_depth_range

__all__ = ["FULL_FOCAL", "PAIR_BASELINE", "RAIL_STEP", "RAIL_VIEWS", "load_rail_scene", "load_middlebury_scene",
           "ground_truth_occlusion", "size_scale", "load_middlebury2006", "scene_disparity"]

FULL_FOCAL = 3740.0  # px, at full size
PAIR_BASELINE = 0.160  # m, view1 to view5
RAIL_STEP = PAIR_BASELINE / 4  # m between neighbouring views
RAIL_VIEWS = tuple(range(7))
_SIZE_SCALES = {1: (1100, 1500), 2: (550, 750), 3: (370, 549), 4: (270, 369)}  # scale: image widths (px) it covers


def size_scale(width: int) -> int:
    """The size of a 2005/2006 image from its width (px): 1 full, 2 half, 3 third, 4 quarter.

    Example:
        >>> size_scale(1270), size_scale(635), size_scale(423), size_scale(317)
        (1, 2, 3, 4)
    """
    for scale, (low, high) in _SIZE_SCALES.items():
        if low <= width <= high:
            return scale
    raise ValueError(f"width: a 2005/2006 Middlebury image is 270–1500 px wide (full, half, third or quarter "
                     f"size), got {width}; pass scale= (1, 2, 3 or 4) for another crop")


def _dmin(folder: Path) -> float:
    tokens = read_text_file(folder / "dmin.txt", "folder").split()  # a byte-order mark, CRLF: the same text
    try:
        if len(tokens) != 1:
            raise ValueError(f"it holds {len(tokens)} values{': ' + ' '.join(tokens[:4]) if tokens else ''}")
        dmin = float(tokens[0])
    except ValueError as error:
        raise ValueError(f"folder: {folder / 'dmin.txt'} must hold one number, the full-size disparity offset "
                         f"({error}); is it the right file?") from None
    if not np.isfinite(dmin) or dmin < 0:
        raise ValueError(f"folder: {folder / 'dmin.txt'} must hold a finite number ≥ 0, got {dmin}")
    return dmin


def _disparity_png(path: Path, shape) -> np.ndarray:
    """A disparity PNG → (H, W) float64 intensity (≈ full-size disparity px), NaN where 0 (unknown)."""
    raw = read_image_file(path, "folder", truth=True)  # a JPEG, whatever its name, is no ground truth
    if raw.ndim != 2 or raw.dtype != np.uint8:
        raise ValueError(f"folder: {path} must be an 8-bit 1-channel disparity PNG, got {raw.dtype} {raw.shape}")
    if raw.shape != shape:
        raise ValueError(f"folder: {path} is {raw.shape[0]}×{raw.shape[1]} but view1.png is {shape[0]}×{shape[1]} (H×W)")
    return np.where(raw > 0, raw.astype(np.float64), np.nan)


def _rail_camera(k: int, width: int, height: int, scale: int, dmin: float) -> Camera:
    """View k's camera at a size: f = 3740 / scale, centre at x = (k − 1) · 40 mm, cx shifted by (k − 1)·doffs/4."""
    focal = FULL_FOCAL / scale
    cx = (width - 1) / 2.0 + (k - 1) * (dmin / scale) / 4.0
    K = np.array([[focal, 0.0, cx], [0.0, focal, (height - 1) / 2.0], [0.0, 0.0, 1.0]])
    pose = np.eye(4)
    pose[0, 3] = -(k - 1) * RAIL_STEP  # cam_from_world: the centre (k − 1)·40 mm right of view1's
    return Camera(K, pose, width, height)


def load_rail_scene(folder, neighbors=(0, 2), size=None, scale: int | None = None, name: str | None = None) -> Scene:
    """A Middlebury 2005/2006 scene folder → calibrated multi-view ``Scene``.

    ``scene[0]`` is view1 with its ground-truth depth (H, W) metres (NaN unknown), ``scene[1:]`` the rail
    views ``neighbors`` (indices 0–6 other than 1; depth unknown, NaN), ``scene.right[0]`` view5 with the
    truth of ``disp5.png`` (NaN if absent). ``meta``: ``baseline`` 0.160 m (view1–view5), ``doffs`` (px at
    this size), ``focal`` (px), ``ndisp``, ``scale`` (1 full … 4 quarter), ``d_min``/``d_max`` (m).
    ``scale``: None infers it from the width (``size_scale``). ``size`` (H, W): resampled after loading
    (colour by area, depth by nearest pixel centre, cameras and pixel meta accordingly).

    Example:
        >>> from ddp_lite.data.samples import sample_scene
        >>> scene = load_rail_scene(sample_scene("Plastic"))
        >>> len(scene), scene.meta["scale"], round(scene.meta["baseline"], 2)
        (3, 4.0, 0.16)
    """
    folder = existing_path(folder, "folder")
    if not folder.is_dir() or not is_rail_folder(folder):
        raise ValueError(f"folder: {folder} must be a 2005/2006 Middlebury scene folder holding view1.png, "
                         f"disp1.png and dmin.txt (view0…view6.png, disp5.png optional)")
    neighbors = tuple(neighbors)
    bad = [k for k in neighbors if isinstance(k, bool) or k not in RAIL_VIEWS or k == 1]
    if bad or len(set(neighbors)) != len(neighbors):
        raise ValueError(f"neighbors must be distinct rail view indices in 0–6 other than 1 (view1 is the "
                         f"reference), got {neighbors!r}")
    missing = [f"view{k}.png" for k in (*neighbors, 5) if not (folder / f"view{k}.png").is_file()]
    if missing:
        raise ValueError(f"folder: {folder} lacks {', '.join(missing)} (asked for neighbours {neighbors} and the "
                         f"stereo partner view5)")
    size = check_optional_size(size)
    dmin = _dmin(folder)
    rgb1 = read_rgb(folder / "view1.png", "folder")
    H, W = rgb1.shape[:2]
    if scale is None:
        scale = size_scale(W)
    elif isinstance(scale, bool) or scale not in (1, 2, 3, 4):
        raise ValueError(f"scale must be 1 (full), 2 (half), 3 (third) or 4 (quarter size), got {scale!r}")

    def depth_of(file: str) -> np.ndarray:
        if not (folder / file).is_file():
            return np.full((H, W), np.nan, np.float32)
        intensity = _disparity_png(folder / file, (H, W))
        return (FULL_FOCAL * PAIR_BASELINE / (intensity + dmin)).astype(np.float32)

    def view(k: int, depth: np.ndarray) -> View:
        rgb = rgb1 if k == 1 else read_rgb(folder / f"view{k}.png", "folder")
        if rgb.shape[:2] != (H, W):
            raise ValueError(f"folder: view{k}.png is {rgb.shape[0]}×{rgb.shape[1]} but view1.png is {H}×{W} (H×W)")
        return View(rgb, depth, _rail_camera(k, W, H, scale, dmin), f"view{k}")
    depth1 = require_valid_depth(depth_of("disp1.png"), "folder", folder / "disp1.png")
    check_scene_depth(depth1, "folder", folder / "disp1.png", f"check dmin.txt ({dmin:g} px at full size) and that "
                                                              f"disp1.png is the dataset's disparity (intensity = "
                                                              f"{scale} × disparity)")
    unknown = np.full((H, W), np.nan, np.float32)
    meta = {"baseline": PAIR_BASELINE, "doffs": dmin / scale, "focal": FULL_FOCAL / scale,
            "ndisp": float(np.ceil(256.0 / scale)), "scale": float(scale), **scene_depth_range([depth1])}
    scene = Scene(name or folder.name, [view(1, depth1)] + [view(k, unknown) for k in neighbors],
                  [view(5, depth_of("disp5.png"))], meta, sources=[folder])
    return scene if size is None else resize_scene(scene, size)


def load_middlebury_scene(folder, neighbors=(0, 2), size=None, name: str | None = None) -> Scene:
    """Any Middlebury scene folder with ground truth → ``Scene`` with view1 / im0 as ``scene[0]``:
    a 2005/2006 folder (``load_rail_scene``: rail neighbours, view5 as the stereo partner) or a 2014 one
    (``middlebury.load_middlebury``: im1 as the stereo partner, which is also its only neighbour)."""
    folder = existing_path(folder, "folder")
    if is_rail_folder(folder):
        return load_rail_scene(folder, neighbors, size, name=name)
    if is_2014_folder(folder):
        return load_middlebury(folder, size, name)
    raise ValueError(f"folder: {folder} is not a Middlebury scene with ground truth: expected view1.png, "
                     f"disp1.png and dmin.txt (2005/2006) or im0.png, calib.txt and disp0GT.pfm (2014)")


def load_middlebury2006(folder, size=None, name: str | None = None) -> Scene:
    """A Middlebury 2005/2006 scene folder (view1.png, view5.png, disp1.png, dmin.txt; disp5.png optional), at
    any of the dataset's sizes → one-view stereo ``Scene`` (view1 and view5): ``load_rail_scene`` with no
    rail neighbours, which gives the calibration (f = 3740 px / size, baseline 160 mm, ``doffs``)."""
    return load_rail_scene(folder, neighbors=(), size=size, name=name)


def scene_disparity(scene: Scene, depth) -> np.ndarray:
    """Depth (H, W) metres of ``scene[0]`` → disparity (H, W) px of its stereo pair at the scene's size,
    d = f·B / Z − doffs (NaN stays NaN).

    Example:
        >>> from ddp_lite.data.samples import sample_scene
        >>> scene = load_rail_scene(sample_scene("Plastic"))
        >>> d = scene_disparity(scene, scene[0].depth)
        >>> bool(np.nanmin(d) > 0)
        True
    """
    fb = float(scene[0].camera.focal * scene.meta["baseline"])
    with np.errstate(divide="ignore", invalid="ignore"):
        return (fb / np.asarray(depth, np.float64) - float(scene.meta.get("doffs", 0.0))).astype(np.float32)


def ground_truth_occlusion(folder, tolerance: float = 1.0) -> np.ndarray:
    """The reference pixels the stereo partner does not see, from the ground truth → (H, W) bool at the
    folder's own size. 2014: ``mask0nocc.png`` == 128. 2005/2006: view1's pixel x with disparity d lands
    at x − d in view5; it is occluded where it falls outside view5 or where view5's truth there is nearer
    by more than ``tolerance`` px (the left-right cross-check on the truth). Unknown truth → False."""
    folder = existing_path(folder, "folder")
    if is_2014_folder(folder):
        mask = read_image_file(folder / "mask0nocc.png", "folder", truth=True)
        if mask.ndim != 2:
            raise ValueError(f"folder: {folder / 'mask0nocc.png'} must be a 1-channel mask (255 seen, 128 occluded)")
        return mask == 128
    if not is_rail_folder(folder) or not (folder / "disp5.png").is_file():
        raise ValueError(f"folder: {folder} needs disp1.png and disp5.png (2005/2006) or mask0nocc.png (2014)")
    shape = read_image_file(folder / "disp1.png", "folder", truth=True).shape
    scale = size_scale(shape[1])
    d1 = _disparity_png(folder / "disp1.png", shape) / scale  # (H, W) px at this size
    d5 = _disparity_png(folder / "disp5.png", shape) / scale
    H, W = shape
    columns = np.arange(W)[None, :] - np.nan_to_num(d1, nan=0.0)
    target = np.rint(columns).astype(int)
    outside = np.isfinite(d1) & (target < 0)
    inside = np.clip(target, 0, W - 1)
    seen = d5[np.arange(H)[:, None], inside]
    with np.errstate(invalid="ignore"):
        hidden = np.isfinite(d1) & np.isfinite(seen) & (seen > d1 + tolerance)
    return outside | (hidden & ~outside)
