"""Independent fits side by side: on a CPU, one torch thread each, as many at once as torch has threads.

A net of the kit's sizes does not keep two cores busy: two one-thread fits side by side do more work
than one two-thread fit, and more still where a machine has more cores (``docs/studies/benchmark_history.md``,
"Ensembles side by side"). Whatever fits do not depend on each other run here: the members of an ensemble or a blend, the
views of a multi-view scene, the rows of a table. A fit run side by side gives the numbers it gives
with ``torch.set_num_threads(1)``, on any machine (one thread's sums are taken in one order).

Example:
    >>> run_side_by_side(lambda k: k * k, 3, workers=2)
    [0, 1, 4]
"""
from __future__ import annotations

import contextlib
from concurrent.futures import ThreadPoolExecutor

import torch

from .device import resolve_device
from .memory import estimate_peak_memory_gb, memory_limit_gb
from ..paper.variants import get_variant

__all__ = ["side_by_side_workers", "run_side_by_side", "run_fits", "torch_threads"]


def side_by_side_workers(config, options, variant: str, shape, n_neighbors: int, jobs: int, callback=None) -> int:
    """How many of ``jobs`` fits of ``config`` run with ``options`` (``variant``, images of ``shape`` (H, W),
    ``n_neighbors`` warp partners) run at once: on a CPU one per torch thread, as many as fit in memory side
    by side; 1 with a ``callback`` (it may draw figures, which wants the main thread) or on a GPU."""
    device = resolve_device(options)
    if device.type != "cpu" or callback is not None:
        return 1
    workers = max(1, min(int(jobs), torch.get_num_threads()))
    limit, _ = memory_limit_gb(options, device)
    if limit is not None and workers > 1:
        one = estimate_peak_memory_gb(config, get_variant(variant).out_channels, *shape, n_neighbors)
        workers = min(workers, max(1, int(limit // one)))
    return workers


def run_side_by_side(fit, count: int, workers: int) -> list:
    """``[fit(k) for k in range(count)]``: ``workers`` at a time in threads, each on one torch thread, the
    last round too when fewer are left than ``workers`` (a core then idles, but a fit's numbers do not
    depend on how many cores the machine has); with ``workers`` 1, in turn on all threads."""
    if workers <= 1 or count <= 1:
        return [fit(k) for k in range(count)]
    with torch_threads(1), ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(fit, range(count)))


@contextlib.contextmanager
def torch_threads(count: int):
    """torch's intra-op threads set to ``count`` inside the block, as they were after it. Set here, before
    fits start in other threads: each new thread takes the count torch has when it first runs an op."""
    before = torch.get_num_threads()
    torch.set_num_threads(int(count))
    try:
        yield
    finally:
        torch.set_num_threads(before)


def run_fits(fit, jobs, options) -> list:
    """``[fit(k) for k in range(len(jobs))]`` side by side, as many at once as every job allows
    (:func:`side_by_side_workers`); ``jobs``: one ``(config, variant, shape (H, W), n_neighbors)`` per fit, all
    run with the :class:`~ddp_lite.method.runtime.options.RunOptions` ``options``."""
    workers = min((side_by_side_workers(config, options, variant, shape, n_neighbors, len(jobs))
                   for config, variant, shape, n_neighbors in jobs), default=1)
    return run_side_by_side(fit, len(jobs), workers)
