"""Which views help a reference view most: MVSNet's view-selection score.

DDP's warp loss compares the reference image with N = 2 neighbouring images warped into it; a
neighbour helps when it sees the same surfaces from a moderately different angle. MVSNet (Yao et
al. 2018) scores a candidate view j by a sum over 3D points both views see of a piecewise
Gaussian of the triangulation angle θ between the two rays:
``exp(-(θ - θ0)² / (2σ²))`` with θ0 = 5°, σ = 1° below θ0 and 10° above (a small angle
triangulates badly, a large one sees different sides). Here the points are the reference view's
ground-truth depth on every ``stride``-th pixel, and a point counts as seen by view j when it
projects inside j's image with a depth within 2 % of j's own depth there (not occluded).
"""
from __future__ import annotations

import numpy as np

from ..core.camera import backproject_pixels, project_points
from ..core.views import Scene

__all__ = ["select_neighbors"]

THETA0_DEG, SIGMA_BELOW_DEG, SIGMA_ABOVE_DEG = 5.0, 1.0, 10.0
VISIBLE_TOLERANCE = 0.02  # relative depth difference under which view j sees the point


def select_neighbors(scene: Scene, ref: int, n: int = 2, stride: int = 4) -> list[int]:
    """Indices of the ``n`` best neighbour views of view ``ref`` by MVSNet's score: a sum over
    shared 3D points (ref GT depth, every ``stride``-th pixel) of a piecewise Gaussian of the
    triangulation angle θ (θ0 = 5°, σ1 = 1°, σ2 = 10°), sorted by score, descending."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a Scene, got {type(scene).__name__}")
    if int(ref) != ref or not 0 <= ref < len(scene):
        raise ValueError(f"ref must be a view index in [0, {len(scene)}), got {ref!r}")
    if int(n) != n or not 1 <= n < len(scene):
        raise ValueError(f"n must be in [1, {len(scene) - 1}] for a scene of {len(scene)} views, got {n!r}")
    if int(stride) != stride or stride < 1:
        raise ValueError(f"stride must be a positive integer, got {stride!r}")
    view = scene[ref]
    depth = view.depth[::stride, ::stride].astype(np.float64)  # (h, w)
    v, u = np.mgrid[0:view.depth.shape[0]:stride, 0:view.depth.shape[1]:stride]
    ok = np.isfinite(depth)
    world = backproject_pixels(u[ok], v[ok], depth[ok], view.camera)  # (M, 3)
    c_ref = view.camera.center
    scores = []
    for j, other in enumerate(scene.views):
        if j == ref:
            continue
        cam = other.camera
        uj, vj, z = project_points(world, cam)  # (M,) each; NaN behind view j
        front = np.isfinite(uj)
        ui, vi = (np.round(np.where(front, x, -1.0)).astype(int) for x in (uj, vj))
        inside = front & (ui >= 0) & (ui < cam.width) & (vi >= 0) & (vi < cam.height)
        seen = np.zeros(len(z), bool)  # visible: inside the image and not occluded in view j
        zj = other.depth[vi[inside], ui[inside]]
        seen[inside] = np.abs(zj - z[inside]) <= VISIBLE_TOLERANCE * z[inside]
        a, b = world[seen] - c_ref, world[seen] - cam.center
        cos = np.einsum("ij,ij->i", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        theta = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        sigma = np.where(theta <= THETA0_DEG, SIGMA_BELOW_DEG, SIGMA_ABOVE_DEG)
        scores.append((float(np.exp(-(theta - THETA0_DEG) ** 2 / (2 * sigma ** 2)).sum()), j))
    scores.sort(key=lambda s: (-s[0], s[1]))
    return [j for _, j in scores[: int(n)]]
