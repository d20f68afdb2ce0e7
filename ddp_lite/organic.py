"""Curved, photo-textured scenes: where linear interpolation of disparity is no longer exact.

Why these scenes exist: the built-in scenes (``house``, ``desk``, ``room``, ``street``) are
made of planes and boxes. On a plane, disparity 1/z is an *affine* function of the pixel
coordinates, so a linear fill of a hole from its border is exact there, and the classical
baselines DDP is compared with look better than they would on real data. Real surfaces are
curved (terrain, rocks, trunks, bodies) and carry photographic, not procedural, texture. The
scenes here are mostly curved: a height-field terrain, ellipsoids (boulders, organic blobs, a
dome seen from inside), cylinders and cones on tilted axes and thin rods, textured with photos
bundled with scikit-image.

New primitives, with the interface of ``render.Plane``/``Sphere``: ``intersect(o, d)`` takes a
ray origin o (3,) and directions d (N, 3) (world frame, metres) and returns the ray parameter
of the first hit t (N,) (``inf`` on a miss; the renderer's rays have camera z = 1, so t is the
depth); ``surface(x)`` takes world points (M, 3) on the surface and returns
``(local (M, 3) metres in the object frame, st (M, 2) metres along the surface, normal (M, 3))``:

- ``Ellipsoid``: a sphere after scaling the object frame by 1/radii: one quadratic;
- ``Cone``: a capped frustum between points a and b (equal radii: a tilted cylinder): one
  quadratic for the side, one linear equation per cap;
- ``Capsule``: a cylinder with round ends (branches, rods): the same side plus two spheres;
- ``HeightField``: terrain y = -h(x, z) (y is down; h is a sum of Gaussian bumps and
  sinusoids, analytic with an analytic gradient): found by vectorised ray marching and refined
  by bisection, as it has no closed form.

``PhotoTexture`` samples a photo by the surface coordinates st (bilinear, mirrored-repeat
tiling), so the colour is a function of the surface point only and every view sees the same
colour: the photo-consistency DDP's warp loss relies on.

Scenes registered in ``scenes.SCENES`` when ``ddp_lite`` is imported: ``hills`` (terrain,
boulders, a tree, branches, sky), ``sculpture`` (a blob of ellipsoids on bumpy ground inside a
dome) and ``logs`` (tilted cylinders, cones and rods in a round room).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .render import EPS, unit_vector, yaw_matrix
from .scenes import _jitter, _sky, _tex, register_scene
from .textures import fbm, lattice_hash

__all__ = ["PHOTOS", "PhotoTexture", "Ellipsoid", "Cone", "Capsule", "HeightField"]

# Photos that scikit-image ships inside its own package (no pooch download, no network).
PHOTOS = ("astronaut", "brick", "camera", "chelsea", "coffee", "grass", "gravel", "moon", "retina", "rocket")


# ----------------------------------------------------------------------------------------------
# Photographic texture
# ----------------------------------------------------------------------------------------------

@functools.lru_cache(maxsize=32)
def _photo(image: str, pixels: int, crop: tuple) -> np.ndarray:
    """The bundled photo ``image``, cropped (top, bottom, left, right fractions) and resized with
    anti-aliasing to ``pixels`` columns → (h, pixels, 3) float32 RGB in [0, 1], read-only."""
    from skimage import data, transform, util

    array = util.img_as_float(getattr(data, image)())
    if array.ndim == 2:  # grey photos (grass, gravel, brick, moon) → 3 equal channels
        array = np.repeat(array[:, :, None], 3, axis=2)
    array = array[:, :, :3]  # drop an alpha channel
    H, W = array.shape[:2]
    top, bottom, left, right = crop
    array = array[int(round(top * H)):int(round(bottom * H)), int(round(left * W)):int(round(right * W))]
    rows = max(2, int(round(pixels * array.shape[0] / array.shape[1])))
    # pre-filtered once: a photo sampled far below its resolution would alias differently per view
    array = transform.resize(array, (rows, pixels), anti_aliasing=True, preserve_range=True)
    array = np.clip(array, 0.0, 1.0).astype(np.float32)
    array.setflags(write=False)
    return array


@functools.lru_cache(maxsize=32)
def _luminance_std(image: str, pixels: int, crop: tuple) -> float:
    """Standard deviation of the sampled photo's luminance (0–1 units)."""
    return float((_photo(image, pixels, crop) @ np.array([0.299, 0.587, 0.114], np.float32)).std())


