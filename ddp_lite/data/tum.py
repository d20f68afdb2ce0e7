"""TUM RGB-D sequence folders ↔ ``Scene``: reader and fixture writer.

**TUM RGB-D** (Sturm et al. 2012): ``rgb.txt`` and ``depth.txt`` list ``timestamp path`` per
line; ``groundtruth.txt`` lists ``timestamp tx ty tz qx qy qz qw``, the colour camera's optical
centre and orientation in the world (so ``world_from_cam``); ``#`` starts a comment. Depth PNGs
are 16-bit, metres × 5000, 0 = no reading. Colour and depth are stamped separately (~30 Hz
each, not in step): a colour frame is paired with the nearest unused depth frame within
``max_difference`` seconds (the greedy nearest-first matching of TUM's ``associate.py``), and
its pose is interpolated (position linearly, orientation by slerp) between the two
ground-truth samples around its timestamp. Intrinsics: the published fr1/fr2/fr3 colour
calibrations (fr1 and fr2 with lens distortion, undistorted here with OpenCV) or your own K.
Conventions as in ``formats``: depth float32 metres, NaN = no reading; OpenCV cameras.
"""
from __future__ import annotations

import os

import re
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ..core.files import write_bytes_atomic
from ..core.camera import Camera, check_intrinsics
from ..core.checks import check_bool, report_skipped
from .file_writers import checked_depth_png_bytes, rgb_png_bytes
from .fileio import check_plausible_depth, check_same_size, read_depth, read_rgb
from .resample import finish_scene, undistort_rgbd
from .textparse import parse_error, parse_floats, quaternion_rotation, text_lines
from ..core.views import Scene, View


# The published colour-camera calibrations of the TUM RGB-D benchmark (480×640; "file formats" /
# "camera calibration" pages): fx, fy, cx, cy and the OpenCV distortion k1, k2, p1, p2, k3.
# fr3 images were undistorted by the dataset authors; "ros" is the ROS default the depth was registered with.
TUM_INTRINSICS = {
    "fr1": ((517.306408, 516.469215, 318.643040, 255.313989), (0.262383, -0.953104, -0.005358, 0.002628, 1.163314)),
    "fr2": ((520.908620, 521.007327, 325.141442, 249.701764), (0.231222, -0.784899, -0.003257, -0.000105, 0.917205)),
    "fr3": ((535.4, 539.2, 320.1, 247.6), (0.0, 0.0, 0.0, 0.0, 0.0)),
    "ros": ((525.0, 525.0, 319.5, 239.5), (0.0, 0.0, 0.0, 0.0, 0.0)),
}


TUM_DEPTH_FACTOR = 5000.0  # stored value per metre


def read_tum_list(path) -> list[tuple[float, str]]:
    """``rgb.txt`` / ``depth.txt`` → [(timestamp s, relative path)], in file order.

    Example:
        >>> import tempfile, pathlib
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "rgb.txt"
        >>> _ = p.write_text("# timestamp filename\\n1.0 rgb/1.0.png\\n")
        >>> read_tum_list(p)
        [(1.0, 'rgb/1.0.png')]
    """
    entries, lines, files = [], {}, {}
    for line, text in text_lines(path):
        tokens = text.split()
        if len(tokens) != 2:
            raise parse_error(path, line, f"expected 'timestamp filename', got {text!r}")
        stamp = float(parse_floats(tokens[:1], path, line, "the timestamp")[0])
        if stamp in lines:  # two frames at one instant: the association would keep one at random
            raise parse_error(path, line, f"timestamp {tokens[0]} was already listed on line {lines[stamp]}; "
                                    f"every frame needs its own timestamp")
        lines[stamp] = line
        named = os.path.normpath(tokens[1])
        if named in files:  # one image for two instants: every frame would read the same pixels
            raise parse_error(path, line, f"{tokens[1]} was already listed on line {files[named]}; every frame "
                                    f"needs its own file (a list that names one file for every frame is broken)")
        files[named] = line
        entries.append((stamp, tokens[1]))
    if not entries:
        raise parse_error(path, None, "lists no frames")
    return entries


def read_tum_trajectory(path) -> tuple[np.ndarray, np.ndarray]:
    """``groundtruth.txt`` → timestamps (N,) s, sorted, and ``world_from_cam`` poses (N, 4, 4)."""
    stamps, poses = [], []
    for line, text in text_lines(path):
        tokens = text.split()
        if len(tokens) != 8:
            raise parse_error(path, line, f"expected 'timestamp tx ty tz qx qy qz qw' (8 numbers), got {len(tokens)}")
        values = parse_floats(tokens, path, line, "the pose")
        pose = np.eye(4)
        pose[:3, :3] = quaternion_rotation(values[4:8], path, line)
        pose[:3, 3] = values[1:4]
        stamps.append(values[0])
        poses.append(pose)
    if not stamps:
        raise parse_error(path, None, "holds no poses")
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
    """(K 3×3, distortion (5,), what to call it in a message) from a name ('fr1', 'fr2', 'fr3', 'ros'), a 3×3 K, or None: the folder's
    ``intrinsics.txt`` (the kit's addition for your own captures: one line ``fx fy cx cy``, pixels,
    pixel (0, 0) = centre of the top-left pixel), else the TUM camera its name says (``freiburg1`` …)."""
    if intrinsics is None and (folder / "intrinsics.txt").is_file():
        lines = text_lines(folder / "intrinsics.txt")
        if len(lines) != 1 or len(lines[0][1].split()) != 4:
            raise parse_error(folder / "intrinsics.txt", lines[0][0] if lines else None, "expected one line 'fx fy cx cy'")
        fx, fy, cx, cy = parse_floats(lines[0][1].split(), folder / "intrinsics.txt", lines[0][0], "fx fy cx cy")
        return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]), np.zeros(5), f"{folder / 'intrinsics.txt'}"
    named = intrinsics is None
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
        label = (f"intrinsics ({intrinsics!r}, the TUM camera {folder.name!r} names)" if named
                 else f"intrinsics ({intrinsics!r}, a 480×640 TUM camera)")
        return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]), np.array(dist), label
    K = np.asarray(intrinsics, dtype=np.float64)
    if K.shape != (3, 3) or not np.all(np.isfinite(K)):
        raise ValueError(f"intrinsics must be a name or a finite 3×3 K in pixels, got shape {K.shape}")
    return K, np.zeros(5), "intrinsics"


