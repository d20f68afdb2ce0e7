"""Multi-view fusion: calibrated depth maps → one Open3D point cloud (paper Sec. 4.1 Tanks and Temples, Table 3).

The paper fuses its depth maps with **Fusibile** (Galliani et al. 2015) and reports two of its
parameters in Table 3: **C**, "the number of images in which a point has to have consistent
depth values", and **D**, the "threshold of difference in disparity allowed for two points
from two different depth maps to be merged" (supplement, "Reconstruction Pipeline").
``fuse_depths`` follows Fusibile's kernel, vectorised over the pixels of one view pair:

1. back-project a reference pixel p (depth z) to the world point X;
2. project X into another view j: pixel x_j and depth z_j; view j does not vote if x_j falls
   outside its image or X is behind it (nor if the two centres coincide: no baseline);
3. sample view j's depth z'_j at x_j, **nearest** pixel (Fusibile's point-sampled texture);
4. compare them as disparities with the pair's own baseline, as Fusibile does:
   ``|f·B/z_j - f·B/z'_j| < D`` px, f = reference focal length (px), B = distance between the
   two camera centres (m). So D is in pixels of disparity: on a 1920 px TnT image D = 1 is
   tight; the same D on a 64 px wide image is ~30× looser in depth (scale D with the width);
   relative to depth, D ≈ (f·B/z)·|Δz|/z, so it is a relative-depth test that tightens with
   the baseline;
5. (MVSNet's geometric check, on top of Fusibile's) back-project view j's pixel with z'_j and
   project it into the reference: it must land within ``reproj_threshold`` px of p;
6. keep X if at least **C = min_views** *other* views agree (Fusibile's ``num_consistent``; the
   reference itself is not counted, so C = 1 in Table 3 still asks for one confirming view);
   the fused point (and colour) is the mean of X and the agreeing views' points;
7. the agreeing pixels of the other views are marked used and are not fused again as
   references (Fusibile's ``used_pixels``), so a surface seen by n views is not output n times.

Fusibile also compares surface normals (its angle threshold); depth maps carry no normals here,
so that test is left out. ``tsdf_fuse`` is the volumetric alternative (Curless & Levoy 1996,
Open3D's ``ScalableTSDFVolume``); ``render_point_cloud`` draws a cloud without an OpenGL context.
"""
from __future__ import annotations

import os

import matplotlib
import numpy as np

from ..core.files import atomic_path
from ..core.camera import Camera, backproject_pixels, look_at, project_points
from ..core.checks import check_depth
from .open3d_loader import import_open3d  # Open3D itself on first use: ~1 s, only the point-cloud functions need it

__all__ = ["points_from_depth", "fuse_depths", "tsdf_fuse", "save_ply", "render_point_cloud"]


def _check_view(depth, camera, rgb=None, index: str = "") -> tuple:
    """float64 depth (H, W) with NaN holes, the camera, float64 rgb (or None); errors name the argument."""
    if not isinstance(camera, Camera):
        raise TypeError(f"camera{index} must be a ddp_lite.core.camera.Camera, got {type(camera).__name__}")
    array = check_depth(depth, f"depth{index}", min_valid=0, shape=(camera.height, camera.width), dtype=np.float64)
    if rgb is None:
        return array, camera, None
    image = np.asarray(rgb)
    if image.shape != array.shape + (3,):
        raise ValueError(f"image{index} must be (H, W, 3) = {array.shape + (3,)}, got {image.shape}")
    if image.dtype.kind in "ui" and image.dtype != np.bool_:  # 8- or 16-bit colour: scaled by its range, once
        image = image.astype(np.float64) / float(np.iinfo(image.dtype).max)
    image = image.astype(np.float64)
    if not np.all(np.isfinite(image)):
        raise ValueError(f"image{index} must be finite, in [0, 1]")
    if image.size and (image.min() < 0.0 or image.max() > 1.0):
        raise ValueError(f"image{index} must be colours in [0, 1] (a float image) or an integer image, got values in "
                         f"[{image.min():.4g}, {image.max():.4g}]" + ("; a 0-255 image stored as floats? divide it "
                                                                       "by 255" if image.max() > 1.0 else ""))
    return array, camera, image


