"""``ddp-lite``: the kit's main job without a browser.

    ddp-lite demo [--out ddp_demo.png] [--scene house] [--holes edge|sgm|random] [--iterations 300]
    ddp-lite scenes
    ddp-lite complete --rgb image.png --depth depth.png --depth-scale 0.001 --out filled.npy
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

from .atomic import atomic_path


def _demo(args) -> int:
    import dataclasses

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .baselines import fill_colorization, fill_linear
    from .experiments import error_table, format_table, make_case
    from .fit import FitConfig, complete_depth
    from .metrics import hole_rmse
    from .profiles import get_profile
    from .viz import save_figure, show_depth, show_error, show_image

    start = time.perf_counter()
    profile = dataclasses.replace(get_profile("class"), size=tuple(args.size))
    case = make_case(args.scene, profile, holes=args.holes, seed=args.seed)
    print(f"{case.scene}\n{args.holes} holes: {np.isnan(case.depth).mean():.0%} of the reference view; "
          f"warp loss uses views {[n.name for n in case.neighbors]}")
    config = FitConfig.for_profile(profile, variant="rgbd+warp", iterations=args.iterations, seed=args.seed,
                                   device=args.device)
    result = complete_depth(case.rgb, case.depth, case.camera, case.neighbors, variant="rgbd+warp", config=config,
                            gt_depth=case.scored_gt, transform=case.transform)
    estimates = {"linear": fill_linear(case.depth), "colorization": fill_colorization(case.depth, case.rgb),
                 "DDP rgbd+warp": result.depth}
    table = error_table(case, estimates)
    for name, depth in estimates.items():
        table[name]["holes (m)"] = hole_rmse(depth, case.gt, case.holes)
    print(format_table(table, 3, f"RMSE in the holes (sky not scored), DDP after {result.iterations} iterations: "
                                 "normalised disparity ×100, its part near depth edges, metres"))

    ddp_error, linear_error = table["DDP rgbd+warp"]["holes (m)"], table["linear"]["holes (m)"]
    vmin, vmax = float(np.nanmin(case.gt)), float(np.nanmax(case.scored_gt))
    fig, axes = plt.subplots(2, 3, figsize=(13, 6.5))
    show_image(axes[0, 0], case.rgb, f"'{case.name}' reference view")
    show_depth(axes[0, 1], case.depth, f"input ({np.isnan(case.depth).mean():.0%} holes)", vmin, vmax)
    show_depth(axes[0, 2], case.gt, "ground truth", vmin, vmax)
    show_depth(axes[1, 0], result.depth, f"DDP (hole RMSE {ddp_error:.3f} m)", vmin, vmax)
    error_vmax = float(np.nanpercentile(np.abs(result.depth - case.gt)[case.holes], 99))
    show_error(axes[1, 1], result.depth, case.gt, "DDP |error| in holes", mask=case.holes, vmax=error_vmax)
    show_error(axes[1, 2], estimates["linear"], case.gt, f"linear fill |error| (RMSE {linear_error:.3f} m)",
               mask=case.holes, vmax=error_vmax)
    fig.tight_layout()
    save_figure(fig, args.out)
    print(f"figure written to {os.path.abspath(args.out)}; took {time.perf_counter() - start:.1f} s")
    return 0


def _scenes(args) -> int:
    from .scenes import list_scenes
    for name, description in list_scenes().items():
        print(f"{name:<8} {description}")
    return 0


def _read_depth(path: str, scale: float) -> np.ndarray:
    if path.endswith(".npy"):
        depth = np.load(path).astype(np.float32)
    elif path.endswith(".pfm"):
        from .datasets import read_pfm
        depth = read_pfm(path).astype(np.float32)
    else:
        import cv2
        depth = cv2.imread(path, cv2.IMREAD_UNCHANGED)
        if depth is None:
            raise ValueError(f"--depth: cannot read {path!r} as an image")
        depth = depth.astype(np.float32)
    depth = depth * scale
    depth[~np.isfinite(depth) | (depth <= 0)] = np.nan  # the file's own hole marker (0, inf) → NaN
    return depth


def _complete(args) -> int:
    import cv2

    from .fit import FitConfig, complete_depth
    bgr = cv2.imread(args.rgb, cv2.IMREAD_COLOR)
    if bgr is None:
        raise SystemExit(f"--rgb: cannot read {args.rgb!r} as an image")
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB).astype(np.float32) / 255.0
    depth = _read_depth(args.depth, args.depth_scale)
    config = FitConfig.for_profile(args.profile, variant=args.variant, device=args.device,
                                   **({"iterations": args.iterations} if args.iterations else {}))
    result = complete_depth(rgb, depth, variant=args.variant, config=config)
    filled = result.merged(depth) if args.keep_input else result.depth
    with atomic_path(args.out) as tmp, open(tmp, "wb") as handle:
        np.save(handle, filled)
    print(f"filled {np.isnan(depth).mean():.1%} holes in {result.seconds:.1f} s → {args.out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ddp-lite", description="Depth completion with a Deep Depth Prior.")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="fill the holes of a synthetic scene with DDP; compare with classical fills")
    demo.add_argument("--out", default="ddp_demo.png", help="figure path (default: ddp_demo.png)")
    demo.add_argument("--scene", default="house")
    demo.add_argument("--holes", choices=("edge", "sgm", "random"), default="edge",
                      help="a band across a depth edge plus blobs (default), real SGM holes, or blobs")
    demo.add_argument("--iterations", type=int, default=300)
    demo.add_argument("--size", type=int, nargs=2, default=(96, 128), metavar=("H", "W"))
    demo.add_argument("--seed", type=int, default=0)
    demo.add_argument("--device", default=None)
    demo.set_defaults(run=_demo)
    scenes = sub.add_parser("scenes", help="list the built-in synthetic scenes")
    scenes.set_defaults(run=_scenes)
    complete = sub.add_parser("complete", help="fill the holes of your own RGB-D image (no neighbours)")
    complete.add_argument("--rgb", required=True)
    complete.add_argument("--depth", required=True, help=".npy (metres), .pfm, or 16-bit PNG (see --depth-scale)")
    complete.add_argument("--depth-scale", type=float, default=1.0, help="metres per stored unit (0.001 for mm PNG)")
    complete.add_argument("--variant", choices=("d", "rgbd"), default="rgbd")
    complete.add_argument("--profile", default=None, help="ci, class or paper (default: $DDP_PROFILE or class)")
    complete.add_argument("--iterations", type=int, default=None)
    complete.add_argument("--keep-input", action="store_true", help="keep valid input depth (SGM+DDP style)")
    complete.add_argument("--out", required=True, help=".npy path for the filled depth (metres)")
    complete.add_argument("--device", default=None)
    complete.set_defaults(run=_complete)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except (ValueError, TypeError) as error:
        print(f"ddp-lite {args.command}: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