def read_tum(folder, intrinsics=None, every: int = 1, max_frames: int | None = None, max_difference: float = 0.02,
             undistort: bool = True, depth_factor: float = TUM_DEPTH_FACTOR, size=None, name: str | None = None,
             strict: bool = False) -> Scene:
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
        strict: refuse (``ValueError``) a folder whose frames cannot all be used (no partner frame, no
            pose) instead of leaving them out with a warning naming them.
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
    strict = check_bool(strict, "strict")
    K, dist, intrinsics_name = _tum_intrinsics(folder, intrinsics)
    rgb_list, depth_list = read_tum_list(folder / "rgb.txt"), read_tum_list(folder / "depth.txt")
    stamps, poses = read_tum_trajectory(folder / "groundtruth.txt")
    pairs = associate([t for t, _ in rgb_list], [t for t, _ in depth_list], max_difference)
    if not pairs:
        raise ValueError(f"folder: no colour frame of {folder / 'rgb.txt'} has a depth frame within "
                         f"{max_difference} s in {folder / 'depth.txt'}")
    paired_rgb, paired_depth = {i for i, _ in pairs}, {j for _, j in pairs}
    # uneven lists, or streams out of step: say which frames, never drop them in silence
    report_skipped(folder, [rgb_list[i][1] for i in range(len(rgb_list)) if i not in paired_rgb],
                   "colour frame(s)", f"have no depth frame within {max_difference} s ({len(depth_list)} depth frames "
                   f"listed; max_difference sets the tolerance)", strict, total=len(rgb_list))
    report_skipped(folder, [depth_list[j][1] for j in range(len(depth_list)) if j not in paired_depth],
                   "depth frame(s)", f"have no colour frame within {max_difference} s", strict, total=len(depth_list))
    chosen, unposed = [], []  # every-th pair, until max_frames of them have a pose
    for i, j in pairs[::int(every)]:
        if max_frames is not None and len(chosen) >= max_frames:
            break
        world_from_cam = _interpolate_pose(stamps, poses, rgb_list[i][0], max_difference)
        if world_from_cam is None:
            unposed.append(rgb_list[i][1])
        else:
            chosen.append((i, j, world_from_cam))
    report_skipped(folder, unposed, "frame(s)", f"have no ground-truth pose within {max_difference} s in "
                   f"{folder / 'groundtruth.txt'}", strict, total=len(unposed) + len(chosen))
    views, read = [], [folder]
    for i, j, world_from_cam in chosen:
        stamp, rgb_path = rgb_list[i]
        rgb = read_rgb(folder / rgb_path, "folder")
        scale, scale_name = 1.0 / float(depth_factor), "1/depth_factor (CLI: --depth-scale)"
        depth = read_depth(folder / depth_list[j][1], scale, "folder", scale_name=scale_name)
        if np.isfinite(depth).any():  # TUM depth is metric: a wrong factor shows as an implausible range
            check_plausible_depth(depth[np.isfinite(depth)], scale, f"folder: {depth_list[j][1]}", scale_name)
        read += [(folder / rgb_path).parent, (folder / depth_list[j][1]).parent]
        check_same_size(rgb.shape, depth.shape, folder / rgb_path, f"folder: {rgb_path}",  # TUM pairs are registered 1:1
                        f"{depth_list[j][1]}")
        check_intrinsics(K, rgb.shape[1], rgb.shape[0], intrinsics_name)  # before undistorting with it
        if undistort and np.any(dist != 0):
            rgb, depth = undistort_rgbd(rgb, depth, K, dist)
        camera = Camera(K, np.linalg.inv(world_from_cam), rgb.shape[1], rgb.shape[0])
        views.append(View(rgb, depth, camera, f"{stamp:.6f}"))
    if not views:
        raise ValueError(f"folder: no frame of {folder} has a ground-truth pose within {max_difference} s")
    return finish_scene(name or folder.name, views, size, read)


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
        write_bytes_atomic(folder / rgb_name, rgb_png_bytes(view.rgb))
        write_bytes_atomic(folder / depth_name, checked_depth_png_bytes(np.asarray(depth), TUM_DEPTH_FACTOR, folder / depth_name))
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
