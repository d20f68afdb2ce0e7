"""A whole sequence, view by view: DDP (RGBD + warp) on every view, then one fused point cloud.

The paper's own experiments are sequences (Tanks and Temples, 87–180+ views): every view's depth
is completed with the warp loss over N = 2 neighbours chosen by MVSNet's score (``neighbors.
select_neighbors``), SGM's depth is kept where valid and DDP's taken in the holes ("SGM+DDP"),
and the views are fused into one point cloud (Fusibile; here ``fusion.fuse_depths``).

:func:`run_sequence` does that for any ``Scene`` (read your data with ``ddp_lite.formats``):

1. **plan**: per view, its neighbours and a *job key*, a hash of everything the result depends
   on (its pixels and camera, its neighbours', the fit config, the disparity range). All inputs
   are checked here, before any fit starts;
2. **skip** the views the manifest records as done under the same key whose files are all there;
   everything else (never started, started but not finished, inputs or config changed) is redone;
3. **fit** the rest through :func:`runner.run_jobs`: in-process, or on Dask workers;
4. **write**, per finished view, ``depth/<view>.npy`` (float32 metres, NaN where nothing is
   known), ``depth/<view>.png`` (16-bit millimetres, 0 = none; beyond 65.535 m → 0, counted in
   the manifest) and ``preview/<view>.png`` (colour, input, completed), each atomically, and only
   then mark the view done in ``manifest.json`` (rewritten atomically after every change). A run
   killed at any moment leaves whole files and a manifest that says what is finished;
5. **fuse** every finished view into ``fused.ply`` (Open3D), Fusibile-style with C = 1 and
   D = 0.25 px per 64 px of image width (as notebook 07).

Only this process writes files: a worker returns arrays, so a remote cluster needs no shared disk.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .atomic import write_bytes_atomic
from .camera import Camera
from .fileio import depth_png_bytes, npy_bytes
from .disparity import DisparityTransform
from .fit import FitConfig, _check_fit_inputs, complete_depth, estimate_peak_memory_gb
from .runner import run_jobs
from .neighbors import select_neighbors
from .views import Scene

__all__ = ["ViewJob", "plan_jobs", "fit_view", "run_sequence", "read_manifest", "measure_fit_cost",
           "estimate_sequence", "format_estimate", "MANIFEST", "VARIANT"]

MANIFEST = "manifest.json"
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


def _stem(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]", "_", name) or "view"


def _job_key(view, neighbors, config: FitConfig, transform: DisparityTransform) -> str:
    """sha256 over what the result depends on: pixels, cameras, neighbours, config, disparity range."""
    digest = hashlib.sha256()
    for rgb, depth, camera in [(view.rgb, view.depth, view.camera)] + [(n.rgb, None, n.camera) for n in neighbors]:
        for array in (rgb, depth, camera.K, camera.cam_from_world):
            if array is not None:
                digest.update(np.ascontiguousarray(array).tobytes())
    settings = dataclasses.asdict(config.replace(progress=False, device=None, max_memory_gb=None))
    digest.update(json.dumps([settings, dataclasses.asdict(transform), VARIANT], sort_keys=True, default=str).encode())
    return digest.hexdigest()[:16]


def plan_jobs(scene: Scene, config: FitConfig, views=None, threads: int = 1) -> list[ViewJob]:
    """One :class:`ViewJob` per view of ``scene`` (or per index in ``views``), inputs checked.

    Neighbours: the N = 2 best by MVSNet's score (``select_neighbors``) among *all* views; the
    disparity range: one for the whole scene (its ``meta`` d_min/d_max, else from every view's
    valid depth with ``config.disparity_margin``), so the views' fills are on one scale.

    Example:
        >>> from ddp_lite.scenes import make_scene
        >>> jobs = plan_jobs(make_scene("desk", size=(24, 32), n_views=3), FitConfig(iterations=1))
        >>> [(j.name, j.neighbor_names) for j in jobs][0]
        ('desk0', ['desk2', 'desk1'])
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a ddp_lite.Scene, got {type(scene).__name__}")
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
                                                  margin=config.disparity_margin)
    n = min(N_NEIGHBORS, len(scene) - 1)
    jobs = []
    for i in chosen:
        view = scene[i]
        neighbors = [scene[j] for j in select_neighbors(scene, i, n)]
        pairs = [(v.rgb, v.camera) for v in neighbors]
        try:  # every check complete_depth makes, here, before the first fit
            _check_fit_inputs(view.rgb, view.depth, view.camera, pairs, VARIANT, config, None, transform)
        except ValueError as error:
            raise ValueError(f"view {i} ({view.name!r}): {error}") from None
        jobs.append(ViewJob(view.name, stems[i], i, view.rgb, view.depth, view.camera, pairs,
                            [v.name for v in neighbors], config, transform, int(threads),
                            _job_key(view, neighbors, config, transform)))
    return jobs


