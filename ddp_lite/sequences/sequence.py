"""A whole sequence, view by view: DDP (RGBD + warp) on every view, then one fused point cloud.

The paper's own experiments are sequences (Tanks and Temples, 87–180+ views): every view's depth
is completed with the warp loss over N = 2 neighbours chosen by MVSNet's score (``neighbors.
select_neighbors``), SGM's depth is kept where valid and DDP's taken in the holes ("SGM+DDP"),
and the views are fused into one point cloud (Fusibile; here ``fusion.fuse_depths``).

:func:`run_sequence` does that for any ``Scene`` (read your data with ``ddp_lite.data.formats``):

1. **plan**: per view, its neighbours and a *job key*, a hash of everything the result depends
   on (its pixels and camera, its neighbours', the fit config, the disparity range). All inputs
   are checked here, before any fit starts;
2. **skip** the views the manifest records as done under the same key whose files are all there;
   everything else (never started, started but not finished, inputs or config changed) is redone;
3. **fit** the rest through :func:`runner.run_jobs`: in-process (one-thread fits side by side, as
   many as torch has threads: ``method.runtime.side_by_side``), or on Dask workers;
4. **write**, per finished view, ``depth/<view>.npy`` (float32 metres, NaN where nothing is
   known), ``depth/<view>.png`` (16-bit millimetres, 0 = none; beyond 65.535 m → 0, counted in
   the manifest) and ``preview/<view>.png`` (colour, input, completed), each atomically, and only
   then mark the view done in ``manifest.json`` (rewritten atomically after every change). A run
   killed at any moment leaves whole files and a manifest that says what is finished;
5. **fuse** every finished view into ``fused.ply`` (Open3D), Fusibile-style with C = 1 and
   D = 0.25 px per 64 px of image width (as notebook 07).

Only this process writes files: a worker returns arrays, so a remote cluster needs no shared disk.

The steps live in their own modules: planning and the
per-view fit in ``sequence_jobs``, the output folder (manifest, files, fusion) in
``sequence_files``, the dry run's cost estimate in ``sequence_cost``.
"""
from __future__ import annotations

import contextlib
import json
import time

import numpy as np

from ..method.config import FitConfig
from ..method.runtime.options import RunOptions, run_options
from ..method.runtime.side_by_side import side_by_side_workers, torch_threads
from ..core.progress import CommandClock
from .runner import run_jobs
from .sequence_files import (MANIFEST, view_files, view_finished, fuse_views, write_manifest, write_view, check_out_folder,
                             read_manifest)
from .sequence_jobs import VARIANT, fit_view, plan_jobs
from ..core.views import Scene

__all__ = ["run_sequence"]


