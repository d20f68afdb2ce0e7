"""Notebook 12's plumbing: MVS depth with holes where its probability is low (paper Table 4), and
Kinect-style readings filled and scored by PSNR (paper Fig. 8).

- ``sweep_views``: ``plane_sweep`` of every view of a scene against its best neighbours.
- ``complete_views``: DDP (the profile's config, run as a notebook's) on each view's holes, "MVS+DDP" style:
  the input kept where valid; the views' fits side by side.
- ``fused_scores``: Fusibile-style fusion of a list of depth maps, scored P/R/F (%) against points.
- ``reprojection_psnr``: the paper's PSNR for NYU (Sec. 4.4): warp a neighbour image into the
  reference view through a depth map and compare with the reference image, 20·log10(1/√MSE).
- ``fill_table``: DDP and classical fills of one reading → depth PSNR in its holes (against the exact
  depth) and reprojection PSNR there.
- ``nyu_fill_table``: the same fills on a real NYU v2 Kinect frame (the labelled ``.mat``), with the
  dataset's own filled depth as one more row, scored on held-out blobs of its raw depth.
"""
from __future__ import annotations

import numpy as np

from ..classical.baselines import fill
from ..method.config import FitConfig
from ..method.complete import complete_depth
from ..method.profiles import get_profile
from ..method.runtime.options import RunOptions
from ..method.runtime.side_by_side import run_fits
from ..evaluation.fusion import fuse_depths, points_from_depth
from ..evaluation.metrics import cloud_scores, psnr
from ..world.neighbors import select_neighbors
from ..evaluation.plane_sweep import plane_sweep
from ..core.views import Scene
from ..method.paper.warp import warp_to_reference

__all__ = ["sweep_views", "scene_neighbors", "complete_views", "fused_scores",
           "reprojection_psnr", "fill_table", "nyu_fill_table"]


def sweep_views(views, neighbors_of, d_min: float, d_max: float, **options) -> list:
    """``plane_sweep`` of each of ``views`` against ``neighbors_of(i)`` (a list of views) → list of SweepResult."""
    return [plane_sweep(view, neighbors_of(i), d_min, d_max, **options) for i, view in enumerate(views)]


def scene_neighbors(scene: Scene, n: int):
    """``i → [scene views]``: the ``n`` best neighbours of view i by MVSNet's score (``select_neighbors``)."""
    return lambda i: [scene[j] for j in select_neighbors(scene, i, n)]


def complete_views(views, depths, neighbors_of, profile=None, variant: str = "rgbd+warp", log=print,
                   options: RunOptions = RunOptions(progress=False)) -> list:
    """DDP (``FitConfig.for_profile``, run as a notebook's: ``Profile.notebook_settings``) on each of ``depths``
    (H, W metres, NaN holes) of ``views``, with ``neighbors_of(i)`` as warp partners → list of (H, W) depths, the
    input kept where it was valid. The views' fits are independent: they run side by side
    (:mod:`ddp_lite.method.runtime.side_by_side`), as ``options`` say (no progress bars by default)."""
    config = FitConfig.for_profile(profile, variant=variant, **get_profile(profile).notebook_settings())

    def fit(i: int):
        return complete_depth(views[i].rgb, depths[i], views[i].camera, neighbors_of(i), variant=variant, config=config,
                              options=options)
    jobs = [(config, variant, np.shape(depth), len(neighbors_of(i))) for i, depth in enumerate(depths)]
    out = []
    for i, (depth, result) in enumerate(zip(depths, run_fits(fit, jobs, options))):
        out.append(result.merged(depth))
        log(f"view {i}: {np.isnan(depth).mean():.0%} holes, {result.iterations} iterations, {result.seconds:.0f} s")
    return out


def fused_scores(depths, cameras, gt_points, tau: float, min_views: int = 1, disp_threshold: float = 0.25) -> dict:
    """``fuse_depths`` of (H, W) metre maps seen by ``cameras`` → {"P", "R", "F" (%), "points"} against
    ``gt_points`` (N, 3) at distance ``tau`` metres (a single map: its own cloud, no vote)."""
    if len(depths) == 1:
        points = points_from_depth(depths[0], cameras[0])
    else:
        points = np.asarray(fuse_depths(list(depths), list(cameras), min_views=min_views,
                                        disp_threshold=disp_threshold).points)
    return {**cloud_scores(points, gt_points, tau), "points": len(points)}