def _mirror(x: np.ndarray, n: int) -> np.ndarray:
    """Continuous texel coordinates x (M,) → [0, n] with mirrored repeat: no seams between tiles."""
    m = np.mod(x, 2.0 * n)
    return np.where(m < n, m, 2.0 * n - m)


def _bilinear(image: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Sample (h, w, 3) at texel coordinates x, y (M,) (texel i covers [i, i + 1)) → (M, 3)."""
    h, w = image.shape[:2]
    x = np.clip(x - 0.5, 0.0, w - 1.0)  # texel centres sit at i + 0.5
    y = np.clip(y - 0.5, 0.0, h - 1.0)
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    top = image[y0, x0] * (1.0 - fx) + image[y0, x1] * fx
    bottom = image[y1, x0] * (1.0 - fx) + image[y1, x1] * fx
    return top * (1.0 - fy) + bottom * fy


@dataclass(frozen=True)
class PhotoTexture:
    """A photo from ``skimage.data`` (one of ``PHOTOS``) laid on a surface by its coordinates st.

    ``scale``: metres per image width; ``tint`` RGB multiplier; ``pixels``: width (texels) of the
    anti-aliased copy that is sampled; ``crop`` (top, bottom, left, right) fractions of the photo;
    ``variation``: strength of a slow, solid (3D) tone modulation that hides the tiling's repeats.
    Same interface as ``textures.Texture`` (``kind``, ``label``, ``albedo``).
    """

    image: str = "gravel"
    scale: float = 1.0
    tint: tuple = (1.0, 1.0, 1.0)
    pixels: int = 256
    crop: tuple = (0.0, 1.0, 0.0, 1.0)
    variation: float = 0.25

    def __post_init__(self):
        if self.image not in PHOTOS:
            raise ValueError(f"image must be one of {PHOTOS} (bundled with scikit-image), got {self.image!r}")
        if not (np.isfinite(self.scale) and self.scale > 0):
            raise ValueError(f"scale must be positive metres per image width, got {self.scale!r}")
        if int(self.pixels) != self.pixels or self.pixels < 4:
            raise ValueError(f"pixels must be an integer >= 4, got {self.pixels!r}")
        top, bottom, left, right = self.crop
        if not (0 <= top < bottom <= 1 and 0 <= left < right <= 1):
            raise ValueError(f"crop must be (top, bottom, left, right) fractions with top < bottom, left < right, "
                             f"got {self.crop!r}")

    @property
    def kind(self) -> str:
        """``"photo"`` (the renderer only treats ``"sky"`` specially)."""
        return "photo"

    @property
    def image_array(self) -> np.ndarray:
        """The sampled photo (h, pixels, 3) float32 [0, 1] (cached, read-only)."""
        return _photo(self.image, int(self.pixels), tuple(float(c) for c in self.crop))

    @property
    def label(self) -> int:
        """3 (textured), or 1 (textureless) if the photo's luminance barely varies (std < 0.02)."""
        return 1 if _luminance_std(self.image, int(self.pixels), tuple(float(c) for c in self.crop)) < 0.02 else 3

    def shift(self, seed: int) -> np.ndarray:
        """Where the photo sits on the surface for ``seed``: an st offset (2,) metres in [0, 2·scale)."""
        return lattice_hash(int(seed), np.array([1, 2])) * 2.0 * self.scale

    def albedo(self, local: np.ndarray, st: np.ndarray, seed: int) -> np.ndarray:
        """Colours (M, 3) at surface points: ``local`` (M, 3) metres in the object frame,
        ``st`` (M, 2) metres along the surface; ``seed`` shifts the photo on the surface."""
        image = self.image_array
        h, w = image.shape[:2]
        texels_per_metre = w / self.scale
        shift = self.shift(seed)
        x = _mirror((st[:, 0] + shift[0]) * texels_per_metre, w)  # (M,)
        y = _mirror((st[:, 1] + shift[1]) * texels_per_metre, h)
        colour = _bilinear(image, x, y).astype(np.float64) * np.asarray(self.tint)[None]  # (M, 3)
        if self.variation > 0:  # slow tone changes over a few tiles: a photo repeated looks tiled
            tone = fbm(local / (1.5 * self.scale), int(seed) + 11, octaves=2)
            colour *= (1.0 - self.variation / 2.0 + self.variation * tone)[:, None]
        return np.clip(colour, 0.0, 1.0)


# ----------------------------------------------------------------------------------------------
# Primitives
# ----------------------------------------------------------------------------------------------

def _roots(a, b, c):
    """Roots (near, far) (N,) each of a·t² + b·t + c, sorted, ``inf`` where a root does not exist
    or lies behind the origin (t <= EPS). From inside a closed quadric ``near`` is the exit point,
    so a dome can be seen from within; ``a`` may be negative (a ray steeper than a cone's wall)."""
    disc = b * b - 4.0 * a * c
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-b - root) / (2.0 * a)
        t2 = (-b + root) / (2.0 * a)
    ok = (disc >= 0) & (np.abs(a) > EPS)
    t1 = np.where(ok & (t1 > EPS), t1, np.inf)
    t2 = np.where(ok & (t2 > EPS), t2, np.inf)
    return np.minimum(t1, t2), np.maximum(t1, t2)


