"""Where a fit's time goes: torch.profiler (CPU) over N iterations, top ops by self CPU time.

    python benchmarks/profile_fit.py                         # rgbd+warp, 96×128 UNet 32–512 and 48×64 16–128
    python benchmarks/profile_fit.py --set bf16=True --rows 20

The case is bench_fit's (a slanted plane, textured image, 20 % holes, two neighbours); a 5-iteration
fit warms up first. The table includes the fit's set-up (net build, warpers), which is small.
"""
from __future__ import annotations

import argparse
import os
import sys

import torch
from torch.profiler import ProfilerActivity, profile

sys.path.insert(0, os.path.dirname(__file__))
from bench_fit import case, check_sets, config_and_options, cpu_summary, parse_overrides  # noqa: E402
from _common import parse_args, positive_int  # noqa: E402

SIZES = {"96x128": ((96, 128), (32, 64, 128, 256, 512)), "48x64": ((48, 64), (16, 32, 64, 128))}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=positive_int, default=30)
    parser.add_argument("--variant", default="rgbd+warp", choices=("d", "rgbd", "rgbd+warp"))
    parser.add_argument("--rows", type=positive_int, default=15)
    parser.add_argument("--threads", type=positive_int, default=1)
    parser.add_argument("--only", choices=sorted(SIZES), help="one size only")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="FitConfig field or RunOptions override")
    args = parse_args(parser, argv, lambda a: check_sets(a.set))
    torch.set_num_threads(args.threads)
    from ddp_lite.method.complete import complete_depth
    print(cpu_summary())
    print(f"torch {torch.__version__}, {torch.get_num_threads()} thread(s), overrides {parse_overrides(args.set)}")
    for name, ((height, width), channels) in SIZES.items():
        if args.only and name != args.only:
            continue
        rgb, depth, ref, nbrs = case(height, width)
        kwargs = dict(camera=ref, neighbors=nbrs) if args.variant == "rgbd+warp" else {}
        config, kwargs["options"] = config_and_options(parse_overrides(args.set), channels=channels, lr=1e-2,
                                                       eval_every=10 ** 9)
        complete_depth(rgb, depth, variant=args.variant, config=config.replace(iterations=5), **kwargs)
        with profile(activities=[ProfilerActivity.CPU]) as prof:
            result = complete_depth(rgb, depth, variant=args.variant, config=config.replace(iterations=args.iterations),
                                    **kwargs)
        print(f"\n== {args.variant} {height}x{width} UNet {'-'.join(map(str, channels))}: {args.iterations} iterations, "
              f"{result.seconds / args.iterations:.3f} s/it under the profiler")
        print(prof.key_averages().table(sort_by="self_cpu_time_total", row_limit=args.rows, max_name_column_width=40))


if __name__ == "__main__":
    main()
