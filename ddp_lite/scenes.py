"""Scenes: calibrated RGB-D views, and the kit's synthetic multi-view scenes.

A ``View`` is one calibrated image with its depth; a ``Scene`` is an ordered list of views of
one static world (plus, for stereo scenes, a rectified right image per view).

Why synthetic scenes? Depth completion is judged *inside the holes*, where a real sensor has,
by definition, no answer. A ray-cast world gives every pixel its exact depth, so we can cut
holes any way we like (or let a real stereo matcher cut them, see ``holes.py``) and still
measure the error where it matters.

How the renderer works (all NumPy, no loop over pixels):

1. **Rays.** For pixel (u, v) the camera-frame direction is ``d = K⁻¹ (u, v, 1)``, whose z is
   exactly 1. Rotated into the world, a point ``C + t·d`` on that ray has camera depth
   ``z = t``, so the ray parameter of the first hit *is* the depth map, with no conversion.
2. **Intersections.** Each primitive (``Plane``, ``Box``, ``Sphere``, ``Cylinder``) returns
   the ray parameter of its first hit (``inf`` on a miss) in closed form: one linear equation
   for a plane, the slab test for a box, a quadratic for a sphere or a cylinder's side. The
   nearest hit over the few primitives wins (a loop over primitives, not pixels).
3. **Colour.** The albedo comes from a procedural texture evaluated in the surface's *own*
   coordinates (metres along the surface, or the 3D point in the object's frame), so a
   surface point has the same colour in every view: multi-view photo-consistency holds, which
   is what DDP's warp loss relies on. A fixed directional light adds mild Lambert shading
   (``ambient + (1 - ambient)·max(0, n·l)``), view-independent, so it keeps photo-consistency too.
4. **Anti-aliasing.** Colour is supersampled on an ``s × s`` sub-pixel grid (``s`` odd, 3 by
   default) and averaged. **Depth is not averaged**: it is the depth of the single sub-sample at
   the pixel *centre* (odd ``s`` puts one there), i.e. the nearest surface along the ray through
   the pixel centre. An averaged depth at an object edge would be a point floating between
   foreground and background that exists nowhere; the centre sample stays exact, and the
   label map is taken at the same sample.

World frame: the same axes as the OpenCV camera, x right, **y down**, z forward (metres), so
"up" is -y and the ground is the plane y = 0 (a 1 m tall box spans y ∈ [-1, 0]).

Sky: a textureless, unshaded colour gradient on a *far plane* (``Scene.meta["sky_depth"]``
metres ahead), so the ground truth is finite everywhere and hole errors can be measured there
too; it is the place where stereo fails (paper Fig. 3).

Texture classes, rendered per view into ``Scene.labels[i]`` (uint8, (H, W)) — see ``LABELS``:
0 sky, 1 textureless (flat paint), 2 planks (strong RGB edges on a flat surface, paper Fig. 4),
3 textured (fine seeded noise, bricks, tiles: stereo works here).

Cameras move along a short sideways path, each turned toward the scene centre. View 0 sits in
the middle of the path, then views alternate left and right of it (offsets 0, -1, +1, -2, ...
steps), so view 0 has neighbours on both sides. Every view also gets a rectified right view
(``Scene.right[i]``): same K and rotation, centre shifted by ``meta["baseline"]`` along the
camera's x axis, so a stereo matcher can run on any view.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from .atomic import atomic_path
from .camera import Camera, look_at

__all__ = ["View", "Scene", "Texture", "Plane", "Box", "Sphere", "Cylinder", "render", "make_scene",
           "list_scenes", "register_scene", "select_neighbors", "LABELS", "LABEL_SKY",
           "LABEL_TEXTURELESS", "LABEL_PLANKS", "LABEL_TEXTURED", "SCENES"]

LABEL_SKY, LABEL_TEXTURELESS, LABEL_PLANKS, LABEL_TEXTURED = 0, 1, 2, 3  # Scene.labels values
LABELS = {LABEL_SKY: "sky", LABEL_TEXTURELESS: "textureless", LABEL_PLANKS: "planks", LABEL_TEXTURED: "textured"}


@dataclass(eq=False)
class View:
    """One calibrated view: ``rgb`` (H, W, 3) float32 in [0, 1], ``depth`` (H, W) float32 metres
    (NaN = unknown), ``camera`` (its ``width × height`` match the arrays)."""

    rgb: np.ndarray
    depth: np.ndarray
    camera: Camera
    name: str = ""

    def __post_init__(self):
        self.rgb = np.asarray(self.rgb, dtype=np.float32)
        self.depth = np.asarray(self.depth, dtype=np.float32)
        H, W = self.depth.shape[:2] if self.depth.ndim == 2 else (None, None)
        if self.depth.ndim != 2:
            raise ValueError(f"depth must be (H, W), got shape {self.depth.shape}")
        if self.rgb.shape != (H, W, 3):
            raise ValueError(f"rgb must be (H, W, 3) = {(H, W, 3)}, got {self.rgb.shape}")
        if (self.camera.height, self.camera.width) != (H, W):
            raise ValueError(f"camera is {self.camera.width}×{self.camera.height} but the images are {W}×{H}")

    @property
    def mask(self) -> np.ndarray:
        """Valid-depth mask (H, W) bool, True where depth is finite."""
        return np.isfinite(self.depth)

    @property
    def neighbor(self) -> tuple[np.ndarray, Camera]:
        """``(rgb, camera)``: the form ``complete_depth(neighbors=...)`` takes."""
        return self.rgb, self.camera


@dataclass(eq=False)
class Scene:
    """A named, ordered set of views of one static world.

    ``right`` optionally holds a rectified right view per view (stereo rigs); ``meta`` holds
    scene facts (floats) such as the stereo baseline (metres) or the DDP disparity range;
    ``labels`` optionally holds a (H, W) uint8 texture-class map per view (see ``LABELS``).
    """

    name: str
    views: list[View]
    right: list[View] = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    labels: list = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.views)

    def __getitem__(self, index: int) -> View:
        return self.views[index]

    @property
    def size(self) -> tuple[int, int]:
        """``(H, W)`` of the views."""
        return self.views[0].depth.shape

    def __repr__(self) -> str:
        finite = [v.depth[np.isfinite(v.depth)] for v in self.views]
        depths = np.concatenate(finite) if self.views else np.zeros(1)
        depths = depths if depths.size else np.full(1, np.nan)
        H, W = self.size if self.views else (0, 0)
        stereo = f", stereo pairs={len(self.right)}" if self.right else ""
        return (f"Scene('{self.name}', {len(self.views)} views of {H}×{W}{stereo}, "
                f"depth {np.min(depths):.2f}–{np.max(depths):.2f} m)")

    def save(self, path) -> None:
        """Write the scene to an ``.npz`` file atomically (temporary file, then rename)."""
        arrays = {"name": np.array(self.name), "n_views": np.array(len(self.views)),
                  "n_right": np.array(len(self.right)), "n_labels": np.array(len(self.labels)),
                  "meta_keys": np.array(list(self.meta.keys()), dtype=str),
                  "meta_values": np.array([float(v) for v in self.meta.values()], dtype=np.float64)}
        for prefix, views in (("view", self.views), ("right", self.right)):
            for i, view in enumerate(views):
                arrays[f"{prefix}{i}_rgb"] = view.rgb
                arrays[f"{prefix}{i}_depth"] = view.depth
                arrays[f"{prefix}{i}_K"] = view.camera.K
                arrays[f"{prefix}{i}_pose"] = view.camera.cam_from_world
                arrays[f"{prefix}{i}_name"] = np.array(view.name)
        for i, label in enumerate(self.labels):
            arrays[f"labels{i}"] = np.asarray(label)
        with atomic_path(path) as tmp, open(tmp, "wb") as handle:
            np.savez_compressed(handle, **arrays)

    @classmethod
    def load(cls, path) -> "Scene":
        """Read a scene written by :meth:`save`."""
        with np.load(os.fspath(path), allow_pickle=False) as data:
            def read(prefix, count):
                views = []
                for i in range(count):
                    depth = data[f"{prefix}{i}_depth"]
                    camera = Camera(data[f"{prefix}{i}_K"], data[f"{prefix}{i}_pose"], depth.shape[1], depth.shape[0])
                    views.append(View(data[f"{prefix}{i}_rgb"], depth, camera, str(data[f"{prefix}{i}_name"])))
                return views
            meta = {str(k): float(v) for k, v in zip(data["meta_keys"], data["meta_values"])}
            n_labels = int(data["n_labels"]) if "n_labels" in data.files else 0
            labels = [data[f"labels{i}"] for i in range(n_labels)]
            return cls(str(data["name"]), read("view", int(data["n_views"])), read("right", int(data["n_right"])),
                       meta, labels)


# ----------------------------------------------------------------------------------------------
# Procedural textures: seeded, defined on the surface, so every view sees the same colours.
# ----------------------------------------------------------------------------------------------

_M1, _M2 = np.uint64(0xFF51AFD7ED558CCD), np.uint64(0xC4CEB9FE1A85EC53)


def _hash(*ints) -> np.ndarray:
    """Integer lattice coordinates (int64 arrays) → uniform floats in [0, 1) (murmur3 finaliser)."""
    h = np.zeros(np.broadcast(*ints).shape, dtype=np.uint64)
    for k, value in enumerate(ints):
        v = np.asarray(value, dtype=np.int64).astype(np.uint64)
        h = (h ^ v) * np.uint64(0x9E3779B97F4A7C15 + 2 * k + 1)
        h ^= h >> np.uint64(29)
    h ^= h >> np.uint64(33)
    h *= _M1
    h ^= h >> np.uint64(33)
    h *= _M2
    h ^= h >> np.uint64(33)
    return (h >> np.uint64(11)).astype(np.float64) * (1.0 / 2 ** 53)


def _value_noise(p: np.ndarray, seed: int) -> np.ndarray:
    """Smooth value noise in [0, 1) at points p (M, D), lattice spacing 1, D = 2 or 3."""
    cell = np.floor(p)
    f = p - cell
    w = f * f * (3.0 - 2.0 * f)  # (M, D) smoothstep weights
    cell = cell.astype(np.int64)
    dims = p.shape[1]
    out = np.zeros(len(p))
    for corner in range(2 ** dims):  # the 4 or 8 lattice corners
        bits = [(corner >> d) & 1 for d in range(dims)]
        weight = np.ones(len(p))
        for d, b in enumerate(bits):
            weight *= w[:, d] if b else 1.0 - w[:, d]
        out += weight * _hash(seed, *[cell[:, d] + b for d, b in enumerate(bits)])
    return out


def _fbm(p: np.ndarray, seed: int, octaves: int = 3) -> np.ndarray:
    """Fractal value noise in [0, 1): octaves at doubling frequency, halving amplitude."""
    total, norm = np.zeros(len(p)), 0.0
    for k in range(octaves):
        amp = 0.5 ** k
        total += amp * _value_noise(p * 2.0 ** k + 17.3 * k, seed + 1013 * k)
        norm += amp
    return total / norm


def _mix(a, b, t):
    """Blend colours a, b (3,) by t (M,) → (M, 3)."""
    t = np.clip(t, 0.0, 1.0)[:, None]
    return np.asarray(a)[None] * (1.0 - t) + np.asarray(b)[None] * t


@dataclass(frozen=True)
class Texture:
    """A procedural surface colour. ``kind``: "flat", "sky", "planks", "noise", "bricks", "tiles";
    ``color``/``color2`` RGB in [0, 1]; ``scale`` metres (noise cell, plank/brick/tile width)."""

    kind: str = "flat"
    color: tuple = (0.8, 0.8, 0.8)
    color2: tuple = (0.3, 0.3, 0.3)
    scale: float = 0.05

    @property
    def label(self) -> int:
        """Texture class (see ``LABELS``)."""
        return {"sky": 0, "flat": 1, "planks": 2}.get(self.kind, 3)

    def albedo(self, local: np.ndarray, st: np.ndarray, seed: int) -> np.ndarray:
        """Colours (M, 3) at surface points: ``local`` (M, 3) metres in the object frame,
        ``st`` (M, 2) metres along the surface."""
        c1, c2, scale = np.asarray(self.color), np.asarray(self.color2), self.scale
        if self.kind == "flat":
            return np.broadcast_to(c1, (len(st), 3)).copy()
        if self.kind == "sky":  # horizon colour → zenith colour over `scale` metres of height
            return _mix(c1, c2, -st[:, 1] / scale)
        if self.kind == "noise":  # solid (3D) noise: no seams on spheres or box corners
            n = _fbm(local / scale, seed)
            return _mix(c1, c2, (n - 0.5) * 2.2 + 0.5)
        if self.kind == "planks":  # vertical planks: s across, t along the boards
            s, t = st[:, 0] / scale, st[:, 1]
            board = np.floor(s).astype(np.int64)
            tone = _hash(seed, board)  # (M,) one tone per board
            grain = _fbm(np.stack([(s - board) * 6.0, t * 0.8 + 31.0 * tone], 1), seed + 7, octaves=2)
            colour = _mix(c1, c2, 0.15 + 0.7 * tone) * (0.8 + 0.4 * grain)[:, None]
            frac = s - board
            gap = (frac < 0.06) | (frac > 0.97)  # dark seams between boards
            colour[gap] *= 0.35
            return colour
        if self.kind == "bricks":  # running bond, brick width = scale, height = scale / 3
            h = scale / 3.0
            row = np.floor(st[:, 1] / h).astype(np.int64)
            s = st[:, 0] / scale + 0.5 * (row % 2)
            col = np.floor(s).astype(np.int64)
            tone = _hash(seed, row, col)
            colour = _mix(c1, c2, tone) * (0.85 + 0.3 * _fbm(local / (0.2 * scale), seed + 3, 2))[:, None]
            mortar = ((s - col) < 0.06) | ((st[:, 1] / h - row) < 0.15)
            colour[mortar] = 0.5 * (colour[mortar] * 0.2 + 0.75)
            return colour
        if self.kind == "tiles":  # checkerboard tiles with a little noise
            i = np.floor(st[:, 0] / scale).astype(np.int64) + np.floor(st[:, 1] / scale).astype(np.int64)
            colour = np.where((i % 2 == 0)[:, None], c1[None], c2[None])
            return colour * (0.85 + 0.3 * _fbm(local / (0.1 * scale), seed, 2))[:, None]
        raise ValueError(f"texture kind must be flat, sky, planks, noise, bricks or tiles, got {self.kind!r}")


# ----------------------------------------------------------------------------------------------
# Primitives: closed-form first hits. Rays: origin o (3,), directions d (N, 3); return t (N,).
# ----------------------------------------------------------------------------------------------

_EPS = 1e-9


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _yaw_matrix(yaw_deg: float) -> np.ndarray:
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
        n, u = _unit(self.normal), _unit(self.u)
        return np.asarray(self.point, float), n, u, np.cross(n, u)

    def intersect(self, o, d):
        p0, n, u, v = self._frame()
        denom = d @ n  # (N,)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((p0 - o) @ n) / denom
        t = np.where((np.abs(denom) > _EPS) & (t > _EPS), t, np.inf)
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
        R, c, h = _yaw_matrix(self.yaw_deg), np.asarray(self.center, float), np.asarray(self.half_size, float)
        ol, dl = (o - c) @ R, d @ R  # (3,), (N, 3) in the box frame
        dl = np.where(np.abs(dl) < _EPS, _EPS, dl)
        t1, t2 = (-h - ol) / dl, (h - ol) / dl  # (N, 3) slab entries and exits
        near, far = np.minimum(t1, t2).max(1), np.maximum(t1, t2).min(1)
        return np.where((far >= near) & (near > _EPS), near, np.inf)

    def surface(self, x):
        R, c, h = _yaw_matrix(self.yaw_deg), np.asarray(self.center, float), np.asarray(self.half_size, float)
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
        return np.where((disc >= 0) & (t > _EPS), t, np.inf)

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
        t_side = np.where((disc >= 0) & (a > _EPS) & (t_side > _EPS) & (y >= y0) & (y <= y1), t_side, np.inf)
        best = t_side
        for yc in (y0, y1):  # the two caps
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (yc - o[1]) / dy
            px, pz = ox + t * dx, oz + t * dz
            ok = (np.abs(dy) > _EPS) & (t > _EPS) & (px * px + pz * pz <= self.radius ** 2)
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


# ----------------------------------------------------------------------------------------------
# Rendering
# ----------------------------------------------------------------------------------------------

LIGHT = _unit([-0.35, -1.0, -0.55])  # towards the light: up (-y), left, towards the cameras
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


def render(primitives, camera: Camera, seed: int = 0, supersample: int = 3):
    """Ray-cast ``primitives`` → rgb (H, W, 3) float32 [0, 1], depth (H, W) float32 metres
    (centre sample; inf where nothing is hit), labels (H, W) uint8 (255 = nothing hit)."""
    if not isinstance(camera, Camera):
        raise TypeError(f"camera must be a ddp_lite.Camera, got {type(camera).__name__}")
    if int(supersample) != supersample or supersample < 1 or supersample % 2 == 0:
        raise ValueError(f"supersample must be an odd positive integer, got {supersample!r}")
    if len(primitives) == 0:
        raise ValueError("primitives must not be empty")
    H, W, s = camera.height, camera.width, int(supersample)
    offsets = (np.arange(s) + 0.5) / s - 0.5  # sub-pixel offsets; the middle one is 0
    K_inv = np.linalg.inv(camera.K)
    world_from_cam = camera.world_from_cam
    o, R_wc = world_from_cam[:3, 3], world_from_cam[:3, :3]
    rgb = np.zeros((H, W, 3))
    depth = np.zeros((H, W))
    labels = np.zeros((H, W), np.uint8)
    rows_per_chunk = max(1, _CHUNK // (W * s * s))
    for r0 in range(0, H, rows_per_chunk):
        rows = np.arange(r0, min(H, r0 + rows_per_chunk))
        v, u, dv, du = np.meshgrid(rows, np.arange(W), offsets, offsets, indexing="ij")  # (h, W, s, s)
        pix = np.stack([u + du, v + dv, np.ones_like(u, dtype=float)], -1).reshape(-1, 3)
        d = (pix @ K_inv.T) @ R_wc.T  # (N, 3): camera z-component 1, so t = depth
        colour, t, label = _shade(primitives, seed, o, d)
        colour = colour.reshape(len(rows), W, s * s, 3)
        rgb[rows] = colour.mean(2)
        centre = (s // 2) * s + s // 2
        depth[rows] = t.reshape(len(rows), W, s * s)[:, :, centre]
        labels[rows] = label.reshape(len(rows), W, s * s)[:, :, centre]
    return np.clip(rgb, 0.0, 1.0).astype(np.float32), depth.astype(np.float32), labels


# ----------------------------------------------------------------------------------------------
# The named scenes
# ----------------------------------------------------------------------------------------------

def _jitter(rng, colour, amount=0.08):
    """A seeded variation of a base colour, so a new seed changes colours as well as patterns."""
    return tuple(np.clip(np.asarray(colour) * (1.0 + rng.uniform(-amount, amount, 3)), 0.0, 1.0))


def _tex(rng, kind, color, color2=(0.0, 0.0, 0.0), scale=0.05):
    return Texture(kind, _jitter(rng, color), _jitter(rng, color2), scale)


def _sky(rng, distance, height):
    return Plane((0.0, 0.0, distance), (0, 0, -1), (1, 0, 0),
                 Texture("sky", _jitter(rng, (0.82, 0.88, 0.95), 0.03), _jitter(rng, (0.42, 0.6, 0.88), 0.03),
                         height))


def _house(rng):
    prims = [
        _sky(rng, 60.0, 30.0),
        Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), _tex(rng, "noise", (0.35, 0.55, 0.2), (0.15, 0.3, 0.08), 0.08)),
        Plane((0, -2.0, 8.0), (0, 0, -1), (1, 0, 0), _tex(rng, "planks", (0.75, 0.5, 0.3), (0.45, 0.26, 0.12), 0.35),
              (3.5, 2.0)),
        Box((0, -4.2, 8.3), (3.9, 0.2, 0.6), _tex(rng, "flat", (0.45, 0.2, 0.15))),  # roof eave
        Plane((1.9, -2.5, 7.98), (0, 0, -1), (1, 0, 0), _tex(rng, "flat", (0.92, 0.9, 0.82)), (0.7, 0.65)),  # shutter
        Box((-0.9, -0.6, 5.0), (0.7, 0.6, 0.5), _tex(rng, "noise", (0.7, 0.66, 0.6), (0.3, 0.28, 0.26), 0.05), 20.0),
        Sphere((1.5, -0.5, 6.0), 0.5, _tex(rng, "noise", (0.25, 0.45, 0.15), (0.05, 0.2, 0.05), 0.04)),
    ]
    return prims, dict(eye=(0.0, -1.6, 0.0), target=(0.0, -1.9, 8.0), fov=60.0, baseline=0.5, sky=60.0)


def _desk(rng):
    prims = [
        Plane((0, 0, 2.2), (0, 0, -1), (1, 0, 0), _tex(rng, "flat", (0.88, 0.86, 0.8))),  # painted wall
        Plane((-0.55, -0.45, 2.19), (0, 0, -1), (1, 0, 0),
              _tex(rng, "noise", (0.9, 0.7, 0.3), (0.2, 0.3, 0.6), 0.02), (0.25, 0.18)),  # poster
        Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), _tex(rng, "noise", (0.6, 0.42, 0.25), (0.35, 0.22, 0.1), 0.015)),
        Box((-0.33, -0.06, 1.0), (0.15, 0.06, 0.11), _tex(rng, "noise", (0.75, 0.2, 0.15), (0.3, 0.05, 0.05), 0.01),
            15.0),
        Box((0.3, -0.15, 1.35), (0.1, 0.15, 0.04), _tex(rng, "bricks", (0.9, 0.8, 0.2), (0.6, 0.3, 0.1), 0.05),
            -25.0),
        Cylinder(0.02, 0.85, (-0.12, 0.0), 0.045, _tex(rng, "noise", (0.2, 0.35, 0.75), (0.9, 0.9, 0.95), 0.008)),
        Cylinder(-0.12, 1.5, (-0.32, 0.0), 0.04, _tex(rng, "flat", (0.2, 0.55, 0.3))),  # plain bottle
        Sphere((0.22, -0.07, 0.8), 0.07, _tex(rng, "noise", (0.95, 0.55, 0.1), (0.5, 0.2, 0.05), 0.01)),
    ]
    return prims, dict(eye=(0.0, -0.45, 0.0), target=(0.0, -0.1, 1.3), fov=60.0, baseline=0.08, sky=None)


def _room(rng):
    prims = [
        Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), _tex(rng, "tiles", (0.8, 0.78, 0.72), (0.5, 0.45, 0.4), 0.4)),
        Plane((0, -2.6, 0), (0, 1, 0), (1, 0, 0), _tex(rng, "flat", (0.95, 0.95, 0.93))),  # ceiling
        Plane((0, 0, 6.0), (0, 0, -1), (1, 0, 0), _tex(rng, "flat", (0.85, 0.82, 0.75))),  # back wall
        Plane((-2.5, 0, 0), (1, 0, 0), (0, 0, 1), _tex(rng, "planks", (0.7, 0.48, 0.3), (0.4, 0.25, 0.12), 0.25)),
        Plane((2.5, 0, 0), (-1, 0, 0), (0, 0, -1), _tex(rng, "flat", (0.9, 0.85, 0.6))),  # right wall
        Plane((2.49, -1.5, 3.5), (-1, 0, 0), (0, 0, -1), _tex(rng, "noise", (0.2, 0.4, 0.7), (0.9, 0.8, 0.5), 0.04),
              (0.6, 0.4)),  # painting
        Box((-1.2, -0.4, 3.5), (0.9, 0.4, 0.45), _tex(rng, "noise", (0.55, 0.3, 0.35), (0.25, 0.1, 0.15), 0.03)),
        Box((1.6, -0.9, 4.6), (0.5, 0.9, 0.3), _tex(rng, "noise", (0.5, 0.35, 0.2), (0.25, 0.15, 0.08), 0.05), -10.0),
        Box((0.8, -0.25, 1.4), (0.25, 0.25, 0.25), _tex(rng, "noise", (0.3, 0.3, 0.35), (0.7, 0.7, 0.75), 0.02),
            30.0),
        Cylinder(0.4, 2.6, (-1.6, 0.0), 0.12, _tex(rng, "flat", (0.3, 0.3, 0.3))),  # lamp stand
        Sphere((-0.3, -0.25, 1.9), 0.25, _tex(rng, "noise", (0.9, 0.3, 0.2), (0.95, 0.9, 0.8), 0.03)),
    ]
    return prims, dict(eye=(0.0, -1.3, 0.0), target=(0.0, -0.9, 4.0), fov=58.0, baseline=0.2, sky=None)


def _street(rng):
    prims = [
        _sky(rng, 150.0, 60.0),
        Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), _tex(rng, "noise", (0.5, 0.5, 0.52), (0.15, 0.15, 0.17), 0.2)),
        Plane((0, -7.0, 45.0), (0, 0, -1), (1, 0, 0), _tex(rng, "bricks", (0.7, 0.4, 0.3), (0.5, 0.25, 0.2), 0.6),
              (30.0, 7.0)),  # far buildings
        Plane((-7.0, -5.0, 25.0), (1, 0, 0), (0, 0, 1), _tex(rng, "bricks", (0.75, 0.65, 0.5), (0.5, 0.4, 0.3), 0.5),
              (20.0, 5.0)),  # left facade
        Plane((8.0, -3.0, 20.0), (-1, 0, 0), (0, 0, -1), _tex(rng, "flat", (0.7, 0.7, 0.68)), (10.0, 3.0)),  # concrete
        Box((-3.0, -0.75, 12.0), (0.9, 0.75, 2.1), _tex(rng, "noise", (0.75, 0.15, 0.12), (0.3, 0.05, 0.05), 0.08)),
        Box((2.5, -0.75, 18.0), (0.9, 0.75, 2.1), _tex(rng, "noise", (0.2, 0.3, 0.7), (0.05, 0.1, 0.3), 0.08), 5.0),
        Cylinder(-5.0, 8.0, (-5.0, 0.0), 0.12, _tex(rng, "flat", (0.35, 0.35, 0.35))),
        Cylinder(4.5, 11.0, (-5.0, 0.0), 0.12, _tex(rng, "flat", (0.35, 0.35, 0.35))),
        Sphere((5.5, -0.6, 9.0), 0.6, _tex(rng, "noise", (0.25, 0.5, 0.15), (0.05, 0.2, 0.05), 0.06)),
    ]
    return prims, dict(eye=(0.0, -1.65, 0.0), target=(0.0, -1.5, 20.0), fov=80.0, baseline=0.54, sky=150.0)


SCENES = {
    "house": (_house, "facade of wooden planks, textureless sky and shutter, a stone box and a bush in front"),
    "desk": (_desk, "objects on a table against a plain wall: many occlusion edges, 0.5–2.2 m"),
    "room": (_room, "indoor, Kinect-like (use kinect_noise): tiled floor, plain walls, furniture, 1.5–6 m"),
    "street": (_street, "KITTI-like rectified stereo rig: road, cars, poles, facades, sky at 150 m"),
}


def register_scene(name: str, builder, description: str) -> None:
    """Add a named scene to ``SCENES``: ``builder(rng)`` → (primitives, rig dict with eye, target,
    fov, baseline, sky), ``description`` one line for :func:`list_scenes`."""
    if not isinstance(name, str) or not name.isidentifier() or name != name.lower():
        raise ValueError(f"name must be a short lower-case identifier, got {name!r}")
    if not callable(builder):
        raise TypeError(f"builder must be callable(rng) -> (primitives, rig), got {type(builder).__name__}")
    if not isinstance(description, str) or not description.strip():
        raise ValueError(f"description must be a non-empty one-line string, got {description!r}")
    old = SCENES.get(name)
    same = old is not None and (old[0].__module__, old[0].__qualname__) == (builder.__module__, builder.__qualname__)
    if old is not None and not same:  # re-importing (reloading) the defining module is fine
        raise ValueError(f"a scene named {name!r} is already registered by {old[0].__module__}")
    SCENES[name] = (builder, description)


class _SceneList(dict):
    def __repr__(self) -> str:
        return "\n".join(f"{name:<8} {text}" for name, text in self.items())


def list_scenes() -> dict:
    """{name: one-line description} of the built-in scenes (prints as a table)."""
    return _SceneList({name: text for name, (_, text) in SCENES.items()})


def _path_offsets(n_views: int) -> np.ndarray:
    """0, -1, +1, -2, +2, ... : view 0 in the middle of the path."""
    k = np.arange(n_views)
    return np.where(k % 2 == 1, -(k + 1) // 2, k // 2).astype(float)


def check_size(size) -> tuple[int, int]:
    """``size`` as (H, W) ints, each ≥ 8; ``ValueError`` naming ``size`` otherwise."""
    try:
        H, W = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ValueError(f"size must be (H, W), got {size!r}") from None
    if H < 8 or W < 8 or tuple(size) != (H, W):
        raise ValueError(f"size must be two integers >= 8, got {size!r}")
    return H, W


def make_scene(name: str, size=(96, 128), n_views: int = 5, seed: int = 0, fov_x_deg: float | None = None,
               supersample: int = 3) -> Scene:
    """Render the named synthetic scene: ``n_views`` views of ``size`` (H, W) with exact depth
    (metres), a rectified right view each, texture labels, and ``meta`` (d_min, d_max, baseline, ...)."""
    if not isinstance(name, str) or name not in SCENES:
        raise ValueError(f"name must be one of {sorted(SCENES)}, got {name!r}")
    H, W = check_size(size)
    if int(n_views) != n_views or n_views < 1:
        raise ValueError(f"n_views must be a positive integer, got {n_views!r}")
    if int(seed) != seed or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    build, _ = SCENES[name]
    rng = np.random.default_rng(int(seed))
    prims, rig = build(rng)
    fov = rig["fov"] if fov_x_deg is None else float(fov_x_deg)
    if not 10.0 <= fov <= 150.0:
        raise ValueError(f"fov_x_deg must be in [10, 150] degrees, got {fov_x_deg!r}")
    eye0, target = np.array(rig["eye"]), np.array(rig["target"])
    step = 0.06 * np.linalg.norm(target - eye0)  # ~3.4° apart at the target: good for MVS
    baseline = rig["baseline"]
    views, right, labels = [], [], []
    for i, offset in enumerate(_path_offsets(int(n_views))):
        pose = look_at(eye0 + np.array([offset * step, 0.0, 0.0]), target)
        for out, p, tag in ((views, pose, f"{name}{i}"), (right, None, f"{name}{i}R")):
            if p is None:  # rectified right view: same rotation, centre + baseline along camera x
                p = pose.copy()
                p[0, 3] -= baseline
            camera = Camera.from_fov(W, H, fov, p)
            rgb, depth, label = render(prims, camera, seed=int(seed), supersample=supersample)
            if not np.all(np.isfinite(depth)):
                raise RuntimeError(f"scene {name!r} leaves pixels without a surface; widen its geometry")
            out.append(View(rgb, depth, camera, tag))
            if p is pose:
                labels.append(label)
    near, far = (float(f(np.stack([v.depth for v in views]))) for f in (np.min, np.max))
    meta = {"d_min": float(np.floor(0.9 * near * 100.0)) / 100.0,  # a margin below the nearest surface
            "d_max": float(np.ceil(far * 100.0)) / 100.0,  # the farthest surface (the sky, if any)
            "baseline": float(baseline), "fov_x_deg": float(fov), "seed": float(seed),
            "sky_depth": float(rig["sky"] or 0.0), "path_step": float(step)}
    return Scene(name, views, right, meta, labels)


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
    pix = np.stack([u[ok], v[ok], np.ones(ok.sum())], 1)  # (M, 3)
    cam_pts = (pix @ np.linalg.inv(view.camera.K).T) * depth[ok][:, None]  # (M, 3) ref camera frame
    world = cam_pts @ view.camera.world_from_cam[:3, :3].T + view.camera.world_from_cam[:3, 3]  # (M, 3)
    c_ref = view.camera.center
    scores = []
    for j, other in enumerate(scene.views):
        if j == ref:
            continue
        cam = other.camera
        pts = world @ cam.cam_from_world[:3, :3].T + cam.cam_from_world[:3, 3]  # (M, 3) in view j
        z = pts[:, 2]
        uv = (pts @ cam.K.T)[:, :2] / np.maximum(z, 1e-9)[:, None]
        ui, vi = np.round(uv[:, 0]).astype(int), np.round(uv[:, 1]).astype(int)
        inside = (z > 0) & (ui >= 0) & (ui < cam.width) & (vi >= 0) & (vi < cam.height)
        seen = np.zeros(len(z), bool)  # visible: inside the image and not occluded in view j
        zj = other.depth[vi[inside], ui[inside]]
        seen[inside] = np.abs(zj - z[inside]) <= 0.02 * z[inside]
        a, b = world[seen] - c_ref, world[seen] - cam.center
        cos = np.einsum("ij,ij->i", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        theta = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        sigma = np.where(theta <= 5.0, 1.0, 10.0)
        scores.append((float(np.exp(-(theta - 5.0) ** 2 / (2 * sigma ** 2)).sum()), j))
    scores.sort(key=lambda s: (-s[0], s[1]))
    return [j for _, j in scores[: int(n)]]