def fit_view(job: ViewJob) -> dict:
    """Run one view's DDP fit (on whatever process calls it) → {"depth", "ddp", "iterations", "seconds"}.

    ``depth`` (H, W) float32 metres is SGM+DDP: the input where valid, DDP in the holes; ``ddp`` is
    DDP's own output everywhere. ``job.threads`` torch threads (1 by default, so a run gives the
    same numbers in-process and on any worker)."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(int(job.threads))
    try:
        result = complete_depth(job.rgb, job.depth, job.camera, job.neighbors, variant=VARIANT,
                                config=job.config.replace(progress=False), transform=job.transform)
    finally:
        torch.set_num_threads(threads)
    return {"depth": result.merged(job.depth).astype(np.float32), "ddp": result.depth.astype(np.float32),
            "iterations": int(result.iterations), "seconds": float(result.seconds)}


# ------------------------------------------------------------------------------------------------
# files
# ------------------------------------------------------------------------------------------------

def read_manifest(out) -> dict:
    """The manifest of an output folder ({} if there is none yet)."""
    path = Path(out) / MANIFEST
    if not path.exists():
        return {}
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise ValueError(f"{path} is not a ddp-lite manifest ({error}); move it away to start afresh") from None


def _write_manifest(out: Path, manifest: dict) -> None:
    write_bytes_atomic(out / MANIFEST, (json.dumps(manifest, indent=1, sort_keys=False) + "\n").encode("utf-8"))


def _files(job: ViewJob) -> dict:
    return {"npy": f"depth/{job.stem}.npy", "png": f"depth/{job.stem}.png", "preview": f"preview/{job.stem}.png"}


def _finished(out: Path, entry: dict | None, job: ViewJob) -> bool:
    return (entry is not None and entry.get("status") == "done" and entry.get("key") == job.key
            and all((out / f).is_file() for f in _files(job).values()))


def _write_view(out: Path, job: ViewJob, result: dict) -> int:
    """Write a finished view's files atomically; → the number of pixels a 16-bit mm PNG cannot hold."""
    files = _files(job)
    write_bytes_atomic(out / files["npy"], npy_bytes(result["depth"]))
    png, overflow = depth_png_bytes(result["depth"])  # millimetres
    write_bytes_atomic(out / files["png"], png)
    _write_preview(out / files["preview"], job, result["depth"])
    return overflow


def _write_preview(path: Path, job: ViewJob, completed: np.ndarray) -> None:
    from matplotlib.figure import Figure  # no pyplot: no global figure state in a long run

    from .viz import save_figure, show_depth, show_image

    finite = np.concatenate([job.depth[np.isfinite(job.depth)], completed[np.isfinite(completed)]])
    vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (None, None)
    fig = Figure(figsize=(11, 3.2))
    axes = fig.subplots(1, 3)
    show_image(axes[0], job.rgb, f"view {job.name}")
    show_depth(axes[1], job.depth, f"input ({np.isnan(job.depth).mean():.0%} holes)", vmin, vmax)
    show_depth(axes[2], completed, "SGM+DDP (input kept, DDP in the holes)", vmin, vmax)
    fig.tight_layout()
    save_figure(fig, path, dpi=80)


def _fuse(out: Path, scene: Scene, manifest: dict):
    """Fuse every finished view's depth into ``fused.ply``; → (path or None, point count, views used)."""
    from .fusion import fuse_depths, save_ply

    done = [(name, entry) for name, entry in manifest["views"].items() if entry.get("status") == "done"]
    if len(done) < 2:
        return None, 0, [name for name, _ in done]
    by_name = {v.name: v for v in scene.views}
    views = [by_name[name] for name, _ in done]
    depths = [np.load(out / entry["files"]["npy"]) for _, entry in done]
    width = views[0].camera.width
    cloud = fuse_depths(depths, [v.camera for v in views], [v.rgb for v in views], min_views=1,
                        disp_threshold=0.25 * width / 64)
    save_ply(cloud, out / "fused.ply")
    return out / "fused.ply", len(cloud.points), [name for name, _ in done]


# ------------------------------------------------------------------------------------------------
# the run
# ------------------------------------------------------------------------------------------------

