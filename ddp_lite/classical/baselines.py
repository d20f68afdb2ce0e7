"""Classical depth completion: what DDP is compared against.

Every method has one signature, ``fn(depth, rgb=None) -> depth``: ``depth`` (H, W) float metres
with NaN holes, ``rgb`` (H, W, 3) in [0, 1] (used by the colour-guided fills); the answer is a new
float32 (H, W) map with no NaN, equal to the input wherever the input was valid. Inputs are
never modified.

The fills live by kind: those that see the depth alone in :mod:`ddp_lite.classical.depth_fills`
(``nearest``, ``linear``, ``cubic``, ``telea``, ``navier-stokes``, ``biharmonic``), those guided by
the colour image in :mod:`ddp_lite.classical.guided_fills` (``colorization``, ``guided-filter``,
``bilateral-solver``, ``cross-bilateral``); each module says how its fills work.
"""
from __future__ import annotations

import numpy as np

from .depth_fills import (fill_biharmonic, fill_cubic, fill_ebi, fill_fbf, fill_linear, fill_navier_stokes, fill_nearest,
                          fill_telea)
from .guided_fills import (fill_bilateral_solver, fill_colorization, fill_cross_bilateral, fill_fast_global_smoother,
                           fill_guided_filter)

__all__ = ["BASELINES", "fill"]


BASELINES = {
    "nearest": fill_nearest,
    "linear": fill_linear,
    "cubic": fill_cubic,
    "telea": fill_telea,
    "navier-stokes": fill_navier_stokes,
    "biharmonic": fill_biharmonic,
    "ebi": fill_ebi,
    "fbf": fill_fbf,
    "colorization": fill_colorization,
    "guided-filter": fill_guided_filter,
    "bilateral-solver": fill_bilateral_solver,
    "cross-bilateral": fill_cross_bilateral,
    "fast-global-smoother": fill_fast_global_smoother,
}


def fill(depth, rgb=None, method: str = "linear") -> np.ndarray:
    """Fill the NaN holes of (H, W) depth (metres) with ``method``, a key of ``BASELINES`` → (H, W) float32.

    Example:
        >>> fill(np.array([[1.0, np.nan, 3.0], [1.0, 2.0, 3.0]]), method="linear").tolist()
        [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]
    """
    if method not in BASELINES:
        raise ValueError(f"method must be one of {sorted(BASELINES)}, got {method!r}")
    return BASELINES[method](depth, rgb)
