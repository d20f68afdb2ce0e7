"""The fills on OpenCV's contrib modules against what they replaced or stand in for, on Motorcycle at 250×370.

    python benchmarks/bench_contrib_fills.py [--factor 2] [--holes blobs-1 blobs-2 blobs-3 occlusion] [--repeat 3]

Speed: the cross-bilateral fill and one joint bilateral pass, the kit's former float64 NumPy pass
(``tests/fill_references.py``, the 11×11 square) against ``cv2.ximgproc.jointBilateralFilter`` (a disc);
the kit's masked guided filter (kept) beside ``cv2.ximgproc.guidedFilter`` unmasked, for scale. Quality:
hole RMSE (disparity px) of nearest, linear, telea, the guided fills and the new ``ebi``, ``fbf`` and
``fast-global-smoother``, each with its time. Prints the CPU and its flags; asserts nothing.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from isa import CPU_FLAGS, cpu_flags  # noqa: E402
from fill_references import numpy_joint_bilateral  # noqa: E402

import ddp_lite.classical.guided_fills as guided  # noqa: E402
from ddp_lite.classical.baselines import BASELINES  # noqa: E402
from ddp_lite.studies.real_cases import REAL_HOLES, make_real_case  # noqa: E402
from _common import parse_args, positive_int  # noqa: E402

FILLS = ("nearest", "linear", "telea", "guided-filter", "cross-bilateral", "fast-global-smoother", "ebi", "fbf")


def best_time(fn, repeat: int) -> float:
    """The least wall time of ``repeat`` calls of ``fn()`` (s)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def old_cross_bilateral(disparity, rgb):
    """The cross-bilateral fill as it was: the float64 NumPy pass over the 11×11 square."""
    keep = guided.joint_bilateral_fill
    guided.joint_bilateral_fill = lambda d, g, s, r, radius: numpy_joint_bilateral(d, g, s, r, radius, disc=False)[0]
    try:
        return guided.fill_cross_bilateral(disparity, rgb)
    finally:
        guided.joint_bilateral_fill = keep


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--factor", type=positive_int, default=2, help="Motorcycle pooled by this (2: 250×370)")
    parser.add_argument("--holes", nargs="+", default=["blobs-1", "blobs-2", "blobs-3", "occlusion"], choices=REAL_HOLES)
    parser.add_argument("--repeat", type=positive_int, default=3)
    args = parse_args(parser, argv)
    model, flags = cpu_flags()
    print(f"CPU: {model}; flags: {', '.join(f for f in CPU_FLAGS if f in flags) or 'none of ' + str(CPU_FLAGS)}; "
          f"cv2 {cv2.__version__}, {cv2.getNumThreads()} threads")
    cases = [make_real_case(holes, factor=args.factor) for holes in args.holes]
    case = cases[0]
    disparity, rgb = case.fb / case.depth, case.rgb
    grey = rgb.astype(np.float64) @ np.array([0.2989, 0.5870, 0.1140])
    print(f"\nspeed on {case.name} {disparity.shape[0]}×{disparity.shape[1]} (best of {args.repeat})")
    rows = [
        ("joint bilateral pass, NumPy float64 square (before)", lambda: numpy_joint_bilateral(disparity, grey, 5.0, 0.08, 5, False)),
        ("joint bilateral pass, cv2.ximgproc (after)", lambda: guided.joint_bilateral_fill(disparity, grey, 5.0, 0.08, 5)),
        ("cross-bilateral fill, NumPy passes (before)", lambda: old_cross_bilateral(disparity, rgb)),
        ("cross-bilateral fill, cv2.ximgproc passes (after)", lambda: guided.fill_cross_bilateral(disparity, rgb)),
        ("guided-filter fill, the kit's masked filter (kept)", lambda: guided.fill_guided_filter(disparity, rgb)),
        ("cv2.ximgproc.guidedFilter unmasked, one call (for scale)",
         lambda: cv2.ximgproc.guidedFilter((rgb * 255).astype(np.float32), np.nan_to_num(disparity).astype(np.float32),
                                           2, 1e-4 * 255 ** 2)),
    ]
    for label, fn in rows:
        print(f"  {label:58s} {best_time(fn, args.repeat) * 1000:8.1f} ms")

    print("\nhole RMSE, disparity px (time of one fill)")
    print(f"  {'fill':22s}" + "".join(f"{c.name.split('/')[1]:>18s}" for c in cases) + f"{'mean':>9s}{'/linear':>9s}")
    results = {}
    methods = {name: BASELINES[name] for name in FILLS}
    methods["cross-bilateral (before)"] = old_cross_bilateral
    for name, fn in methods.items():
        cells, errors = [], []
        for c in cases:
            start = time.perf_counter()
            filled = fn(c.fb / c.depth, c.rgb)
            seconds = time.perf_counter() - start
            errors.append(c.rmse_px(c.fb / np.maximum(filled, 1e-6)))
            cells.append(f"{errors[-1]:7.3f} ({seconds:5.2f}s)")
        results[name] = np.array(errors)
        ratio = np.mean(results[name] / results["linear"]) if "linear" in results else 1.0
        print(f"  {name:22s}" + "".join(f"{cell:>18s}" for cell in cells) + f"{np.mean(errors):9.3f}{ratio:9.2f}")


if __name__ == "__main__":
    main()
