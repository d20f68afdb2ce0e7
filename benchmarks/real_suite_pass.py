"""A pass of the real suite for the recipes for real photographs: half of the scenes on every hole kind, ``kit`` and
``photo``, rgbd and rgbd+warp, seeds 0–1, at quarter size (≈ 320×280) by default: whether a recipe chosen at the
eighth size holds at twice it.

    python benchmarks/real_suite_pass.py --data DIR                 # quarter size, half A (the scenes chosen on)
    python benchmarks/real_suite_pass.py --data DIR --half b        # the other half, to confirm on
    python benchmarks/real_suite_pass.py --data DIR --report        # the tables from the rows so far
    python benchmarks/real_suite_pass.py --data DIR --size eighth --half all --kinds dropouts   # the new kind, eighth
    python benchmarks/real_suite_pass.py --data DIR --profile ci --threads 1 --cases Art/dropouts --seeds 0 \\
        --variants rgbd --out /tmp/smoke.jsonl                      # a smoke slice: one case

``DIR``: a folder of Middlebury scenes with ground truth (``python -m data_fetch fetch middlebury2005|2006|2014q``).
The cases are ``ddp_lite.studies.real_suite``'s at ``--size``: every hole kind (the 20 % blobs, a sensor's small
dropouts, SGBM's holes, the truth's occlusions; ``--kinds``: some of them) on each scene of the half
(``SUITE_HALF_A``, or the rest), and DepthComp's strokes on Plastic, that kind's one case, whichever the half. It
prints the expected wall time first (from the recorded time of a quarter-size fit, then from its own fits as they
finish), fits a case's recipes side by side (one torch thread each; ``--threads``), appends one JSON row per fill
or fit to ``--out`` (default ``benchmarks/results/real_suite_quarter.jsonl``, as the eighth size's
``real_suite_eighth.jsonl``; at the eighth size ``real_suite_eighth_kit_photo.jsonl``) and skips what is there, so
a stopped run resumes where it stopped; then ``bench_real.py``'s per-scene table and means per hole kind. Asserts
nothing.
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import torch  # noqa: E402

import bench_real  # noqa: E402
from _common import check_rows_out, data_root, parse_args, positive_int, seed_int  # noqa: E402
from ddp_lite.method.profiles import PROFILES  # noqa: E402
from ddp_lite.studies.real_suite import SUITE_HOLES, SUITE_SIZES, suite_case_names, suite_half  # noqa: E402

RECIPES = ("kit", "photo")
VARIANTS = ("rgbd", "rgbd+warp")
SEEDS = (0, 1)
ONE_CASE_KINDS = ("Plastic/depthcomp",)  # a hole kind with one case: in the pass whichever the half


def pass_cases(data, half: str, kinds=SUITE_HOLES) -> list[str]:
    """The pass's case names under ``data``: each of ``kinds`` on each scene of ``half`` ("A", "B" or "all"), and
    the kinds of one case (``ONE_CASE_KINDS``) whichever the half, in the suite's order (kind by kind)."""
    names = [n for n in suite_case_names(data) if n.split("/")[1] in kinds]
    return [n for n in names if half == "all" or suite_half(n) == half or n in ONE_CASE_KINDS]


def default_out(size: str) -> Path:
    """Where a pass at ``size`` keeps its rows: ``real_suite_quarter.jsonl``; at the eighth size a file of its own
    (``real_suite_eighth.jsonl`` holds the earlier recipes' rows)."""
    name = "real_suite_quarter.jsonl" if size == "quarter" else f"real_suite_{size}_kit_photo.jsonl"
    return bench_real.RESULTS / name


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, type=data_root, metavar="DIR",
                        help="a folder of Middlebury scenes with ground truth")
    parser.add_argument("--half", type=lambda text: {"a": "A", "b": "B"}.get(text.lower(), text),
                        choices=("A", "B", "all"), default="A",
                        help="the scenes: half a (chosen on), half b (confirmed on) or all of them")
    parser.add_argument("--size", choices=sorted(SUITE_SIZES), default="quarter", help="the pooled size of the scenes")
    parser.add_argument("--kinds", nargs="+", choices=SUITE_HOLES, default=list(SUITE_HOLES), help="the hole kinds")
    parser.add_argument("--cases", nargs="+", metavar="SCENE/HOLES", help="only these cases of the pass")
    parser.add_argument("--recipes", nargs="+", default=list(RECIPES), metavar="RECIPE")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=VARIANTS)
    parser.add_argument("--seeds", nargs="+", type=seed_int, default=list(SEEDS))
    parser.add_argument("--profile", default="class", choices=sorted(PROFILES))
    parser.add_argument("--threads", type=positive_int, default=2,
                        help="torch threads: fits side by side, one thread each")
    parser.add_argument("--out", type=Path, help="the rows file (default: results/real_suite_quarter.jsonl, or "
                        "real_suite_eighth_kit_photo.jsonl)")
    parser.add_argument("--report", action="store_true", help="print the tables of --out and stop")
    def check(args):  # every argument before any work: a ValueError naming the option is a usage error
        args.out = args.out or default_out(args.size)
        check_rows_out(args.out)
        if args.report:
            return
        for recipe in args.recipes:
            try:
                bench_real.recipe_config(args.profile, VARIANTS[0], recipe, 0).validate()
            except (ValueError, TypeError) as error:
                raise ValueError(f"--recipes: {recipe!r}: {error}") from None
        args.names = pass_cases(args.data, args.half, args.kinds)
        if args.cases:
            unknown = sorted(set(args.cases) - set(args.names))
            if unknown:
                raise ValueError(f"--cases: not in the half {args.half} pass under {args.data}: {unknown}")
            args.names = [n for n in args.names if n in set(args.cases)]
    args = parse_args(parser, argv, check)
    if not args.report:
        torch.set_num_threads(args.threads)
        bench_real.run(args.data, args.size, args.recipes, args.variants, args.seeds, args.out, args.profile,
                       args.names)
    bench_real.report(args.out)


if __name__ == "__main__":
    main()
