"""Fusion and classical baselines: how long they take at the kit's sizes, and how well they do.

    OMP_NUM_THREADS=1 python benchmarks/bench_fusion.py

Prints figures only (no asserts). Times are the best of 3 runs after one warm-up call (Open3D's
first TSDF integration carries a one-off start-up cost of ~1.5 s, printed separately).
Fusion: the 'desk' scene, 8 views at 96×128, exact depth. Baselines: view 0 of 'desk' at
96×128 with 15 % random holes; hole RMSE in metres against the exact depth.
"""
from __future__ import annotations

import argparse
import time


from ddp_lite.classical.baselines import BASELINES
from ddp_lite.evaluation.fusion import fuse_depths, tsdf_fuse
from ddp_lite.classical.holes import random_holes
from ddp_lite.evaluation.metrics import hole_rmse
from ddp_lite.world.scenes import make_scene
from _common import parse_args


def _best_of(fn, repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main(argv=None) -> None:
    parse_args(argparse.ArgumentParser(description=__doc__.splitlines()[0]), argv)  # no options: --check-args, --help
    scene = make_scene("desk", size=(96, 128), n_views=8, seed=0)
    depths, cameras, images = [v.depth for v in scene], [v.camera for v in scene], [v.rgb for v in scene]

    print("fusion, desk, 8 views at 96×128 (exact depth)")
    start = time.perf_counter()
    tsdf_fuse(depths[:1], cameras[:1], images[:1], voxel_length=0.01)
    print(f"  open3d TSDF first call (start-up)      {time.perf_counter() - start:7.3f} s")
    fuse_depths(depths, cameras, images)  # warm-up
    for min_views, disp in ((1, 0.25), (2, 0.25), (2, 1.0), (4, 0.25)):
        seconds = _best_of(lambda: fuse_depths(depths, cameras, images, min_views=min_views, disp_threshold=disp))
        points = len(fuse_depths(depths, cameras, images, min_views=min_views, disp_threshold=disp).points)
        print(f"  fuse_depths C={min_views} D={disp:<4}              {seconds:7.3f} s  {points:6d} points")
    for voxel in (0.01, 0.005):
        seconds = _best_of(lambda: tsdf_fuse(depths, cameras, images, voxel_length=voxel))
        points = len(tsdf_fuse(depths, cameras, images, voxel_length=voxel).points)
        print(f"  tsdf_fuse voxel {voxel * 100:.1f} cm                {seconds:7.3f} s  {points:6d} points")

    gt, rgb = depths[0], images[0]
    depth, mask = random_holes(gt, fraction=0.15, seed=0)
    print(f"\nbaselines, desk view 0 at 96×128, {1 - mask.mean():.0%} random holes")
    print(f"  {'method':<14} {'seconds':>8} {'hole RMSE (m)':>14}")
    for name, fn in BASELINES.items():
        out = fn(depth, rgb)
        seconds = _best_of(lambda: fn(depth, rgb))
        print(f"  {name:<14} {seconds:8.4f} {hole_rmse(out, gt, ~mask):14.4f}")


if __name__ == "__main__":
    main()
