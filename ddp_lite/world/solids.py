"""Curved solids for the renderer: ``Ellipsoid``, ``Cone`` (capped frustum, tilted cylinder), ``Capsule``.

Same interface as ``render.Plane``/``Sphere``: ``intersect(o, d)`` takes a ray origin o (3,) and
directions d (N, 3) (world frame, metres) and returns the ray parameter of the first hit t (N,)
(``inf`` on a miss; the renderer's rays have camera z = 1, so t is the depth); ``surface(x)``
takes world points (M, 3) on the surface and returns ``(local (M, 3) metres in the object frame,
st (M, 2) metres along the surface, normal (M, 3))``:

- ``Ellipsoid``: a sphere after scaling the object frame by 1/radii: one quadratic;
- ``Cone``: a capped frustum between points a and b (equal radii: a tilted cylinder): one
  quadratic for the side, one linear equation per cap;
- ``Capsule``: a cylinder with round ends (branches, rods): the same side plus two spheres.

``inside=True`` (ellipsoid, cone) makes a solid seen from within (a dome, a round room): the
first hit is the far wall and normals point inwards. Angles about an axis are mirrored
(``_angle_coord``) so a photo wrapped round a solid has no seam.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .render import EPS, unit_vector, yaw_matrix


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
        normal = normalise_rows((local / r ** 2) @ R.T)  # gradient of |local / r|²
        if self.inside:
            normal = -normal
        around = 0.5 * (r[1] + r[2]) * _angle_coord(p[:, 2], -p[:, 1])  # arc about x, 0 on top
        along = r[0] * np.arcsin(np.clip(p[:, 0], -1.0, 1.0))  # arc along x from the mid meridian
        return local, np.stack([around, along], 1), normal


def normalise_rows(v: np.ndarray) -> np.ndarray:
    """(N, 3) vectors → the same, each scaled to unit length."""
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
            normal = normalise_rows(radial / np.maximum(rho, 1e-12)[:, None] - k * w[None])
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
        normal = normalise_rows(x - nearest)
        u1, u2 = q @ e1, q @ e2
        st = np.stack([self.radius * _angle_coord(u2, u1), h], 1)
        return np.stack([u1, u2, h], 1), st, normal
