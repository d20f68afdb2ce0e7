"""Loaders: files fetched by ``data_fetch`` → the kit's own ``Scene`` / ``View`` / ``Camera``.

Every loader turns its dataset's "no value" marker into NaN here and nowhere else (Middlebury:
``inf`` disparity; KITTI: 0 in the 16-bit PNG; NYU: 0 depth; Middlebury 2006: 0 disparity), and
returns depth as float32 metres, images as float32 (H, W, 3) in [0, 1], cameras in the OpenCV
convention with the (left / first) camera at the world origin.

Formats:

* **PFM** (Middlebury 2014 disparities): header ``PF`` (3 channels) or ``Pf`` (1 channel), then
  ``width height``, then a scale whose *sign* gives the byte order (negative = little-endian),
  each ending in one whitespace byte; float32 rows follow **bottom to top**.
* **Middlebury calib.txt**: ``cam0=[f 0 cx0; 0 f cy; 0 0 1]``, ``cam1=[...]``, ``doffs`` = cx1 − cx0
  (px), ``baseline`` (mm), ``width``, ``height``, ``ndisp``; depth Z = f·B / (d + doffs).
* **KITTI 2015**: disparity PNG uint16, d = value / 256, 0 = no ground truth; calibration
  ``P_rect_02``/``P_rect_03`` (3×4), baseline = (P2[0,3] − P3[0,3]) / f.
* **Tanks and Temples, MVSNet cams** ``<id>_cam.txt``: ``extrinsic`` + 4×4 world→camera,
  ``intrinsic`` + 3×3, then ``depth_min depth_interval [depth_num depth_max]``.
* **NYU Depth v2**: labelled ``.mat`` (HDF5, read with h5py) or an image + a depth PNG/NPY in mm.

``make_middlebury_fixture`` writes a tiny Middlebury-format scene from the kit's renderer, so
tests and notebooks can run the real-data path offline.
"""
from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from .atomic import write_bytes_atomic
from .camera import Camera
from .checks import check_size
from .scenes import make_scene  # the renderer, for make_middlebury_fixture only
from .stereo import disparity_to_depth, pixel_disparity  # disparity_to_depth re-exported: its old home
from .views import Scene, View

__all__ = ["read_pfm", "write_pfm", "MiddleburyCalib", "parse_middlebury_calib", "read_middlebury_calib",
           "disparity_to_depth", "load_middlebury", "load_middlebury2006", "make_middlebury_fixture", "resize_scene",
           "read_kitti_disparity", "read_kitti_calib", "load_kitti", "read_mvsnet_cam", "load_tnt",
           "read_depth_image", "load_nyu", "NYU_K"]

# NYU Depth v2 RGB intrinsics at 640×480 (fx_rgb, fy_rgb, cx_rgb, cy_rgb of the toolbox's camera_params.m).
NYU_K = np.array([[5.1885790117450188e+02, 0.0, 3.2558244941119034e+02],
                  [0.0, 5.1946961112127485e+02, 2.5373616633400465e+02],
                  [0.0, 0.0, 1.0]])


# ------------------------------------------------------------------------------------------------
# small helpers
# ------------------------------------------------------------------------------------------------

def _existing(path, name: str) -> Path:
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{name}: {path} does not exist")
    return path


def _read_text(path, name: str) -> str:
    """A small text file (calibration) → str; a clear error naming it if it is not UTF-8 text."""
    path = _existing(path, name)
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"{name}: {path} is not a UTF-8 text file (byte {error.start}); is it the right file?") from None


def _require_valid(depth: np.ndarray, what: str, path) -> np.ndarray:
    """Refuse a ground-truth map with no valid pixel: it is a wrong file, not a scene."""
    if not np.isfinite(depth).any():
        raise ValueError(f"{what}: {path} has no valid disparity (every pixel is the 'unknown' marker)")
    return depth


