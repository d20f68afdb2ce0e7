"""What a fit returns, :class:`DepthResult`, and "SGM+DDP", :func:`merge`: the input where it is valid, a
result in its holes. Below the fit (:mod:`ddp_lite.method.fit`) and the kit's combinations of fits
(:mod:`ddp_lite.method.kit.combine`), which both build results; it imports only ``core`` and the paper's
disparity transform.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.checks import check_depth, unmask
from .paper.disparity import DisparityTransform

__all__ = ["DepthResult", "merge"]


@dataclass
class DepthResult:
    """What :func:`~ddp_lite.method.complete.complete_depth` returns. Arrays are NumPy, (H, W) or (H, W, 3).

    For the mean of several fits (``config.combination.ensemble > 1``, ``fits`` of them) ``iterations`` and
    ``seconds`` are totals over the fits; ``history``, ``best_iteration`` and ``state`` are the
    first fit's.
    """

    depth: np.ndarray  # metres, holes filled
    disparity: np.ndarray  # [0, 1], see ``transform``
    rgb: np.ndarray | None  # the net's colour output (None for depth only)
    history: dict  # per-iteration loss terms; per-evaluation held-out and hole errors; lr_decay_iteration
    transform: DisparityTransform
    iterations: int  # iterations run
    best_iteration: int  # the iteration whose output is returned
    seconds: float
    state: dict | None = field(default=None, repr=False)  # the net's final weights (CPU), for warm starts
    fits: int = 1  # how many fits' disparities were averaged (config.combination.ensemble)

    def merged(self, input_depth) -> np.ndarray:
        """"SGM+DDP": the input where it is valid, this result in its holes."""
        return merge(input_depth, self.depth)


def merge(input_depth, ddp_depth) -> np.ndarray:
    """(H, W) metres: ``input_depth`` where it is finite, ``ddp_depth`` in its holes ("SGM+DDP").

    ``input_depth`` follows the kit's convention (NaN holes, a masked array's mask = holes); a 0 or
    negative "hole" marker, or inf, is refused rather than kept as a depth."""
    input_depth = check_depth(input_depth, "input_depth", min_valid=0)
    ddp_depth = np.asarray(unmask(ddp_depth, "ddp_depth", holes=True))
    if not (np.issubdtype(ddp_depth.dtype, np.floating) or np.issubdtype(ddp_depth.dtype, np.integer)):
        raise TypeError(f"ddp_depth must be an (H, W) array of metres, got dtype {ddp_depth.dtype}")
    ddp_depth = ddp_depth.astype(np.float32)
    if input_depth.shape != ddp_depth.shape:
        raise ValueError(f"input_depth {input_depth.shape} and ddp_depth {ddp_depth.shape} must have the same shape")
    return np.where(np.isfinite(input_depth), input_depth, ddp_depth).astype(np.float32)
