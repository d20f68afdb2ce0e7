"""Middlebury stereo (2014 and 2005/2006) → a one-view stereo ``Scene``, and a tiny offline fixture.

* **calib.txt** (2014): ``cam0=[f 0 cx0; 0 f cy; 0 0 1]``, ``cam1=[...]``, ``doffs`` = cx1 − cx0
  (px), ``baseline`` (mm), ``width``, ``height``, ``ndisp``; depth Z = f·B / (d + doffs).
  Disparities are PFM (``disp0.pfm``), ``inf`` = unknown → NaN.
* **2005/2006**: read by ``middlebury_rail`` (seven views on a rail, any of the dataset's sizes);
  its ``load_middlebury2006`` gives the stereo pair alone.

A stereo scene has the left view at the world origin, the rectified right view in ``right``,
``meta`` baseline (m), doffs/ndisp/focal (px), d_min/d_max (m). ``MiddleburyCalib`` and
``stereo_scene`` serve KITTI too (``datasets.load_kitti``). ``load_motorcycle`` reads the real
Middlebury 2014 pair that scikit-image ships (offline); ``make_middlebury_fixture`` writes a tiny
Middlebury-2014-format scene from the kit's renderer, for tests of the file readers.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from ..core.files import write_bytes_atomic
from ..core.camera import Camera, check_intrinsics
from .file_writers import rgb_png_bytes, write_pfm
from .fileio import existing_path, read_image_file, read_pfm, read_rgb, read_text_file
from .resample import check_optional_size, scene_depth_range, resize_scene
from ..world.scenes import make_scene  # the renderer, for make_middlebury_fixture only
from ..classical.stereo import disparity_to_depth, pixel_disparity
from ..core.views import Scene, View


MIN_BASELINE_MM = 10.0  # a calib.txt baseline below it is metres written as millimetres (Middlebury's: 100–600 mm)


def check_scene_depth(depth: np.ndarray, what: str, path, cause: str) -> None:
    """Refuse ground-truth depth (H, W) metres, NaN unknown, whose valid values no scene of a stereo dataset
    holds (any depth outside ``fileio.DEPTH_RANGE_M``, or a median outside ``fileio.MEDIAN_RANGE_M``): a unit
    or calibration error (``cause`` names the suspect), refused before it is used as truth."""
    from .fileio import DEPTH_RANGE_M, MEDIAN_RANGE_M
    valid = depth[np.isfinite(depth)]
    if not valid.size:
        return
    low, high, median = float(valid.min()), float(valid.max()), float(np.median(valid))
    if not (DEPTH_RANGE_M[0] <= low and high <= DEPTH_RANGE_M[1] and MEDIAN_RANGE_M[0] <= median <= MEDIAN_RANGE_M[1]):
        raise ValueError(f"{what}: {path} gives depths {low:.3g}–{high:.3g} m (median {median:.3g} m), which no scene "
                         f"holds (depths within {DEPTH_RANGE_M[0]:g}–{DEPTH_RANGE_M[1]:g} m, median within "
                         f"{MEDIAN_RANGE_M[0]:g}–{MEDIAN_RANGE_M[1]:g} m): {cause}")


def require_valid_depth(depth: np.ndarray, what: str, path) -> np.ndarray:
    """Refuse a ground-truth map with no valid pixel: it is a wrong file, not a scene."""
    if not np.isfinite(depth).any():
        raise ValueError(f"{what}: {path} has no valid disparity (every pixel is the 'unknown' marker)")
    return depth


@dataclass(frozen=True, eq=False)
class MiddleburyCalib:
    """A Middlebury ``calib.txt``: ``K0``/``K1`` (3×3 px), ``doffs`` (px, cx1 − cx0), ``baseline``
    (**metres**; the file gives mm), ``width``/``height``/``ndisp`` (px), ``extra`` (other keys)."""

    K0: np.ndarray
    K1: np.ndarray
    doffs: float
    baseline: float
    width: int
    height: int
    ndisp: int
    extra: dict = field(default_factory=dict)

    @property
    def focal(self) -> float:
        """Focal length f (px) of the left camera, the f in Z = f·B / (d + doffs)."""
        return float(self.K0[0, 0])

    def cameras(self) -> tuple[Camera, Camera]:
        """``(left, right)``: left at the world origin, right translated by ``baseline`` metres along x."""
        right_pose = np.eye(4)
        right_pose[0, 3] = -self.baseline  # camera centre at (+B, 0, 0) in the left camera's frame
        return (Camera(self.K0, np.eye(4), self.width, self.height),
                Camera(self.K1, right_pose, self.width, self.height))

    def depth(self, disparity) -> np.ndarray:
        """Disparity (H, W) px → depth (H, W) float32 metres; ``inf`` → NaN."""
        return disparity_to_depth(disparity, self.focal, self.baseline, self.doffs)


def _matrix(text: str, key: str) -> np.ndarray:
    rows = [r.split() for r in text.strip().strip("[]").split(";")]
    try:
        K = np.array(rows, dtype=np.float64)
    except ValueError:
        raise ValueError(f"text: {key} must be a 3×3 matrix like [f 0 cx; 0 f cy; 0 0 1], got {text!r}") from None
    if K.shape != (3, 3):
        raise ValueError(f"text: {key} must be 3×3, got shape {K.shape}")
    return K


def parse_middlebury_calib(text: str) -> MiddleburyCalib:
    """The contents of a Middlebury ``calib.txt`` → ``MiddleburyCalib`` (baseline converted mm → m)."""
    if not isinstance(text, str):
        raise ValueError(f"text must be the contents of calib.txt (str), got {type(text).__name__}")
    entries = {}
    for line in text.splitlines():
        if "=" in line:
            key, value = line.split("=", 1)
            if key.strip() in entries:
                raise ValueError(f"text: {key.strip()} appears twice in calib.txt")
            entries[key.strip()] = value.strip()
    missing = [k for k in ("cam0", "cam1", "doffs", "baseline", "width", "height", "ndisp") if k not in entries]
    if missing:
        raise ValueError(f"text: calib.txt lacks {', '.join(missing)}")
    try:
        numbers = {k: float(v) for k, v in entries.items() if k not in ("cam0", "cam1")}
    except ValueError as error:
        raise ValueError(f"text: a calib.txt value is not a number ({error})") from None
    for key in ("doffs", "baseline", "width", "height", "ndisp"):
        if not np.isfinite(numbers[key]):
            raise ValueError(f"text: {key} must be a finite number, got {entries[key]!r}")
    if numbers["baseline"] <= 0:
        raise ValueError(f"text: baseline must be positive (mm), got {numbers['baseline']}")
    if numbers["baseline"] < MIN_BASELINE_MM:  # metres written where millimetres belong: depths 1000× too near
        raise ValueError(f"text: baseline is {entries['baseline']}, read as millimetres ({numbers['baseline'] / 1000:.3g} "
                         f"m), less than the {MIN_BASELINE_MM:g} mm of any stereo rig in this format (Middlebury's "
                         f"are about 100–600 mm); a calib.txt gives the baseline in millimetres: is it in metres "
                         f"({numbers['baseline']:g} m would be baseline={numbers['baseline'] * 1000:g})?")
    for key in ("width", "height", "ndisp"):
        if numbers[key] != int(numbers[key]) or numbers[key] <= 0:
            raise ValueError(f"text: {key} must be a positive integer, got {entries[key]!r}")
    K0, K1 = _matrix(entries["cam0"], "cam0"), _matrix(entries["cam1"], "cam1")
    for key, K in (("cam0", K0), ("cam1", K1)):
        check_intrinsics(K, int(numbers["width"]), int(numbers["height"]), f"text: {key}")
    extra = {k: v for k, v in numbers.items() if k not in ("doffs", "baseline", "width", "height", "ndisp")}
    return MiddleburyCalib(K0, K1, numbers["doffs"], numbers["baseline"] / 1000.0, int(numbers["width"]),
                           int(numbers["height"]), int(numbers["ndisp"]), extra)


def read_middlebury_calib(path) -> MiddleburyCalib:
    """Read a Middlebury ``calib.txt`` file (see ``parse_middlebury_calib``)."""
    text = read_text_file(path, "path")
    try:
        return parse_middlebury_calib(text)
    except ValueError as error:
        raise ValueError(f"{error} (in {path})") from None


def stereo_scene(name, rgb0, rgb1, depth0, depth1, calib: MiddleburyCalib, size) -> Scene:
    """A one-view stereo Scene (left view + rectified right view) from loaded arrays."""
    size = check_optional_size(size)
    cam0, cam1 = calib.cameras()
    for what, array in (("left image", rgb0), ("right image", rgb1), ("left depth", depth0), ("right depth", depth1)):
        if array.shape[:2] != (calib.height, calib.width):
            raise ValueError(f"{what} is {array.shape[0]}×{array.shape[1]} but calib says {calib.height}×{calib.width} (H×W)")
    # the depth range comes from the full-resolution map, so it does not depend on ``size``
    meta = {"baseline": float(calib.baseline), "doffs": float(calib.doffs), "ndisp": float(calib.ndisp),
            "focal": cam0.focal, **scene_depth_range([depth0])}
    scene = Scene(name, [View(rgb0, depth0, cam0, f"{name}-left")], [View(rgb1, depth1, cam1, f"{name}-right")], meta)
    return scene if size is None else resize_scene(scene, size)


def load_middlebury(folder, size=None, name: str | None = None) -> Scene:
    """A Middlebury 2014 scene folder (im0.png, im1.png, disp0.pfm or MiddEval3's disp0GT.pfm, calib.txt;
    disp1.pfm optional) →
    one-view stereo ``Scene``: GT depth (metres, NaN where disparity is inf), ``right`` view, and
    ``meta`` (baseline m, doffs px, ndisp, focal px, d_min, d_max). ``size`` (H, W) resamples
    (colour by area, depth by nearest, K accordingly). Note: Z = f·B/(d + doffs), doffs ≠ 0 here."""
    folder = existing_path(folder, "folder")
    calib = read_middlebury_calib(folder / "calib.txt")
    truth = folder / "disp0.pfm" if (folder / "disp0.pfm").exists() or not (folder / "disp0GT.pfm").exists() \
        else folder / "disp0GT.pfm"  # the evaluation set's (MiddEval3) name for the same file
    disparity = read_pfm(truth)
    if disparity.ndim != 2:
        raise ValueError(f"folder: {truth} must be a 1-channel PFM")
    depth0 = require_valid_depth(calib.depth(disparity), "folder", truth)
    check_scene_depth(depth0, "folder", truth, f"check calib.txt's baseline ({calib.baseline * 1000:g} mm), focal "
                                              f"({calib.focal:g} px) and doffs ({calib.doffs:g} px)")
    depth1 = calib.depth(read_pfm(folder / "disp1.pfm")) if (folder / "disp1.pfm").exists() \
        else np.full_like(depth0, np.nan)
    return stereo_scene(name or folder.name, read_rgb(folder / "im0.png", "folder"),
                         read_rgb(folder / "im1.png", "folder"), depth0, depth1, calib, size)


# scikit-image's Motorcycle pair: Middlebury 2014, down-sampled 4× (its docstring gives the calibration)
MOTORCYCLE_CALIB = dict(focal=994.978, cx=311.193, cy=254.877, doffs=31.086, baseline_mm=193.001, ndisp=70)


def load_motorcycle(size=None) -> Scene:
    """The real Middlebury 2014 *Motorcycle* pair shipped by scikit-image (500×741, offline) → one-view
    stereo ``Scene``: left view with ground-truth depth (metres, NaN where the truth is unknown, 7 % of
    the pixels), the rectified right view (depth unknown), ``meta`` as ``load_middlebury``. ``size`` (H, W)
    resamples (colour by area, depth by nearest pixel centre, K and doffs accordingly).

    Z = f·B / (d + doffs) with f 994.978 px, B 193.001 mm, doffs 31.086 px: 2.1–5.0 m.

    Example:
        >>> scene = load_motorcycle(size=(125, 185))
        >>> scene[0].depth.shape, round(scene.meta["baseline"], 3)
        ((125, 185), 0.193)
    """
    from skimage import data  # the notebooks' stack; imported here so the module loads without it

    left, right, disparity = data.stereo_motorcycle()  # (500, 741, 3) uint8 ×2, (500, 741) px, NaN unknown
    c = MOTORCYCLE_CALIB
    K0 = np.array([[c["focal"], 0.0, c["cx"]], [0.0, c["focal"], c["cy"]], [0.0, 0.0, 1.0]])
    K1 = K0.copy()
    K1[0, 2] += c["doffs"]
    H, W = disparity.shape
    calib = MiddleburyCalib(K0, K1, c["doffs"], c["baseline_mm"] / 1000.0, W, H, c["ndisp"])
    depth0 = calib.depth(np.where(np.isfinite(disparity), disparity, np.inf))
    rgb0, rgb1 = (np.asarray(image, np.float32) / 255.0 for image in (left, right))
    return stereo_scene("motorcycle", rgb0, rgb1, depth0, np.full_like(depth0, np.nan), calib, size)


def make_middlebury_fixture(folder, size=(48, 64), seed: int = 0, scene: str = "desk",
                            hole_fraction: float = 0.1) -> Path:
    """Write a tiny Middlebury-2014-format scene (im0.png, im1.png, disp0.pfm, disp1.pfm, calib.txt)
    rendered by ``make_scene(scene, size, n_views=1, seed)`` into ``folder``; ``hole_fraction`` of
    disp0 is set to ``inf`` (unknown). doffs = 0 (the renderer's right view shares K). Returns the folder."""
    size = check_optional_size(size)
    if not 0.0 <= hole_fraction < 1.0:
        raise ValueError(f"hole_fraction must be in [0, 1), got {hole_fraction!r}")
    synthetic = make_scene(scene, size=size, n_views=1, seed=seed)
    left, right = synthetic.views[0], synthetic.right[0]
    K, baseline = left.camera.K, float(synthetic.meta["baseline"])
    disp0, disp1 = (pixel_disparity(v.depth, K[0, 0], baseline) for v in (left, right))  # doffs = 0
    rng = np.random.default_rng(seed)
    disp0[rng.random(disp0.shape) < hole_fraction] = np.inf
    return _write_middlebury_folder(folder, left.rgb, right.rgb, disp0, disp1, K, right.camera.K, 0.0, baseline)


def write_motorcycle_folder(folder) -> Path:
    """Write the real pair of ``load_motorcycle`` (scikit-image's, 500×741) into ``folder`` in Middlebury
    2014's own file format (im0.png, im1.png, disp0.pfm with ``inf`` = unknown, calib.txt with ``doffs``
    and the baseline in mm), so that ``load_middlebury`` reads it like a fetched scene. Returns the folder."""
    from skimage import data

    left, right, disparity = data.stereo_motorcycle()
    c = MOTORCYCLE_CALIB
    K0 = np.array([[c["focal"], 0.0, c["cx"]], [0.0, c["focal"], c["cy"]], [0.0, 0.0, 1.0]])
    K1 = K0.copy()
    K1[0, 2] += c["doffs"]
    disp0 = np.where(np.isfinite(disparity), disparity, np.inf).astype(np.float32)
    disp1 = np.full_like(disp0, np.inf)  # the right view's truth is not shipped
    return _write_middlebury_folder(folder, left.astype(np.float32) / 255.0, right.astype(np.float32) / 255.0,
                                    disp0, disp1, K0, K1, c["doffs"], c["baseline_mm"] / 1000.0, ndisp=c["ndisp"])


def _write_middlebury_folder(folder, rgb0, rgb1, disp0, disp1, K0, K1, doffs: float, baseline: float,
                             ndisp: int | None = None) -> Path:
    """im0.png, im1.png, disp0.pfm, disp1.pfm and calib.txt of a Middlebury 2014 scene, each written atomically."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)

    def matrix(M):
        return "[" + "; ".join(" ".join(repr(float(v)) for v in row) for row in M) + "]"
    finite = disp0[np.isfinite(disp0)]
    H, W = disp0.shape
    ndisp = int(np.ceil(finite.max())) + 1 if ndisp is None else int(ndisp)
    calib = (f"cam0={matrix(K0)}\ncam1={matrix(K1)}\ndoffs={float(doffs)!r}\nbaseline={baseline * 1000.0!r}\n"
             f"width={W}\nheight={H}\nndisp={ndisp}\nisint=0\n"
             f"vmin={int(np.floor(finite.min()))}\nvmax={int(np.ceil(finite.max()))}\n")
    write_bytes_atomic(folder / "im0.png", rgb_png_bytes(rgb0))
    write_bytes_atomic(folder / "im1.png", rgb_png_bytes(rgb1))
    write_pfm(folder / "disp0.pfm", disp0)
    write_pfm(folder / "disp1.pfm", disp1)
    write_bytes_atomic(folder / "calib.txt", calib.encode("ascii"))
    return folder
