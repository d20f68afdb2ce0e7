"""Classical depth completion: what DDP is compared against.

Every method has one signature, ``fn(depth, rgb=None) -> depth``: ``depth`` (H, W) float metres
with NaN holes, ``rgb`` (H, W, 3) in [0, 1] (used by the colour-guided fills); the answer is a new
float32 (H, W) map with no NaN, equal to the input wherever the input was valid. Inputs are
never modified.

The fills live by kind: those that see the depth alone in :mod:`ddp_lite.classical.depth_fills`
(``nearest``, ``linear``, ``cubic``, ``telea``, ``navier-stokes``, ``biharmonic``, ``ebi``, ``fbf``), those
guided by the colour image in :mod:`ddp_lite.classical.guided_fills` (``colorization``, ``guided-filter``,
``bilateral-solver``, ``cross-bilateral``, ``fast-global-smoother``); each module says how its fills work.
Several call OpenCV's contrib modules (``cv2.ximgproc``, ``cv2.xphoto``).

``PAPER_TABLE6`` maps the rows of the paper's Table 6 (Middlebury, disparity RMSE) to the kit's fills;
``ebi`` and ``fbf`` are the closest OpenCV methods, not the papers' own (their docstrings say how they
differ). ``PAPER_TABLE6_RMSE`` holds the paper's numbers; ``PAPER_TABLE6_NOT_IN_KIT`` the rows the kit has
no classical fill for (SSI, Depthcomp; DDP is the kit itself).
"""
from __future__ import annotations

import numpy as np

from .depth_fills import (fill_biharmonic, fill_cubic, fill_ebi, fill_fbf, fill_linear, fill_navier_stokes, fill_nearest,
                          fill_telea)
from .guided_fills import (fill_bilateral_solver, fill_colorization, fill_cross_bilateral, fill_fast_global_smoother,
                           fill_guided_filter)

__all__ = ["BASELINES", "fill", "PAPER_TABLE6", "PAPER_TABLE6_RMSE", "PAPER_TABLE6_NOT_IN_KIT"]


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


# the paper's Table 6 row → the kit's fill (for the rows the kit has)
PAPER_TABLE6 = {
    "Linear Inter": "linear",
    "Cubic Inter": "cubic",
    "FMM": "telea",
    "GIF": "guided-filter",
    "FBF": "fbf",
    "EBI": "ebi",
}

# the paper's Table 6, disparity RMSE: row → (Plastic, Baby, Bowling, Average), as printed
PAPER_TABLE6_RMSE = {
    "SSI": (1.7573, 2.9638, 6.4936, 3.74),
    "Linear Inter": (1.3432, 1.3473, 1.4503, 1.38),
    "Cubic Inter": (1.2661, 1.3384, 1.4460, 1.35),
    "FMM": (0.9580, 0.8349, 1.2422, 1.01),
    "GIF": (0.7947, 0.6008, 0.9436, 0.78),
    "FBF": (0.8643, 0.6238, 0.5918, 0.69),
    "EBI": (0.6952, 0.6755, 0.4857, 0.62),
    "Depthcomp": (0.6618, 0.3697, 0.4292, 0.49),
    "DDP": (0.4951, 0.3232, 0.5743, 0.46),
}

# rows of Table 6 with no classical fill in the kit: SSI (Herrera et al. 2013) and Depthcomp (Atapour-Abarghouei
# & Breckon 2017) are not implemented; DDP is what the rest of the kit fits
PAPER_TABLE6_NOT_IN_KIT = ("SSI", "Depthcomp", "DDP")


def fill(depth, rgb=None, method: str = "linear") -> np.ndarray:
    """Fill the NaN holes of (H, W) depth (metres) with ``method``, a key of ``BASELINES`` → (H, W) float32.

    Example:
        >>> fill(np.array([[1.0, np.nan, 3.0], [1.0, 2.0, 3.0]]), method="linear").tolist()
        [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]
    """
    if method not in BASELINES:
        raise ValueError(f"method must be one of {sorted(BASELINES)}, got {method!r}")
    return BASELINES[method](depth, rgb)