def _read_rgb(path, name: str = "path") -> np.ndarray:
    """An 8- or 16-bit image file → (H, W, 3) float32 RGB in [0, 1]."""
    image = cv2.imread(str(_existing(path, name)), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ValueError(f"{name}: {path} is not an image OpenCV can read")
    if image.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"{name}: {path} must be an 8- or 16-bit image, got {image.dtype}")
    scale = 255.0 if image.dtype == np.uint8 else 65535.0
    if image.ndim == 2:
        image = np.repeat(image[:, :, None], 3, axis=2)
    else:
        image = cv2.cvtColor(image[:, :, :3], cv2.COLOR_BGR2RGB)
    return (image.astype(np.float32) / np.float32(scale))


def _png_bytes(rgb: np.ndarray) -> bytes:
    bgr = cv2.cvtColor(np.clip(rgb * 255.0 + 0.5, 0, 255).astype(np.uint8), cv2.COLOR_RGB2BGR)
    ok, buffer = cv2.imencode(".png", bgr)
    if not ok:
        raise RuntimeError("OpenCV could not encode a PNG")
    return buffer.tobytes()


def _check_size(size):
    return None if size is None else check_size(size)


def _resize(rgb, depth, camera: Camera, size):
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
    H, W = _check_size(size)
    sx = W / scene.views[0].camera.width

    def view(v: View) -> View:
        rgb, depth, camera = _resize(v.rgb, v.depth, v.camera, (H, W))
        return View(rgb.copy(), depth.copy(), camera, v.name)
    labels = [cv2.resize(np.asarray(l), (W, H), interpolation=cv2.INTER_NEAREST_EXACT) for l in scene.labels]
    meta = {k: (float(v) * sx if k in _PIXEL_META else v) for k, v in scene.meta.items()}
    return Scene(scene.name, [view(v) for v in scene.views], [view(v) for v in scene.right], meta, labels)


def _depth_range(depths) -> dict:
    """``d_min``/``d_max`` for DDP's disparity transform, as ``make_scene`` sets them (empty if no depth)."""
    finite = np.concatenate([d[np.isfinite(d)] for d in depths])
    if finite.size == 0:
        return {}
    return {"d_min": float(np.floor(0.9 * finite.min() * 100.0)) / 100.0,
            "d_max": float(np.ceil(finite.max() * 100.0)) / 100.0}


# ------------------------------------------------------------------------------------------------
# PFM
# ------------------------------------------------------------------------------------------------

def _pfm_header(data: bytes, path) -> tuple[int, int, int, float, int]:
    """(channels, width, height, scale, data offset) of a PFM: three header lines (``\n`` or
    ``\r\n`` line ends; ``#`` comment lines skipped), or the same tokens on fewer lines."""
    tokens, offset = [], 0
    while len(tokens) < 4:
        end = data.find(b"\n", offset, offset + 256)
        if end < 0:
            raise ValueError(f"path: {path} is not a PFM file (expected 'PF' or 'Pf', width, height, scale)")
        line, offset = data[offset:end].strip(), end + 1
        if not line.startswith(b"#"):
            tokens += line.split()
    kind, width, height, scale = tokens[:4] if len(tokens) == 4 else (None,) * 4
    if kind not in (b"PF", b"Pf") or not (width.isdigit() and height.isdigit()):
        raise ValueError(f"path: {path} is not a PFM file (expected 'PF' or 'Pf', width, height, scale)")
    try:
        scale = float(scale)
    except ValueError:
        raise ValueError(f"path: {path} has a PFM scale that is not a number: {scale!r}") from None
    if int(width) == 0 or int(height) == 0 or scale == 0.0 or not np.isfinite(scale):
        raise ValueError(f"path: {path} has an empty size or a zero or non-finite scale in its PFM header")
    return 3 if kind == b"PF" else 1, int(width), int(height), scale, offset


def read_pfm(path) -> np.ndarray:
    """A PFM file → float32 (H, W) or (H, W, 3), top row first, native byte order (either file endianness)."""
    data = _existing(path, "path").read_bytes()
    channels, width, height, scale, offset = _pfm_header(data, path)
    count = width * height * channels
    if len(data) - offset < 4 * count:
        raise ValueError(f"path: {path} is truncated: {len(data) - offset} data bytes, expected {4 * count}")
    array = np.frombuffer(data, dtype="<f4" if scale < 0 else ">f4", count=count, offset=offset)
    shape = (height, width, 3) if channels == 3 else (height, width)
    return np.flipud(array.reshape(shape)).astype(np.float32)


