"""Notebook 05's full ablation table (Table 2): every scene × seed, which the notebook runs only in part
at `class` (one seed per scene, to keep the live notebook short).

    python benchmarks/bench_ablation.py                       # class: house, desk × seeds 0, 1 (~20 min on 2 cores)
    python benchmarks/bench_ablation.py --profile ci          # seconds per fit
    python benchmarks/bench_ablation.py --scenes house desk room --seeds 0 1 2 --holes sgm

Prints the per-case hole errors and the mean ± std table, as notebook 05 does; asserts nothing.
"""
from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

from _common import add_profile_args, profile_from_args, parse_args, seed_int, positive_float  # noqa: E402

from ddp_lite.evaluation.experiments import TABLE2_CONFIGS, ablation, format_mean_spread  # noqa: E402
from ddp_lite.method.kit.recipes import get_recipe  # noqa: E402
from ddp_lite.world.scenes import SCENES  # noqa: E402


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_profile_args(parser)
    parser.add_argument("--scenes", nargs="+", default=["house", "desk"], choices=sorted(SCENES))
    parser.add_argument("--seeds", nargs="+", type=seed_int, default=None, help="default: the profile's seeds")
    parser.add_argument("--holes", default="edge", choices=("edge", "sgm", "random"))
    parser.add_argument("--tau", type=positive_float, default=0.01, help="P/R/F distance as a fraction of the median depth")
    args = parse_args(parser, argv)
    profile = profile_from_args(args)
    seeds = args.seeds if args.seeds is not None else list(profile.seeds)
    cases = [(scene, seed) for scene in args.scenes for seed in seeds]
    print(profile.describe(get_recipe()))  # the size and budget, and what DDP_RECIPE's recipe runs
    start = time.perf_counter()
    runs, _ = ablation(cases, TABLE2_CONFIGS, profile, holes=args.holes, tau=args.tau)
    print()
    print(format_mean_spread(runs, title=f"mean ± std over {len(cases)} (scene, seed) cases, {args.holes} holes "
                                         "(hole RMSE ×100, edge band, P/R/F %)"))
    print(f"\n{len(cases) * len(TABLE2_CONFIGS)} fits in {time.perf_counter() - start:.0f} s "
          f"({args.threads} thread(s); time it alone)")


if __name__ == "__main__":
    main()
