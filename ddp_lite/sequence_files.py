"""A sequence run's output folder: the manifest, each view's files, and the fused point cloud.

Layout: ``manifest.json`` (what is done, under which job key; rewritten atomically after every
change), ``depth/<view>.npy`` (float32 metres, NaN where nothing is known), ``depth/<view>.png``
(16-bit millimetres, 0 = none; beyond 65.535 m → 0, counted), ``preview/<view>.png`` (colour,
input, completed) and ``fused.ply`` (Open3D; Fusibile-style with C = 1 and D = 0.25 px per 64 px
of image width). Every file is written atomically; only the calling process writes.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure  # no pyplot: no global figure state in a long run

from .atomic import write_bytes_atomic
from .fileio import depth_png_bytes, npy_bytes
from .fusion import fuse_depths, save_ply
from .sequence_jobs import ViewJob
from .viz import save_figure, show_depth, show_image
from .views import Scene

MANIFEST = "manifest.json"


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