def write_pfm(path, array) -> None:
    """Write (H, W), (H, W, 1) or (H, W, 3) real values as a little-endian float32 PFM, atomically."""
    values = np.asarray(array)
    if values.dtype == bool or not (np.issubdtype(values.dtype, np.integer) or np.issubdtype(values.dtype, np.floating)):
        raise ValueError(f"array must hold real numbers, got dtype {values.dtype}")
    if values.ndim == 3 and values.shape[2] == 1:
        values = values[:, :, 0]
    if not (values.ndim == 2 or (values.ndim == 3 and values.shape[2] == 3)) or min(values.shape[:2]) == 0:
        raise ValueError(f"array must be (H, W), (H, W, 1) or (H, W, 3), got shape {np.shape(array)}")
    write_bytes_atomic(path, pfm_bytes(values))


def npy_bytes(values) -> bytes:
    """Any array → the bytes of a ``.npy`` file (``np.load`` reads them back)."""
    buffer = io.BytesIO()
    np.save(buffer, values)
    return buffer.getvalue()


def depth_png_bytes(depth, factor: float = 1000.0) -> tuple[bytes, int]:
    """(H, W) depth × ``factor`` (1000: millimetres) → (16-bit PNG bytes, how many pixels did not fit).
    NaN becomes 0 (the usual depth-PNG "no value"); values beyond 65535 are written as 0 too."""
    scaled = np.round(np.nan_to_num(np.asarray(depth, np.float64), nan=0.0) * factor)
    overflow = scaled > 65535
    ok, buffer = cv2.imencode(".png", np.where(overflow, 0, scaled).astype(np.uint16))
    if not ok:
        raise RuntimeError("OpenCV could not encode a 16-bit PNG")
    return buffer.tobytes(), int(overflow.sum())


def pfm_bytes(values) -> bytes:
    """(H, W) or (H, W, 3) real values → the bytes of a little-endian float32 PFM file."""
    height, width = values.shape[:2]
    header = f"{'PF' if values.ndim == 3 else 'Pf'}\n{width} {height}\n-1.0\n".encode("ascii")
    return header + np.ascontiguousarray(np.flipud(values).astype("<f4")).tobytes()  # a copy: the input is untouched


# ------------------------------------------------------------------------------------------------
# Middlebury 2014 (and 2006)
# ------------------------------------------------------------------------------------------------

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
    for key in ("width", "height", "ndisp"):
        if numbers[key] != int(numbers[key]) or numbers[key] <= 0:
            raise ValueError(f"text: {key} must be a positive integer, got {entries[key]!r}")
    K0, K1 = _matrix(entries["cam0"], "cam0"), _matrix(entries["cam1"], "cam1")
    extra = {k: v for k, v in numbers.items() if k not in ("doffs", "baseline", "width", "height", "ndisp")}
    return MiddleburyCalib(K0, K1, numbers["doffs"], numbers["baseline"] / 1000.0, int(numbers["width"]),
                           int(numbers["height"]), int(numbers["ndisp"]), extra)


def read_middlebury_calib(path) -> MiddleburyCalib:
    """Read a Middlebury ``calib.txt`` file (see ``parse_middlebury_calib``)."""
    text = _read_text(path, "path")
    try:
        return parse_middlebury_calib(text)
    except ValueError as error:
        raise ValueError(f"{error} (in {path})") from None


def _stereo_scene(name, rgb0, rgb1, depth0, depth1, calib: MiddleburyCalib, size) -> Scene:
    """A one-view stereo Scene (left view + rectified right view) from loaded arrays."""
    size = _check_size(size)
    cam0, cam1 = calib.cameras()
    for what, array in (("left image", rgb0), ("right image", rgb1), ("left depth", depth0), ("right depth", depth1)):
        if array.shape[:2] != (calib.height, calib.width):
            raise ValueError(f"{what} is {array.shape[1]}×{array.shape[0]} but calib says {calib.width}×{calib.height}")
    # the depth range comes from the full-resolution map, so it does not depend on ``size``
    meta = {"baseline": float(calib.baseline), "doffs": float(calib.doffs), "ndisp": float(calib.ndisp),
            "focal": cam0.focal, **_depth_range([depth0])}
    scene = Scene(name, [View(rgb0, depth0, cam0, f"{name}-left")], [View(rgb1, depth1, cam1, f"{name}-right")], meta)
    return scene if size is None else resize_scene(scene, size)