def points_from_depth(depth, camera, rgb=None):
    """World points of the valid pixels of (H, W) depth (metres, z along the optical axis).

    Returns ``points`` (N, 3) float64 metres, row-major over the valid pixels, or
    ``(points, colours)`` with colours (N, 3) in [0, 1] when ``rgb`` (H, W, 3) is given.

    Example:
        >>> cam = Camera.from_fov(width=4, height=3, fov_x_deg=90.0)
        >>> points_from_depth(np.full((3, 4), 2.0), cam).shape
        (12, 3)
    """
    depth, camera, image = _check_view(depth, camera, rgb)
    v, u = np.nonzero(np.isfinite(depth))
    points = backproject_pixels(u.astype(np.float64), v.astype(np.float64), depth[v, u], camera)
    return points if image is None else (points, image[v, u])


def _check_views(depths, cameras, images):
    if not isinstance(depths, (list, tuple)) or not isinstance(cameras, (list, tuple)):
        raise TypeError("depths and cameras must be lists (one (H, W) depth map and one Camera per view)")
    if len(depths) != len(cameras) or len(depths) == 0:
        raise ValueError(f"depths and cameras must be non-empty and the same length, got {len(depths)} and "
                         f"{len(cameras)}")
    if images is not None and (not isinstance(images, (list, tuple)) or len(images) != len(depths)):
        raise ValueError(f"images must be None or a list of {len(depths)} (H, W, 3) images")
    return [_check_view(d, c, None if images is None else images[i], f"[{i}]")
            for i, (d, c) in enumerate(zip(depths, cameras))]


def _to_cloud(points: np.ndarray, colours=None):
    o3d = import_open3d()

    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.ascontiguousarray(points, np.float64)))
    if colours is not None:
        cloud.colors = o3d.utility.Vector3dVector(np.ascontiguousarray(np.clip(colours, 0.0, 1.0), np.float64))
    return cloud


