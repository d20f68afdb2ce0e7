"""Depth ↔ normalised disparity, the representation DDP fits (paper Sec. 3.2).

DDP does not fit metres. It clips depth to ``[d_min, d_max]`` (far things stop dominating,
near ones cannot blow up), adds a constant ``c`` (which narrows the ratio between the largest
and smallest value), inverts, and rescales linearly so the result fills ``[0, 1]`` — the range
of the network's sigmoid output:

    Z = 1 / (clip(D, d_min, d_max) + c),     z = (Z - Z_far) / (Z_near - Z_far)

with ``Z_near = 1 / (d_min + c)`` and ``Z_far = 1 / (d_max + c)``. So disparity 1 is the
nearest allowed depth and 0 the farthest.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ...core.checks import check_real

__all__ = ["DisparityTransform", "TNT_DEPTH_RANGES"]

# The supplement's per-scene table (Tanks and Temples): (d_min, d_max, constant), metres.
TNT_DEPTH_RANGES = {
    "Ignatius": (2.0, 7.5, 0.0),
    "Barn": (2.0, 16.5, 2.0),
    "Caterpillar": (2.0, 7.5, 0.0),
    "Meetingroom": (0.2, 25.0, 4.0),
    "Truck": (0.5, 10.0, 2.0),
    "Courtroom": (0.2, 46.0, 4.0),
    "Church": (0.2, 16.0, 4.0),
}


@dataclass(frozen=True)
class DisparityTransform:
    """The paper's clip-shift-invert-scale map between depth (metres) and disparity in [0, 1].

    Example:
        >>> t = DisparityTransform(d_min=1.0, d_max=10.0)
        >>> float(t.to_disparity(np.array([1.0]))[0]), float(t.to_depth(np.array([0.0]))[0])
        (1.0, 10.0)
    """

    d_min: float
    d_max: float
    constant: float = 0.0

    def __post_init__(self):
        for name in ("d_min", "d_max", "constant"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)}")
        if not 0.0 < self.d_min < self.d_max:
            raise ValueError(f"need 0 < d_min < d_max, got d_min={self.d_min}, d_max={self.d_max}")
        if self.constant < 0.0:
            raise ValueError(f"constant must be >= 0, got {self.constant}")

    @classmethod
    def from_depth(cls, depth, constant: float = 0.0, margin: float = 1.25) -> "DisparityTransform":
        """A range that holds the valid (finite) depths of ``depth`` (H, W) with a ``margin`` factor
        on both sides, so a hole may be a little nearer or farther than anything observed."""
        check_real(margin, "margin", 1.0)
        if np.ma.isMaskedArray(depth):  # masked = hole: what lies under the mask is no depth
            depth = np.ma.filled(depth.astype(np.float64), np.nan)
        valid = np.asarray(depth, dtype=np.float64)
        valid = valid[np.isfinite(valid)]
        if valid.size == 0:
            raise ValueError("depth has no finite value to derive d_min/d_max from")
        lo, hi = np.percentile(valid, [0.5, 99.5])
        return cls(d_min=float(lo / margin), d_max=float(hi * margin), constant=constant)

    def check_covers(self, depth: np.ndarray, name: str = "transform") -> None:
        """Refuse (``ValueError`` naming ``name``) a range that does not cover the bulk of the valid ``depth``
        (H, W) metres (its 0.5–99.5th percentiles, the range :meth:`from_depth` covers before its margin):
        a fit could not reproduce those pixels, and every one of them would come back clipped."""
        lo, hi = np.percentile(depth[np.isfinite(depth)], [0.5, 99.5])
        if lo < self.d_min or hi > self.d_max:
            outside = int(((depth < self.d_min) | (depth > self.d_max)).sum())
            raise ValueError(f"{name}: [{self.d_min:.4g}, {self.d_max:.4g}] m does not cover the valid depth "
                             f"(0.5–99.5th percentiles {lo:.4g}–{hi:.4g} m; {outside} pixel(s) outside would come "
                             f"back clipped); widen it, or pass {name}=None to derive it from the depth")

    @classmethod
    def for_tnt_scene(cls, name: str) -> "DisparityTransform":
        """The supplement's values for a Tanks and Temples scene (e.g. ``"Ignatius"``)."""
        if name not in TNT_DEPTH_RANGES:
            raise ValueError(f"name must be one of {sorted(TNT_DEPTH_RANGES)}, got {name!r}")
        return cls(*TNT_DEPTH_RANGES[name])

    @property
    def near(self) -> float:
        """Unscaled disparity ``1 / (d_min + c)`` of the nearest allowed depth (1/m)."""
        return 1.0 / (self.d_min + self.constant)

    @property
    def far(self) -> float:
        """Unscaled disparity ``1 / (d_max + c)`` of the farthest allowed depth (1/m)."""
        return 1.0 / (self.d_max + self.constant)

    def to_disparity(self, depth):
        """Depth in metres (any shape, NumPy or torch; NaN stays NaN) → disparity in [0, 1]."""
        lib = torch if isinstance(depth, torch.Tensor) else np
        inverse = 1.0 / (lib.clip(depth, self.d_min, self.d_max) + self.constant)
        return (inverse - self.far) / (self.near - self.far)

    def to_depth(self, disparity):
        """Disparity in [0, 1] (values outside are clipped) → depth in metres, same type and shape."""
        lib = torch if isinstance(disparity, torch.Tensor) else np
        inverse = lib.clip(disparity, 0.0, 1.0) * (self.near - self.far) + self.far
        return 1.0 / inverse - self.constant