def load_middlebury(folder, size=None, name: str | None = None) -> Scene:
    """A Middlebury 2014 scene folder (im0.png, im1.png, disp0.pfm, calib.txt; disp1.pfm optional) →
    one-view stereo ``Scene``: GT depth (metres, NaN where disparity is inf), ``right`` view, and
    ``meta`` (baseline m, doffs px, ndisp, focal px, d_min, d_max). ``size`` (H, W) resamples
    (colour by area, depth by nearest, K accordingly). Note: Z = f·B/(d + doffs), doffs ≠ 0 here."""
    folder = _existing(folder, "folder")
    calib = read_middlebury_calib(folder / "calib.txt")
    disparity = read_pfm(folder / "disp0.pfm")
    if disparity.ndim != 2:
        raise ValueError(f"folder: {folder / 'disp0.pfm'} must be a 1-channel PFM")
    depth0 = _require_valid(calib.depth(disparity), "folder", folder / "disp0.pfm")
    depth1 = calib.depth(read_pfm(folder / "disp1.pfm")) if (folder / "disp1.pfm").exists() \
        else np.full_like(depth0, np.nan)
    return _stereo_scene(name or folder.name, _read_rgb(folder / "im0.png", "folder"),
                         _read_rgb(folder / "im1.png", "folder"), depth0, depth1, calib, size)


def load_middlebury2006(folder, focal: float = 3740.0, baseline: float = 0.160, size=None,
                        name: str | None = None) -> Scene:
    """A Middlebury 2005/2006 full-size scene folder (view1.png, view5.png, disp1.png, dmin.txt;
    disp5.png optional) → one-view stereo ``Scene``. Disparity = PNG value (0 = unknown → NaN) and
    Z = focal·baseline / (d + dmin). The defaults (3740 px, 160 mm) are the values the dataset page
    gives for the full-size images; the principal point is assumed at the image centre."""
    folder = _existing(folder, "folder")
    try:
        dmin = float(_read_text(folder / "dmin.txt", "folder").split()[0])
    except (IndexError, ValueError) as error:
        raise ValueError(f"folder: {folder / 'dmin.txt'} must hold one number ({error})") from None
    if not np.isfinite(dmin):
        raise ValueError(f"folder: {folder / 'dmin.txt'} must hold a finite number, got {dmin}")
    rgb0, rgb1 = _read_rgb(folder / "view1.png", "folder"), _read_rgb(folder / "view5.png", "folder")
    H, W = rgb0.shape[:2]
    K0 = np.array([[focal, 0.0, (W - 1) / 2.0], [0.0, focal, (H - 1) / 2.0], [0.0, 0.0, 1.0]])
    K1 = K0.copy()
    K1[0, 2] += dmin
    calib = MiddleburyCalib(K0, K1, dmin, float(baseline), W, H, 256)

    def depth_of(file):
        if not (folder / file).exists():
            return np.full((H, W), np.nan, np.float32)
        raw = cv2.imread(str(folder / file), cv2.IMREAD_UNCHANGED)
        if raw is None or raw.ndim != 2:
            raise ValueError(f"folder: {folder / file} must be a 1-channel disparity PNG")
        return calib.depth(np.where(raw > 0, raw.astype(np.float64), np.nan))
    depth1 = _require_valid(depth_of("disp1.png"), "folder", folder / "disp1.png") if (folder / "disp1.png").exists() \
        else depth_of("disp1.png")
    return _stereo_scene(name or folder.name, rgb0, rgb1, depth1, depth_of("disp5.png"), calib, size)