def run_sequence(scene: Scene, out, config: FitConfig | None = None, views=None, client=None, threads: int = 1,
                 retries: int = 2, source: dict | None = None, fuse: bool = True, log=print) -> dict:
    """Complete every view of ``scene`` (or ``views``, indices) with DDP rgbd+warp; write files; fuse.

    Args:
        scene: the sequence (``ddp_lite.formats.load_sequence`` reads TUM, COLMAP, saved scenes).
        out: output folder (see the module docstring for its files); a re-run skips finished views.
        config: the fit's config; None → ``FitConfig.for_profile()`` (``DDP_PROFILE``).
        client: a ``distributed.Client`` (``runner.open_client``) or None for in-process.
        threads: torch threads per fit. retries: Dask retries of a fit that raised.
        source: what to record as the input (path, format, options) in the manifest.
    Returns:
        {"computed": [names], "skipped": [names], "failed": {name: message}, "fused": path or None,
        "points": int, "manifest": path}.
    """
    config = FitConfig.for_profile(variant=VARIANT) if config is None else config
    out = Path(out)
    jobs = plan_jobs(scene, config, views, threads)  # every input checked: nothing has run yet
    manifest = read_manifest(out)
    manifest.setdefault("views", {})
    manifest.update({"format": 1, "source": source or {"scene": scene.name}, "variant": VARIANT,
                     "config": json.loads(json.dumps(dataclasses.asdict(config), default=str))})
    todo, skipped = {}, []
    for job in jobs:
        if _finished(out, manifest["views"].get(job.name), job):
            skipped.append(job.name)
            continue
        manifest["views"][job.name] = {
            "index": job.index, "key": job.key, "status": "running", "neighbors": job.neighbor_names,
            "inputs": {"size": list(job.depth.shape), "valid_fraction": round(float(np.isfinite(job.depth).mean()), 6),
                       "K": job.camera.K.tolist(), "cam_from_world": job.camera.cam_from_world.tolist()},
            "files": _files(job), "started": time.strftime("%Y-%m-%dT%H:%M:%S")}
        todo[f"ddp-view-{job.stem}-{job.key}"] = job
    out.mkdir(parents=True, exist_ok=True)
    _write_manifest(out, manifest)
    log(f"{len(jobs)} views: {len(skipped)} already done, {len(todo)} to fit"
        + (f" on {len(client.scheduler_info()['workers'])} Dask workers" if client is not None and todo else ""))
    computed, failed = [], {}
    for key, outcome in run_jobs(fit_view, {k: (job,) for k, job in todo.items()}, client=client, retries=retries):
        job = todo[key]
        entry = manifest["views"][job.name]
        if isinstance(outcome, BaseException):
            entry.update(status="failed", error=f"{type(outcome).__name__}: {outcome}")
            failed[job.name] = entry["error"]
            log(f"  view {job.name}: FAILED ({entry['error']})")
        else:
            overflow = _write_view(out, job, outcome)
            entry.update(status="done", iterations=outcome["iterations"], seconds=round(outcome["seconds"], 3),
                         png_overflow_pixels=overflow, finished=time.strftime("%Y-%m-%dT%H:%M:%S"))
            entry.pop("error", None)
            computed.append(job.name)
            log(f"  view {job.name}: {outcome['iterations']} iterations, {outcome['seconds']:.1f} s")
        _write_manifest(out, manifest)
    fused, points = None, 0
    if fuse:
        fused, points, used = _fuse(out, scene, manifest)
        manifest["fused"] = {"file": "fused.ply" if fused else None, "points": points, "views": used}
        _write_manifest(out, manifest)
        if fused:
            log(f"fused {len(used)} views → {fused} ({points} points)")
    return {"computed": computed, "skipped": skipped, "failed": failed, "fused": fused, "points": points,
            "manifest": out / MANIFEST}


# ------------------------------------------------------------------------------------------------
# paper scale on paper: the dry run
# ------------------------------------------------------------------------------------------------

