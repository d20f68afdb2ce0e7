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

from ..core.files import path_inside, regular_file, write_bytes_atomic, writing_inside
from ..data.file_writers import depth_png_bytes, npy_bytes
from ..data.fileio import load_npy
from ..evaluation.fusion import fuse_depths, save_ply
from .sequence_jobs import ViewJob
from ..evaluation.viz import save_figure, shared_colorbar, show_depth, show_image
from ..core.views import Scene

MANIFEST = "manifest.json"


def read_manifest(out) -> dict:
    """The manifest of an output folder ({} if there is none yet); one that is not a ddp-lite
    manifest (not JSON, not an object, ``views`` not a mapping of view entries) → ``ValueError``
    naming it, before anything is fitted or written."""
    path = Path(out) / MANIFEST
    if not path.exists():
        return {}
    try:
        manifest = json.loads(regular_file(path, "out").read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise ValueError(f"{path} is not a ddp-lite manifest ({error}); move it away to start afresh") from None
    views = manifest.get("views", {}) if isinstance(manifest, dict) else None
    if not isinstance(views, dict) or not all(isinstance(entry, dict) for entry in views.values()):
        raise ValueError(f"{path} is not a ddp-lite manifest (expected a JSON object whose 'views' maps view names "
                         f"to entries); move it away to start afresh")
    return manifest


def check_out_folder(out, inputs) -> Path:
    """``out`` as a ``Path`` if it can hold a run's files without touching an input; else ``ValueError``.

    ``inputs``: the files and folders the scene was read from (``Scene.sources``, the caller's own
    path). Refused, before anything is fitted: ``out`` a file; ``out`` *is* an input (a TUM
    folder's depth PNGs would be overwritten); ``out`` *contains* an input (its files would be
    written beside the inputs, and ``depth/`` is where captures keep theirs); ``out`` *inside* an
    input folder (a re-run's reader would find the outputs first: COLMAP's ``depth/<name>.png.png``
    shadows ``depth/<stem>.png``). Paths are compared after resolving symlinks."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"out: {out} is a file; give a folder for the run's files")
    target = out.resolve()
    for source in inputs:
        source = Path(source).resolve()
        if target == source:
            problem = "is the input itself: its files would be overwritten, and a re-run would read the outputs"
        elif target in source.parents:
            problem = f"contains the input {source}: outputs would be written among the inputs"
        elif source in target.parents:
            problem = f"lies inside the input {source}: a re-run would read the outputs as input"
        else:
            continue
        raise ValueError(f"out: {out} {problem}. Choose a folder outside the capture, e.g. "
                         f"{source.parent / (source.name + '-ddp')}")
    for name in ("depth", "preview", MANIFEST, "fused.ply"):  # before any fit: nothing written through a link
        path_inside(out, name, "out")
    return out


def write_manifest(out: Path, manifest: dict) -> None:
    """Write the run's manifest (JSON) into ``out`` atomically."""
    with writing_inside(out):
        write_bytes_atomic(out / MANIFEST, (json.dumps(manifest, indent=1, sort_keys=False) + "\n").encode("utf-8"))


def view_files(job: ViewJob) -> dict:
    """{kind: path relative to the output folder} of one view's result files (npy, png, preview)."""
    return {"npy": f"depth/{job.stem}.npy", "png": f"depth/{job.stem}.png", "preview": f"preview/{job.stem}.png"}


def view_finished(out: Path, entry: dict | None, job: ViewJob) -> bool:
    """Done under the same key, every file there, and the depth ``.npy`` readable with the view's shape
    (a corrupt one is redone, not read by the fusion)."""
    if not (entry is not None and entry.get("status") == "done" and entry.get("key") == job.key
            and all((out / f).is_file() for f in view_files(job).values())):
        return False
    try:
        return _load_depth(out / view_files(job)["npy"]).shape == job.depth.shape
    except ValueError:
        return False


def _load_depth(path: Path) -> np.ndarray:
    """A finished view's ``depth/<view>.npy`` → (H, W) float32; anything else → ``ValueError`` naming it."""
    depth = load_npy(path, "out")
    if depth.ndim != 2 or depth.dtype != np.float32:
        raise ValueError(f"out: {path} must hold an (H, W) float32 depth map, got {depth.dtype} {depth.shape}; "
                         f"delete it and re-run to redo the view")
    return depth


def write_view(out: Path, job: ViewJob, result: dict) -> int:
    """Write a finished view's files atomically; → the number of pixels a 16-bit mm PNG cannot hold."""
    files = view_files(job)
    with writing_inside(out):  # never through a link inside the output folder
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
    show_depth(axes[1], job.depth, f"input ({np.isnan(job.depth).mean():.0%} holes)", vmin, vmax, colorbar=False)
    image = show_depth(axes[2], completed, "SGM+DDP\n(input kept, DDP in holes)", vmin, vmax, colorbar=False)
    shared_colorbar(image, axes[1:], label="depth (m)")  # both depths on one scale
    fig.tight_layout()
    save_figure(fig, path, dpi=80)


def fuse_views(out: Path, scene: Scene, manifest: dict):
    """Fuse every finished view's depth into ``fused.ply``; → (path or None, point count, views used)."""
    by_name = {v.name: v for v in scene.views}
    # views of this scene only: a manifest may also list views of an earlier run that this scene lacks
    done = [(name, entry) for name, entry in manifest["views"].items()
            if entry.get("status") == "done" and name in by_name and isinstance(entry.get("files"), dict)]
    if len(done) < 2:
        return None, 0, [name for name, _ in done]
    views = [by_name[name] for name, _ in done]
    depths = [_load_depth(out / entry["files"]["npy"]) for _, entry in done]
    width = views[0].camera.width
    cloud = fuse_depths(depths, [v.camera for v in views], [v.rgb for v in views], min_views=1,
                        disp_threshold=0.25 * width / 64)
    if not cloud.has_points():  # nothing agreed across views: no file, said by the count
        return None, 0, [name for name, _ in done]
    with writing_inside(out):
        save_ply(cloud, out / "fused.ply")
    return out / "fused.ply", len(cloud.points), [name for name, _ in done]
