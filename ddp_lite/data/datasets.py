"""Loaders: files fetched by ``data_fetch`` → the kit's own ``Scene`` / ``View`` / ``Camera``.

Every loader turns its dataset's "no value" marker into NaN in its loader and nowhere else
(Middlebury: ``inf`` disparity; KITTI: 0 in the 16-bit PNG; NYU: 0 depth; Middlebury 2006: 0
disparity), and returns depth as float32 metres, images as float32 (H, W, 3) in [0, 1], cameras in
the OpenCV convention with the (left / first) camera at the world origin.

Here: KITTI, Tanks and Temples, NYU. Middlebury lives in ``ddp_lite.data.middlebury``, the file formats
(PFM, depth PNG, ``.npy``) in ``ddp_lite.data.fileio`` (readers) and ``ddp_lite.data.file_writers``,
resampling in ``ddp_lite.data.resample``.

* **KITTI 2015**: disparity PNG uint16, d = value / 256, 0 = no ground truth; calibration
  ``P_rect_02``/``P_rect_03`` (3×4), baseline = (P2[0,3] − P3[0,3]) / f.
* **Tanks and Temples, MVSNet cams** ``<id>_cam.txt``: ``extrinsic`` + 4×4 world→camera,
  ``intrinsic`` + 3×3, then ``depth_min depth_interval [depth_num depth_max]``.
* **NYU Depth v2**: labelled ``.mat`` (HDF5, read with h5py) or an image + a depth PNG/NPY in mm.
"""
from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from ..core.files import regular_file
from ..core.camera import Camera, check_intrinsics
from ..core.checks import check_bool, report_skipped
from .file_writers import depth_png_bytes, npy_bytes, pfm_bytes
from .fileio import (check_same_size, existing_path, read_depth, read_depth_image, read_image_file, read_rgb,
                     read_text_file)
from .middlebury import MiddleburyCalib, check_scene_depth, require_valid_depth, stereo_scene
from .resample import check_optional_size, scene_depth_range, resize_view
from ..core.views import Scene, View

__all__ = ["read_kitti_disparity", "read_kitti_calib", "load_kitti", "read_mvsnet_cam", "load_tnt", "load_nyu", "NYU_K"]

# NYU Depth v2 RGB intrinsics at 480×640 (H×W) (fx_rgb, fy_rgb, cx_rgb, cy_rgb of the toolbox's camera_params.m).
NYU_K = np.array([[5.1885790117450188e+02, 0.0, 3.2558244941119034e+02],
                  [0.0, 5.1946961112127485e+02, 2.5373616633400465e+02],
                  [0.0, 0.0, 1.0]])


# ------------------------------------------------------------------------------------------------
# KITTI 2015
# ------------------------------------------------------------------------------------------------

def read_kitti_disparity(path) -> np.ndarray:
    """A KITTI 16-bit disparity PNG → (H, W) float32 px: value / 256, 0 (no ground truth) → NaN."""
    raw = read_image_file(path, "path", truth=True)
    if raw.dtype != np.uint16 or raw.ndim != 2:
        raise ValueError(f"path: {path} must be a 1-channel 16-bit PNG (KITTI disparity), got {(raw.dtype, raw.shape)}")
    disparity = raw.astype(np.float32) / np.float32(256.0)
    disparity[raw == 0] = np.nan
    return disparity


