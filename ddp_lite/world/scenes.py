"""The kit's synthetic multi-view scenes: a catalogue of named worlds, rendered on demand.

Why synthetic scenes? Depth completion is judged *inside the holes*, where a real sensor has,
by definition, no answer. A ray-cast world gives every pixel its exact depth, so we can cut
holes any way we like (or let a real stereo matcher cut them, see ``stereo.py``) and still
measure the error where it matters. The pieces live in their own modules: the data model
(``views``: ``View``, ``Scene``, ``LABEL_*``), surface textures (``textures``), primitives and
the ray-caster (``render``), view selection (``neighbors``); this module names scenes and
renders them.

Sky: a textureless, unshaded colour gradient on a *far plane* (``Scene.meta["sky_depth"]``
metres ahead), so the ground truth is finite everywhere and hole errors can be measured there
too; it is the place where stereo fails (paper Fig. 3).

Texture classes, rendered per view into ``Scene.labels[i]`` (uint8, (H, W)) — see ``LABELS``:
sky, textureless (flat paint), planks (strong RGB edges on a flat surface, paper Fig. 4),
textured (fine seeded noise, bricks, tiles: stereo works here).

Cameras move along a short sideways path, each turned toward the scene centre. View 0 sits in
the middle of the path, then views alternate left and right of it (offsets 0, -1, +1, -2, ...
steps), so view 0 has neighbours on both sides. Every view also gets a rectified right view
(``Scene.right[i]``): same K and rotation, centre shifted by ``meta["baseline"]`` along the
camera's x axis, so a stereo matcher can run on any view.
"""
from __future__ import annotations

import numpy as np

from ..core.camera import Camera, look_at
from ..core.checks import check_size
from .organic import ORGANIC_SCENES
from .render import Box, Cylinder, Plane, Sphere, check_supersample, render, sky_plane
from .scene_cache import cached_scene
from .textures import seeded_texture
from ..core.views import Scene, View

__all__ = ["make_scene", "list_scenes", "register_scene", "SCENES"]


def _house(rng):
    prims = [
        sky_plane(rng, 60.0, 30.0),
        Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), seeded_texture(rng, "noise", (0.35, 0.55, 0.2), (0.15, 0.3, 0.08), 0.08)),
        Plane((0, -2.0, 8.0), (0, 0, -1), (1, 0, 0), seeded_texture(rng, "planks", (0.75, 0.5, 0.3), (0.45, 0.26, 0.12), 0.35),
              (3.5, 2.0)),
        Box((0, -4.2, 8.3), (3.9, 0.2, 0.6), seeded_texture(rng, "flat", (0.45, 0.2, 0.15))),  # roof eave
        Plane((1.9, -2.5, 7.98), (0, 0, -1), (1, 0, 0), seeded_texture(rng, "flat", (0.92, 0.9, 0.82)), (0.7, 0.65)),  # shutter
        Box((-0.9, -0.6, 5.0), (0.7, 0.6, 0.5), seeded_texture(rng, "noise", (0.7, 0.66, 0.6), (0.3, 0.28, 0.26), 0.05), 20.0),
        Sphere((1.5, -0.5, 6.0), 0.5, seeded_texture(rng, "noise", (0.25, 0.45, 0.15), (0.05, 0.2, 0.05), 0.04)),
    ]
    return prims, dict(eye=(0.0, -1.6, 0.0), target=(0.0, -1.9, 8.0), fov=60.0, baseline=0.5, sky=60.0)


def _desk(rng):
    prims = [
        Plane((0, 0, 2.2), (0, 0, -1), (1, 0, 0), seeded_texture(rng, "flat", (0.88, 0.86, 0.8))),  # painted wall
        Plane((-0.55, -0.45, 2.19), (0, 0, -1), (1, 0, 0),
              seeded_texture(rng, "noise", (0.9, 0.7, 0.3), (0.2, 0.3, 0.6), 0.02), (0.25, 0.18)),  # poster
        Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), seeded_texture(rng, "noise", (0.6, 0.42, 0.25), (0.35, 0.22, 0.1), 0.015)),
        Box((-0.33, -0.06, 1.0), (0.15, 0.06, 0.11), seeded_texture(rng, "noise", (0.75, 0.2, 0.15), (0.3, 0.05, 0.05), 0.01),
            15.0),
        Box((0.3, -0.15, 1.35), (0.1, 0.15, 0.04), seeded_texture(rng, "bricks", (0.9, 0.8, 0.2), (0.6, 0.3, 0.1), 0.05),
            -25.0),
        Cylinder(0.02, 0.85, (-0.12, 0.0), 0.045, seeded_texture(rng, "noise", (0.2, 0.35, 0.75), (0.9, 0.9, 0.95), 0.008)),
        Cylinder(-0.12, 1.5, (-0.32, 0.0), 0.04, seeded_texture(rng, "flat", (0.2, 0.55, 0.3))),  # plain bottle
        Sphere((0.22, -0.07, 0.8), 0.07, seeded_texture(rng, "noise", (0.95, 0.55, 0.1), (0.5, 0.2, 0.05), 0.01)),
    ]
    return prims, dict(eye=(0.0, -0.45, 0.0), target=(0.0, -0.1, 1.3), fov=60.0, baseline=0.08, sky=None)