def fuse_depths(depths, cameras, images=None, min_views: int = 2, disp_threshold: float = 0.25,
                reproj_threshold: float | None = 1.0):
    """Fusibile-style consistency fusion of N depth maps → ``open3d.geometry.PointCloud`` (world, metres).

    ``depths``: list of (H_i, W_i) metres with NaN holes; ``cameras``: list of ``Camera``;
    ``images``: optional list of (H_i, W_i, 3) in [0, 1] (then the cloud has colours).
    ``min_views`` = Table 3's C: how many *other* views must agree (0 keeps every valid pixel once).
    ``disp_threshold`` = Table 3's D, pixels of disparity ``f·B/z`` with the pair's baseline B.
    The paper used D = 0.5–4 on ~1920 px wide TnT images; disparity scales with the image width,
    so the default 0.25 px suits the kit's 64–128 px images (at 64 px and 1–2 m, D = 1 would
    merge depths ~30 % apart between neighbouring desk views; 0.25 rejects a +20 % error).
    ``reproj_threshold``: MVSNet's round-trip check in reference pixels; ``None`` turns it off
    (pure Fusibile). See the module docstring for the exact steps.

    Example:
        >>> from ddp_lite.world.scenes import make_scene
        >>> scene = make_scene("desk", size=(48, 64), n_views=4)
        >>> cloud = fuse_depths([v.depth for v in scene], [v.camera for v in scene], min_views=2)
    """
    views = _check_views(depths, cameras, images)
    n = len(views)
    if isinstance(min_views, bool) or int(min_views) != min_views or not 0 <= min_views <= n - 1:
        raise ValueError(f"min_views must be an integer in [0, {n - 1}] for {n} views, got {min_views!r}")
    if not (np.isscalar(disp_threshold) and disp_threshold > 0):
        raise ValueError(f"disp_threshold must be a positive number of pixels, got {disp_threshold!r}")
    if reproj_threshold is not None and not (np.isscalar(reproj_threshold) and reproj_threshold > 0):
        raise ValueError(f"reproj_threshold must be a positive number of pixels or None, got {reproj_threshold!r}")

    used = [np.zeros(d.shape, bool) for d, _, _ in views]
    out_points, out_colours = [], []
    for i, (depth, cam, image) in enumerate(views):
        rows_i, cols_i = np.nonzero(np.isfinite(depth) & ~used[i])  # (M,) reference pixels not fused yet
        if len(rows_i) == 0:
            continue
        u, v = cols_i.astype(np.float64), rows_i.astype(np.float64)
        X = backproject_pixels(u, v, depth[rows_i, cols_i], cam)  # (M, 3)
        point_sum = X.copy()
        colour_sum = None if image is None else image[rows_i, cols_i].copy()
        count = np.zeros(len(u), int)
        matches = []  # per other view: (index, agreeing mask (M,), its pixel row, col)
        for j, (depth_j, cam_j, image_j) in enumerate(views):
            fb = cam.K[0, 0] * np.linalg.norm(cam.center - cam_j.center)  # f·B, px·m
            if j == i or fb < 1e-9:  # no baseline, no disparity to compare: this view cannot vote
                continue
            H, W = depth_j.shape
            uj, vj, zj = project_points(X, cam_j)
            col, row = np.floor(uj + 0.5), np.floor(vj + 0.5)  # nearest pixel; NaN behind the camera
            inside = (col >= 0) & (col < W) & (row >= 0) & (row < H)
            col, row = np.where(inside, col, 0).astype(int), np.where(inside, row, 0).astype(int)
            sampled = np.where(inside, depth_j[row, col], np.nan)  # view j's own depth there
            with np.errstate(invalid="ignore", divide="ignore"):
                agree = np.abs(fb / zj - fb / sampled) < disp_threshold  # NaN → False
            Xj = backproject_pixels(col.astype(np.float64), row.astype(np.float64), np.nan_to_num(sampled, nan=1.0),
                                    cam_j)
            if reproj_threshold is not None:
                ur, vr, _ = project_points(Xj, cam)
                with np.errstate(invalid="ignore"):
                    agree &= np.hypot(ur - u, vr - v) < reproj_threshold
            count += agree
            point_sum[agree] += Xj[agree]
            if colour_sum is not None:
                colour_sum[agree] += image_j[row[agree], col[agree]]
            matches.append((j, agree, row, col))
        keep = count >= min_views
        out_points.append(point_sum[keep] / (count[keep, None] + 1.0))
        if colour_sum is not None:
            out_colours.append(colour_sum[keep] / (count[keep, None] + 1.0))
        for j, agree, row, col in matches:  # Fusibile: don't fuse these pixels again as references
            used[j][row[agree & keep], col[agree & keep]] = True
    points = np.concatenate(out_points) if out_points else np.zeros((0, 3))
    if images is None:
        return _to_cloud(points)
    return _to_cloud(points, np.concatenate(out_colours) if out_colours else np.zeros((0, 3)))


