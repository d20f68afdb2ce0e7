"""The real Motorcycle cases at the paper's size and schedule: DDP (``paper`` and ``kit`` recipes, rgbd and
rgbd+warp) against every classical fill, with seconds per iteration and peak memory. Meant for a GPU.

    python benchmarks/paper_scale.py                                  # 500×740, 16000 iterations per fit
    python benchmarks/paper_scale.py --budget-s 480 --out paper.jsonl # the schedule cut to fit 480 s
    python benchmarks/paper_scale.py --size 32 48 --iterations 3      # a tiny end-to-end run on a CPU
    python benchmarks/paper_scale.py --table6 --data DIR --budget-s 540  # Table 6's scenes, < 10 min on one GPU

The five hole kinds of ``ddp_lite.studies.real_cases`` (three blob patterns, real SGBM holes, occlusion
holes), the pair pooled to the profile's size (``factor_for_profile``: ``paper`` → full size, 500×740).
A fit runs on CUDA when the machine has it (``RunOptions.device`` None). ``--budget-s`` times a few
iterations of each recipe and variant first, then cuts every fit's iterations, and its learning-rate
milestones in proportion, so that the fits fill the time left; it prints how many iterations ran.
The table is ``bench_quality.py``'s (hole RMSE in disparity px; ratio = DDP / the best classical fill
of the case). Two recipes whose configs are equal at this profile fit once. Asserts nothing.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.kit import recipes  # noqa: E402
from ddp_lite.classical import baselines  # noqa: E402
from ddp_lite.studies.real_cases import REAL_HOLES, factor_for_profile  # noqa: E402
from ddp_lite.studies.table6 import TABLE6_SCENES, table6_case, table6_data_line, table6_sources  # noqa: E402
from ddp_lite.method.runtime.device import resolve_device  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402
from _common import (add_profile_args, check_rows_out, existing_folder, parse_args, positive_float, positive_int,  # noqa: E402
                     profile_from_args, seed_int)
from bench_quality import build_case, region_errors, report, rmse_px  # noqa: E402

RECIPES = ("paper", "kit")
# the paper's Table 6: Middlebury 2005/2006 (Plastic, Baby, Bowling) with Depthcomp's holes, disparity RMSE (px)
PAPER_TABLE_6 = {"DDP": 0.46, "Depthcomp": 0.49, "EBI": 0.62, "FBF": 0.69, "GIF": 0.78, "FMM (Telea)": 1.01,
                 "cubic": 1.35, "linear": 1.38}
VARIANTS = ("rgbd", "rgbd+warp")


def scaled_schedule(iterations: int, milestones, run: int) -> tuple[int, tuple[int, ...]]:
    """A schedule of ``iterations`` with learning-rate ``milestones`` cut to ``run`` iterations: each
    milestone at the same fraction of the run (rounded, at least 1), those that fall at or past its end
    dropped. Returns ``(run, milestones)``.

    Example:
        >>> scaled_schedule(16000, (12000, 15000), 4000)
        (4000, (3000, 3750))
    """
    if isinstance(run, bool) or int(run) != run or run < 1:
        raise ValueError(f"run must be a positive number of iterations, got {run!r}")
    scaled = sorted({max(1, round(m * run / iterations)) for m in milestones})
    return int(run), tuple(m for m in scaled if m < run)


def iterations_for_budget(seconds_left: float, fits: list[tuple[float, float]], most: int) -> int:
    """The iteration count per fit that fills ``seconds_left``: ``fits`` lists each planned fit as
    ``(setup seconds, seconds per iteration)``; at least 1, at most ``most``.

    Example:
        >>> iterations_for_budget(100.0, [(5.0, 0.25), (5.0, 0.25)], 16000)   # (100 - 10) / 0.5
        180
    """
    setup, per_iteration = sum(s for s, _ in fits), sum(p for _, p in fits)
    if per_iteration <= 0:
        return most
    return int(min(most, max(1, (seconds_left - setup) // per_iteration)))


def peak_memory_mb(device: torch.device) -> float:
    """Peak memory so far (MB): the CUDA allocator's since its last reset on a GPU, else the process's
    resident-set peak (``ru_maxrss``, which never goes down)."""
    if device.type == "cuda":
        return torch.cuda.max_memory_allocated(device) / 2 ** 20
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KB on Linux


def configs(profile, recipes, variants, seed: int) -> dict:
    """{(recipe, variant): FitConfig} at the profile."""
    return {(recipe, variant): FitConfig.for_profile(profile, variant=variant, recipe=recipe, seed=seed)
            for recipe in recipes for variant in variants}


def fit(case, variant: str, config) -> tuple[object, float]:
    """``complete_depth`` of a real case → (result, wall seconds including the fit's setup)."""
    neighbors = case.neighbors if variant == "rgbd+warp" else ()
    start = time.perf_counter()
    result = complete_depth(case.rgb, case.depth, case.camera, neighbors, variant=variant, config=config,
                            options=RunOptions(progress=False))
    return result, time.perf_counter() - start


def probe(case, planned: dict, iterations: int) -> dict:
    """{(recipe, variant): (setup seconds, seconds per iteration)} from a short fit of each config on ``case``,
    after one untimed iteration (the first pays for the device's start and the kernels' selection)."""
    key, config = next(iter(planned.items()))
    fit(case, key[1], config.replace(iterations=1, lr_milestones=()))
    timings = {}
    for key, config in planned.items():
        result, wall = fit(case, key[1], config.replace(iterations=iterations, lr_milestones=()))
        per_iteration = result.seconds / max(1, result.iterations)
        timings[key] = (max(0.0, wall - result.seconds), per_iteration)
        print(f"probe {key[0]:<6} {key[1]:<10} {iterations} iterations: {per_iteration:.3f} s/it, "
              f"{timings[key][0]:.1f} s setup", flush=True)
    return timings


def run(args) -> None:
    started = time.perf_counter()
    profile = profile_from_args(args)
    factor = factor_for_profile(profile)
    planned = configs(profile, args.recipes, args.variants, args.seed)
    full = next(iter(planned.values())).paper.iterations
    milestones = next(iter(planned.values())).paper.lr_milestones
    device = resolve_device(RunOptions())
    if args.table6:  # the paper's own Table 6 scenes, pooled to the profile's size
        names = [f"table6/{scene}" for scene in TABLE6_SCENES]
        cases = [(case, case.fb) for case in (table6_case(s, profile, args.seed, args.data) for s in TABLE6_SCENES)]
        shipped = all(copy.dataset == "shipped" for copy in table6_sources(profile).values())
        if not args.data:
            print(table6_data_line(profile), flush=True)  # installed (data_fetch), else shipped
        where = f"Table 6 scenes ({'from ' + args.data if args.data else 'shipped, quarter size' if shipped else 'installed'})"
    else:
        names = [f"motorcycle-{factor}/{holes}" for holes in args.holes]  # bench_quality's case names
        cases = [build_case(name, profile) for name in names]
        where = f"Motorcycle pooled by {factor}"
    size = f"{cases[0][0].depth.shape[0]}x{cases[0][0].depth.shape[1]}"
    print(f"profile '{profile.name}', {where}: {size}, on {device}; "
          f"schedule {full} iterations, lr milestones {milestones}", flush=True)
    distinct = {}  # {key: config}: a config equal to one already planned (kit and paper at ``paper``) fits once
    for key, config in planned.items():
        if not any(config == other and key[1] == other_key[1] for other_key, other in distinct.items()):
            distinct[key] = config
    rows = []
    for name, (case, fb) in zip(names, cases):
        disparity_in = fb / case.depth
        for method, fill in baselines.BASELINES.items():
            start = time.perf_counter()
            filled = fill(disparity_in, case.rgb)
            rows.append(dict(case=name, method=method, variant=None, seed=None, size=size, px=rmse_px(fb / filled, case, fb),
                             seconds=time.perf_counter() - start, **region_errors(case, fb / filled)))
    run_iterations = full if args.iterations is None else args.iterations
    if args.budget_s is not None:
        timings = probe(cases[0][0], distinct, args.probe_iterations)
        # result.seconds / result.iterations is per iteration of one member of an ensemble or blend
        fits = [(timings[key][0], timings[key][1] * config.fit_count()) for key, config in distinct.items()
                for _ in cases]
        left = args.budget_s - (time.perf_counter() - started)
        run_iterations = iterations_for_budget(left, fits, run_iterations)
    run_iterations, run_milestones = scaled_schedule(full, milestones, run_iterations)
    print(f"ran {run_iterations} of {full} iterations per fit, lr milestones {run_milestones}"
          + (f" (to fit --budget-s {args.budget_s:g})" if args.budget_s is not None else ""), flush=True)
    timing = {}
    for key, config in distinct.items():
        config = config.replace(iterations=run_iterations, lr_milestones=run_milestones)
        for name, (case, fb) in zip(names, cases):
            if device.type == "cuda":
                torch.cuda.reset_peak_memory_stats(device)
            result, wall = fit(case, key[1], config)
            memory = peak_memory_mb(device)
            merged = result.merged(case.depth)
            for recipe, variant in [k for k in planned if planned[k] == planned[key] and k[1] == key[1]]:
                rows.append(dict(case=name, method=recipe, variant=variant, seed=args.seed, size=size, profile=profile.name, px=rmse_px(merged, case, fb),
                                 seconds=wall, iterations=result.iterations,
                                 seconds_per_iteration=result.seconds / max(1, result.iterations),
                                 peak_mb=memory, **region_errors(case, merged)))
            timing.setdefault(key, []).append((result.iterations, result.seconds / max(1, result.iterations),
                                               wall, memory))
            print(f"{name:<22} {key[0]:<6} {key[1]:<10} {rows[-1]['px']:.3f} px, {result.iterations} it, "
                  f"{wall:.1f} s", flush=True)
    path = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="ddp-paper-scale-")) / "rows.jsonl"
    write_rows(path, rows)
    report(str(path))
    print_timing(timing, planned, device)
    others = min(v for k, v in PAPER_TABLE_6.items() if k != "DDP")
    print(f"\nthe paper (Table 6, other Middlebury scenes, full size, 16000 iterations): DDP "
          f"{PAPER_TABLE_6['DDP']} px, {PAPER_TABLE_6['DDP'] / others:.2f}× the best other method, "
          f"{PAPER_TABLE_6['DDP'] / PAPER_TABLE_6['linear']:.2f}× linear")
    print(f"whole run {time.perf_counter() - started:.0f} s"
          + (f" against --budget-s {args.budget_s:g}" if args.budget_s is not None else ""))