def measure_fit_cost(profile="paper", size=(96, 128), iterations=(2, 8), threads: int = 1) -> dict:
    """Measure one rgbd+warp iteration of ``profile``'s net on this machine, per pixel.

    A 3-view synthetic scene at ``size`` is fitted once (warm-up), then for ``iterations[0]`` and
    ``iterations[1]`` iterations; the difference of the two times divided by the extra iterations and the pixels is
    the CPU cost of a pixel-iteration (start-up excluded). The convolution FLOPs of one iteration
    (forward + backward, counted by ``torch.utils.flop_counter``; element-wise work, SSIM and the
    warp's sampling are not counted) per pixel give a hardware-free cost. The UNet is fully
    convolutional, so both scale with the pixel count (the CPU cost per pixel still falls a little
    with size, as per-iteration overheads spread: 96×128 is a conservative base). Returns
    {"cpu_seconds_per_pixel_iteration", "flops_per_pixel_iteration", "size", "threads"}.
    """
    import torch
    from torch.utils.flop_counter import FlopCounterMode

    from .scenes import make_scene

    scene = make_scene("desk", size=size, n_views=3, seed=0)
    base = FitConfig.for_profile(profile, variant=VARIANT, progress=False, auto_stop=False, bf16=False,
                                 max_memory_gb=None)
    neighbors = [scene[1].as_neighbor(), scene[2].as_neighbor()]
    previous = torch.get_num_threads()
    torch.set_num_threads(int(threads))
    try:
        complete_depth(scene[0].rgb, scene[0].depth, scene[0].camera, neighbors, VARIANT,
                       base.replace(iterations=1, lr_milestones=()))  # warm-up: first-call costs out of the timing
        times = []
        for n in iterations:
            start = time.perf_counter()
            complete_depth(scene[0].rgb, scene[0].depth, scene[0].camera, neighbors, VARIANT,
                           base.replace(iterations=int(n), lr_milestones=()))
            times.append(time.perf_counter() - start)
        with FlopCounterMode(display=False) as counter:
            complete_depth(scene[0].rgb, scene[0].depth, scene[0].camera, neighbors, VARIANT,
                           base.replace(iterations=1, lr_milestones=()))
    finally:
        torch.set_num_threads(previous)
    pixels = size[0] * size[1]
    return {"cpu_seconds_per_pixel_iteration": (times[1] - times[0]) / (iterations[1] - iterations[0]) / pixels,
            "flops_per_pixel_iteration": counter.get_total_flops() / pixels, "size": tuple(size),
            "threads": int(threads)}


def estimate_sequence(n_views: int, size, profile="paper", cost: dict | None = None, gpu_tflops: float = 5.0) -> dict:
    """Jobs, compute and memory of completing ``n_views`` views of ``size`` (H, W) at ``profile``.

    ``cost``: :func:`measure_fit_cost`'s result (measured now if None). GPU-hours = total convolution
    FLOPs / ``gpu_tflops`` (an *assumed* sustained rate, not a measurement: ~5 TFLOP/s is a third of
    a V100's fp32 peak; replace it with your GPU's by timing one view). CPU-hours use the measured
    single-thread CPU cost. Memory per job: ``fit.estimate_peak_memory_gb`` (CPU-calibrated)."""
    config = FitConfig.for_profile(profile, variant=VARIANT)
    cost = measure_fit_cost(profile) if cost is None else cost
    H, W = size
    iterations = config.resolved_iterations(VARIANT)
    pixel_iterations = float(n_views) * iterations * H * W
    return {"jobs": int(n_views), "size": (H, W), "iterations": iterations, "profile": getattr(profile, "name", profile),
            "gpu_hours": pixel_iterations * cost["flops_per_pixel_iteration"] / (gpu_tflops * 1e12) / 3600.0,
            "gpu_tflops_assumed": gpu_tflops,
            "cpu_hours_one_thread": pixel_iterations * cost["cpu_seconds_per_pixel_iteration"] / 3600.0,
            "memory_gb_per_job": estimate_peak_memory_gb(config, 4, H, W, N_NEIGHBORS), "cost": cost}


def _round(hours: float) -> str:
    return f"{hours:.2g}" if hours < 10 else f"{hours:.0f}"


def format_estimate(estimate: dict, command: str | None = None) -> str:
    """The dry run's printout of :func:`estimate_sequence`."""
    e, c = estimate, estimate["cost"]
    H, W = e["size"]
    lines = [
        f"{e['jobs']} jobs (one DDP rgbd+warp fit per view), {W}×{H} px, {e['iterations']} iterations each "
        f"(profile '{e['profile']}')",
        f"  compute: {c['flops_per_pixel_iteration'] / 1e6:.2f} MFLOP per pixel-iteration (convolutions, forward + "
        f"backward, counted at {c['size'][1]}×{c['size'][0]})",
        f"  GPU:     ≈ {_round(e['gpu_hours'])} GPU-hours at an assumed {e['gpu_tflops_assumed']:g} TFLOP/s sustained "
        f"(≈ {60 * e['gpu_hours'] / max(e['jobs'], 1):.1f} min per view)",
        f"  CPU:     ≈ {_round(e['cpu_hours_one_thread'])} CPU-hours on this machine, one thread per fit "
        f"({c['cpu_seconds_per_pixel_iteration'] * 1e6:.2f} µs per pixel-iteration, measured now)",
        f"  memory:  ≈ {e['memory_gb_per_job']:.1f} GB peak per job (fit.estimate_peak_memory_gb, CPU-calibrated)",
    ]
    if command:
        lines += ["run it on a Dask cluster (one GPU per worker; README 'Your own data' shows dask-jobqueue on Slurm):",
                  f"  {command}"]
    return "\n".join(lines)
