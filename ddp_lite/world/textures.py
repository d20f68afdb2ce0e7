"""Procedural surface textures for the synthetic renderer: seeded, defined on the surface.

A texture's colour is a function of a point in the surface's *own* coordinates (``local``: the
3D point in the object's frame, metres; ``st``: metres along the surface), never of the pixel,
so a surface point has the same colour in every view: the multi-view photo-consistency DDP's
warp loss relies on. Randomness is a hash of integer lattice coordinates and ``seed`` (no global
RNG), so a scene renders identically on every machine.

Kinds: ``flat`` (one colour: textureless), ``sky`` (a vertical gradient), ``planks`` (strong
colour edges on a flat surface, paper Fig. 4), ``noise`` (3D fractal value noise), ``bricks``,
``tiles``. ``Texture.label`` is the texture class written into ``Scene.labels``
(``views.LABEL_*``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.views import LABEL_PLANKS, LABEL_SKY, LABEL_TEXTURED, LABEL_TEXTURELESS

__all__ = ["Texture", "fbm", "lattice_hash"]

_M1, _M2 = np.uint64(0xFF51AFD7ED558CCD), np.uint64(0xC4CEB9FE1A85EC53)


def lattice_hash(*ints) -> np.ndarray:
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
        out += weight * lattice_hash(seed, *[cell[:, d] + b for d, b in enumerate(bits)])
    return out


def fbm(p: np.ndarray, seed: int, octaves: int = 3) -> np.ndarray:
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
        return {"sky": LABEL_SKY, "flat": LABEL_TEXTURELESS, "planks": LABEL_PLANKS}.get(self.kind, LABEL_TEXTURED)

    def albedo(self, local: np.ndarray, st: np.ndarray, seed: int) -> np.ndarray:
        """Colours (M, 3) at surface points: ``local`` (M, 3) metres in the object frame,
        ``st`` (M, 2) metres along the surface."""
        c1, c2, scale = np.asarray(self.color), np.asarray(self.color2), self.scale
        if self.kind == "flat":
            return np.broadcast_to(c1, (len(st), 3)).copy()
        if self.kind == "sky":  # horizon colour → zenith colour over `scale` metres of height
            return _mix(c1, c2, -st[:, 1] / scale)
        if self.kind == "noise":  # solid (3D) noise: no seams on spheres or box corners
            n = fbm(local / scale, seed)
            return _mix(c1, c2, (n - 0.5) * 2.2 + 0.5)
        if self.kind == "planks":  # vertical planks: s across, t along the boards
            s, t = st[:, 0] / scale, st[:, 1]
            board = np.floor(s).astype(np.int64)
            tone = lattice_hash(seed, board)  # (M,) one tone per board
            grain = fbm(np.stack([(s - board) * 6.0, t * 0.8 + 31.0 * tone], 1), seed + 7, octaves=2)
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
            tone = lattice_hash(seed, row, col)
            colour = _mix(c1, c2, tone) * (0.85 + 0.3 * fbm(local / (0.2 * scale), seed + 3, 2))[:, None]
            mortar = ((s - col) < 0.06) | ((st[:, 1] / h - row) < 0.15)
            colour[mortar] = 0.5 * (colour[mortar] * 0.2 + 0.75)
            return colour
        if self.kind == "tiles":  # checkerboard tiles with a little noise
            i = np.floor(st[:, 0] / scale).astype(np.int64) + np.floor(st[:, 1] / scale).astype(np.int64)
            colour = np.where((i % 2 == 0)[:, None], c1[None], c2[None])
            return colour * (0.85 + 0.3 * fbm(local / (0.1 * scale), seed, 2))[:, None]
        raise ValueError(f"texture kind must be flat, sky, planks, noise, bricks or tiles, got {self.kind!r}")


def jitter_colour(rng, colour, amount=0.08):
    """A seeded variation of a base colour, so a new seed changes colours as well as patterns."""
    return tuple(np.clip(np.asarray(colour) * (1.0 + rng.uniform(-amount, amount, 3)), 0.0, 1.0))


def seeded_texture(rng, kind, color, color2=(0.0, 0.0, 0.0), scale=0.05):
    """A :class:`Texture` whose two colours are seeded variations of ``color`` and ``color2``."""
    return Texture(kind, jitter_colour(rng, color), jitter_colour(rng, color2), scale)