def _room(rng):
    prims = [
        Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), seeded_texture(rng, "tiles", (0.8, 0.78, 0.72), (0.5, 0.45, 0.4), 0.4)),
        Plane((0, -2.6, 0), (0, 1, 0), (1, 0, 0), seeded_texture(rng, "flat", (0.95, 0.95, 0.93))),  # ceiling
        Plane((0, 0, 6.0), (0, 0, -1), (1, 0, 0), seeded_texture(rng, "flat", (0.85, 0.82, 0.75))),  # back wall
        Plane((-2.5, 0, 0), (1, 0, 0), (0, 0, 1), seeded_texture(rng, "planks", (0.7, 0.48, 0.3), (0.4, 0.25, 0.12), 0.25)),
        Plane((2.5, 0, 0), (-1, 0, 0), (0, 0, -1), seeded_texture(rng, "flat", (0.9, 0.85, 0.6))),  # right wall
        Plane((2.49, -1.5, 3.5), (-1, 0, 0), (0, 0, -1), seeded_texture(rng, "noise", (0.2, 0.4, 0.7), (0.9, 0.8, 0.5), 0.04),
              (0.6, 0.4)),  # painting
        Box((-1.2, -0.4, 3.5), (0.9, 0.4, 0.45), seeded_texture(rng, "noise", (0.55, 0.3, 0.35), (0.25, 0.1, 0.15), 0.03)),
        Box((1.6, -0.9, 4.6), (0.5, 0.9, 0.3), seeded_texture(rng, "noise", (0.5, 0.35, 0.2), (0.25, 0.15, 0.08), 0.05), -10.0),
        Box((0.8, -0.25, 1.4), (0.25, 0.25, 0.25), seeded_texture(rng, "noise", (0.3, 0.3, 0.35), (0.7, 0.7, 0.75), 0.02),
            30.0),
        Cylinder(0.4, 2.6, (-1.6, 0.0), 0.12, seeded_texture(rng, "flat", (0.3, 0.3, 0.3))),  # lamp stand
        Sphere((-0.3, -0.25, 1.9), 0.25, seeded_texture(rng, "noise", (0.9, 0.3, 0.2), (0.95, 0.9, 0.8), 0.03)),
    ]
    return prims, dict(eye=(0.0, -1.3, 0.0), target=(0.0, -0.9, 4.0), fov=58.0, baseline=0.2, sky=None)


def _street(rng):
    prims = [
        sky_plane(rng, 150.0, 60.0),
        Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), seeded_texture(rng, "noise", (0.5, 0.5, 0.52), (0.15, 0.15, 0.17), 0.2)),
        Plane((0, -7.0, 45.0), (0, 0, -1), (1, 0, 0), seeded_texture(rng, "bricks", (0.7, 0.4, 0.3), (0.5, 0.25, 0.2), 0.6),
              (30.0, 7.0)),  # far buildings
        Plane((-7.0, -5.0, 25.0), (1, 0, 0), (0, 0, 1), seeded_texture(rng, "bricks", (0.75, 0.65, 0.5), (0.5, 0.4, 0.3), 0.5),
              (20.0, 5.0)),  # left facade
        Plane((8.0, -3.0, 20.0), (-1, 0, 0), (0, 0, -1), seeded_texture(rng, "flat", (0.7, 0.7, 0.68)), (10.0, 3.0)),  # concrete
        Box((-3.0, -0.75, 12.0), (0.9, 0.75, 2.1), seeded_texture(rng, "noise", (0.75, 0.15, 0.12), (0.3, 0.05, 0.05), 0.08)),
        Box((2.5, -0.75, 18.0), (0.9, 0.75, 2.1), seeded_texture(rng, "noise", (0.2, 0.3, 0.7), (0.05, 0.1, 0.3), 0.08), 5.0),
        Cylinder(-5.0, 8.0, (-5.0, 0.0), 0.12, seeded_texture(rng, "flat", (0.35, 0.35, 0.35))),
        Cylinder(4.5, 11.0, (-5.0, 0.0), 0.12, seeded_texture(rng, "flat", (0.35, 0.35, 0.35))),
        Sphere((5.5, -0.6, 9.0), 0.6, seeded_texture(rng, "noise", (0.25, 0.5, 0.15), (0.05, 0.2, 0.05), 0.06)),
    ]
    return prims, dict(eye=(0.0, -1.65, 0.0), target=(0.0, -1.5, 20.0), fov=80.0, baseline=0.54, sky=150.0)


