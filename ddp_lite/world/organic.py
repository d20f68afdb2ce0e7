"""Curved, photo-textured scenes: where linear interpolation of disparity is no longer exact.

Why these scenes exist: the built-in scenes (``house``, ``desk``, ``room``, ``street``) are
made of planes and boxes. On a plane, disparity 1/z is an *affine* function of the pixel
coordinates, so a linear fill of a hole from its border is exact there, and the classical
baselines DDP is compared with look better than they would on real data. Real surfaces are
curved (terrain, rocks, trunks, bodies) and carry photographic, not procedural, texture. The
scenes here are mostly curved: a height-field terrain, ellipsoids (boulders, organic blobs, a
dome seen from inside), cylinders and cones on tilted axes and thin rods, textured with photos
bundled with scikit-image.

Their pieces live in their own modules: ``solids``
(``Ellipsoid``, ``Cone``, ``Capsule``), ``terrain`` (``HeightField``), ``photo_texture``
(``PhotoTexture``, ``PHOTOS``). World frame as in ``render``: x right, y down, z forward, metres.

Scenes listed in ``scenes.SCENES`` (from :data:`ORGANIC_SCENES`): ``hills`` (terrain,
boulders, a tree, branches, sky), ``sculpture`` (a blob of ellipsoids on bumpy ground inside a
dome) and ``logs`` (tilted cylinders, cones and rods in a round room).
"""
from __future__ import annotations

import numpy as np

from .photo_texture import PhotoTexture
from .render import sky_plane
from .solids import Capsule, Cone, Ellipsoid
from .terrain import HeightField
from .textures import jitter_colour, seeded_texture

__all__ = ["ORGANIC_SCENES"]


def _photo_tex(rng, image, scale, tint=(1.0, 1.0, 1.0), crop=(0.0, 1.0, 0.0, 1.0), variation=0.25):
    """A PhotoTexture whose tint varies a little with the seed (as ``seeded_texture`` does for colours)."""
    return PhotoTexture(image, scale, jitter_colour(rng, tint), crop=crop, variation=variation)


def _bumps(rng, n, x_range, z_range, height_range, sigma_range) -> np.ndarray:
    """n seeded Gaussian bumps (n, 4): cx, cz, height, sigma (metres)."""
    return np.stack([rng.uniform(*x_range, n), rng.uniform(*z_range, n), rng.uniform(*height_range, n),
                     rng.uniform(*sigma_range, n)], 1)


def _waves(rng, n, k_range, amplitude_range) -> np.ndarray:
    """n seeded sinusoids (n, 4) in random directions: kx, kz (rad/m), phase (rad), amplitude (m)."""
    angle, k = rng.uniform(0, 2 * np.pi, n), rng.uniform(*k_range, n)
    return np.stack([k * np.cos(angle), k * np.sin(angle), rng.uniform(0, 2 * np.pi, n),
                     rng.uniform(*amplitude_range, n)], 1)


def _terrain(hills, waves, texture, max_distance=60.0):
    """A HeightField from hill (n, 4) and wave (m, 4) parameters, shifted so that h(0, 0) = 0: the
    ground passes under the cameras at y = 0, whatever hills the seed put near them."""
    field = HeightField(texture, tuple(tuple(float(v) for v in b) for b in hills),
                        tuple(tuple(float(v) for v in w) for w in waves), 0.0, float(max_distance))
    return HeightField(texture, field.bumps, field.waves, -float(field.height(np.zeros(1), np.zeros(1))[0]),
                       float(max_distance))


def _ground_y(field: HeightField, x: float, z: float) -> float:
    """World y of the terrain surface at (x, z)."""
    return -float(field.height(np.array([x]), np.array([z]))[0])


_WOOD = (0.2, 0.7, 0.8, 1.0)  # the table's wood grain right of the saucer in `coffee`
_FUR = (0.0, 0.3, 0.3, 0.7)  # the cat's forehead fur in `chelsea`