def tsdf_fuse(depths, cameras, images=None, voxel_length: float = 0.01, sdf_trunc: float | None = None):
    """TSDF fusion (Open3D ``ScalableTSDFVolume``) of N depth maps → ``open3d.geometry.PointCloud`` (metres).

    ``voxel_length`` (m) is the voxel size; ``sdf_trunc`` (m, default 4 voxels) the truncation of the
    signed distance. ``images`` (H, W, 3) in [0, 1] colour the result; without them the cloud has
    no colours. The points are the zero crossings of the averaged signed distance.
    """
    o3d = import_open3d()

    views = _check_views(depths, cameras, images)
    if not (np.isscalar(voxel_length) and voxel_length > 0):
        raise ValueError(f"voxel_length must be a positive length in metres, got {voxel_length!r}")
    sdf_trunc = 4.0 * voxel_length if sdf_trunc is None else sdf_trunc
    if not (np.isscalar(sdf_trunc) and sdf_trunc > voxel_length):
        raise ValueError(f"sdf_trunc must be a length in metres larger than voxel_length, got {sdf_trunc!r}")
    colour = o3d.pipelines.integration.TSDFVolumeColorType.RGB8 if images is not None else \
        o3d.pipelines.integration.TSDFVolumeColorType.NoColor
    volume = o3d.pipelines.integration.ScalableTSDFVolume(voxel_length=float(voxel_length),
                                                          sdf_trunc=float(sdf_trunc), color_type=colour)
    for depth, cam, image in views:
        H, W = depth.shape
        rgb = np.full((H, W, 3), 0.5) if image is None else image
        rgb8 = np.ascontiguousarray(np.clip(rgb * 255.0 + 0.5, 0, 255).astype(np.uint8))
        depth32 = np.ascontiguousarray(np.nan_to_num(depth, nan=0.0).astype(np.float32))  # 0 = no reading
        far = float(np.nanmax(depth)) + 1.0 if np.isfinite(depth).any() else 1.0
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            o3d.geometry.Image(rgb8), o3d.geometry.Image(depth32), depth_scale=1.0, depth_trunc=far,
            convert_rgb_to_intensity=False)
        K = cam.K
        intrinsic = o3d.camera.PinholeCameraIntrinsic(W, H, K[0, 0], K[1, 1], K[0, 2], K[1, 2])
        volume.integrate(rgbd, intrinsic, np.ascontiguousarray(cam.cam_from_world))
    return volume.extract_point_cloud()


def save_ply(cloud, path) -> None:
    """Write an ``open3d.geometry.PointCloud`` to a ``.ply`` file atomically (temporary file, then rename)."""
    o3d = import_open3d()

    if not isinstance(cloud, o3d.geometry.PointCloud):
        raise TypeError(f"cloud must be an open3d.geometry.PointCloud, got {type(cloud).__name__}")
    path = os.fspath(path)
    if not path.lower().endswith(".ply"):
        raise ValueError(f"path must end in .ply, got {path!r}")
    if not cloud.has_points():  # Open3D cannot write one; said here, not as "could not write"
        raise ValueError(f"cloud has no points (every depth was a hole, or no point was seen by enough views); "
                         f"nothing was written to {path!r}")
    with atomic_path(path, suffix=".ply") as tmp:  # Open3D picks the format from the suffix
        if not o3d.io.write_point_cloud(tmp, cloud):
            raise OSError(f"open3d could not write {path!r}")


def _default_camera(points: np.ndarray) -> Camera:
    """A 96×128 (H×W), 60° camera looking along +z at the cloud's centre, just far enough back to see every point."""
    centre = (points.min(0) + points.max(0)) / 2.0
    offset = points - centre  # (N, 3)
    tan_x = 0.95 * np.tan(np.radians(30.0))  # a 5 % margin inside the frame
    tan_y = tan_x * 96.0 / 128.0
    # a point at (x, y, z) is inside the frame when |x| ≤ tan_x · (distance + z), same for y
    distance = np.max(np.maximum(np.abs(offset[:, 0]) / tan_x, np.abs(offset[:, 1]) / tan_y) - offset[:, 2])
    distance = max(float(distance), float(np.ptp(points[:, 2])) / 2.0 + 1e-3, 1e-3)  # stay in front of the cloud
    return Camera.from_fov(128, 96, 60.0, look_at(centre - np.array([0.0, 0.0, distance]), centre))


