"""What `ddp-lite complete` gives on a real full-size photograph: DDP fitted at the working size, its
fill brought back to full size in the holes, against classical fills computed at full size.

    python benchmarks/bench_complete.py                     # class, three blob patterns, seed 0
    python benchmarks/bench_complete.py --profile ci --patterns 1 --threads 2

The case is scikit-image's Middlebury Motorcycle pair (500×741; truth from the calibration, NaN where
Middlebury does not know) with Depthcomp-style blob holes (10 % of the pixels, blobs a tenth of the
shorter side) added to its unknown pixels, as in the README's `complete` example. The fit runs
exactly as `complete` runs it (``working_size.shrink``, ``complete_depth``,
``working_size.fill_holes_at_full_size``); every fill is scored in the holes where the truth is
known, as the RMSE of disparity in full-size pixels (f·B / Z). One JSON line per pattern with
``--out``. Prints the CPU beside the fit time.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from _common import add_profile_args, profile_from_args, parse_args, seed_int, check_rows_out  # noqa: E402
from bench_fit import cpu_summary  # noqa: E402

from ddp_lite.classical import baselines  # noqa: E402
from ddp_lite.classical.holes import random_holes  # noqa: E402
from ddp_lite.data.middlebury import load_motorcycle  # noqa: E402
from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.sequences.working_size import fill_holes_at_full_size, shrink, working_shape  # noqa: E402

FILLS = ("linear", "navier-stokes", "colorization", "bilateral-solver")


def run_pattern(pattern: int, profile, seed: int) -> dict:
    """One blob pattern: DDP at the working size and each of ``FILLS`` at full size → a row of px RMSEs."""
    scene = load_motorcycle()
    view, truth = scene[0], scene[0].depth  # (500, 741) metres, NaN = unknown
    fb = float(view.camera.focal * scene.meta["baseline"])  # px · m: disparity = fb / Z
    H, W = truth.shape
    depth, _ = random_holes(truth, fraction=0.1, seed=pattern, blob_size=min(H, W) / 10)
    holes = ~np.isfinite(depth)
    scored = holes & np.isfinite(truth)

    def rmse_px(filled) -> float:
        return float(np.sqrt(np.mean((fb / filled[scored] - fb / truth[scored]) ** 2)))

    shape = working_shape(depth.shape, max(profile.size))
    small_rgb, small_depth = shrink(view.rgb, depth, shape)
    config = FitConfig.for_profile(profile, variant="rgbd", seed=seed)
    start = time.perf_counter()
    result = complete_depth(small_rgb, small_depth, variant="rgbd", config=config, options=RunOptions(progress=False))
    row = dict(pattern=pattern, profile=profile.name, seed=seed, working=list(shape), holes=float(holes.mean()),
               fit_seconds=time.perf_counter() - start, DDP=rmse_px(fill_holes_at_full_size(depth, result.depth)))
    for name in FILLS:  # the fills take any positive map: they fill disparity here, as bench_quality does
        row[name] = rmse_px(fb / baselines.BASELINES[name](fb / depth, view.rgb))
    return row


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_profile_args(parser)
    parser.add_argument("--patterns", type=seed_int, nargs="+", default=[1, 2, 3], help="blob patterns (hole seeds)")
    parser.add_argument("--seed", type=seed_int, default=0, help="the fit's seed")
    parser.add_argument("--out", help="append one JSON line per pattern here")
    args = parse_args(parser, argv, lambda a: check_rows_out(a.out) if a.out else None)
    profile = profile_from_args(args)
    print(cpu_summary())
    rows = []
    for pattern in args.patterns:
        rows.append(run_pattern(pattern, profile, args.seed))
        if args.out:
            with open(args.out, "a") as out:
                out.write(json.dumps(rows[-1]) + "\n")
    columns = ("DDP",) + FILLS
    print(f"\nhole RMSE at full size (disparity px), DDP at {rows[0]['working'][0]}×{rows[0]['working'][1]} "
          f"('{profile.name}', seed {args.seed})")
    print(f"{'pattern':<9}" + "".join(f"{c:>17}" for c in columns) + f"{'fit s':>8}")
    for row in rows:
        print(f"{row['pattern']:<9}" + "".join(f"{row[c]:>17.3f}" for c in columns) + f"{row['fit_seconds']:>8.1f}")
    print(f"{'mean':<9}" + "".join(f"{np.mean([r[c] for r in rows]):>17.3f}" for c in columns))


if __name__ == "__main__":
    main()
