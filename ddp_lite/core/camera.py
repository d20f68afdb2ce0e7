"""Pinhole cameras in the OpenCV convention.

Frames: x right, y down, z forward (metres). Pixel (0, 0) is the *centre* of the top-left
pixel, so a pixel's integer coordinates (u, v) = (column, row) name its centre, and the image
spans [-0.5, W - 0.5] × [-0.5, H - 0.5]. ``cam_from_world`` maps homogeneous world points to
camera points; the relative pose of a neighbour seen from a reference camera is
``nbr_from_ref = nbr.cam_from_world @ inv(ref.cam_from_world)``.
"""
from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np
import torch

from .checks import check_int, check_real

__all__ = ["Camera", "check_intrinsics", "relative_pose", "pixel_grid", "backproject", "project", "look_at", "view_overlap", "pixel_rays",
           "backproject_pixels", "project_points"]

MIN_FOCAL_RATIO, MAX_FOCAL_RATIO = 1e-3, 1e4  # focal length / larger image side


def _as_matrix(value, shape: tuple[int, int], name: str) -> np.ndarray:
    array = np.array(value, dtype=np.float64, copy=True)
    if array.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must contain only finite values")
    return array


def _check_size(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a positive integer, got {type(value).__name__} {value!r}")
    if not np.isfinite(value) or int(value) != value or value <= 0:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def check_intrinsics(K, width: int, height: int, name: str = "K") -> np.ndarray:
    """Intrinsics checked against the image they are used with → K as a float64 3×3 copy.

    The one rule wherever intrinsics enter (``Camera``, the readers, the command line): ``K`` (3×3,
    pixels, pixel (0, 0) = the centre of the top-left pixel) must be finite and invertible with
    positive focal lengths and last row [0, 0, 1]; its focal lengths plausible for a ``width ×
    height`` image (``MIN_FOCAL_RATIO``–``MAX_FOCAL_RATIO`` × the larger side: a field of view
    strictly between 0° and 180°); and its principal point inside the image. A K for another image
    size (a 480×640 camera's (319.5, 239.5) on a 32×48 image) fails the last; ``Camera.resized``
    scales K with the image. ``ValueError`` naming ``name`` (the argument or file K came from)."""
    width, height = _check_size(width, "width"), _check_size(height, "height")
    K = _as_matrix(K, (3, 3), name)
    if abs(np.linalg.det(K)) < 1e-12 or K[0, 0] <= 0 or K[1, 1] <= 0:
        raise ValueError(f"{name} must be invertible with positive focal lengths (pixels), got\n{K}")
    if not np.allclose(K[2], [0.0, 0.0, 1.0]):
        raise ValueError(f"{name}'s last row must be [0, 0, 1], got {K[2].tolist()}")
    # a pinhole's field of view lies strictly between 0° and 180°; far outside these bounds
    # (≈ 0.006° … 179.9°) a focal length is a unit mistake (mm for px, a scale applied twice)
    for axis, focal in (("fx", K[0, 0]), ("fy", K[1, 1])):
        ratio = focal / max(width, height)
        if not MIN_FOCAL_RATIO <= ratio <= MAX_FOCAL_RATIO:
            raise ValueError(f"{name}: focal length {axis}={focal:.6g} px is implausible for a {height}×{width} (H×W) "
                             f"image (expected {MIN_FOCAL_RATIO:g}–{MAX_FOCAL_RATIO:g} × the larger side); "
                             f"is it in pixels?")
    cx, cy = float(K[0, 2]), float(K[1, 2])
    if not (-0.5 <= cx <= width - 0.5 and -0.5 <= cy <= height - 0.5):
        raise ValueError(f"{name}: the principal point ({cx:.6g}, {cy:.6g}) px lies outside the {height}×{width} "
                         f"(H×W) image it is used with (x in [-0.5, {width - 0.5:g}], y in [-0.5, {height - 0.5:g}]); "
                         f"intrinsics belong to one image size, and these look like a ~{2 * cy + 1:.0f}×{2 * cx + 1:.0f} "
                         f"image's. Give the K of this image size (Camera.resized scales one)")
    return K


@dataclass(frozen=True, eq=False)
class Camera:
    """A calibrated pinhole camera: intrinsics ``K`` (3×3, pixels), ``cam_from_world`` (4×4).

    Example:
        >>> cam = Camera.from_fov(width=128, height=96, fov_x_deg=60.0)
        >>> cam.K.shape, cam.center.tolist()
        ((3, 3), [0.0, 0.0, 0.0])
    """

    K: np.ndarray
    cam_from_world: np.ndarray
    width: int
    height: int

    def __post_init__(self):
        for name in ("width", "height"):
            _check_size(getattr(self, name), name)
        K = check_intrinsics(self.K, self.width, self.height, "K")
        pose = _as_matrix(self.cam_from_world, (4, 4), "cam_from_world")
        if not np.allclose(pose[3], [0.0, 0.0, 0.0, 1.0]):
            raise ValueError(f"cam_from_world's last row must be [0, 0, 0, 1], got {pose[3].tolist()}")
        rotation = pose[:3, :3]
        if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
            raise ValueError("cam_from_world's upper-left 3×3 block must be a rotation matrix")
        K.setflags(write=False)
        pose.setflags(write=False)
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "cam_from_world", pose)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    @classmethod
    def from_fov(cls, width: int, height: int, fov_x_deg: float, cam_from_world=None) -> "Camera":
        """A camera with square pixels, principal point at the image centre, horizontal FOV in degrees."""
        check_real(fov_x_deg, "fov_x_deg", 0.0, 180.0, low_open=True, high_open=True)
        focal = 0.5 * width / np.tan(np.radians(fov_x_deg) / 2.0)
        K = np.array([[focal, 0.0, (width - 1) / 2.0], [0.0, focal, (height - 1) / 2.0], [0.0, 0.0, 1.0]])
        return cls(K, np.eye(4) if cam_from_world is None else cam_from_world, width, height)

    @property
    def world_from_cam(self) -> np.ndarray:
        """Inverse pose (4×4): camera points → world points."""
        return np.linalg.inv(self.cam_from_world)

    @property
    def center(self) -> np.ndarray:
        """Camera centre in world coordinates, (3,) metres."""
        return self.world_from_cam[:3, 3]

    @property
    def focal(self) -> float:
        """Horizontal focal length in pixels."""
        return float(self.K[0, 0])

    def resized(self, width: int, height: int) -> "Camera":
        """The same camera for an image resampled to ``width × height`` (pixel centres kept)."""
        check_int(width, "width", minimum=1), check_int(height, "height", minimum=1)
        sx, sy = width / self.width, height / self.height
        K = self.K.copy()
        K[0, 0] *= sx
        K[1, 1] *= sy
        K[0, 2] = (K[0, 2] + 0.5) * sx - 0.5
        K[1, 2] = (K[1, 2] + 0.5) * sy - 0.5
        return Camera(K, self.cam_from_world, width, height)

    def __repr__(self) -> str:
        c = self.center
        return (f"Camera({self.height}×{self.width} (H×W), f={self.focal:.1f}px, "
                f"centre=({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m)")