def render_point_cloud(cloud, camera=None, ax=None, point_size: int = 1, background=(1.0, 1.0, 1.0),
                       depth_range=None, colorbar: bool = True):
    """Render a point cloud through a pinhole camera with a z-buffer → (H, W, 3) float32 image in [0, 1].

    Each point is splatted as a ``point_size`` × ``point_size`` square; where splats overlap the
    nearest point wins. Colours come from the cloud, or from its depth (viridis, near = yellow)
    if it has none: ``depth_range`` (near, far) in metres fixes that colour scale, so that several
    renders compare (default: the cloud's own 1st-99th percentile). ``camera``: default a 96×128 (H×W),
    60° view along +z (the kit's scenes are seen along +z), centred on the cloud and just far
    enough back to frame all of it. With ``ax``, the image is also drawn there, with a depth colour
    bar when the colours are depths (``colorbar=False``: none, for renders that share one
    ``depth_range`` and so one :func:`~ddp_lite.evaluation.viz.shared_colorbar`). No OpenGL: works headless.
    """
    o3d = import_open3d()

    if isinstance(cloud, o3d.geometry.PointCloud):
        points = np.asarray(cloud.points, np.float64)
        colours = np.asarray(cloud.colors, np.float64) if cloud.has_colors() else None
    else:
        points, colours = np.asarray(cloud, np.float64), None
    if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
        raise ValueError(f"cloud must be a non-empty open3d PointCloud or (N, 3) array, got shape {points.shape}")
    if isinstance(point_size, bool) or int(point_size) != point_size or point_size < 1:
        raise ValueError(f"point_size must be a positive integer (pixels), got {point_size!r}")
    camera = _default_camera(points) if camera is None else camera
    if not isinstance(camera, Camera):
        raise TypeError(f"camera must be a ddp_lite.core.camera.Camera or None, got {type(camera).__name__}")
    H, W = camera.height, camera.width
    u, v, z = project_points(points, camera)
    by_depth = colours is None
    if by_depth:
        visible = np.isfinite(u)
        if depth_range is not None:
            lo, hi = (float(x) for x in depth_range)
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
                raise ValueError(f"depth_range must be (near, far) metres with near < far, got {depth_range!r}")
        else:
            lo, hi = (np.percentile(z[visible], q) for q in (1, 99)) if visible.any() else (0.0, 1.0)
        colours = matplotlib.colormaps["viridis_r"](np.clip((z - lo) / max(hi - lo, 1e-9), 0, 1))[:, :3]
    col, row = np.floor(u + 0.5), np.floor(v + 0.5)
    offsets = np.arange(point_size) - (point_size - 1) // 2
    shape = (len(points), point_size, point_size)
    cols = np.broadcast_to(col[:, None, None] + offsets[None, None, :], shape).ravel()  # (N·s²,)
    rows = np.broadcast_to(row[:, None, None] + offsets[None, :, None], shape).ravel()
    depth = np.repeat(z, point_size ** 2)
    source = np.repeat(np.arange(len(points)), point_size ** 2)
    ok = np.isfinite(cols) & (cols >= 0) & (cols < W) & (rows >= 0) & (rows < H)
    pixel = rows[ok].astype(int) * W + cols[ok].astype(int)
    order = np.lexsort((depth[ok], pixel))  # by pixel, then nearest first
    pixel, first = np.unique(pixel[order], return_index=True)  # the nearest splat per pixel
    image = np.empty((H * W, 3), np.float32)
    image[:] = background
    image[pixel] = colours[source[ok][order][first]]
    image = image.reshape(H, W, 3)
    if ax is not None:
        ax.imshow(image, interpolation="nearest")
        ax.axis("off")
        if by_depth and colorbar:
            scale = matplotlib.cm.ScalarMappable(matplotlib.colors.Normalize(lo, hi), matplotlib.colormaps["viridis_r"])
            ax.figure.colorbar(scale, ax=ax, fraction=0.046, pad=0.04, label="depth along the view (m)")
    return image