def _hills(rng):
    # each term costs every marching step of every ray: a few hills, mounds and ripples suffice
    hills = np.concatenate([_bumps(rng, 4, (-14, 14), (9, 35), (0.8, 3.0), (2.5, 6.0)),  # far hills
                            _bumps(rng, 4, (-4, 4), (3, 10), (-0.1, 0.35), (0.5, 1.2))])  # mounds nearby
    waves = np.concatenate([_waves(rng, 2, (0.5, 1.6), (0.08, 0.2)), _waves(rng, 1, (2.0, 4.0), (0.03, 0.06))])
    ground = _terrain(hills, waves, _photo_tex(rng, "grass", 5.0, (0.6, 0.85, 0.4)), max_distance=65.0)
    prims = [sky_plane(rng, 60.0, 30.0), ground]
    for _ in range(5):  # boulders, a third buried
        x, z = rng.uniform(-4.0, 4.0), rng.uniform(4.0, 12.0)
        r = rng.uniform(0.35, 0.8) * np.array([rng.uniform(1.0, 1.6), rng.uniform(0.6, 0.9), rng.uniform(0.9, 1.3)])
        image = "gravel" if rng.random() < 0.6 else "moon"
        tint = (0.75, 0.7, 0.62) if image == "gravel" else (0.95, 0.9, 0.85)
        prims.append(Ellipsoid((x, _ground_y(ground, x, z) - 0.5 * r[1], z), tuple(r),
                               _photo_tex(rng, image, 1.2, tint), rng.uniform(0, 180)))
    x, z = rng.uniform(-3.0, 3.0), rng.uniform(12.0, 16.0)  # a tree: leaning trunk and a crown
    foot = np.array([x, _ground_y(ground, x, z) + 0.3, z])
    top = foot + np.array([rng.uniform(-0.6, 0.6), -3.2, rng.uniform(-0.4, 0.4)])
    bark = _photo_tex(rng, "coffee", 0.6, (0.8, 0.7, 0.6), _WOOD)
    prims += [Cone(tuple(foot), tuple(top), 0.22, 0.12, bark),
              Ellipsoid(tuple(top + np.array([0.0, -0.6, 0.0])), (1.5, 1.1, 1.3),
                        _photo_tex(rng, "grass", 1.0, (0.35, 0.6, 0.25)), rng.uniform(0, 180))]
    for _ in range(4):  # fallen branches and leaning sticks: thin, tilted, partly in the ground
        x, z = rng.uniform(-2.5, 2.5), rng.uniform(3.0, 8.0)
        a = np.array([x, _ground_y(ground, x, z) + 0.05, z])
        tilt, heading = np.radians(rng.uniform(15, 70)), rng.uniform(0, 2 * np.pi)
        length = rng.uniform(1.0, 2.2)
        b = a + length * np.array([np.sin(tilt) * np.cos(heading), -np.cos(tilt), np.sin(tilt) * np.sin(heading)])
        prims.append(Capsule(tuple(a), tuple(b), rng.uniform(0.025, 0.05), bark))
    x, z = rng.uniform(2.5, 4.0), rng.uniform(6.0, 8.0)  # a painted fence post: textureless on purpose
    prims.append(Capsule((x, _ground_y(ground, x, z) + 0.1, z), (x + 0.25, _ground_y(ground, x, z) - 1.6, z + 0.1),
                         0.06, seeded_texture(rng, "flat", (0.85, 0.85, 0.8))))
    return prims, dict(eye=(0.0, -1.6, 0.0), target=(0.0, -0.8, 9.0), fov=60.0, baseline=0.5, sky=60.0)


def _sculpture(rng):
    dome = Ellipsoid((0.0, 1.0, 3.2), (5.0, 4.5, 5.5), _photo_tex(rng, "brick", 2.0, (0.9, 0.8, 0.7)), inside=True)
    hills = _bumps(rng, 7, (-3, 3), (1, 7), (-0.15, 0.25), (0.3, 0.9))
    waves = _waves(rng, 2, (3.0, 6.0), (0.03, 0.05))
    ground = _terrain(hills, waves, _photo_tex(rng, "gravel", 1.2, (0.85, 0.75, 0.6)), max_distance=20.0)
    prims = [dome, ground]
    centre = np.array([0.0, 0.0, 3.2])
    centre[1] = _ground_y(ground, 0.0, 3.2) - 0.45
    fur = _photo_tex(rng, "chelsea", 1.0, (1.0, 0.95, 0.9), _FUR)
    for i in range(6):  # overlapping ellipsoids: one smooth organic blob
        offset = rng.normal(0.0, 1.0, 3) * np.array([0.3, 0.2, 0.2]) + np.array([0.0, -0.12 * i, 0.0])
        radii = rng.uniform(0.22, 0.45) * np.array([rng.uniform(0.8, 1.3), rng.uniform(0.8, 1.3), rng.uniform(0.8, 1.3)])
        prims.append(Ellipsoid(tuple(centre + offset), tuple(radii), fur, rng.uniform(0, 180)))
    for _ in range(3):  # pebbles around it
        x, z = rng.uniform(-1.2, 1.2), rng.uniform(2.0, 3.0)
        r = rng.uniform(0.08, 0.16) * np.array([1.3, 0.7, 1.0])
        prims.append(Ellipsoid((x, _ground_y(ground, x, z) - 0.3 * r[1], z), tuple(r),
                               _photo_tex(rng, "retina", 0.5, (1.0, 0.9, 0.8), (0.25, 0.75, 0.25, 0.75)),
                               rng.uniform(0, 180)))
    return prims, dict(eye=(0.0, -1.3, 0.0), target=(0.0, -0.45, 3.2), fov=60.0, baseline=0.3, sky=None)


