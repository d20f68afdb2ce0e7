"""Synthetic scenes and SGM holes: rendering time, SGM hole fractions and SGM depth error.

    OMP_NUM_THREADS=1 python benchmarks/bench_scenes.py

Prints figures only (no asserts). Rendering time is per image (left or right), 3×3 supersampling.
SGM error is measured outside the holes against the exact depth: median |d - d*| / d* and
mean |d - d*| in metres; "textured" excludes the sky and plain paint labels.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from ddp_lite.world.scenes import list_scenes, make_scene
from ddp_lite.classical.stereo import sgm_depth
from _common import parse_args


def main(argv=None) -> None:
    parse_args(argparse.ArgumentParser(description=__doc__.splitlines()[0]), argv)  # no options: --check-args, --help
    print("rendering (s per image, 3×3 supersampling, 2 views + their right views each)")
    for size in ((96, 128), (192, 256)):
        row = []
        for name in list_scenes():
            start = time.perf_counter()
            make_scene(name, size=size, n_views=2)
            row.append(f"{name} {(time.perf_counter() - start) / 4:.3f}")
        print(f"  {size[0]}×{size[1]}: " + ", ".join(row))
    for size in ((96, 128), (192, 256)):
        print(f"\nSGM at {size[0]}×{size[1]} (view 0, seed 0)")
        print(f"  {'scene':<7} {'params':<7} {'holes':>6} {'in flat':>8} {'in tex':>7} {'med rel':>8} "
              f"{'mean abs':>9} {'med rel tex':>12} {'mean abs tex':>13} {'ms':>5}")
        for name in list_scenes():
            scene = make_scene(name, size=size, n_views=1)
            gt, flat = scene[0].depth, scene.labels[0] <= 1
            for params in ("dense", "sparse"):
                start = time.perf_counter()
                depth, mask = sgm_depth(scene, 0, params)
                ms = 1000 * (time.perf_counter() - start)
                rel = np.abs(depth - gt) / gt
                print(f"  {name:<7} {params:<7} {1 - mask.mean():>6.1%} {1 - mask[flat].mean() if flat.any() else 0:>8.1%} "
                      f"{1 - mask[~flat].mean():>7.1%} {np.median(rel[mask]):>8.3f} "
                      f"{np.mean(np.abs(depth - gt)[mask]):>8.3f}m {np.median(rel[mask & ~flat]):>12.3f} "
                      f"{np.mean(np.abs(depth - gt)[mask & ~flat]):>12.3f}m {ms:>5.0f}")


if __name__ == "__main__":
    main()
