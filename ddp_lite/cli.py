"""``ddp-lite``: the kit's main job without a browser.

    ddp-lite demo [--out ddp_demo.png] [--scene house] [--iterations 300]
    ddp-lite scenes
    ddp-lite complete --rgb image.png --depth depth.png --depth-scale 0.001 --out filled.npy
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import numpy as np


def _demo(args) -> int:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .baselines import fill_linear
    from .fit import FitConfig, complete_depth
    from .holes import sgm_depth
    from .metrics import hole_rmse
    from .scenes import make_scene, select_neighbors
    from .viz import save_figure, show_depth, show_error, show_image

    start = time.perf_counter()
    height, width = args.size
    scene = make_scene(args.scene, size=(height, width), seed=args.seed)
    ref = 0
    view = scene[ref]
    depth, _ = sgm_depth(scene, ref)
    neighbors = [scene[i] for i in select_neighbors(scene, ref, 2)]
    print(f"{scene}\nSGM leaves {np.isnan(depth).mean():.0%} of the reference view as holes; "
          f"warp loss uses views {[n.name for n in neighbors]}")
    config = FitConfig.for_profile("class", variant="rgbd+warp", iterations=args.iterations, seed=args.seed,
                                   device=args.device)
    result = complete_depth(view.rgb, depth, view.camera, neighbors, variant="rgbd+warp", config=config,
                            gt_depth=view.depth)
    classical = fill_linear(depth, view.rgb)
    ddp_error = hole_rmse(result.depth, view.depth, depth)
    classical_error = hole_rmse(classical, view.depth, depth)
    print(f"hole RMSE  DDP (rgbd+warp, {result.iterations} it): {ddp_error:.3f} m   "
          f"linear interpolation: {classical_error:.3f} m")

    holes = np.isnan(depth)
    finite = view.depth[np.isfinite(view.depth)]
    vmin, vmax = float(finite.min()), float(np.percentile(finite, 99))
    fig, axes = plt.subplots(2, 3, figsize=(13, 6.5))
    show_image(axes[0, 0], view.rgb, f"'{scene.name}' reference view")
    show_depth(axes[0, 1], depth, f"SGM input ({holes.mean():.0%} holes)", vmin, vmax)
    show_depth(axes[0, 2], view.depth, "ground truth", vmin, vmax)
    show_depth(axes[1, 0], result.depth, f"DDP (hole RMSE {ddp_error:.3f} m)", vmin, vmax)
    show_error(axes[1, 1], result.depth, view.depth, "DDP |error| in holes", mask=holes)
    show_error(axes[1, 2], classical, view.depth, f"linear fill |error| (RMSE {classical_error:.3f} m)",
               mask=holes, vmax=float(np.nanpercentile(np.abs(result.depth - view.depth)[holes], 99)))
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
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(args.out)), suffix=".npy")
    with os.fdopen(fd, "wb") as handle:
        np.save(handle, filled)
    os.replace(tmp, args.out)
    print(f"filled {np.isnan(depth).mean():.1%} holes in {result.seconds:.1f} s → {args.out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ddp-lite", description="Depth completion with a Deep Depth Prior.")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="fill SGM holes in a synthetic scene; compare with linear fill")
    demo.add_argument("--out", default="ddp_demo.png", help="figure path (default: ddp_demo.png)")
    demo.add_argument("--scene", default="house")
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