def make_middlebury_fixture(folder, size=(48, 64), seed: int = 0, scene: str = "desk",
                            hole_fraction: float = 0.1) -> Path:
    """Write a tiny Middlebury-2014-format scene (im0.png, im1.png, disp0.pfm, disp1.pfm, calib.txt)
    rendered by ``make_scene(scene, size, n_views=1, seed)`` into ``folder``; ``hole_fraction`` of
    disp0 is set to ``inf`` (unknown). doffs = 0 (the renderer's right view shares K). Returns the folder."""
    size = _check_size(size)
    if not 0.0 <= hole_fraction < 1.0:
        raise ValueError(f"hole_fraction must be in [0, 1), got {hole_fraction!r}")
    synthetic = make_scene(scene, size=size, n_views=1, seed=seed)
    left, right = synthetic.views[0], synthetic.right[0]
    K, baseline = left.camera.K, float(synthetic.meta["baseline"])
    disp0, disp1 = (pixel_disparity(v.depth, K[0, 0], baseline) for v in (left, right))  # doffs = 0
    rng = np.random.default_rng(seed)
    disp0[rng.random(disp0.shape) < hole_fraction] = np.inf
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)

    def matrix(M):
        return "[" + "; ".join(" ".join(repr(float(v)) for v in row) for row in M) + "]"
    finite = disp0[np.isfinite(disp0)]
    calib = (f"cam0={matrix(K)}\ncam1={matrix(right.camera.K)}\ndoffs=0\nbaseline={baseline * 1000.0!r}\n"
             f"width={size[1]}\nheight={size[0]}\nndisp={int(np.ceil(finite.max())) + 1}\nisint=0\n"
             f"vmin={int(np.floor(finite.min()))}\nvmax={int(np.ceil(finite.max()))}\n")
    write_bytes_atomic(folder / "im0.png", _png_bytes(left.rgb))
    write_bytes_atomic(folder / "im1.png", _png_bytes(right.rgb))
    write_pfm(folder / "disp0.pfm", disp0)
    write_pfm(folder / "disp1.pfm", disp1)
    write_bytes_atomic(folder / "calib.txt", calib.encode("ascii"))
    return folder


# ------------------------------------------------------------------------------------------------
# KITTI 2015
# ------------------------------------------------------------------------------------------------

def read_kitti_disparity(path) -> np.ndarray:
    """A KITTI 16-bit disparity PNG → (H, W) float32 px: value / 256, 0 (no ground truth) → NaN."""
    raw = cv2.imread(str(_existing(path, "path")), cv2.IMREAD_UNCHANGED)
    if raw is None or raw.dtype != np.uint16 or raw.ndim != 2:
        raise ValueError(f"path: {path} must be a 1-channel 16-bit PNG (KITTI disparity), "
                         f"got {None if raw is None else (raw.dtype, raw.shape)}")
    disparity = raw.astype(np.float32) / np.float32(256.0)
    disparity[raw == 0] = np.nan
    return disparity


def read_kitti_calib(path) -> tuple[np.ndarray, float]:
    """A KITTI ``calib_cam_to_cam/<id>.txt`` → (K (3×3) of the rectified left colour camera, baseline m)."""
    values = {}
    for line in _read_text(path, "path").splitlines():
        if ":" in line:
            key, rest = line.split(":", 1)
            values[key.strip()] = rest.split()
    try:
        P2 = np.array(values["P_rect_02"], dtype=np.float64).reshape(3, 4)
        P3 = np.array(values["P_rect_03"], dtype=np.float64).reshape(3, 4)
    except (KeyError, ValueError):
        raise ValueError(f"path: {path} needs P_rect_02 and P_rect_03 (12 numbers each)") from None
    focal = P2[0, 0]
    if not (np.all(np.isfinite(P2)) and np.all(np.isfinite(P3)) and focal > 0):
        raise ValueError(f"path: {path}: P_rect_02 must be finite with a positive focal length, got f={focal}")
    baseline = float((P2[0, 3] - P3[0, 3]) / focal)
    if not baseline > 0:
        raise ValueError(f"path: {path}: P_rect_02 and P_rect_03 give baseline {baseline} m; the right camera "
                         f"must sit to the right of the left one (are they the same or swapped?)")
    return P2[:, :3].copy(), baseline