SCENES = {
    "house": (_house, "facade of wooden planks, textureless sky and shutter, a stone box and a bush in front"),
    "desk": (_desk, "objects on a table against a plain wall: many occlusion edges, 0.5–2.2 m"),
    "room": (_room, "indoor, Kinect-like (use kinect_noise): tiled floor, plain walls, furniture, 1.5–6 m"),
    "street": (_street, "KITTI-like rectified stereo rig: road, cars, poles, facades, sky at 150 m"),
    **ORGANIC_SCENES,  # the curved, photo-textured scenes of ddp_lite.world.organic
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


def _render_view(prims, W: int, H: int, fov: float, pose, seed: int, supersample: int, tag: str):
    """One rendered view of the scene's primitives from ``pose`` → (View, labels (H, W) uint8)."""
    camera = Camera.from_fov(W, H, fov, pose)
    rgb, depth, label = render(prims, camera, seed=int(seed), supersample=supersample)
    if not np.all(np.isfinite(depth)):
        raise RuntimeError(f"scene view {tag!r} leaves pixels without a surface; widen its geometry")
    return View(rgb, depth, camera, tag), label


def make_scene(name: str, size=(96, 128), n_views: int = 5, seed: int = 0, fov_x_deg: float | None = None,
               supersample: int = 3) -> Scene:
    """Render the named synthetic scene: ``n_views`` views of ``size`` (H, W) with exact depth
    (metres), a rectified right view each, texture labels, and ``meta`` (d_min, d_max, baseline, ...).
    With ``DDP_CACHE`` set, a scene rendered before is read back instead (:mod:`ddp_lite.world.scene_cache`)."""
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
    n_views, seed, supersample = int(n_views), int(seed), check_supersample(supersample)
    return cached_scene(lambda: _render_scene(name, prims, rig, (H, W), n_views, seed, fov, supersample),
                        name, (H, W), n_views, seed, fov_x_deg, supersample)


def _render_scene(name: str, prims, rig: dict, size: tuple[int, int], n_views: int, seed: int, fov: float,
                  supersample: int) -> Scene:
    """Every view of the scene ``prims`` and ``rig`` describe (``make_scene``'s arguments, checked)."""
    H, W = size
    eye0, target = np.array(rig["eye"]), np.array(rig["target"])
    step = 0.06 * np.linalg.norm(target - eye0)  # ~3.4° apart at the target: good for MVS
    baseline = rig["baseline"]
    views, right, labels = [], [], []
    for i, offset in enumerate(_path_offsets(n_views)):
        pose = look_at(eye0 + np.array([offset * step, 0.0, 0.0]), target)
        right_pose = pose.copy()  # rectified right view: same rotation, centre + baseline along camera x
        right_pose[0, 3] -= baseline
        left_view, label = _render_view(prims, W, H, fov, pose, seed, supersample, f"{name}{i}")
        right_view, _ = _render_view(prims, W, H, fov, right_pose, seed, supersample, f"{name}{i}R")
        views.append(left_view)
        right.append(right_view)
        labels.append(label)
    near, far = (float(f(np.stack([v.depth for v in views]))) for f in (np.min, np.max))
    meta = {"d_min": float(np.floor(0.9 * near * 100.0)) / 100.0,  # a margin below the nearest surface
            "d_max": float(np.ceil(far * 100.0)) / 100.0,  # the farthest surface (the sky, if any)
            "baseline": float(baseline), "fov_x_deg": float(fov), "seed": float(seed),
            "sky_depth": float(rig["sky"] or 0.0), "path_step": float(step)}
    return Scene(name, views, right, meta, labels)
