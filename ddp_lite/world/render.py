"""The synthetic renderer: primitives with closed-form ray hits, and a NumPy ray-caster.

How it works (all NumPy, no loop over pixels):

1. **Rays.** For pixel (u, v) the camera-frame direction is ``d = K⁻¹ (u, v, 1)``, whose z is
   exactly 1. Rotated into the world, a point ``C + t·d`` on that ray has camera depth
   ``z = t``, so the ray parameter of the first hit *is* the depth map, with no conversion.
2. **Intersections.** Each primitive (``Plane``, ``Box``, ``Sphere``, ``Cylinder``; more in
   ``solids.py`` and ``terrain.py``) returns the ray parameter of its first hit (``inf`` on a miss) in closed
   form: one linear equation for a plane, the slab test for a box, a quadratic for a sphere or a
   cylinder's side. The nearest hit over the few primitives wins (a loop over primitives, not
   pixels). Interface: ``intersect(o (3,), d (N, 3)) -> t (N,)`` and ``surface(x (M, 3)) ->
   (local (M, 3), st (M, 2), normal (M, 3))``, metres; ``texture`` a :class:`~ddp_lite.world.textures.Texture`.
3. **Colour.** The albedo comes from the primitive's texture in the surface's own coordinates,
   so a point has the same colour in every view. A fixed directional light adds mild Lambert
   shading (``ambient + (1 - ambient)·max(0, n·l)``), view-independent, so it keeps
   photo-consistency too; the sky is not shaded.
4. **Anti-aliasing.** Colour is supersampled on an ``s × s`` sub-pixel grid (``s`` odd, 3 by
   default) and averaged. **Depth is not averaged**: it is the depth of the single sub-sample at
   the pixel *centre* (odd ``s`` puts one there), i.e. the nearest surface along the ray through
   the pixel centre. An averaged depth at an object edge would be a point floating between
   foreground and background that exists nowhere; the centre sample stays exact, and the
   label map is taken at the same sample.

World frame: the same axes as the OpenCV camera, x right, **y down**, z forward (metres), so
"up" is -y and the ground is the plane y = 0 (a 1 m tall box spans y ∈ [-1, 0]).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.camera import Camera, pixel_rays
from .textures import Texture, jitter_colour

__all__ = ["Plane", "Box", "Sphere", "Cylinder", "render", "check_supersample", "EPS", "unit_vector", "yaw_matrix",
           "LIGHT", "AMBIENT"]

# Primitives: closed-form first hits. Rays: origin o (3,), directions d (N, 3); return t (N,).

EPS = 1e-9


def unit_vector(v) -> np.ndarray:
    """``v`` (3,) scaled to length 1, float64."""
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def yaw_matrix(yaw_deg: float) -> np.ndarray:
    """Rotation about the world y axis (columns: the object's x, y, z axes in the world)."""
    a = np.radians(yaw_deg)
    return np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])


@dataclass(frozen=True)
class Plane:
    """A plane through ``point`` with unit ``normal`` (facing the viewer); texture axes ``u`` and
    ``v = normal × u``; optional ``half_extent`` (a, b) metres makes it a rectangle."""

    point: tuple
    normal: tuple
    u: tuple
    texture: Texture
    half_extent: tuple = (np.inf, np.inf)

    def _frame(self):
        n, u = unit_vector(self.normal), unit_vector(self.u)
        return np.asarray(self.point, float), n, u, np.cross(n, u)

    def intersect(self, o, d):
        p0, n, u, v = self._frame()
        denom = d @ n  # (N,)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((p0 - o) @ n) / denom
        t = np.where((np.abs(denom) > EPS) & (t > EPS), t, np.inf)
        if np.isfinite(self.half_extent).any():
            x = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d - p0  # (N, 3)
            inside = (np.abs(x @ u) <= self.half_extent[0]) & (np.abs(x @ v) <= self.half_extent[1])
            t = np.where(inside, t, np.inf)
        return t

    def surface(self, x):
        """Points (M, 3) → local points (M, 3), surface coords (M, 2), normals (M, 3)."""
        p0, n, u, v = self._frame()
        local = x - p0
        st = np.stack([local @ u, local @ v], 1)
        return local, st, np.broadcast_to(n, x.shape)