def load_kitti(root, index: int = 0, split: str = "training", disparity: str = "disp_occ_0", size=None) -> Scene:
    """KITTI 2015 pair ``index`` (frame 10) under ``root`` (the unpacked zips) → one-view stereo ``Scene``
    with sparse GT depth (NaN where no LiDAR point; all NaN on ``testing``) and ``meta['baseline']`` m."""
    if split not in ("training", "testing"):
        raise ValueError(f"split must be 'training' or 'testing', got {split!r}")
    if isinstance(index, bool) or int(index) != index or index < 0:
        raise ValueError(f"index must be a non-negative integer, got {index!r}")
    base = _existing(root, "root") / split
    stem = f"{int(index):06d}"
    rgb0 = _read_rgb(base / "image_2" / f"{stem}_10.png", "root")
    rgb1 = _read_rgb(base / "image_3" / f"{stem}_10.png", "root")
    K, baseline = read_kitti_calib(base / "calib_cam_to_cam" / f"{stem}.txt")
    H, W = rgb0.shape[:2]
    gt = base / disparity / f"{stem}_10.png"
    disp = _require_valid(read_kitti_disparity(gt), "root", gt) if split == "training" \
        else np.full((H, W), np.nan, np.float32)
    calib = MiddleburyCalib(K, K, 0.0, baseline, W, H, 256)
    return _stereo_scene(f"kitti{stem}", rgb0, rgb1, calib.depth(disp), np.full((H, W), np.nan, np.float32),
                         calib, size)


# ------------------------------------------------------------------------------------------------
# Tanks and Temples (MVSNet-format cameras)
# ------------------------------------------------------------------------------------------------

def _nearest_rotation(R: np.ndarray, path) -> np.ndarray:
    """Re-orthonormalise a rotation printed with few digits (SVD); refuse anything far from one."""
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-3 or np.linalg.det(R) <= 0:
        raise ValueError(f"path: {path}: the extrinsic's 3×3 block is not a rotation")
    U, _, Vt = np.linalg.svd(R)
    return U @ Vt


def read_mvsnet_cam(path, width: int, height: int) -> tuple[Camera, dict]:
    """An MVSNet ``<id>_cam.txt`` → (``Camera`` for a ``width × height`` image, {depth_min, depth_interval
    [, depth_num, depth_max]} metres/scene units). 'extrinsic' is world→camera (cam_from_world)."""
    text = _read_text(path, "path")
    try:
        extrinsic = text.split("extrinsic", 1)[1].split("intrinsic", 1)[0].split()
        after = text.split("intrinsic", 1)[1].split()
        pose = np.array(extrinsic, dtype=np.float64).reshape(4, 4)
        K = np.array(after[:9], dtype=np.float64).reshape(3, 3)
        depth = [float(v) for v in after[9:13]]
    except (IndexError, ValueError):
        raise ValueError(f"path: {path} is not an MVSNet cam file ('extrinsic' 4×4, 'intrinsic' 3×3, depths)") from None
    pose[:3, :3] = _nearest_rotation(pose[:3, :3], path)
    info = dict(zip(("depth_min", "depth_interval", "depth_num", "depth_max"), depth))
    return Camera(K, pose, width, height), info


