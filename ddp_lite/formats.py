"""Your own captures → the kit's ``Scene``: TUM RGB-D folders, COLMAP text models, saved scenes.

Three formats people already have, read into the kit's conventions (float32 (H, W, 3) images in
[0, 1]; float32 (H, W) depth in metres, or the reconstruction's own units, NaN = no value;
``Camera`` in the OpenCV convention with pixel (0, 0) the *centre* of the top-left pixel; poses
``cam_from_world``). Each has a writer, so tests and notebooks can make a fixture from a
synthetic scene and read it back.

* **TUM RGB-D** (Sturm et al. 2012): ``rgb.txt`` and ``depth.txt`` list ``timestamp path`` per
  line; ``groundtruth.txt`` lists ``timestamp tx ty tz qx qy qz qw``, the colour camera's optical
  centre and orientation in the world (so ``world_from_cam``); ``#`` starts a comment. Depth PNGs
  are 16-bit, metres × 5000, 0 = no reading. Colour and depth are stamped separately (~30 Hz
  each, not in step): a colour frame is paired with the nearest unused depth frame within
  ``max_difference`` seconds (the greedy nearest-first matching of TUM's ``associate.py``), and
  its pose is interpolated (position linearly, orientation by slerp) between the two
  ground-truth samples around its timestamp. Intrinsics: the published fr1/fr2/fr3 colour
  calibrations (fr1 and fr2 with lens distortion, undistorted here with OpenCV) or your own K.
* **COLMAP** text model (``cameras.txt``, ``images.txt``): a camera line is
  ``CAMERA_ID MODEL WIDTH HEIGHT PARAMS...``; an image takes two lines,
  ``IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME`` (the quaternion and translation of
  ``cam_from_world``) and then its 2D points (possibly an empty line). COLMAP puts the centre
  of the top-left pixel at (0.5, 0.5), the kit at (0, 0): cx, cy are shifted by -0.5 on reading,
  +0.5 on writing. Depth per image: COLMAP's dense ``.bin`` maps (``stereo/depth_maps/NAME.
  geometric.bin``: an ASCII header ``width&height&channels&`` then float32 values, column by
  column), or 16-bit PNG / ``.npy`` / ``.pfm`` files named after the image, times a scale.
  COLMAP's units are whatever the reconstruction's scale is (metres only if you scaled it).
* **The kit's own** ``Scene.save`` files (``.npz``), or a folder holding exactly one.

Every reader refuses a malformed file with its path and line number before anything runs.
"""
from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from .atomic import write_bytes_atomic
from .camera import Camera
from .checks import check_size
from .datasets import _depth_range, _png_bytes, _read_rgb, _resize, depth_png_bytes, npy_bytes, pfm_bytes, read_pfm
from .views import Scene, View

__all__ = ["TUM_INTRINSICS", "TUM_DEPTH_FACTOR", "read_tum", "write_tum", "associate", "read_tum_list",
           "read_tum_trajectory", "COLMAP_MODELS", "ColmapCamera", "read_colmap_cameras", "read_colmap_images",
           "read_colmap_depth", "write_colmap_depth", "read_colmap", "write_colmap", "read_scene", "load_sequence",
           "FORMATS"]

# The published colour-camera calibrations of the TUM RGB-D benchmark (640×480; "file formats" /
# "camera calibration" pages): fx, fy, cx, cy and the OpenCV distortion k1, k2, p1, p2, k3.
# fr3 images were undistorted by the dataset authors; "ros" is the ROS default the depth was registered with.
TUM_INTRINSICS = {
    "fr1": ((517.306408, 516.469215, 318.643040, 255.313989), (0.262383, -0.953104, -0.005358, 0.002628, 1.163314)),
    "fr2": ((520.908620, 521.007327, 325.141442, 249.701764), (0.231222, -0.784899, -0.003257, -0.000105, 0.917205)),
    "fr3": ((535.4, 539.2, 320.1, 247.6), (0.0, 0.0, 0.0, 0.0, 0.0)),
    "ros": ((525.0, 525.0, 319.5, 239.5), (0.0, 0.0, 0.0, 0.0, 0.0)),
}
TUM_DEPTH_FACTOR = 5000.0  # stored value per metre


# ------------------------------------------------------------------------------------------------
# shared helpers
# ------------------------------------------------------------------------------------------------

def _fail(path, line: int | None, message: str) -> ValueError:
    where = f"{path}, line {line}" if line is not None else f"{path}"
    return ValueError(f"{where}: {message}")


