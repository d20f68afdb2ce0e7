"""Ensembles: the mean disparity of K fits from seeds seed, seed+1, ... (``FitConfig.ensemble = K``).

    Z = 1/K Σ_k Z_k,   I = 1/K Σ_k I_k,   D = depth of Z

Not in the paper. One fit's hole error moves ±10 % and more with the seed (other weights, noise
and held-out pixels); the mean keeps what the fits agree on. Members run side by side in threads
where cores and memory allow (:func:`parallel_members`, :func:`run_members`).
"""
from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import torch

from .config import FitConfig
from .device import resolve_device
from .loop import estimate_peak_memory_gb, memory_limit_gb
from .variants import get_variant

__all__ = ["parallel_members", "run_members", "mean_outputs"]


def parallel_members(config: FitConfig, variant: str, shape, n_neighbors: int, callback) -> int:
    """How many ensemble members run at once: on a CPU, one per torch thread (each member then
    computes on one thread), as many as fit in memory side by side; 1 with a callback (it may
    draw figures, which wants the main thread) or on a GPU."""
    device = resolve_device(config)
    if device.type != "cpu" or callback is not None:
        return 1
    workers = min(int(config.ensemble), torch.get_num_threads())
    limit, _ = memory_limit_gb(config, device)
    if limit is not None and workers > 1:
        one = estimate_peak_memory_gb(config, get_variant(variant).out_channels, *shape, n_neighbors)
        workers = min(workers, max(1, int(limit // one)))
    return workers


def run_members(fit_member, members: int, workers: int) -> list:
    """``[fit_member(k) for k in range(members)]``: in rounds of ``workers`` side by side in threads,
    each on one torch thread; what is left over (fewer than ``workers``) in turn on all threads.

    A small net does not keep two cores busy: two one-thread fits side by side do ~1.3× the work
    of one two-thread fit (``benchmarks/bench_ensemble.py --fits``), but one one-thread fit alone
    leaves a core idle, hence whole rounds only. A member run side by side gives the numbers it
    gives with ``torch.set_num_threads(1)``.
    """
    side_by_side = members - members % workers if workers > 1 else 0
    results = []
    if side_by_side:
        threads = torch.get_num_threads()
        torch.set_num_threads(1)
        try:
            with ThreadPoolExecutor(max_workers=workers) as pool:
                results = list(pool.map(fit_member, range(side_by_side)))
        finally:
            torch.set_num_threads(threads)
    return results + [fit_member(k) for k in range(side_by_side, members)]


def mean_outputs(members: list, weights=None) -> tuple[np.ndarray, np.ndarray | None]:
    """(Z (H, W), I (H, W, 3) or None): the members' mean disparity and colour output, float32;
    with ``weights`` (one per member, summing to 1) their weighted sum (a blend, ``ddp_lite.method.blend``)."""
    def combine(arrays):
        if weights is None:
            return np.mean(arrays, axis=0).astype(np.float32)
        return sum(w * a for w, a in zip(weights, arrays)).astype(np.float32)
    rgbs = [m.rgb for m in members if m.rgb is not None]
    return combine([m.disparity for m in members]), (combine(rgbs) if rgbs else None)
