"""Ensembles: the mean disparity of K fits from seeds seed, seed+1, ... (``CombinationConfig.ensemble = K``).

    Z = 1/K Σ_k Z_k,   I = 1/K Σ_k I_k,   D = depth of Z

Not in the paper. One fit's hole error moves with the seed (other weights, noise and held-out
pixels), often by more than a lever changes it (``docs/studies/benchmark_history.md``, "The width
study"); the mean keeps what the fits agree on. Members run side by side in threads
where cores and memory allow (:mod:`ddp_lite.method.runtime.side_by_side`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["mean_outputs"]


def mean_outputs(members: list, weights=None) -> tuple[np.ndarray, np.ndarray | None]:
    """(Z (H, W), I (H, W, 3) or None): the members' mean disparity and colour output, float32;
    with ``weights`` (one per member, summing to 1) their weighted sum (a blend, ``ddp_lite.method.kit.blend``)."""
    def combine(arrays):
        if weights is None:
            return np.mean(arrays, axis=0).astype(np.float32)
        return sum(w * a for w, a in zip(weights, arrays)).astype(np.float32)
    rgbs = [m.rgb for m in members if m.rgb is not None]
    return combine([m.disparity for m in members]), (combine(rgbs) if rgbs else None)