def _angle_coord(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """|atan2(y, x)| in [0, π]: an angle that is continuous all the way round (mirrored at 0 and π
    instead of jumping by 2π), so a photo wrapped round a solid has no seam."""
    return np.abs(np.arctan2(y, x))


@dataclass(frozen=True)
class Ellipsoid:
    """An ellipsoid with ``center`` (3,) and semi-axes ``radii`` (3,) metres along the object's
    x, y, z axes, turned by ``yaw_deg`` about y; ``inside=True`` for one seen from within (a dome):
    the first hit is then the far wall and the normals point inwards, towards the viewer.

    Surface coordinates: the photo is wrapped about the object's x axis (seam-free, see
    ``_angle_coord``), so its poles sit on the left and right sides, seen edge-on from cameras
    looking along +z, and not on top, where a camera above the ground would see them.
    """

    center: tuple
    radii: tuple
    texture: object
    yaw_deg: float = 0.0
    inside: bool = False

    def _frame(self):
        return yaw_matrix(self.yaw_deg), np.asarray(self.center, float), np.asarray(self.radii, float)

    def intersect(self, o, d):
        R, c, r = self._frame()
        ol = ((o - c) @ R) / r  # (3,) origin in the unit-sphere frame
        dl = (d @ R) / r  # (N, 3) directions there; t is unchanged by this linear map
        near, _ = _roots(np.einsum("ij,ij->i", dl, dl), 2.0 * (dl @ ol), np.full(len(d), ol @ ol - 1.0))
        return near

    def surface(self, x):
        R, c, r = self._frame()
        local = (x - c) @ R  # (M, 3) object frame
        p = local / r  # (M, 3) on the unit sphere
        normal = _normalise((local / r ** 2) @ R.T)  # gradient of |local / r|²
        if self.inside:
            normal = -normal
        around = 0.5 * (r[1] + r[2]) * _angle_coord(p[:, 2], -p[:, 1])  # arc about x, 0 on top
        along = r[0] * np.arcsin(np.clip(p[:, 0], -1.0, 1.0))  # arc along x from the mid meridian
        return local, np.stack([around, along], 1), normal


def _normalise(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _axis_frame(a, b):
    """Segment a → b: origin a (3,), unit axis w (3,), length L, and e1, e2 (3,) completing a
    right-handed frame. e1 points up (-y) for a slanted axis and along x for a near-vertical one,
    so the two lines where ``_angle_coord`` mirrors the photo (towards ±e1) lie on the top and
    the bottom of a log, and on the left and right of a pole or a round room, not facing the cameras."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    L = float(np.linalg.norm(b - a))
    w = (b - a) / L
    helper = np.array([0.0, -1.0, 0.0]) if abs(w[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = unit_vector(helper - (helper @ w) * w)
    return a, w, L, e1, np.cross(w, e1)


def _side_hits(o, d, a, w, L, ra, rb):
    """First hit t (N,) of rays with the side of the frustum a → a + L·w, radius ra → rb (no caps)."""
    k = (rb - ra) / L  # radius gained per metre along the axis
    oa = o - a  # (3,)
    h0, dw = oa @ w, d @ w  # axial position of the origin, axial speed (N,)
    c0 = ra + k * h0  # radius at the origin's axial position
    A = np.einsum("ij,ij->i", d, d) - (1.0 + k * k) * dw * dw  # |radial|² = r(h)² as a quadratic in t
    B = 2.0 * (d @ oa - h0 * dw - k * c0 * dw)
    C = np.full(len(d), oa @ oa - h0 * h0 - c0 * c0)
    near, far = _roots(A, B, C)  # hits of the infinite double cone
    best = np.full(len(d), np.inf)
    for t in (far, near):  # near wins where both lie on the finite piece; far covers the rest
        h = h0 + np.where(np.isfinite(t), t, 0.0) * dw
        best = np.where(np.isfinite(t) & (h >= 0.0) & (h <= L), t, best)
    return best


def _disc_hits(o, d, centre, w, radius):
    """First hit t (N,) of rays with the disc at ``centre`` (3,), normal ±w, ``radius``."""
    dw = d @ w
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((centre - o) @ w) / dw
    p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d - centre  # (N, 3)
    ok = (np.abs(dw) > EPS) & (t > EPS) & (np.einsum("ij,ij->i", p, p) <= radius * radius)
    return np.where(ok, t, np.inf)


def _sphere_hits(o, d, centre, radius):
    oc = o - centre
    near, _ = _roots(np.einsum("ij,ij->i", d, d), 2.0 * (d @ oc), np.full(len(d), oc @ oc - radius ** 2))
    return near


@dataclass(frozen=True)
class Cone:
    """A capped cone frustum on any axis: from point ``a`` (3,) with ``radius_a`` to point ``b``
    (3,) with ``radius_b`` (metres). Equal radii make a tilted cylinder; ``radius_b = 0`` a pointed
    cone. ``inside=True``: seen from within (a round room), normals point inwards.

    Surface coordinates: st = (mean radius · |angle about the axis|, metres along the axis) on
    the side, metres in the cap's plane on the caps.
    """

    a: tuple
    b: tuple
    radius_a: float
    radius_b: float
    texture: object
    inside: bool = False

    def intersect(self, o, d):
        a, w, L, _, _ = _axis_frame(self.a, self.b)
        t = _side_hits(o, d, a, w, L, self.radius_a, self.radius_b)
        for centre, radius in ((a, self.radius_a), (a + L * w, self.radius_b)):
            if radius > 0:
                t = np.minimum(t, _disc_hits(o, d, centre, w, radius))
        return t

    def surface(self, x):
        a, w, L, e1, e2 = _axis_frame(self.a, self.b)
        q = x - a  # (M, 3)
        h = q @ w  # (M,) axial position
        radial = q - h[:, None] * w  # (M, 3)
        rho = np.linalg.norm(radial, axis=1)
        k = (self.radius_b - self.radius_a) / L
        r_h = self.radius_a + k * h
        u1, u2 = q @ e1, q @ e2
        local = np.stack([u1, u2, h], 1)  # (M, 3) in the (e1, e2, w) frame
        # gradient of |radial|² - r(h)²: radial/ρ - k·w, up to a positive factor
        with np.errstate(divide="ignore", invalid="ignore"):
            normal = _normalise(radial / np.maximum(rho, 1e-12)[:, None] - k * w[None])
        st = np.stack([0.5 * (self.radius_a + self.radius_b) * _angle_coord(u2, u1), h], 1)
        on_cap = rho < r_h * (1.0 - 1e-6)  # strictly inside the side: must be a cap
        cap_b = on_cap & (h > 0.5 * L)
        normal[on_cap] = -w
        normal[cap_b] = w
        st[on_cap] = np.stack([u1[on_cap], u2[on_cap] + np.where(cap_b[on_cap], 2.0 * L, -2.0 * L)], 1)
        return local, st, (-normal if self.inside else normal)


@dataclass(frozen=True)
class Capsule:
    """A cylinder of ``radius`` (metres) from point ``a`` (3,) to point ``b`` (3,) with
    hemispherical ends: branches, rods, poles at any angle.

    Surface coordinates: st = (radius · |angle about the axis|, metres along the axis, running
    on over the round ends).
    """

    a: tuple
    b: tuple
    radius: float
    texture: object

    def intersect(self, o, d):
        a, w, L, _, _ = _axis_frame(self.a, self.b)
        t = _side_hits(o, d, a, w, L, self.radius, self.radius)
        t = np.minimum(t, _sphere_hits(o, d, a, self.radius))
        return np.minimum(t, _sphere_hits(o, d, a + L * w, self.radius))

    def surface(self, x):
        a, w, L, e1, e2 = _axis_frame(self.a, self.b)
        q = x - a  # (M, 3)
        h = q @ w  # (M,)
        nearest = a + np.clip(h, 0.0, L)[:, None] * w  # (M, 3) closest point on the segment
        normal = _normalise(x - nearest)
        u1, u2 = q @ e1, q @ e2
        st = np.stack([self.radius * _angle_coord(u2, u1), h], 1)
        return np.stack([u1, u2, h], 1), st, normal


@dataclass(frozen=True)
class HeightField:
    """Terrain y = -h(x, z) (world y is down; h > 0 is above the plane y = 0), with
    h = ``base`` + Σ bumps + Σ waves: ``bumps`` ((cx, cz, height, sigma), ...) Gaussian hills
    (metres), ``waves`` ((kx, kz, phase, amplitude), ...) sinusoids sin(kx·x + kz·z + phase)
    (rad/m, rad, metres).

    Intersection (no closed form): each ray is marched, vectorised over all rays, inside the
    slab where the surface can be, up to ``max_distance`` metres. A step is the larger of
    - a *safe* step: a ray point ``g`` metres above the ground, descending ``d_y`` per unit of t
      while the ground can rise at most ``slope_bound()``·|d_xz|, cannot reach it sooner;
    - a floor of ``step`` metres growing to ``rel_step``·t at distance t (a pixel's footprint
      grows the same way), so that grazing rays near a hill's silhouette still advance.
    Only a floor step can cross the surface (a ridge thinner than it can be missed); the
    crossing step is then bisected to ``tol`` metres, and the secant point of the last bracket
    returned. Surface coordinates st = (x, z) metres; normals from the analytic gradient.
    """

    texture: object
    bumps: tuple = ()
    waves: tuple = ()
    base: float = 0.0
    max_distance: float = 60.0
    step: float = 0.01
    rel_step: float = 0.005
    tol: float = 1e-4

    def height(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        """h(x, z) metres (up is positive) at world x, z (N,)."""
        h = np.full(np.shape(x), float(self.base))
        for cx, cz, height, sigma in self.bumps:
            h += height * np.exp(-((x - cx) ** 2 + (z - cz) ** 2) / (2.0 * sigma * sigma))
        for kx, kz, phase, amplitude in self.waves:
            h += amplitude * np.sin(kx * x + kz * z + phase)
        return h

    def gradient(self, x: np.ndarray, z: np.ndarray):
        """(∂h/∂x, ∂h/∂z) (N,) each, at world x, z (N,)."""
        gx, gz = np.zeros(np.shape(x)), np.zeros(np.shape(x))
        for cx, cz, height, sigma in self.bumps:
            g = height * np.exp(-((x - cx) ** 2 + (z - cz) ** 2) / (2.0 * sigma * sigma)) / (sigma * sigma)
            gx -= g * (x - cx)
            gz -= g * (z - cz)
        for kx, kz, phase, amplitude in self.waves:
            c = amplitude * np.cos(kx * x + kz * z + phase)
            gx += kx * c
            gz += kz * c
        return gx, gz

    def bounds(self) -> tuple[float, float]:
        """(lowest, highest) h anywhere, metres: the slab a ray must cross to meet the surface.

        The bumps' sum is taken on a grid over their support, widened by a curvature bound for
        what lies between grid points (``_bump_extremes``): far tighter than the sum of all
        heights (hills apart do not stack) and still never too narrow. A loose slab only costs
        marching steps; a wrong one would cut hill tops off.
        """
        lowest, highest, _ = _bump_extremes(tuple(self.bumps))
        waves = sum(abs(w[3]) for w in self.waves)
        return float(self.base) + lowest - waves, float(self.base) + highest + waves

    def slope_bound(self) -> float:
        """An upper bound of |∇h| (m/m): the bumps' (see ``bounds``) plus Σ |amplitude|·|k|."""
        _, _, bumps = _bump_extremes(tuple(self.bumps))
        return float(bumps + sum(abs(w[3]) * np.hypot(w[0], w[1]) for w in self.waves))

    def _below(self, o, d, t):
        """Signed height of ray points o + t·d (t (n,), d (n, 3)) over the surface: > 0 underground."""
        p = o + t[:, None] * d  # (n, 3)
        return p[:, 1] + self.height(p[:, 0], p[:, 2])

    def intersect(self, o, d):
        N = len(d)
        low, high = self.bounds()
        low, high = low - self.tol, high + self.tol  # a flat field has a slab of zero thickness
        dy = d[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            t_top, t_bottom = (-high - o[1]) / dy, (-low - o[1]) / dy  # where the ray crosses the slab's faces
        flat = np.abs(dy) < EPS
        inside_slab = -high <= o[1] <= -low
        t0 = np.where(flat, 0.0 if inside_slab else np.inf, np.minimum(t_top, t_bottom))
        t1 = np.where(flat, np.inf if inside_slab else -np.inf, np.maximum(t_top, t_bottom))
        t0, t1 = np.maximum(t0, EPS), np.minimum(t1, self.max_distance)
        # d/dt of the height over ground is at most d_y + slope·|d_xz|: how fast a ray can close in
        closing = dy + self.slope_bound() * np.hypot(d[:, 0], d[:, 2])  # (N,)
        out = np.full(N, np.inf)
        rays = np.nonzero(t0 < t1)[0]  # rays that cross the slab in range
        t, t_end = t0[rays], t1[rays]
        f = self._below(o, d[rays], t)
        out[rays[f >= 0]] = t[f >= 0]  # starts underground (eye inside a hill): hit at once
        keep = f < 0
        rays, t, t_end, f = rays[keep], t[keep], t_end[keep], f[keep]
        brackets = []  # (rays, t above, t below, f above, f below) per pass
        while rays.size:  # march: one step for every live ray per pass, the live set shrinks
            with np.errstate(divide="ignore"):
                safe = np.where(closing[rays] > 0, -f / closing[rays], np.inf)
            t_next = np.minimum(t + np.maximum(safe, np.maximum(self.step, self.rel_step * t)), t_end)
            f_next = self._below(o, d[rays], t_next)
            crossed = f_next >= 0  # from above to below the surface within this step
            brackets.append((rays[crossed], t[crossed], t_next[crossed], f[crossed], f_next[crossed]))
            live = ~crossed & (t_next < t_end)
            rays, t, t_end, f = rays[live], t_next[live], t_end[live], f_next[live]
        rays, a, b, fa, fb = (np.concatenate(parts) for parts in zip(*brackets)) if brackets else [np.zeros(0)] * 5
        rays = rays.astype(np.int64)
        while rays.size:  # bisect, keeping f(a) < 0 <= f(b); a ray leaves once its bracket is < tol
            done = (b - a) < self.tol
            # the last bracket's secant point is closer still than its ends
            out[rays[done]] = a[done] + (b - a)[done] * fa[done] / np.minimum(fa - fb, -1e-300)[done]
            rays, a, b, fa, fb = rays[~done], a[~done], b[~done], fa[~done], fb[~done]
            m = 0.5 * (a + b)
            fm = self._below(o, d[rays], m)
            under = fm >= 0
            a, fa = np.where(under, a, m), np.where(under, fa, fm)
            b, fb = np.where(under, m, b), np.where(under, fm, fb)
        return out

    def surface(self, x):
        gx, gz = self.gradient(x[:, 0], x[:, 2])
        normal = _normalise(np.stack([-gx, -np.ones(len(x)), -gz], 1))  # up (-y), away from the ground
        return x.copy(), x[:, [0, 2]].copy(), normal


@functools.lru_cache(maxsize=64)
def _bump_extremes(bumps: tuple) -> tuple[float, float, float]:
    """(min, max, max |∇|) of Σ bumps over the whole plane, as safe bounds (see ``HeightField.bounds``).

    Evaluated on a grid over the bumps' support (beyond 4 σ of every bump, all of them add less
    than Σ|height|·e⁻⁸) and widened for what lies between grid points, using H = Σ |height| / σ²,
    which bounds the Hessian of Σ bumps: at an interior extremum the gradient vanishes, so a grid
    point δ ≤ spacing/√2 away differs by at most ½·H·δ²; the gradient changes by at most H·δ.
    """
    if not bumps:
        return 0.0, 0.0, 0.0
    b = np.asarray(bumps, float)  # (n, 4) cx, cz, height, sigma
    reach = 4.0 * b[:, 3]
    lo_x, hi_x = np.min(b[:, 0] - reach), np.max(b[:, 0] + reach)
    lo_z, hi_z = np.min(b[:, 1] - reach), np.max(b[:, 1] + reach)
    spacing = max(0.1 * float(b[:, 3].min()), max(hi_x - lo_x, hi_z - lo_z) / 400.0)  # ≤ 401² points
    x, z = (g.ravel() for g in np.meshgrid(np.arange(lo_x, hi_x + spacing, spacing),
                                            np.arange(lo_z, hi_z + spacing, spacing)))
    field = HeightField(None, tuple(map(tuple, b)))
    total = field.height(x, z)
    slope = np.hypot(*field.gradient(x, z))
    hessian = float(np.sum(np.abs(b[:, 2]) / b[:, 3] ** 2))
    delta = spacing / np.sqrt(2.0)
    outside = float(np.sum(np.abs(b[:, 2]))) * np.exp(-8.0)
    return (min(float(total.min()) - 0.5 * hessian * delta ** 2, -outside),
            max(float(total.max()) + 0.5 * hessian * delta ** 2, outside),
            float(slope.max()) + hessian * delta)


# ----------------------------------------------------------------------------------------------
# The scenes
# ----------------------------------------------------------------------------------------------

def _photo_tex(rng, image, scale, tint=(1.0, 1.0, 1.0), crop=(0.0, 1.0, 0.0, 1.0), variation=0.25):
    """A PhotoTexture whose tint varies a little with the seed (as ``_tex`` does for colours)."""
    return PhotoTexture(image, scale, _jitter(rng, tint), crop=crop, variation=variation)


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
    prims = [_sky(rng, 60.0, 30.0), ground]
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
                         0.06, _tex(rng, "flat", (0.85, 0.85, 0.8))))
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


register_scene("hills", _hills, "terrain height field, photo grass, ellipsoid boulders, a tree, branches, sky at 60 m")
register_scene("sculpture", _sculpture, "organic blob of overlapping ellipsoids on bumpy gravel, inside a brick dome, 2–8 m")
register_scene("logs", _logs, "tilted logs, cones and thin rods on bumpy ground in a round room, 1.5–6 m")