@dataclass(frozen=True)
class Box:
    """A box with ``center`` (3,), ``half_size`` (3,) metres, turned by ``yaw_deg`` about y."""

    center: tuple
    half_size: tuple
    texture: Texture
    yaw_deg: float = 0.0

    def intersect(self, o, d):
        R, c, h = yaw_matrix(self.yaw_deg), np.asarray(self.center, float), np.asarray(self.half_size, float)
        ol, dl = (o - c) @ R, d @ R  # (3,), (N, 3) in the box frame
        dl = np.where(np.abs(dl) < EPS, EPS, dl)
        t1, t2 = (-h - ol) / dl, (h - ol) / dl  # (N, 3) slab entries and exits
        near, far = np.minimum(t1, t2).max(1), np.maximum(t1, t2).min(1)
        return np.where((far >= near) & (near > EPS), near, np.inf)

    def surface(self, x):
        R, c, h = yaw_matrix(self.yaw_deg), np.asarray(self.center, float), np.asarray(self.half_size, float)
        local = (x - c) @ R  # (M, 3)
        axis = np.argmax(np.abs(local) / h, axis=1)  # (M,) which face
        sign = np.sign(local[np.arange(len(x)), axis])
        normal = np.zeros_like(local)
        normal[np.arange(len(x)), axis] = sign
        # face coordinates: the two other axes (x face: z, y; y face: x, z; z face: x, y)
        pairs = np.array([[2, 1], [0, 2], [0, 1]])[axis]  # (M, 2)
        st = np.take_along_axis(local, pairs, 1) + 10.0 * axis[:, None]
        return local, st, normal @ R.T


@dataclass(frozen=True)
class Sphere:
    """A sphere with ``center`` (3,) and ``radius`` metres."""

    center: tuple
    radius: float
    texture: Texture

    def intersect(self, o, d):
        oc = o - np.asarray(self.center, float)
        a, b = np.einsum("ij,ij->i", d, d), 2.0 * (d @ oc)
        disc = b * b - 4.0 * a * (oc @ oc - self.radius ** 2)
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a)
        return np.where((disc >= 0) & (t > EPS), t, np.inf)

    def surface(self, x):
        local = x - np.asarray(self.center, float)
        st = np.stack([self.radius * np.arctan2(local[:, 0], -local[:, 2]), local[:, 1]], 1)
        return local, st, local / self.radius


@dataclass(frozen=True)
class Cylinder:
    """A vertical (along y) capped cylinder: axis through ``(x, z)``, ``y_range`` (top, bottom)
    with y down, ``radius`` metres."""

    x: float
    z: float
    y_range: tuple
    radius: float
    texture: Texture

    def intersect(self, o, d):
        ox, oz = o[0] - self.x, o[2] - self.z
        dx, dy, dz = d[:, 0], d[:, 1], d[:, 2]
        a = dx * dx + dz * dz
        b = 2.0 * (ox * dx + oz * dz)
        disc = b * b - 4.0 * a * (ox * ox + oz * oz - self.radius ** 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_side = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a)
        y = o[1] + t_side * dy
        y0, y1 = min(self.y_range), max(self.y_range)
        t_side = np.where((disc >= 0) & (a > EPS) & (t_side > EPS) & (y >= y0) & (y <= y1), t_side, np.inf)
        best = t_side
        for yc in (y0, y1):  # the two caps
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (yc - o[1]) / dy
            px, pz = ox + t * dx, oz + t * dz
            ok = (np.abs(dy) > EPS) & (t > EPS) & (px * px + pz * pz <= self.radius ** 2)
            best = np.minimum(best, np.where(ok, t, np.inf))
        return best

    def surface(self, x):
        local = x - np.array([self.x, 0.0, self.z])
        y0, y1 = min(self.y_range), max(self.y_range)
        radial = np.hypot(local[:, 0], local[:, 2])
        on_cap = (radial < self.radius * (1 - 1e-6)) | (np.abs(local[:, 1] - y0) < 1e-9) | \
                 (np.abs(local[:, 1] - y1) < 1e-9)
        normal = np.stack([local[:, 0], np.zeros(len(x)), local[:, 2]], 1) / self.radius
        cap_sign = np.where(np.abs(local[:, 1] - y0) < np.abs(local[:, 1] - y1), -1.0, 1.0)
        normal[on_cap] = np.stack([np.zeros(on_cap.sum()), cap_sign[on_cap], np.zeros(on_cap.sum())], 1)
        st = np.stack([self.radius * np.arctan2(local[:, 0], -local[:, 2]), local[:, 1]], 1)
        return local, st, normal