def run_sequence(scene: Scene, out, config: FitConfig | None = None, views=None, client=None, threads: int = 1,
                 retries: int = 2, source: dict | None = None, fuse: bool = True, log=print,
                 options: RunOptions | None = None) -> dict:
    """Complete every view of ``scene`` (or ``views``, indices) with DDP rgbd+warp; write files; fuse.

    Args:
        scene: the sequence (``ddp_lite.data.formats.load_sequence`` reads TUM, COLMAP, saved scenes).
        out: output folder (see the module docstring for its files); a re-run skips finished views.
            It must not be, contain or lie inside an input (``scene.sources``, ``source["path"]``):
            ``ValueError`` before any fit.
        config: the fit's config; None → ``FitConfig.for_profile()`` (``DDP_PROFILE``).
        client: a ``distributed.Client`` (``runner.open_client``) or None for in-process: there, with
            ``threads`` = 1, as many views at once as torch has threads (memory permitting), each on
            one thread, so the numbers are those of one view alone on one thread.
        threads: torch threads per fit. retries: Dask retries of a fit that raised.
        source: what to record as the input (path, format, options) in the manifest.
        options: how each fit runs (:class:`RunOptions`: device, memory limit; no progress bar per view).
    Returns:
        {"computed": [names], "skipped": [names], "failed": {name: message}, "fused": path or None,
        "points": int, "manifest": path}.
    """
    config = FitConfig.for_profile(variant=VARIANT) if config is None else config
    options = run_options(options)
    given = [source["path"]] if isinstance(source, dict) and source.get("path") else []
    out = check_out_folder(out, list(getattr(scene, "sources", [])) + given)  # before any work
    jobs = plan_jobs(scene, config, views, threads, options)  # every input checked: nothing has run yet
    manifest = read_manifest(out)
    manifest.setdefault("views", {})
    manifest.update({"format": 1, "source": source or {"scene": scene.name}, "variant": VARIANT,
                     "config": json.loads(json.dumps(config.flat(), default=str))})
    todo, skipped = {}, []
    for job in jobs:
        if view_finished(out, manifest["views"].get(job.name), job):
            skipped.append(job.name)
            continue
        manifest["views"][job.name] = {
            "index": job.index, "key": job.key, "status": "running", "neighbors": job.neighbor_names,
            "inputs": {"size": list(job.depth.shape), "valid_fraction": round(float(np.isfinite(job.depth).mean()), 6),
                       "K": job.camera.K.tolist(), "cam_from_world": job.camera.cam_from_world.tolist()},
            "files": view_files(job), "started": time.strftime("%Y-%m-%dT%H:%M:%S")}
        todo[f"ddp-view-{job.stem}-{job.key}"] = job
    out.mkdir(parents=True, exist_ok=True)
    write_manifest(out, manifest)
    at_once = 1
    if client is None and int(threads) == 1 and todo:
        first = next(iter(todo.values()))
        at_once = side_by_side_workers(config, options, VARIANT, first.depth.shape, len(first.neighbors), len(todo))
    log(f"{len(jobs)} views: {len(skipped)} already done, {len(todo)} to fit"
        + (f" on {len(client.scheduler_info()['workers'])} Dask workers" if client is not None and todo else "")
        + (f", {at_once} at a time in this process" if at_once > 1 else ""))
    computed, failed = [], {}
    clock = CommandClock(max(len(todo), 1))  # the whole run's share and time left, on every view's line
    clock.begin(at_once)  # a view's line comes when it ends: the rate counts the first views from here
    with torch_threads(1) if at_once > 1 else contextlib.nullcontext():  # side by side: one thread each, set once
        for key, outcome in run_jobs(fit_view, {k: (job,) for k, job in todo.items()}, client=client,
                                     retries=retries, workers=at_once):
            job = todo[key]
            entry = manifest["views"][job.name]
            clock.advance()
            whole = f" ({clock.done}/{len(todo)} views; {clock.summary()})"
            if isinstance(outcome, BaseException):
                entry.update(status="failed", error=f"{type(outcome).__name__}: {outcome}")
                failed[job.name] = entry["error"]
                log(f"  view {job.name}: FAILED ({entry['error']}){whole}")
            else:
                overflow = write_view(out, job, outcome)
                entry.update(status="done", iterations=outcome["iterations"], seconds=round(outcome["seconds"], 3),
                             png_overflow_pixels=overflow, finished=time.strftime("%Y-%m-%dT%H:%M:%S"))
                entry.pop("error", None)
                computed.append(job.name)
                log(f"  view {job.name}: {outcome['iterations']} iterations, {outcome['seconds']:.1f} s{whole}"
                    + (f"; {overflow} pixel(s) beyond 65.535 m written as 0 in its 16-bit PNG (the .npy has them)"
                       if overflow else ""))
            write_manifest(out, manifest)
    fused, points = None, 0
    if fuse:
        fused, points, used = fuse_views(out, scene, manifest)
        manifest["fused"] = {"file": "fused.ply" if fused else None, "points": points, "views": used}
        write_manifest(out, manifest)
        if fused:
            log(f"fused {len(used)} views → {fused} ({points} points)")
        else:
            log(f"no fused.ply: {len(used)} view(s) finished ({', '.join(used) or 'none'}); fusing needs at least 2")
    return {"computed": computed, "skipped": skipped, "failed": failed, "fused": fused, "points": points,
            "manifest": out / MANIFEST}
