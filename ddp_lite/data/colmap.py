"""COLMAP text models + per-image depth ↔ ``Scene``: reader and fixture writer.

**COLMAP** text model (``cameras.txt``, ``images.txt``): a camera line is
``CAMERA_ID MODEL WIDTH HEIGHT PARAMS...``; an image takes two lines,
``IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME`` (the quaternion and translation of
``cam_from_world``) and then its 2D points (possibly an empty line). COLMAP puts the centre
of the top-left pixel at (0.5, 0.5), the kit at (0, 0): cx, cy are shifted by -0.5 on reading,
+0.5 on writing. Depth per image: COLMAP's dense ``.bin`` maps (``stereo/depth_maps/NAME.
geometric.bin``, read by ``fileio.read_colmap_depth``), or 16-bit PNG / ``.npy`` / ``.pfm``
files named after the image, times a scale. COLMAP's units are whatever the reconstruction's
scale is (metres only if you scaled it).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from ..core.files import regular_file, write_bytes_atomic
from ..core.camera import Camera, check_intrinsics
from ..core.checks import check_bool, report_skipped
from .file_writers import checked_depth_png_bytes, float_depth, npy_bytes, pfm_bytes, rgb_png_bytes, write_colmap_depth
from .fileio import check_same_size, read_depth, read_rgb
from .resample import finish_scene, undistort_rgbd
from .textparse import parse_error, parse_floats, quaternion_rotation, text_lines
from ..core.views import Scene, View

__all__ = ["COLMAP_MODELS", "ColmapCamera", "read_colmap_cameras", "read_colmap_images", "read_colmap", "write_colmap"]


IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".tif", ".tiff", ".bmp", ".webp")  # what a folder of photos holds

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
    for line, text in text_lines(path):
        tokens = text.split()
        if len(tokens) < 4:
            raise parse_error(path, line, f"expected 'CAMERA_ID MODEL WIDTH HEIGHT PARAMS...', got {text!r}")
        if not (tokens[0].isdigit() and tokens[2].isdigit() and tokens[3].isdigit()) or 0 in (int(tokens[2]), int(tokens[3])):
            raise parse_error(path, line, f"CAMERA_ID, WIDTH and HEIGHT must be positive integers, got {' '.join(tokens[:4])!r}")
        model = tokens[1]
        if model not in COLMAP_MODELS:
            raise parse_error(path, line, f"camera model {model!r} is not supported; use one of {sorted(COLMAP_MODELS)} "
                                    f"(or run 'colmap image_undistorter', which writes PINHOLE cameras)")
        names = COLMAP_MODELS[model]
        params = parse_floats(tokens[4:], path, line, "the camera parameters")
        if len(params) != len(names):
            raise parse_error(path, line, f"{model} needs {len(names)} parameters ({' '.join(names)}), got {len(params)}")
        p = dict(zip(names, params))
        fx, fy = p.get("fx", p.get("f")), p.get("fy", p.get("f"))
        K = np.array([[fx, 0.0, p["cx"] - 0.5], [0.0, fy, p["cy"] - 0.5], [0.0, 0.0, 1.0]])
        dist = np.array([p.get("k1", p.get("k", 0.0)), p.get("k2", 0.0), p.get("p1", 0.0), p.get("p2", 0.0), 0.0])
        try:  # the camera against its own WIDTH HEIGHT, before any image is read
            check_intrinsics(K, int(tokens[2]), int(tokens[3]), "K")
        except ValueError as error:
            raise parse_error(path, line, f"camera {tokens[0]}: {error}") from None
        camera_id = int(tokens[0])
        if camera_id in cameras:
            raise parse_error(path, line, f"CAMERA_ID {camera_id} appears twice")
        cameras[camera_id] = ColmapCamera(camera_id, model, int(tokens[2]), int(tokens[3]), K, dist)
    if not cameras:
        raise parse_error(path, None, "defines no camera")
    return cameras


def read_colmap_images(path) -> list[tuple[int, str, int, np.ndarray, int]]:
    """``images.txt`` → [(image_id, name, camera_id, cam_from_world 4×4, line number)] sorted by name.

    Each image has two lines: the pose line, then its 2D points (which may be empty and are not read)."""
    lines = text_lines(path, keep_blank=True)
    while lines and not lines[-1][1]:  # trailing blank lines are not a points line of a last image
        lines.pop()
    images, seen = [], set()
    for k in range(0, len(lines), 2):
        line, text = lines[k]
        tokens = text.split()
        if len(tokens) < 10:
            raise parse_error(path, line, f"expected 'IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME' (then a line of 2D "
                                    f"points), got {text!r}")
        if not (tokens[0].isdigit() and tokens[8].isdigit()):
            raise parse_error(path, line, f"IMAGE_ID and CAMERA_ID must be integers, got {tokens[0]!r} and {tokens[8]!r}")
        values = parse_floats(tokens[1:8], path, line, "QW QX QY QZ TX TY TZ")
        pose = np.eye(4)
        pose[:3, :3] = quaternion_rotation(np.r_[values[1:4], values[0]], path, line)  # COLMAP writes w first
        pose[:3, 3] = values[4:7]
        name = " ".join(tokens[9:])  # an image name may contain spaces
        if int(tokens[0]) in seen:
            raise parse_error(path, line, f"IMAGE_ID {tokens[0]} appears twice")
        seen.add(int(tokens[0]))
        images.append((int(tokens[0]), name, int(tokens[8]), pose, line))
    if not images:
        raise parse_error(path, None, "lists no images")
    images.sort(key=lambda item: item[1])
    return images


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
        found = [c for c in dict.fromkeys((depth_dir / (image_name + s), depth_dir / (stem + s))) if c.exists()]
        if len(found) == 2:  # one would shadow the other (say, an earlier run's output written here)
            raise FileNotFoundError(f"depth_dir: image {image_name!r} has two depth maps in {depth_dir}: "
                                    f"{found[0].name} and {found[1].name}; keep one (or pass depth_suffix)")
        if found:
            return regular_file(found[0], "depth_dir")
    raise FileNotFoundError(f"depth_dir: no depth map for image {image_name!r} in {depth_dir} "
                            f"(looked for {image_name}{suffixes[0]} and {stem}{suffixes[0]}, suffixes {suffixes})")


def read_colmap(folder, images_dir=None, depth_dir=None, depth_suffix: str | None = None,
                depth_scale: float | None = None, undistort: bool = False, size=None, name: str | None = None,
                strict: bool = False) -> Scene:
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
        strict: refuse (``ValueError``) a workspace with images that ``images.txt`` does not list (COLMAP
            could not register them) instead of leaving them out with a warning naming them.
    Returns:
        ``Scene``, views sorted by image name, named by the image name; COLMAP's world frame and units.
    """
    folder = Path(folder)
    strict = check_bool(strict, "strict")
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
    if images_dir.is_dir():  # images COLMAP did not register have no pose: say which are left out
        listed = {str(Path(image_name)) for _, image_name, _, _, _ in images}
        found = sorted(str(p.relative_to(images_dir)) for p in images_dir.rglob("*")
                       if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file())
        report_skipped(images_dir, [f for f in found if f not in listed], "image(s)",
                       f"are not listed in {images_path} (COLMAP registered no pose for them)", strict, total=len(found))
    views = []
    for image_id, image_name, camera_id, cam_from_world, line in images:
        if camera_id not in cameras:
            raise parse_error(images_path, line, f"CAMERA_ID {camera_id} is not in {cameras_path}")
        cam = cameras[camera_id]
        if np.any(cam.dist != 0) and not undistort:
            raise parse_error(cameras_path, None, f"camera {camera_id} is {cam.model} with lens distortion "
                                            f"{cam.dist[:4].tolist()}; the kit needs pinhole images: pass "
                                            f"undistort=True (CLI: --undistort) or run 'colmap image_undistorter'")
        rgb = read_rgb(images_dir / image_name, "images_dir")
        try:
            check_same_size(rgb.shape, (cam.height, cam.width), images_dir / image_name, f"image {image_name}",
                            f"camera {camera_id}")
        except ValueError as error:
            raise parse_error(images_path, line, str(error)) from None
        depth = read_depth(_depth_path(depth_dir, image_name, depth_suffix), depth_scale, "depth_dir")
        if depth.shape != rgb.shape[:2]:  # COLMAP's --max_image_size makes smaller maps: pixel centres, as resize_view
            depth = cv2.resize(depth, (cam.width, cam.height), interpolation=cv2.INTER_NEAREST_EXACT)
        if np.any(cam.dist != 0):
            rgb, depth = undistort_rgbd(rgb, depth, cam.K, cam.dist)
        views.append(View(rgb, depth, Camera(cam.K, cam_from_world, cam.width, cam.height), image_name))
    return finish_scene(name or folder.name, views, size, [folder, cameras_path.parent, images_dir, depth_dir])


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
        write_bytes_atomic(folder / "images" / name, rgb_png_bytes(view.rgb))
        depth = np.asarray(depth, np.float32)
        if depth_format == "bin":
            write_colmap_depth(folder / "stereo" / "depth_maps" / f"{name}.geometric.bin", depth)
        elif depth_format == "png":
            target = folder / "depth" / f"{Path(name).stem}.png"
            write_bytes_atomic(target, checked_depth_png_bytes(depth, 1.0 / depth_scale, target))
        elif depth_format == "npy":
            write_bytes_atomic(folder / "depth" / f"{Path(name).stem}.npy", npy_bytes(float_depth(depth)))
        else:
            write_bytes_atomic(folder / "depth" / f"{Path(name).stem}.pfm", pfm_bytes(float_depth(depth)))
    write_bytes_atomic(folder / "sparse" / "cameras.txt", ("\n".join(camera_lines) + "\n").encode("utf-8"))
    write_bytes_atomic(folder / "sparse" / "images.txt", ("\n".join(image_lines) + "\n").encode("utf-8"))
    write_bytes_atomic(folder / "sparse" / "points3D.txt", b"# 3D point list (empty: no sparse points written)\n")
    return folder