def _text_lines(path, keep_blank: bool = False) -> list[tuple[int, str]]:
    """(1-based line number, stripped text) of a text file, ``#`` comments dropped (blank lines too unless asked)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path} does not exist (or is not a file)")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise _fail(path, None, f"not a UTF-8 text file (byte {error.start}); is it the right file?") from None
    lines = []
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if line.startswith("#") or (not line and not keep_blank):
            continue
        lines.append((number, line))
    return lines


def _floats(tokens, path, line: int, what: str) -> np.ndarray:
    try:
        values = np.array([float(t) for t in tokens], dtype=np.float64)
    except ValueError:
        raise _fail(path, line, f"{what} must be numbers, got {' '.join(tokens)!r}") from None
    if not np.all(np.isfinite(values)):
        raise _fail(path, line, f"{what} must be finite numbers, got {' '.join(tokens)!r}")
    return values


def _rotation(quat_xyzw: np.ndarray, path, line: int) -> np.ndarray:
    """A (nearly) unit quaternion (x, y, z, w) → 3×3 rotation; refuse zero or far-from-unit ones."""
    norm = float(np.linalg.norm(quat_xyzw))
    if not abs(norm - 1.0) < 1e-3:
        raise _fail(path, line, f"the quaternion must have unit length, got length {norm:.6g}")
    return Rotation.from_quat(quat_xyzw / norm).as_matrix()


def _undistort(rgb: np.ndarray, depth: np.ndarray, K: np.ndarray, dist) -> tuple[np.ndarray, np.ndarray]:
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


def _depth_png_bytes(depth: np.ndarray, factor: float, path_for_errors) -> bytes:
    """(H, W) depth × ``factor`` → 16-bit PNG bytes, NaN → 0; refuse values the format cannot hold."""
    png, overflow = depth_png_bytes(depth, factor)
    if overflow:
        raise ValueError(f"{path_for_errors}: depth up to {np.nanmax(depth):.3f} does not fit a 16-bit PNG at "
                         f"{factor:g} units per metre (max {65535 / factor:.3f}); use .npy, .pfm or .bin")
    return png


def _read_depth_file(path: Path, scale: float | None) -> np.ndarray:
    """A depth map file → (H, W) float32 × ``scale``; 0, negative and non-finite → NaN.

    ``.bin`` (COLMAP dense), ``.npy``, ``.pfm`` store floats (scale defaults to 1); 16-bit ``.png``
    stores integers and needs ``scale`` (metres per unit: 0.001 for millimetres, 1/5000 for TUM)."""
    suffix = path.suffix.lower()
    if suffix == ".bin":
        raw = read_colmap_depth(path)
    elif suffix == ".npy":
        raw = np.load(path, allow_pickle=False)
    elif suffix == ".pfm":
        raw = read_pfm(path)
    elif suffix == ".png":
        raw = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        if raw is None or raw.dtype != np.uint16 or raw.ndim != 2:
            raise ValueError(f"{path}: a depth PNG must be 1-channel 16-bit, got "
                             f"{None if raw is None else (raw.dtype, raw.shape)}")
        if scale is None:
            raise ValueError(f"{path} stores integers; give depth_scale (CLI: --depth-scale), the metres per stored "
                             f"unit (0.001 for millimetres)")
    else:
        raise ValueError(f"{path}: depth maps must be .bin (COLMAP), .png (16-bit), .npy or .pfm")
    if raw.ndim != 2 or not np.issubdtype(raw.dtype, np.number):
        raise ValueError(f"{path} must hold one (H, W) map of numbers, got {raw.dtype} {raw.shape}")
    depth = raw.astype(np.float64) * (1.0 if scale is None else float(scale))
    return np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float32)


def _finish(name: str, views: list[View], size) -> Scene:
    """Resample the views to ``size`` (H, W) if given; d_min/d_max from the depths (as make_scene sets them)."""
    if size is not None:
        resized = [(_resize(v.rgb, v.depth, v.camera, check_size(size)), v.name) for v in views]
        views = [View(rgb.copy(), depth.copy(), camera, name) for (rgb, depth, camera), name in resized]
    return Scene(name, views, [], _depth_range([v.depth for v in views]))


# ------------------------------------------------------------------------------------------------
# TUM RGB-D
# ------------------------------------------------------------------------------------------------

def read_tum_list(path) -> list[tuple[float, str]]:
    """``rgb.txt`` / ``depth.txt`` → [(timestamp s, relative path)], in file order.

    Example:
        >>> import tempfile, pathlib
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "rgb.txt"
        >>> _ = p.write_text("# timestamp filename\\n1.0 rgb/1.0.png\\n")
        >>> read_tum_list(p)
        [(1.0, 'rgb/1.0.png')]
    """
    entries = []
    for line, text in _text_lines(path):
        tokens = text.split()
        if len(tokens) != 2:
            raise _fail(path, line, f"expected 'timestamp filename', got {text!r}")
        stamp = _floats(tokens[:1], path, line, "the timestamp")[0]
        entries.append((float(stamp), tokens[1]))
    if not entries:
        raise _fail(path, None, "lists no frames")
    return entries


def read_tum_trajectory(path) -> tuple[np.ndarray, np.ndarray]:
    """``groundtruth.txt`` → timestamps (N,) s, sorted, and ``world_from_cam`` poses (N, 4, 4)."""
    stamps, poses = [], []
    for line, text in _text_lines(path):
        tokens = text.split()
        if len(tokens) != 8:
            raise _fail(path, line, f"expected 'timestamp tx ty tz qx qy qz qw' (8 numbers), got {len(tokens)}")
        values = _floats(tokens, path, line, "the pose")
        pose = np.eye(4)
        pose[:3, :3] = _rotation(values[4:8], path, line)
        pose[:3, 3] = values[1:4]
        stamps.append(values[0])
        poses.append(pose)
    if not stamps:
        raise _fail(path, None, "holds no poses")
    order = np.argsort(stamps, kind="stable")
    return np.asarray(stamps)[order], np.asarray(poses)[order]


def associate(first, second, max_difference: float = 0.02) -> list[tuple[int, int]]:
    """Pair timestamps of two streams, one-to-one: the closest pairs first, each within ``max_difference`` s.

    Returns ``[(i, j)]`` index pairs sorted by ``i`` (the greedy matching of TUM's ``associate.py``).

    Example:
        >>> associate([0.0, 0.033, 0.066], [0.004, 0.07])
        [(0, 0), (2, 1)]
    """
    a, b = np.asarray(first, np.float64), np.asarray(second, np.float64)
    if max_difference <= 0:
        raise ValueError(f"max_difference must be positive (seconds), got {max_difference!r}")
    gaps = np.abs(a[:, None] - b[None, :])  # (N, M)
    i, j = np.nonzero(gaps < max_difference)
    order = np.lexsort((j, i, gaps[i, j]))  # smallest gap first; ties by index, so the result is unique
    used_a, used_b, pairs = set(), set(), []
    for k in order:
        if i[k] not in used_a and j[k] not in used_b:
            used_a.add(i[k]), used_b.add(j[k])
            pairs.append((int(i[k]), int(j[k])))
    return sorted(pairs)


def _interpolate_pose(stamps: np.ndarray, poses: np.ndarray, t: float, max_difference: float) -> np.ndarray | None:
    """``world_from_cam`` at time ``t``: linear in position, slerp in rotation between the samples around
    ``t``; None when no sample lies within ``max_difference`` s (the motion capture lost the camera)."""
    k = int(np.searchsorted(stamps, t))
    if np.min(np.abs(stamps[max(k - 1, 0):k + 1] - t)) >= max_difference:
        return None
    if k == 0 or k == len(stamps) or stamps[k] == t:
        return poses[min(k, len(stamps) - 1)].copy()
    t0, t1 = stamps[k - 1], stamps[k]
    w = (t - t0) / (t1 - t0)
    pose = np.eye(4)
    pose[:3, 3] = (1.0 - w) * poses[k - 1][:3, 3] + w * poses[k][:3, 3]
    pose[:3, :3] = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([poses[k - 1][:3, :3], poses[k][:3, :3]])))(w).as_matrix()
    return pose


def _tum_intrinsics(folder: Path, intrinsics):
    """(K 3×3, distortion (5,)) from a name ('fr1', 'fr2', 'fr3', 'ros'), a 3×3 K, or None: the folder's
    ``intrinsics.txt`` (the kit's addition for your own captures: one line ``fx fy cx cy``, pixels,
    pixel (0, 0) = centre of the top-left pixel), else the TUM camera its name says (``freiburg1`` …)."""
    if intrinsics is None and (folder / "intrinsics.txt").is_file():
        lines = _text_lines(folder / "intrinsics.txt")
        if len(lines) != 1 or len(lines[0][1].split()) != 4:
            raise _fail(folder / "intrinsics.txt", lines[0][0] if lines else None, "expected one line 'fx fy cx cy'")
        fx, fy, cx, cy = _floats(lines[0][1].split(), folder / "intrinsics.txt", lines[0][0], "fx fy cx cy")
        intrinsics = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    if intrinsics is None:
        found = re.search(r"freiburg([123])", folder.name)
        if not found:
            raise ValueError(f"intrinsics: {folder} has no intrinsics.txt and its name does not say fr1/fr2/fr3; "
                             f"pass intrinsics='fr1', 'fr2', 'fr3', 'ros' or your camera's 3×3 K (pixels), or write "
                             f"'fx fy cx cy' into {folder / 'intrinsics.txt'}")
        intrinsics = f"fr{found.group(1)}"
    if isinstance(intrinsics, str):
        if intrinsics not in TUM_INTRINSICS:
            raise ValueError(f"intrinsics must be one of {sorted(TUM_INTRINSICS)} or a 3×3 K, got {intrinsics!r}")
        (fx, fy, cx, cy), dist = TUM_INTRINSICS[intrinsics]
        return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]), np.array(dist)
    K = np.asarray(intrinsics, dtype=np.float64)
    if K.shape != (3, 3) or not np.all(np.isfinite(K)):
        raise ValueError(f"intrinsics must be a name or a finite 3×3 K in pixels, got shape {K.shape}")
    return K, np.zeros(5)


def read_tum(folder, intrinsics=None, every: int = 1, max_frames: int | None = None, max_difference: float = 0.02,
             undistort: bool = True, depth_factor: float = TUM_DEPTH_FACTOR, size=None, name: str | None = None) -> Scene:
    """A TUM RGB-D sequence folder (``rgb.txt``, ``depth.txt``, ``groundtruth.txt`` + images) → ``Scene``.

    Args:
        folder: the sequence folder (e.g. ``rgbd_dataset_freiburg1_desk``).
        intrinsics: 'fr1', 'fr2', 'fr3', 'ros', or a 3×3 K in pixels; None → the folder's
            ``intrinsics.txt`` ('fx fy cx cy', the kit's addition) or the camera its name says.
        every: keep every ``every``-th associated frame (30 Hz video has tiny baselines); ``max_frames``
            then caps the count.
        max_difference: seconds allowed between a colour frame and its depth frame and pose.
        undistort: remove fr1/fr2's lens distortion with OpenCV (colour bilinear, depth nearest).
        depth_factor: stored units per metre (TUM: 5000); 0 = no reading → NaN.
        size: (H, W) to resample to (colour by area, depth by nearest, K accordingly).
    Returns:
        ``Scene`` with one view per kept frame, named by its colour timestamp; world frame = the
        motion-capture frame, metres; ``meta`` d_min/d_max from the depths.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"folder: {folder} is not a folder")
    if isinstance(every, bool) or int(every) != every or every < 1:
        raise ValueError(f"every must be a positive integer, got {every!r}")
    if max_frames is not None and (isinstance(max_frames, bool) or int(max_frames) != max_frames or max_frames < 1):
        raise ValueError(f"max_frames must be a positive integer or None, got {max_frames!r}")
    K, dist = _tum_intrinsics(folder, intrinsics)
    rgb_list, depth_list = read_tum_list(folder / "rgb.txt"), read_tum_list(folder / "depth.txt")
    stamps, poses = read_tum_trajectory(folder / "groundtruth.txt")
    pairs = associate([t for t, _ in rgb_list], [t for t, _ in depth_list], max_difference)
    if not pairs:
        raise ValueError(f"folder: no colour frame of {folder / 'rgb.txt'} has a depth frame within "
                         f"{max_difference} s in {folder / 'depth.txt'}")
    views, dropped = [], 0
    for i, j in pairs[::int(every)]:
        if max_frames is not None and len(views) >= max_frames:
            break
        stamp, rgb_path = rgb_list[i]
        world_from_cam = _interpolate_pose(stamps, poses, stamp, max_difference)
        if world_from_cam is None:
            dropped += 1
            continue
        rgb = _read_rgb(folder / rgb_path, "folder")
        depth = _read_depth_file(folder / depth_list[j][1], 1.0 / float(depth_factor))
        if rgb.shape[:2] != depth.shape:
            raise ValueError(f"folder: {rgb_path} is {rgb.shape[1]}×{rgb.shape[0]} but {depth_list[j][1]} is "
                             f"{depth.shape[1]}×{depth.shape[0]}; TUM pairs must be registered 1:1")
        if undistort and np.any(dist != 0):
            rgb, depth = _undistort(rgb, depth, K, dist)
        camera = Camera(K, np.linalg.inv(world_from_cam), rgb.shape[1], rgb.shape[0])
        views.append(View(rgb, depth, camera, f"{stamp:.6f}"))
    if dropped:
        warnings.warn(f"{folder}: {dropped} frame(s) had no ground-truth pose within {max_difference} s and were left out")
    if not views:
        raise ValueError(f"folder: no frame of {folder} has a ground-truth pose within {max_difference} s")
    return _finish(name or folder.name, views, size)


def write_tum(scene: Scene, folder, depths=None, start: float = 1_000_000_000.0, fps: float = 30.0,
              depth_delay: float = 0.004) -> Path:
    """Write ``scene`` as a TUM RGB-D folder (a fixture for :func:`read_tum`); returns the folder.

    View k is stamped ``start + k / fps`` s; its depth frame ``depth_delay`` s later (TUM's two
    streams are not in step, so the reader's association is exercised); ground truth at the colour
    stamps; the shared K in ``intrinsics.txt``. ``depths``: per-view (H, W) metres (NaN = no reading)
    to store instead of the views' own. Depth is quantised to 1/5000 m; all views must share one K.
    """
    if not isinstance(scene, Scene) or not scene.views:
        raise TypeError("scene must be a non-empty ddp_lite.Scene")
    depths = [v.depth for v in scene.views] if depths is None else list(depths)
    if len(depths) != len(scene.views):
        raise ValueError(f"depths must hold one map per view ({len(scene.views)}), got {len(depths)}")
    K0 = scene.views[0].camera.K
    if any(not np.allclose(v.camera.K, K0) for v in scene.views):
        raise ValueError("a TUM folder has one camera: every view must share the first view's K")
    folder = Path(folder)
    rgb_lines, depth_lines, gt_lines = (["# timestamp filename"], ["# timestamp filename"],
                                        ["# timestamp tx ty tz qx qy qz qw"])
    for k, (view, depth) in enumerate(zip(scene.views, depths)):
        stamp, depth_stamp = start + k / fps, start + k / fps + depth_delay
        rgb_name, depth_name = f"rgb/{stamp:.6f}.png", f"depth/{depth_stamp:.6f}.png"
        write_bytes_atomic(folder / rgb_name, _png_bytes(view.rgb))
        write_bytes_atomic(folder / depth_name, _depth_png_bytes(np.asarray(depth), TUM_DEPTH_FACTOR, folder / depth_name))
        pose = view.camera.world_from_cam
        q = Rotation.from_matrix(pose[:3, :3]).as_quat()  # x, y, z, w
        rgb_lines.append(f"{stamp:.6f} {rgb_name}")
        depth_lines.append(f"{depth_stamp:.6f} {depth_name}")
        gt_lines.append(f"{stamp:.6f} " + " ".join(repr(float(v)) for v in (*pose[:3, 3], *q)))
    fx, fy, cx, cy = K0[0, 0], K0[1, 1], K0[0, 2], K0[1, 2]
    intrinsics = ["# fx fy cx cy (pixels; pixel (0, 0) = centre of the top-left pixel): ddp-lite's addition to TUM",
                  " ".join(repr(float(v)) for v in (fx, fy, cx, cy))]
    for file, lines in (("rgb.txt", rgb_lines), ("depth.txt", depth_lines), ("groundtruth.txt", gt_lines),
                        ("intrinsics.txt", intrinsics)):
        write_bytes_atomic(folder / file, ("\n".join(lines) + "\n").encode("ascii"))
    return folder


# ------------------------------------------------------------------------------------------------
# COLMAP
# ------------------------------------------------------------------------------------------------

# model → its parameter names, in cameras.txt order
COLMAP_MODELS = {
    "SIMPLE_PINHOLE": ("f", "cx", "cy"),
    "PINHOLE": ("fx", "fy", "cx", "cy"),
    "SIMPLE_RADIAL": ("f", "cx", "cy", "k"),
    "RADIAL": ("f", "cx", "cy", "k1", "k2"),
    "OPENCV": ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"),
}


@dataclass(frozen=True, eq=False)
class ColmapCamera:
    """One ``cameras.txt`` entry in the kit's convention: ``K`` (3×3 px, pixel (0, 0) = centre of the
    top-left pixel, i.e. COLMAP's cx, cy − 0.5) and OpenCV distortion ``dist`` (k1, k2, p1, p2, k3)."""

    camera_id: int
    model: str
    width: int
    height: int
    K: np.ndarray
    dist: np.ndarray


def read_colmap_cameras(path) -> dict[int, ColmapCamera]:
    """``cameras.txt`` → {camera_id: ColmapCamera}; models SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV."""
    cameras = {}
    for line, text in _text_lines(path):
        tokens = text.split()
        if len(tokens) < 4:
            raise _fail(path, line, f"expected 'CAMERA_ID MODEL WIDTH HEIGHT PARAMS...', got {text!r}")
        if not (tokens[0].isdigit() and tokens[2].isdigit() and tokens[3].isdigit()) or 0 in (int(tokens[2]), int(tokens[3])):
            raise _fail(path, line, f"CAMERA_ID, WIDTH and HEIGHT must be positive integers, got {' '.join(tokens[:4])!r}")
        model = tokens[1]
        if model not in COLMAP_MODELS:
            raise _fail(path, line, f"camera model {model!r} is not supported; use one of {sorted(COLMAP_MODELS)} "
                                    f"(or run 'colmap image_undistorter', which writes PINHOLE cameras)")
        names = COLMAP_MODELS[model]
        params = _floats(tokens[4:], path, line, "the camera parameters")
        if len(params) != len(names):
            raise _fail(path, line, f"{model} needs {len(names)} parameters ({' '.join(names)}), got {len(params)}")
        p = dict(zip(names, params))
        fx, fy = p.get("fx", p.get("f")), p.get("fy", p.get("f"))
        K = np.array([[fx, 0.0, p["cx"] - 0.5], [0.0, fy, p["cy"] - 0.5], [0.0, 0.0, 1.0]])
        dist = np.array([p.get("k1", p.get("k", 0.0)), p.get("k2", 0.0), p.get("p1", 0.0), p.get("p2", 0.0), 0.0])
        camera_id = int(tokens[0])
        if camera_id in cameras:
            raise _fail(path, line, f"CAMERA_ID {camera_id} appears twice")
        cameras[camera_id] = ColmapCamera(camera_id, model, int(tokens[2]), int(tokens[3]), K, dist)
    if not cameras:
        raise _fail(path, None, "defines no camera")
    return cameras


def read_colmap_images(path) -> list[tuple[int, str, int, np.ndarray, int]]:
    """``images.txt`` → [(image_id, name, camera_id, cam_from_world 4×4, line number)] sorted by name.

    Each image has two lines: the pose line, then its 2D points (which may be empty and are not read)."""
    lines = _text_lines(path, keep_blank=True)
    while lines and not lines[-1][1]:  # trailing blank lines are not a points line of a last image
        lines.pop()
    images, seen = [], set()
    for k in range(0, len(lines), 2):
        line, text = lines[k]
        tokens = text.split()
        if len(tokens) < 10:
            raise _fail(path, line, f"expected 'IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME' (then a line of 2D "
                                    f"points), got {text!r}")
        if not (tokens[0].isdigit() and tokens[8].isdigit()):
            raise _fail(path, line, f"IMAGE_ID and CAMERA_ID must be integers, got {tokens[0]!r} and {tokens[8]!r}")
        values = _floats(tokens[1:8], path, line, "QW QX QY QZ TX TY TZ")
        pose = np.eye(4)
        pose[:3, :3] = _rotation(np.r_[values[1:4], values[0]], path, line)  # COLMAP writes w first
        pose[:3, 3] = values[4:7]
        name = " ".join(tokens[9:])  # an image name may contain spaces
        if int(tokens[0]) in seen:
            raise _fail(path, line, f"IMAGE_ID {tokens[0]} appears twice")
        seen.add(int(tokens[0]))
        images.append((int(tokens[0]), name, int(tokens[8]), pose, line))
    if not images:
        raise _fail(path, None, "lists no images")
    images.sort(key=lambda item: item[1])
    return images


def read_colmap_depth(path) -> np.ndarray:
    """A COLMAP dense depth map (``*.geometric.bin`` / ``*.photometric.bin``) → (H, W) float32, as stored (0 = none).

    The file: ASCII ``width&height&channels&``, then width·height·channels little-endian float32
    values in column-major order (x fastest is *not* the order: the first column comes first)."""
    data = Path(path).read_bytes()
    header = re.match(rb"(\d+)&(\d+)&(\d+)&", data[:64])
    if header is None:
        raise _fail(path, 1, "not a COLMAP dense map: expected the header 'width&height&channels&'")
    width, height, channels = (int(v) for v in header.groups())
    count = width * height * channels
    if channels != 1 or count == 0:
        raise _fail(path, 1, f"a depth map has 1 channel and a positive size, got {width}&{height}&{channels}&")
    body = data[header.end():]
    if len(body) != 4 * count:
        raise _fail(path, None, f"holds {len(body)} data bytes, expected {4 * count} for {width}×{height}")
    return np.frombuffer(body, dtype="<f4").reshape(width, height).T.astype(np.float32)


def colmap_depth_bytes(depth) -> bytes:
    """(H, W) depth → the bytes of a COLMAP dense ``.bin`` map (NaN stored as 0, COLMAP's 'no depth')."""
    values = np.nan_to_num(np.asarray(depth, np.float32), nan=0.0)
    H, W = values.shape
    return f"{W}&{H}&1&".encode("ascii") + np.ascontiguousarray(values.T).astype("<f4").tobytes()


def write_colmap_depth(path, depth) -> None:
    """Write (H, W) depth as a COLMAP dense ``.bin`` map, atomically."""
    write_bytes_atomic(path, colmap_depth_bytes(depth))


def _find(folder: Path, candidates, what: str) -> Path:
    for candidate in candidates:
        if (folder / candidate).exists():
            return folder / candidate
    raise FileNotFoundError(f"folder: no {what} in {folder} (looked for {', '.join(map(str, candidates))})")


def _depth_path(depth_dir: Path, image_name: str, suffix: str | None) -> Path:
    """The depth file of an image: ``NAME + suffix`` (COLMAP keeps the image's extension) or ``STEM + suffix``."""
    suffixes = [suffix] if suffix else [".geometric.bin", ".photometric.bin", ".png", ".npy", ".pfm"]
    stem = str(Path(image_name).with_suffix(""))
    for s in suffixes:
        for candidate in (depth_dir / (image_name + s), depth_dir / (stem + s)):
            if candidate.is_file():
                return candidate
    raise FileNotFoundError(f"depth_dir: no depth map for image {image_name!r} in {depth_dir} "
                            f"(looked for {image_name}{suffixes[0]} and {stem}{suffixes[0]}, suffixes {suffixes})")


def read_colmap(folder, images_dir=None, depth_dir=None, depth_suffix: str | None = None,
                depth_scale: float | None = None, undistort: bool = False, size=None, name: str | None = None) -> Scene:
    """A COLMAP workspace (a text model + images + per-image depth) → ``Scene``.

    Args:
        folder: holds ``cameras.txt``/``images.txt`` itself or in ``sparse/`` or ``sparse/0/`` (convert a
            binary model first: ``colmap model_converter --output_type TXT``); images in ``images/``
            and depth in ``stereo/depth_maps/`` (COLMAP's dense workspace) or ``depth/`` by default.
        images_dir, depth_dir: other places for them. A depth map is ``NAME + depth_suffix`` or
            ``STEM + depth_suffix`` (default: the first of .geometric.bin, .photometric.bin, .png,
            .npy, .pfm that exists); maps smaller than the image are resampled by nearest pixel.
        depth_scale: units per stored value (metres per mm = 0.001 for a mm PNG; required for PNG;
            default 1 for float files).
        undistort: cameras with distortion (SIMPLE_RADIAL, RADIAL, OPENCV) are refused unless True, then
            their images and depth are undistorted with OpenCV (depth by nearest pixel).
        size: (H, W) to resample to.
    Returns:
        ``Scene``, views sorted by image name, named by the image name; COLMAP's world frame and units.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"folder: {folder} is not a folder")
    cameras_path = _find(folder, ["cameras.txt", "sparse/cameras.txt", "sparse/0/cameras.txt"], "cameras.txt")
    images_path = cameras_path.parent / "images.txt"
    cameras = read_colmap_cameras(cameras_path)
    images = read_colmap_images(images_path)
    images_dir = Path(images_dir) if images_dir is not None else folder / "images"
    if depth_dir is None:
        depth_dir = next((folder / d for d in ("stereo/depth_maps", "depth") if (folder / d).is_dir()), None)
        if depth_dir is None:
            raise FileNotFoundError(f"depth_dir: {folder} has neither stereo/depth_maps/ nor depth/; pass depth_dir")
    depth_dir = Path(depth_dir)
    views = []
    for image_id, image_name, camera_id, cam_from_world, line in images:
        if camera_id not in cameras:
            raise _fail(images_path, line, f"CAMERA_ID {camera_id} is not in {cameras_path}")
        cam = cameras[camera_id]
        if np.any(cam.dist != 0) and not undistort:
            raise _fail(cameras_path, None, f"camera {camera_id} is {cam.model} with lens distortion "
                                            f"{cam.dist[:4].tolist()}; the kit needs pinhole images: pass "
                                            f"undistort=True (CLI: --undistort) or run 'colmap image_undistorter'")
        rgb = _read_rgb(images_dir / image_name, "images_dir")
        if rgb.shape[:2] != (cam.height, cam.width):
            raise _fail(images_path, line, f"image {image_name} is {rgb.shape[1]}×{rgb.shape[0]} but camera {camera_id} "
                                           f"is {cam.width}×{cam.height}")
        depth = _read_depth_file(_depth_path(depth_dir, image_name, depth_suffix), depth_scale)
        if depth.shape != rgb.shape[:2]:  # COLMAP's --max_image_size makes smaller maps: pixel centres, as _resize
            depth = cv2.resize(depth, (cam.width, cam.height), interpolation=cv2.INTER_NEAREST_EXACT)
        if np.any(cam.dist != 0):
            rgb, depth = _undistort(rgb, depth, cam.K, cam.dist)
        views.append(View(rgb, depth, Camera(cam.K, cam_from_world, cam.width, cam.height), image_name))
    return _finish(name or folder.name, views, size)


def write_colmap(scene: Scene, folder, depths=None, depth_format: str = "bin", model: str = "PINHOLE",
                 depth_scale: float = 0.001) -> Path:
    """Write ``scene`` as a COLMAP dense workspace (a fixture for :func:`read_colmap`); returns the folder.

    ``images/<name>.png``, ``sparse/{cameras,images,points3D}.txt`` (one camera per view, ``model``
    PINHOLE or SIMPLE_PINHOLE (needs fx = fy)), and depth as ``stereo/depth_maps/<name>.png.geometric.bin``
    (``depth_format="bin"``) or ``depth/<name>.{png,npy,pfm}``; a PNG stores depth / ``depth_scale``
    as 16-bit integers. ``depths``: per-view maps to store instead of the views' own."""
    if not isinstance(scene, Scene) or not scene.views:
        raise TypeError("scene must be a non-empty ddp_lite.Scene")
    if model not in ("PINHOLE", "SIMPLE_PINHOLE"):
        raise ValueError(f"model must be 'PINHOLE' or 'SIMPLE_PINHOLE', got {model!r}")
    if depth_format not in ("bin", "png", "npy", "pfm"):
        raise ValueError(f"depth_format must be 'bin', 'png', 'npy' or 'pfm', got {depth_format!r}")
    depths = [v.depth for v in scene.views] if depths is None else list(depths)
    if len(depths) != len(scene.views):
        raise ValueError(f"depths must hold one map per view ({len(scene.views)}), got {len(depths)}")
    folder = Path(folder)
    camera_lines = ["# Camera list with one line of data per camera:", "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]"]
    image_lines = ["# Image list with two lines of data per image:",
                   "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME", "#   POINTS2D[] as (X, Y, POINT3D_ID)"]
    for k, (view, depth) in enumerate(zip(scene.views, depths), 1):
        K, cam = view.camera.K, view.camera
        if abs(K[0, 1]) > 1e-12:
            raise ValueError(f"view {k - 1}: COLMAP's pinhole models have no skew, K[0, 1] = {K[0, 1]}")
        cx, cy = K[0, 2] + 0.5, K[1, 2] + 0.5  # COLMAP: the top-left pixel's centre is (0.5, 0.5)
        if model == "SIMPLE_PINHOLE":
            if not np.isclose(K[0, 0], K[1, 1]):
                raise ValueError(f"view {k - 1}: SIMPLE_PINHOLE needs fx = fy, got {K[0, 0]} and {K[1, 1]}")
            params = (K[0, 0], cx, cy)
        else:
            params = (K[0, 0], K[1, 1], cx, cy)
        camera_lines.append(f"{k} {model} {cam.width} {cam.height} " + " ".join(repr(float(p)) for p in params))
        name = f"{view.name or f'view{k - 1:04d}'}.png"
        w, x, y, z = np.roll(Rotation.from_matrix(cam.cam_from_world[:3, :3]).as_quat(), 1)  # → w first
        t = cam.cam_from_world[:3, 3]
        image_lines += [f"{k} " + " ".join(repr(float(v)) for v in (w, x, y, z, *t)) + f" {k} {name}", ""]
        write_bytes_atomic(folder / "images" / name, _png_bytes(view.rgb))
        depth = np.asarray(depth, np.float32)
        if depth_format == "bin":
            write_colmap_depth(folder / "stereo" / "depth_maps" / f"{name}.geometric.bin", depth)
        elif depth_format == "png":
            target = folder / "depth" / f"{Path(name).stem}.png"
            write_bytes_atomic(target, _depth_png_bytes(depth, 1.0 / depth_scale, target))
        elif depth_format == "npy":
            write_bytes_atomic(folder / "depth" / f"{Path(name).stem}.npy", npy_bytes(depth))
        else:
            write_bytes_atomic(folder / "depth" / f"{Path(name).stem}.pfm", pfm_bytes(depth))
    write_bytes_atomic(folder / "sparse" / "cameras.txt", ("\n".join(camera_lines) + "\n").encode("utf-8"))
    write_bytes_atomic(folder / "sparse" / "images.txt", ("\n".join(image_lines) + "\n").encode("utf-8"))
    write_bytes_atomic(folder / "sparse" / "points3D.txt", b"# 3D point list (empty: no sparse points written)\n")
    return folder


# ------------------------------------------------------------------------------------------------
# the kit's own scenes, and one entry point
# ------------------------------------------------------------------------------------------------

def read_scene(path, size=None) -> Scene:
    """A ``Scene.save`` file (``.npz``), or a folder holding exactly one, → ``Scene`` (``size`` resamples)."""
    path = Path(path)
    if path.is_dir():
        found = sorted(path.glob("*.npz"))
        if len(found) != 1:
            raise ValueError(f"path: {path} must hold exactly one saved scene (.npz), found {len(found)}")
        path = found[0]
    if not path.is_file():
        raise FileNotFoundError(f"path: {path} does not exist")
    try:
        scene = Scene.load(path)
    except (KeyError, ValueError, OSError) as error:
        raise ValueError(f"path: {path} is not a scene written by Scene.save ({error})") from None
    if size is not None:
        from .datasets import resize_scene
        scene = resize_scene(scene, size)
    return scene


FORMATS = {"tum": read_tum, "colmap": read_colmap, "scene": read_scene}


def load_sequence(path, format: str, **options) -> Scene:
    """Read a sequence in ``format`` ('tum', 'colmap' or 'scene'); ``options`` go to that reader."""
    if format not in FORMATS:
        raise ValueError(f"format must be one of {sorted(FORMATS)}, got {format!r}")
    return FORMATS[format](path, **options)