def reprojection_psnr(depth, ref, neighbor, mask=None) -> float:
    """PSNR (dB, peak 1) between ``ref``'s image and ``neighbor``'s image warped into ``ref`` through
    ``depth`` (H, W metres), over ``mask`` (H, W bool, default all) where the warp lands in the neighbour.
    ``ref``, ``neighbor``: Views (``rgb``, ``camera``). The paper's measure for NYU, where no ground
    truth depth exists: a better depth reprojects the neighbour closer to the reference."""
    warped, seen = warp_to_reference(neighbor.rgb, depth, ref.camera, neighbor.camera)
    counted = seen if mask is None else seen & np.asarray(mask, bool)
    return psnr(warped, ref.rgb, data_range=1.0, mask=counted)


def fill_table(view, reading, gt, neighbor, ddp_depth, methods=("colorization", "cross-bilateral"),
               extra=None, data_range: float | None = None) -> dict:
    """{method: {"depth PSNR", "reproj. PSNR"}} in the holes of ``reading`` (H, W metres, NaN holes) of
    ``view``: DDP's ``ddp_depth`` and each classical fill of ``methods`` (``extra``: more {name: depth}).
    Depth PSNR against ``gt`` with peak ``data_range`` (default the range of ``gt``), where ``gt`` is
    known; reprojection PSNR of ``neighbor`` through the same pixels, all methods on one pixel set."""
    holes = ~np.isfinite(reading)
    known = holes & np.isfinite(gt)
    peak = float(np.nanmax(gt) - np.nanmin(gt)) if data_range is None else float(data_range)
    depths = {"DDP": ddp_depth, **{m: fill(reading, view.rgb, method=m) for m in methods}, **(extra or {})}
    seen_by_all = np.logical_and.reduce([warp_to_reference(neighbor.rgb, d, view.camera, neighbor.camera)[1]
                                         for d in depths.values()])
    return {name: {"depth PSNR": psnr(d, gt, data_range=peak, mask=known),
                   "reproj. PSNR": reprojection_psnr(d, view, neighbor, holes & seen_by_all)}
            for name, d in depths.items()}


def nyu_fill_table(path, profile=None, index: int = 0, fraction: float = 0.15, seed: int = 0, config=None,
                   methods=("colorization", "cross-bilateral"), options: RunOptions = RunOptions(progress=False)) -> dict:
    """{method: {"depth PSNR"}} (dB) on NYU v2's labelled ``.mat`` frame ``index``, at the profile's size.

    NYU has no second view in the labelled set and no truth in the Kinect's holes, so ``fraction`` of
    the valid raw depth is held out in blobs (``random_holes``, ``seed``) and every fill is scored there,
    against the raw reading, with the peak the raw depth's range: DDP (rgbd, ``config`` or the
    profile's), each classical fill of ``methods``, and the dataset's own fill (which saw those pixels:
    a bound, not a competitor). The fit runs as ``options`` say (no progress bar by default).
    """
    from ..data.datasets import load_nyu
    from ..classical.holes import random_holes
    from ..data.resample import resize_scene

    profile = get_profile(profile) if profile is None or isinstance(profile, str) else profile
    raw = resize_scene(load_nyu(path, index=index, raw=True), profile.size)[0]
    toolbox = resize_scene(load_nyu(path, index=index, raw=False), profile.size)[0].depth
    held_in, _ = random_holes(raw.depth, fraction=fraction, seed=seed)
    held_out = np.isfinite(raw.depth) & ~np.isfinite(held_in)
    config = FitConfig.for_profile(profile, variant="rgbd") if config is None else config
    result = complete_depth(raw.rgb, held_in, raw.camera, (), variant="rgbd", config=config, options=options)
    fills = {"DDP (rgbd)": result.merged(held_in), "dataset's fill": toolbox,
             **{m: fill(held_in, raw.rgb, method=m) for m in methods}}
    peak = float(np.nanmax(raw.depth) - np.nanmin(raw.depth))
    return {name: {"depth PSNR": psnr(d, raw.depth, data_range=peak, mask=held_out)} for name, d in fills.items()}
