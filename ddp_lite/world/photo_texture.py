"""Photographic texture: a photo bundled with scikit-image, laid on a surface by its coordinates.

``PhotoTexture`` samples a photo by the surface coordinates st (metres along the surface;
bilinear, mirrored-repeat tiling), so the colour is a function of the surface point only and
every view sees the same colour: the photo-consistency DDP's warp loss relies on. It has the
interface of ``textures.Texture`` (``kind``, ``label``, ``albedo(local (M, 3), st (M, 2), seed) ->
(M, 3)`` RGB in [0, 1]). Photos are read from ``skimage.data`` (no download), pre-filtered once
to ``pixels`` columns and cached read-only.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .textures import fbm, lattice_hash

# Photos that scikit-image ships inside its own package (no pooch download, no network).
PHOTOS = ("astronaut", "brick", "camera", "chelsea", "coffee", "grass", "gravel", "moon", "retina", "rocket")


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