def load_tnt(folder, indices=None, size=None, depth_dir=None, name: str | None = None) -> Scene:
    """An MVSNet-style TnT scene (``images/<id>.jpg``, ``cams/<id>_cam.txt``) → multi-view ``Scene``.
    ``indices``: positions in the sorted image list (default all: pass a few, and ``size``, for real
    scenes). Depth from ``depth_dir/<id>.pfm`` if given (≤ 0 or non-finite → NaN), else all NaN
    (TnT's ground truth is a point cloud, not depth maps). ``meta``: d_min/d_max from the depth maps,
    else from the first cam file's depth range."""
    folder = _existing(folder, "folder")
    images = sorted(p for p in (folder / "images").glob("*") if p.suffix.lower() in (".jpg", ".jpeg", ".png"))
    if not images:
        raise ValueError(f"folder: {folder / 'images'} holds no .jpg/.png images")
    chosen = range(len(images)) if indices is None else list(indices)
    for i in chosen:
        if isinstance(i, bool) or int(i) != i or not 0 <= i < len(images):
            raise ValueError(f"indices must be positions in [0, {len(images)}), got {i!r}")
    size = _check_size(size)
    views, info0 = [], None
    for i in chosen:
        stem = images[i].stem
        rgb = _read_rgb(images[i], "folder")
        H, W = rgb.shape[:2]
        camera, info = read_mvsnet_cam(folder / "cams" / f"{stem}_cam.txt", W, H)
        info0 = info0 or info
        depth = np.full((H, W), np.nan, np.float32)
        if depth_dir is not None:
            depth = read_pfm(_existing(Path(depth_dir) / f"{stem}.pfm", "depth_dir"))
            if depth.ndim != 2:
                raise ValueError(f"depth_dir: {stem}.pfm must be 1-channel")
            depth = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float32)
            if depth.shape != (H, W):
                # MVSNet depth maps are often smaller than the images: pixel centres, as in _resize
                depth = cv2.resize(depth, (W, H), interpolation=cv2.INTER_NEAREST_EXACT)
        rgb, depth, camera = _resize(rgb, depth, camera, size)
        views.append(View(rgb, depth, camera, stem))
    meta = _depth_range([v.depth for v in views])
    if not meta and info0:
        d_max = info0.get("depth_max", info0["depth_min"] + info0["depth_interval"] * (info0.get("depth_num", 192) - 1))
        meta = {"d_min": float(info0["depth_min"]), "d_max": float(d_max)}
    return Scene(name or folder.name, views, [], meta)


# ------------------------------------------------------------------------------------------------
# NYU Depth v2
# ------------------------------------------------------------------------------------------------

def read_depth_image(path, scale: float = 0.001) -> np.ndarray:
    """A 16-bit depth PNG or a ``.npy`` (millimetres by default) → (H, W) float32 metres = value·scale;
    0 and non-finite → NaN."""
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f"scale must be a positive number (metres per unit), got {scale!r}")
    path = _existing(path, "path")
    if path.suffix.lower() == ".npy":
        raw = np.load(path, allow_pickle=False)
    else:
        raw = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        if raw is None or raw.dtype != np.uint16:
            raise ValueError(f"path: {path} must be a 16-bit depth PNG or a .npy")
    if raw.ndim != 2:
        raise ValueError(f"path: {path} must hold an (H, W) depth map, got shape {raw.shape}")
    depth = raw.astype(np.float64) * float(scale)
    return np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float32)


def load_nyu(path, index: int = 0, depth_path=None, raw: bool = True, depth_scale: float = 0.001, K=None) -> Scene:
    """NYU Depth v2 → one-view ``Scene``. ``path`` is either the labelled ``.mat`` (frame ``index``;
    ``raw`` picks rawDepths (Kinect holes) over the toolbox's filled depths) or an RGB
    image with ``depth_path`` a depth PNG/NPY in millimetres (× ``depth_scale``). ``K`` defaults to
    ``NYU_K`` (640×480)."""
    path = _existing(path, "path")
    if path.suffix.lower() == ".mat":
        import h5py  # a dependency, imported here because only this branch needs it
        with h5py.File(path, "r") as f:
            count = f["images"].shape[0]
            if isinstance(index, bool) or int(index) != index or not 0 <= index < count:
                raise ValueError(f"index must be in [0, {count}), got {index!r}")
            rgb = np.asarray(f["images"][int(index)]).transpose(2, 1, 0).astype(np.float32) / np.float32(255.0)
            depth = np.asarray(f["rawDepths" if raw else "depths"][int(index)], dtype=np.float64).T
        depth = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float32)
        name = f"nyu{int(index):04d}{'-raw' if raw else ''}"
    else:
        if depth_path is None:
            raise ValueError("depth_path must be given when path is an image (not the labelled .mat)")
        rgb, depth = _read_rgb(path), read_depth_image(depth_path, depth_scale)
        name = path.stem
    H, W = depth.shape
    if rgb.shape[:2] != (H, W):
        raise ValueError(f"the image is {rgb.shape[1]}×{rgb.shape[0]} but the depth is {W}×{H}")
    if K is None:
        if (H, W) != (480, 640):
            raise ValueError(f"K must be given for a {W}×{H} image (NYU_K is for 640×480)")
        K = NYU_K
    return Scene(name, [View(rgb, depth, Camera(K, np.eye(4), W, H), name)], [], _depth_range([depth]))
