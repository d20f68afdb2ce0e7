"""Lengths in pixels that scale with the image: a setting tuned at one size, stated so it survives another.

A solve's reach, a rim's width or a blob's size tuned in pixels on images of one size means something else
on an image twice as large: the same surface spans twice the pixels, so a 4 px reach there reaches half as
far across it. A :class:`PixelLength` keeps the value it was tuned at and the largest short side of the
images it was tuned on; on a larger image it grows with the short side:

    pixels(shape) = pixels_tuned · max(1, min(H, W) / tuned_short_side)

At and below the size it was tuned on it is the tuned value exactly (so what was measured there stays
what runs there, bit for bit); above, it is the same fraction of the image's short side as at the largest
tuned image. Smaller images keep the tuned value: nothing was measured there that says a reach of a few
pixels should shrink further.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["PixelLength", "short_side"]


def short_side(shape) -> int:
    """min(H, W) of an (H, W, ...) shape, checked: two positive integers first."""
    shape = tuple(shape)
    if len(shape) < 2 or not all(isinstance(n, int) or hasattr(n, "__index__") for n in shape[:2]) \
            or min(int(shape[0]), int(shape[1])) < 1:
        raise ValueError(f"shape must start with (H, W), two positive integers, got {shape!r}")
    return min(int(shape[0]), int(shape[1]))


@dataclass(frozen=True)
class PixelLength:
    """A length in pixels tuned on images whose short side was at most ``tuned_short_side`` px.

    Example:
        >>> reach = PixelLength(8.0, 138)
        >>> reach.at((138, 173)), reach.at((96, 128)), reach.at((276, 346)), reach.whole((552, 692))
        (8.0, 8.0, 16.0, 32)
    """

    pixels: float  # the value at the size it was tuned at (px)
    tuned_short_side: int  # the largest short side (px) of the images it was tuned on

    def __post_init__(self):
        if isinstance(self.pixels, bool) or not isinstance(self.pixels, (int, float)) or not self.pixels >= 0:
            raise ValueError(f"pixels must be a number >= 0, got {self.pixels!r}")
        if isinstance(self.tuned_short_side, bool) or not isinstance(self.tuned_short_side, int) \
                or self.tuned_short_side < 1:
            raise ValueError(f"tuned_short_side must be a positive integer (px), got {self.tuned_short_side!r}")

    @property
    def fraction(self) -> float:
        """The length as a fraction of the short side, above the tuned size."""
        return self.pixels / self.tuned_short_side

    def scale(self, shape) -> float:
        """max(1, min(H, W) / ``tuned_short_side``) for an image of ``shape`` (H, W, ...)."""
        return max(1.0, short_side(shape) / self.tuned_short_side)

    def at(self, shape) -> float:
        """The length in px on an image of ``shape`` (H, W, ...); the tuned value itself up to the tuned size."""
        scale = self.scale(shape)
        return float(self.pixels) if scale == 1.0 else float(self.pixels) * scale

    def whole(self, shape) -> int:
        """:meth:`at` rounded to whole pixels (a rim's width, a window's radius)."""
        return int(round(self.at(shape)))