LIGHT = unit_vector([-0.35, -1.0, -0.55])  # towards the light: up (-y), left, towards the cameras
AMBIENT = 0.4
_CHUNK = 400_000  # rays per batch, bounds memory at large sizes


def _shade(primitives, seed, o, d):
    """Cast rays o (3,), d (N, 3) → colour (N, 3), ray parameter t (N,), label (N,) uint8."""
    ts = np.stack([p.intersect(o, d) for p in primitives])  # (P, N)
    hit = np.argmin(ts, axis=0)  # (N,)
    t = ts[hit, np.arange(d.shape[0])]
    colour = np.zeros((d.shape[0], 3))
    label = np.full(d.shape[0], 255, np.uint8)
    for k, prim in enumerate(primitives):
        rows = np.nonzero((hit == k) & np.isfinite(t))[0]
        if rows.size == 0:
            continue
        x = o + t[rows, None] * d[rows]  # (M, 3) world points
        local, st, normal = prim.surface(x)
        albedo = prim.texture.albedo(local, st, seed + 7919 * k)
        if prim.texture.kind == "sky":
            shade = np.ones(len(rows))  # the sky glows, no shading
        else:
            shade = AMBIENT + (1.0 - AMBIENT) * np.clip(normal @ LIGHT, 0.0, 1.0)
        colour[rows] = albedo * shade[:, None]
        label[rows] = prim.texture.label
    return colour, t, label


def check_supersample(supersample) -> int:
    """``supersample`` as an int if it is an odd positive integer (the middle sample gives a pixel's depth),
    else ``ValueError``."""
    if int(supersample) != supersample or supersample < 1 or supersample % 2 == 0:
        raise ValueError(f"supersample must be an odd positive integer, got {supersample!r}")
    return int(supersample)


def render(primitives, camera: Camera, seed: int = 0, supersample: int = 3):
    """Ray-cast ``primitives`` → rgb (H, W, 3) float32 [0, 1], depth (H, W) float32 metres
    (centre sample; inf where nothing is hit), labels (H, W) uint8 (255 = nothing hit)."""
    if not isinstance(camera, Camera):
        raise TypeError(f"camera must be a ddp_lite.Camera, got {type(camera).__name__}")
    supersample = check_supersample(supersample)
    if len(primitives) == 0:
        raise ValueError("primitives must not be empty")
    H, W, s = camera.height, camera.width, supersample
    offsets = (np.arange(s) + 0.5) / s - 0.5  # sub-pixel offsets; the middle one is 0
    world_from_cam = camera.world_from_cam
    o, R_wc = world_from_cam[:3, 3], world_from_cam[:3, :3]
    rgb = np.zeros((H, W, 3))
    depth = np.zeros((H, W))
    labels = np.zeros((H, W), np.uint8)
    rows_per_chunk = max(1, _CHUNK // (W * s * s))
    for r0 in range(0, H, rows_per_chunk):
        rows = np.arange(r0, min(H, r0 + rows_per_chunk))
        v, u, dv, du = np.meshgrid(rows, np.arange(W), offsets, offsets, indexing="ij")  # (h, W, s, s)
        d = pixel_rays((u + du).ravel(), (v + dv).ravel(), camera.K) @ R_wc.T  # (N, 3): camera z = 1, so t = depth
        colour, t, label = _shade(primitives, seed, o, d)
        colour = colour.reshape(len(rows), W, s * s, 3)
        rgb[rows] = colour.mean(2)
        centre = (s // 2) * s + s // 2
        depth[rows] = t.reshape(len(rows), W, s * s)[:, :, centre]
        labels[rows] = label.reshape(len(rows), W, s * s)[:, :, centre]
    return np.clip(rgb, 0.0, 1.0).astype(np.float32), depth.astype(np.float32), labels


def sky_plane(rng, distance, height):
    """The sky: a plane facing the camera ``distance`` m away, textured at the scale ``height`` m."""
    return Plane((0.0, 0.0, distance), (0, 0, -1), (1, 0, 0),
                 Texture("sky", jitter_colour(rng, (0.82, 0.88, 0.95), 0.03), jitter_colour(rng, (0.42, 0.6, 0.88), 0.03),
                         height))
