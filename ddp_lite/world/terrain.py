"""Terrain for the renderer: ``HeightField``, y = -h(x, z), found by vectorised ray marching.

h is a sum of Gaussian bumps and sinusoids, analytic with an analytic gradient (y is down, so
h > 0 is above the ground plane y = 0); metres throughout. A ray has no closed-form hit: it is
marched inside the slab where the surface can be (``bounds``), with steps no ray can overshoot
by more than a floor step (``slope_bound``), then refined by bisection. Same interface as the
other primitives (``intersect``, ``surface``; see ``solids``).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .render import EPS
from .solids import normalise_rows


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
        normal = normalise_rows(np.stack([-gx, -np.ones(len(x)), -gz], 1))  # up (-y), away from the ground
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