def read_kitti_calib(path) -> tuple[np.ndarray, float]:
    """A KITTI ``calib_cam_to_cam/<id>.txt`` → (K (3×3) of the rectified left colour camera, baseline m)."""
    values = {}
    for line in read_text_file(path, "path").splitlines():
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
    base = existing_path(root, "root") / split
    stem = f"{int(index):06d}"
    rgb0 = read_rgb(base / "image_2" / f"{stem}_10.png", "root")
    rgb1 = read_rgb(base / "image_3" / f"{stem}_10.png", "root")
    K, baseline = read_kitti_calib(base / "calib_cam_to_cam" / f"{stem}.txt")
    H, W = rgb0.shape[:2]
    check_intrinsics(K, W, H, f"root: {base / 'calib_cam_to_cam' / f'{stem}.txt'}: P_rect_02")
    gt = base / disparity / f"{stem}_10.png"
    disp = require_valid_depth(read_kitti_disparity(gt), "root", gt) if split == "training" \
        else np.full((H, W), np.nan, np.float32)
    calib = MiddleburyCalib(K, K, 0.0, baseline, W, H, 256)
    check_scene_depth(calib.depth(disp), "root", gt, f"check {base / 'calib_cam_to_cam' / f'{stem}.txt'} "
                                                     f"(baseline {baseline:.4g} m, focal {K[0, 0]:g} px)")
    return stereo_scene(f"kitti{stem}", rgb0, rgb1, calib.depth(disp), np.full((H, W), np.nan, np.float32),
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
    text = read_text_file(path, "path")
    try:
        extrinsic = text.split("extrinsic", 1)[1].split("intrinsic", 1)[0].split()
        after = text.split("intrinsic", 1)[1].split()
        pose = np.array(extrinsic, dtype=np.float64).reshape(4, 4)
        K = np.array(after[:9], dtype=np.float64).reshape(3, 3)
        depth = [float(v) for v in after[9:13]]
    except (IndexError, ValueError):
        raise ValueError(f"path: {path} is not an MVSNet cam file ('extrinsic' 4×4, 'intrinsic' 3×3, depths)") from None
    pose[:3, :3] = _nearest_rotation(pose[:3, :3], path)
    check_intrinsics(K, width, height, f"path: {path}: intrinsic")
    info = dict(zip(("depth_min", "depth_interval", "depth_num", "depth_max"), depth))
    return Camera(K, pose, width, height), info


def load_tnt(folder, indices=None, size=None, depth_dir=None, name: str | None = None, strict: bool = False) -> Scene:
    """An MVSNet-style TnT scene (``images/<id>.jpg``, ``cams/<id>_cam.txt``) → multi-view ``Scene``.
    ``indices``: positions in the sorted image list (default all: pass a few, and ``size``, for real
    scenes). Depth from ``depth_dir/<id>.pfm`` if given (≤ 0 or non-finite → NaN), else all NaN
    (TnT's ground truth is a point cloud, not depth maps). ``meta``: d_min/d_max from the depth maps,
    else from the first cam file's depth range. Files in ``images/`` that are not .jpg/.png are named in a
    warning (``strict``: refused)."""
    folder = existing_path(folder, "folder")
    files = sorted(p for p in (folder / "images").glob("*") if p.is_file() and not p.name.startswith("."))
    images = [p for p in files if p.suffix.lower() in (".jpg", ".jpeg", ".png")]
    report_skipped(folder / "images", [p.name for p in files if p not in images], "file(s)", "are not .jpg or .png images",
                   check_bool(strict, "strict"), total=len(files))
    if not images:
        raise ValueError(f"folder: {folder / 'images'} holds no .jpg/.png images")
    chosen = range(len(images)) if indices is None else list(indices)
    for i in chosen:
        if isinstance(i, bool) or int(i) != i or not 0 <= i < len(images):
            raise ValueError(f"indices must be positions in [0, {len(images)}), got {i!r}")
    size = check_optional_size(size)
    views, info0 = [], None
    for i in chosen:
        stem = images[i].stem
        rgb = read_rgb(images[i], "folder")
        H, W = rgb.shape[:2]
        camera, info = read_mvsnet_cam(folder / "cams" / f"{stem}_cam.txt", W, H)
        info0 = info0 or info
        depth = np.full((H, W), np.nan, np.float32)
        if depth_dir is not None:
            depth = read_depth(Path(depth_dir) / f"{stem}.pfm", 1.0, "depth_dir")
            if depth.shape != (H, W):
                # MVSNet depth maps are often smaller than the images: pixel centres, as in resize_view
                depth = cv2.resize(depth, (W, H), interpolation=cv2.INTER_NEAREST_EXACT)
        rgb, depth, camera = resize_view(rgb, depth, camera, size)
        views.append(View(rgb, depth, camera, stem))
    meta = scene_depth_range([v.depth for v in views])
    if not meta and info0:
        d_max = info0.get("depth_max", info0["depth_min"] + info0["depth_interval"] * (info0.get("depth_num", 192) - 1))
        meta = {"d_min": float(info0["depth_min"]), "d_max": float(d_max)}
    return Scene(name or folder.name, views, [], meta)


# ------------------------------------------------------------------------------------------------
# NYU Depth v2
# ------------------------------------------------------------------------------------------------

def load_nyu(path, index: int = 0, depth_path=None, raw: bool = True, depth_scale: float = 0.001, K=None) -> Scene:
    """NYU Depth v2 → one-view ``Scene``. ``path`` is either the labelled ``.mat`` (frame ``index``;
    ``raw`` picks rawDepths (Kinect holes) over the toolbox's filled depths) or an RGB
    image with ``depth_path`` a depth PNG/NPY in millimetres (× ``depth_scale``). ``K`` defaults to
    ``NYU_K`` (480×640)."""
    path = regular_file(path, "path")
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
        rgb, depth = read_rgb(path), read_depth_image(depth_path, depth_scale)
        name = path.stem
    H, W = depth.shape
    check_same_size(rgb.shape, depth.shape, None if path.suffix.lower() == ".mat" else path, "the image",
                    "the depth")
    if K is None:
        if (H, W) != (480, 640):
            raise ValueError(f"K must be given for a {H}×{W} (H×W) image (NYU_K is for 480×640)")
        K = NYU_K
    return Scene(name, [View(rgb, depth, Camera(K, np.eye(4), W, H), name)], [], scene_depth_range([depth]))