def relative_pose(ref: Camera, nbr: Camera) -> np.ndarray:
    """``nbr_from_ref`` (4×4): maps points in the reference camera frame to the neighbour's frame."""
    return nbr.cam_from_world @ np.linalg.inv(ref.cam_from_world)


def view_overlap(ref: "Camera", depth, nbr: "Camera", max_points: int = 4096) -> float:
    """The share of ``ref``'s valid depth pixels (``depth`` (H, W) metres, NaN = hole) that land in
    front of ``nbr`` and inside its image: 0 means the neighbour sees none of the reference."""
    v, u = np.nonzero(np.isfinite(depth))
    step = max(1, len(v) // max_points)
    v, u = v[::step], u[::step]
    points = np.linalg.inv(ref.K) @ np.stack([u, v, np.ones_like(u)]).astype(np.float64) * depth[v, u]
    pose = relative_pose(ref, nbr)
    points = pose[:3, :3] @ points + pose[:3, 3:]
    front = points[2] > 1e-9
    uvw = nbr.K @ points[:, front]
    x, y = uvw[0] / uvw[2], uvw[1] / uvw[2]
    inside = (x >= -0.5) & (x <= nbr.width - 0.5) & (y >= -0.5) & (y <= nbr.height - 0.5)
    return float(inside.sum()) / max(len(v), 1)


def view_parallax(ref: "Camera", depth, nbr: "Camera", max_points: int = 4096) -> float:
    """The largest parallax, in ``nbr``'s pixels, of ``ref``'s valid depth (``depth`` (H, W) metres):
    how far each point lands from where a point at infinity on the same ray would (the shift the
    warp loss measures depth by). 0 for a neighbour at the reference's centre; below a pixel, the
    neighbour's warp cannot tell depths apart (e.g. depth in millimetres with poses in metres)."""
    v, u = np.nonzero(np.isfinite(depth))
    step = max(1, len(v) // max_points)
    v, u = v[::step], u[::step]
    rays = np.linalg.inv(ref.K) @ np.stack([u, v, np.ones_like(u)]).astype(np.float64)  # (3, N), z = 1
    pose = relative_pose(ref, nbr)
    near = nbr.K @ (pose[:3, :3] @ (rays * depth[v, u]) + pose[:3, 3:])  # the point itself
    far = nbr.K @ (pose[:3, :3] @ rays)  # its vanishing point: rotation only
    ok = (near[2] > 1e-9) & (far[2] > 1e-9)
    if not ok.any():
        return 0.0
    shift = np.hypot(near[0, ok] / near[2, ok] - far[0, ok] / far[2, ok], near[1, ok] / near[2, ok] - far[1, ok] / far[2, ok])
    return float(shift.max())


def _point(value, name: str) -> np.ndarray:
    """``value`` as a finite 3-vector (float64); ``ValueError`` naming ``name`` otherwise."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be 3 numbers (x, y, z), got {value!r}") from None
    if array.shape != (3,):
        raise ValueError(f"{name} must be 3 numbers (x, y, z), got shape {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite, got {array.tolist()}")
    return array


def _direction(vector: np.ndarray, name: str, why: str) -> np.ndarray:
    """``vector`` scaled to unit length; ``ValueError`` naming ``name`` when it has (almost) none, which
    would make a NaN pose."""
    length = float(np.linalg.norm(vector))
    if not (np.isfinite(length) and length > 1e-12):
        raise ValueError(f"{name}: {why}")
    return vector / length


def look_at(eye, target, up=(0.0, -1.0, 0.0)) -> np.ndarray:
    """``cam_from_world`` (4×4) of a camera at ``eye`` looking at ``target`` (world metres).

    ``up`` is the world direction that should appear upwards in the image; with the OpenCV
    convention (y down) the default world "up" is -y. Degenerate input (``target`` at ``eye``, ``up``
    zero or along the viewing direction, a NaN or an infinity) → ``ValueError`` naming the argument,
    never a pose of NaNs.
    """
    eye, target, up = _point(eye, "eye"), _point(target, "target"), _point(up, "up")
    forward = _direction(target - eye, "target", f"{target.tolist()} is at eye {eye.tolist()}: no direction to look in")
    _direction(up, "up", "must be a non-zero direction")
    right = _direction(np.cross(forward, up), "up", f"{up.tolist()} is parallel to the viewing direction "
                       f"{forward.tolist()}; give an up that is not along it")  # x = y × z with y = -up
    down = np.cross(forward, right)
    world_from_cam = np.eye(4)
    world_from_cam[:3, 0], world_from_cam[:3, 1], world_from_cam[:3, 2] = right, down, forward
    world_from_cam[:3, 3] = eye
    pose = np.linalg.inv(world_from_cam)
    if not np.isfinite(pose).all():  # the one rule: a geometric helper never returns NaN
        raise ValueError(f"eye/target: {eye.tolist()} → {target.tolist()} gives a non-finite pose")
    return pose


# ---------------------------------------------------------------- NumPy: pixel lists ↔ world points

def pixel_rays(u, v, K) -> np.ndarray:
    """Pixels ``u``, ``v`` (N,) → camera-frame rays ``K⁻¹ (u, v, 1)`` (N, 3) float64 with z = 1, so
    the point at depth z (metres along the optical axis) on pixel (u, v) is ``z · ray``."""
    K = np.asarray(K, dtype=np.float64)
    if K.shape != (3, 3) or not np.isfinite(K).all() or abs(np.linalg.det(K)) < 1e-12:
        raise ValueError(f"K must be a finite, invertible 3×3 matrix, got {K.tolist() if K.size <= 9 else K.shape}")
    pixels = np.stack([u, v, np.ones(len(u))], 1).astype(np.float64)  # (N, 3)
    return pixels @ np.linalg.inv(K).T


def backproject_pixels(u, v, z, camera: Camera) -> np.ndarray:
    """Pixels ``u``, ``v`` (N,) with depths ``z`` (N,) metres → world points (N, 3) float64 metres."""
    points = pixel_rays(u, v, camera.K) * np.asarray(z, dtype=np.float64)[:, None]  # (N, 3) camera frame
    pose = camera.world_from_cam
    return points @ pose[:3, :3].T + pose[:3, 3]


def project_points(points, camera: Camera, eps: float = 1e-9):
    """World points (N, 3) metres → pixel ``u``, ``v`` (N,) and camera depth ``z`` (N,) metres;
    ``u``, ``v`` are NaN where the point is not in front of the camera (z ≤ ``eps``)."""
    local = points @ camera.cam_from_world[:3, :3].T + camera.cam_from_world[:3, 3]  # (N, 3) camera frame
    z = local[:, 2]
    uvw = local @ camera.K.T
    with np.errstate(divide="ignore", invalid="ignore"):
        front = z > eps
        u = np.where(front, uvw[:, 0] / z, np.nan)
        v = np.where(front, uvw[:, 1] / z, np.nan)
    return u, v, z


# ---------------------------------------------------------------- torch: whole images, differentiable

def pixel_grid(height: int, width: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """Homogeneous pixel centres (3, H·W): rows (u, v, 1), u = column, v = row, (0, 0) top-left."""
    v, u = torch.meshgrid(torch.arange(height, dtype=dtype, device=device),
                          torch.arange(width, dtype=dtype, device=device), indexing="ij")
    return torch.stack([u.reshape(-1), v.reshape(-1), torch.ones_like(u).reshape(-1)])


def backproject(depth: torch.Tensor, K: torch.Tensor) -> torch.Tensor:
    """Depth (B, 1, H, W) in metres (z, not ray length) → camera-frame points (B, 3, H, W)."""
    B, _, H, W = depth.shape
    rays = torch.linalg.inv(K.to(depth.dtype)) @ pixel_grid(H, W, depth.dtype, depth.device)  # (3, H·W)
    return rays.reshape(1, 3, H, W) * depth


def project(points: torch.Tensor, K: torch.Tensor, eps: float = 1e-6):
    """Camera-frame points (B, 3, H, W) → pixel coordinates (B, 2, H, W) and depth z (B, 1, H, W)."""
    B, _, H, W = points.shape
    uvw = (K.to(points.dtype) @ points.reshape(B, 3, -1)).reshape(B, 3, H, W)
    z = uvw[:, 2:3]
    return uvw[:, :2] / z.clamp(min=eps), z