def _logs(rng):
    wall = Cone((0.0, 1.5, 2.6), (0.0, -4.0, 2.6), 3.6, 3.6, _photo_tex(rng, "moon", 5.0, (1.0, 0.92, 0.8)),
                inside=True)  # a round room, seen from inside
    hills = _bumps(rng, 7, (-2.5, 2.5), (1, 5), (-0.12, 0.2), (0.25, 0.7))
    waves = _waves(rng, 2, (3.0, 6.0), (0.02, 0.04))
    ground = _terrain(hills, waves, _photo_tex(rng, "gravel", 0.9, (0.8, 0.72, 0.6)), max_distance=15.0)
    prims = [wall, ground]
    wood = _photo_tex(rng, "coffee", 0.5, (0.9, 0.8, 0.7), _WOOD)
    for _ in range(2):  # logs: one end on the ground, the other propped up, seen obliquely
        x, z = rng.uniform(-1.0, 1.0), rng.uniform(2.2, 3.6)
        r = rng.uniform(0.1, 0.18)
        heading, rise = rng.uniform(-0.8, 0.8), rng.uniform(0.25, 0.6)
        ax, az = x - 0.7 * np.cos(heading), z - 0.7 * np.sin(heading)
        a = np.array([ax, _ground_y(ground, ax, az) - 0.5 * r, az])  # the low end half sunk in the ground
        b = a + 1.5 * np.array([np.cos(heading), -rise, np.sin(heading)]) / np.hypot(1.0, rise)
        prims.append(Cone(tuple(a), tuple(b), r, r * rng.uniform(0.8, 1.0), wood))
    for _ in range(2):  # cones on tilted axes
        x, z = rng.uniform(-1.6, 1.6), rng.uniform(1.8, 4.0)
        tilt, heading = np.radians(rng.uniform(15, 45)), rng.uniform(0, 2 * np.pi)
        a = np.array([x, _ground_y(ground, x, z) + 0.05, z])
        b = a + rng.uniform(0.5, 0.9) * np.array([np.sin(tilt) * np.cos(heading), -np.cos(tilt),
                                                   np.sin(tilt) * np.sin(heading)])
        prims.append(Cone(tuple(a), tuple(b), rng.uniform(0.15, 0.25), 0.02,
                          _photo_tex(rng, "retina", 0.6, (1.0, 0.85, 0.7), (0.2, 0.8, 0.2, 0.8))))
    for _ in range(4):  # thin rods leaning against the wall or lying across the floor
        x, z = rng.uniform(-1.8, 1.8), rng.uniform(1.8, 4.5)
        tilt, heading = np.radians(rng.uniform(20, 80)), rng.uniform(0, 2 * np.pi)
        a = np.array([x, _ground_y(ground, x, z) + 0.02, z])
        b = a + rng.uniform(0.8, 1.6) * np.array([np.sin(tilt) * np.cos(heading), -np.cos(tilt),
                                                   np.sin(tilt) * np.sin(heading)])
        prims.append(Capsule(tuple(a), tuple(b), rng.uniform(0.012, 0.025),
                             _photo_tex(rng, "astronaut", 0.4, (1.0, 1.0, 1.0), (0.55, 1.0, 0.0, 0.45))))
    return prims, dict(eye=(0.0, -1.2, 0.0), target=(0.0, -0.35, 3.0), fov=60.0, baseline=0.25, sky=None)


# name → (builder, one-line description): ``scenes.SCENES`` lists them after its own
ORGANIC_SCENES = {
    "hills": (_hills, "terrain height field, photo grass, ellipsoid boulders, a tree, branches, sky at 60 m"),
    "sculpture": (_sculpture, "organic blob of overlapping ellipsoids on bumpy gravel, inside a brick dome, 2–8 m"),
    "logs": (_logs, "tilted logs, cones and thin rods on bumpy ground in a round room, 1.5–6 m"),
}
