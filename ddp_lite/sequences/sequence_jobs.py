"""A sequence's jobs: one picklable ``ViewJob`` per view, planned and checked up front, and its fit.

``plan_jobs`` picks each view's N = 2 neighbours (MVSNet's score, ``neighbors.select_neighbors``),
one disparity range for the whole scene (so the fills share a scale), runs every input check
``complete_depth`` makes, and names each job by a *key*: a sha256 over what its result depends on
(pixels, cameras, neighbours, fit config and run options, disparity range). ``fit_view`` runs one job wherever it
is called (this process or a Dask worker) and returns arrays only: depth float32 (H, W) metres,
NaN = unknown. The variant is always ``VARIANT`` (rgbd+warp).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import re
from dataclasses import dataclass, field

import numpy as np

from ..core.camera import Camera
from ..method.paper.disparity import DisparityTransform
from ..method.config import FitConfig
from ..method.complete import complete_depth
from ..method.runtime.options import RunOptions, run_options
from ..method.runtime.side_by_side import torch_threads
from ..method.input_checks import check_fit_inputs
from ..world.neighbors import select_neighbors
from ..core.views import Scene

VARIANT = "rgbd+warp"

N_NEIGHBORS = 2  # the paper's N


@dataclass
class ViewJob:
    """One view's fit: everything a worker needs (picklable), and the key it is known by."""

    name: str  # the view's name in the scene
    stem: str  # its file-safe name: depth/<stem>.npy
    index: int
    rgb: np.ndarray  # (H, W, 3) [0, 1]
    depth: np.ndarray  # (H, W) metres, NaN = hole
    camera: Camera
    neighbors: list  # [(rgb (H, W, 3), Camera)] × N
    neighbor_names: list
    config: FitConfig
    transform: DisparityTransform
    threads: int = 1
    key: str = field(default="")
    options: RunOptions = field(default_factory=RunOptions)  # how it runs (its progress bar is off in fit_view)


def _stem(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]", "_", name) or "view"


def _job_key(view, neighbors, config: FitConfig, options: RunOptions, transform: DisparityTransform) -> str:
    """sha256 over what the result depends on: pixels, cameras, neighbours, config, disparity range, and the
    run options by their names beside the config's fields, those that change no number (device, memory
    limit, progress bar) at fixed values."""
    digest = hashlib.sha256()
    for rgb, depth, camera in [(view.rgb, view.depth, view.camera)] + [(n.rgb, None, n.camera) for n in neighbors]:
        for array in (rgb, depth, camera.K, camera.cam_from_world):
            if array is not None:
                digest.update(np.ascontiguousarray(array).tobytes())
    run = dataclasses.asdict(options.replace(progress=False, device=None, max_memory_gb=None))
    settings = {**config.flat(), **run}
    digest.update(json.dumps([settings, dataclasses.asdict(transform), VARIANT], sort_keys=True, default=str).encode())
    return digest.hexdigest()[:16]


def plan_jobs(scene: Scene, config: FitConfig, views=None, threads: int = 1, options: RunOptions | None = None
              ) -> list[ViewJob]:
    """One :class:`ViewJob` per view of ``scene`` (or per index in ``views``), inputs checked, each run with
    ``options`` (:class:`RunOptions`; None → ``RunOptions()``).

    Neighbours: the N = 2 best by MVSNet's score (``select_neighbors``) among *all* views; the
    disparity range: one for the whole scene (its ``meta`` d_min/d_max, else from every view's
    valid depth with ``config.disparity_margin``), so the views' fills are on one scale.

    Example:
        >>> from ddp_lite.world.scenes import make_scene
        >>> jobs = plan_jobs(make_scene("desk", size=(24, 32), n_views=3), FitConfig(iterations=1))
        >>> [(j.name, j.neighbor_names) for j in jobs][0]
        ('desk0', ['desk2', 'desk1'])
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a ddp_lite.Scene, got {type(scene).__name__}")
    options = run_options(options)
    if len(scene) < 2:
        raise ValueError(f"a sequence needs at least 2 views (the warp loss uses neighbours), got {len(scene)}")
    chosen = list(range(len(scene))) if views is None else list(views)
    for i in chosen:
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= i < len(scene):
            raise ValueError(f"views must be view indices in [0, {len(scene)}), got {i!r}")
    if len(set(chosen)) != len(chosen):
        raise ValueError(f"views lists an index twice: {chosen}")
    stems = [_stem(v.name or f"view{i:04d}") for i, v in enumerate(scene.views)]
    if len(set(stems)) != len(stems):
        raise ValueError("the views' names must be unique (after replacing characters other than A-Z a-z 0-9 . _ -)")
    meta = scene.meta
    if "d_min" in meta and "d_max" in meta:
        transform = DisparityTransform(float(meta["d_min"]), float(meta["d_max"]))
    else:
        transform = DisparityTransform.from_depth(np.concatenate([v.depth.ravel() for v in scene.views]),
                                                  margin=config.paper.disparity_margin)
    n = min(N_NEIGHBORS, len(scene) - 1)
    jobs = []
    for i in chosen:
        view = scene[i]
        neighbors = [scene[j] for j in select_neighbors(scene, i, n)]
        pairs = [(v.rgb, v.camera) for v in neighbors]
        try:  # every check complete_depth makes, here, before the first fit
            check_fit_inputs(view.rgb, view.depth, view.camera, pairs, VARIANT, config, None, transform)
        except ValueError as error:
            raise ValueError(f"view {i} ({view.name!r}): {error}") from None
        jobs.append(ViewJob(view.name, stems[i], i, view.rgb, view.depth, view.camera, pairs,
                            [v.name for v in neighbors], config, transform, int(threads),
                            _job_key(view, neighbors, config, options, transform), options))
    return jobs


def fit_view(job: ViewJob) -> dict:
    """Run one view's DDP fit (on whatever process calls it) → {"depth", "ddp", "iterations", "seconds"}.

    ``depth`` (H, W) float32 metres is SGM+DDP: the input where valid, DDP in the holes; ``ddp`` is
    DDP's own output everywhere. ``job.threads`` torch threads (1 by default, so a run gives the
    same numbers in-process and on any worker)."""
    with torch_threads(job.threads):  # side by side in this process the caller has set them already: no change
        result = complete_depth(job.rgb, job.depth, job.camera, job.neighbors, variant=VARIANT,
                                config=job.config, transform=job.transform, options=job.options.replace(progress=False))
    return {"depth": result.merged(job.depth).astype(np.float32), "ddp": result.depth.astype(np.float32),
            "iterations": int(result.iterations), "seconds": float(result.seconds)}