def write_rows(path: Path, rows: list[dict]) -> None:
    """``rows`` as JSON lines at ``path``, written atomically (a temporary file, then a rename)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_text("".join(json.dumps(row) + "\n" for row in rows))
    temporary.replace(path)


def print_timing(timing: dict, planned: dict, device: torch.device) -> None:
    """Per fitted config: iterations run, seconds per iteration (median over the cases), seconds per fit
    (with its setup) and peak memory."""
    memory = "peak GPU MB" if device.type == "cuda" else "peak RSS MB"
    header = f"{'recipes':<14}{'variant':<11}{'iterations':>11}{'s/it':>9}{'s/fit':>9}{memory:>13}"
    print(f"\n=== time and memory on {device} ===\n{header}\n" + "-" * len(header))
    for key, values in timing.items():
        same = "+".join(k[0] for k in planned if planned[k] == planned[key] and k[1] == key[1])
        its, per_it, wall, mb = (np.array(v) for v in zip(*values))
        print(f"{same:<14}{key[1]:<11}{int(its.max()):>11}{np.median(per_it):>9.3f}{np.median(wall):>9.1f}"
              f"{mb.max():>13.0f}")


def check_args(args) -> None:
    """Before any work: ``--data`` only with ``--table6``, a writable ``--out``."""
    if args.data and not args.table6:
        raise ValueError("--data acts on nothing without --table6 (Motorcycle's pair ships with the kit)")
    if args.out:
        check_rows_out(args.out)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_profile_args(parser)
    parser.set_defaults(profile="paper")
    parser.add_argument("--recipes", nargs="+", default=list(RECIPES), choices=sorted(recipes.RECIPES))
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=VARIANTS)
    parser.add_argument("--holes", nargs="+", default=list(REAL_HOLES), choices=REAL_HOLES, help="hole kinds")
    parser.add_argument("--seed", type=seed_int, default=0)
    parser.add_argument("--table6", action="store_true",
                        help="the paper's Table 6 scenes (Plastic under DepthComp's holes, Baby1, Bowling1) instead of "
                             "Motorcycle's hole kinds")
    parser.add_argument("--data", metavar="DIR", type=existing_folder, help="with --table6: a folder of Middlebury scenes (HalfSize, as "
                                                      "data_fetch installs them); default the shipped quarter-size copies")
    parser.add_argument("--iterations", type=positive_int, help="iterations per fit (default: the profile's schedule); "
                                                       "the lr milestones scale with it")
    parser.add_argument("--budget-s", type=positive_float, help="cut the iterations so that the whole run takes about this long")
    parser.add_argument("--probe-iterations", type=positive_int, default=10, help="iterations timed per config for --budget-s")
    parser.add_argument("--out", help="write the rows (bench_quality's JSON lines) here")
    args = parse_args(parser, argv, check_args)
    try:
        run(args)
    except (ValueError, TypeError, MemoryError, RuntimeError) as error:
        sys.exit(f"paper_scale.py: {error}")


if __name__ == "__main__":
    main()
