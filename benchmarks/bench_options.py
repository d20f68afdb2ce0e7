"""Interleaved A/B of speed options (FitConfig fields and RunOptions) in one process: s/it of the real fit loop per option.

    python benchmarks/bench_options.py                                   # 96×128 UNet 32–512 and 48×64 16–128
    python benchmarks/bench_options.py --compile                         # also torch.compile of the net
    python benchmarks/bench_options.py --baseline /work/main/ddp_lite    # also another tree's ddp_lite as "baseline"
    python benchmarks/bench_options.py --errors                          # hole error of the inexact options

Absolute s/it move with the machine's load, so every option runs its rounds in turn (A, B, C, A, B,
C, ...) in one process and the table gives the median per option and its ratio to float32. Each
option's net, noise and loss closure are built once by ``complete_depth`` (bench_fit's case,
rgbd+warp) and then stepped by ``ddp_lite.method.loop.run`` (``ddp_lite.fit._run`` before it moved), the fit's own loop.

``--errors``: the options that change numbers (bf16, zero padding) against float32 on real cases
(``make_case(scene, "ci", holes="sgm")``, 48×64, ci net, rgbd, the ci schedule), seeds 0, 1, 2:
the final hole RMSE ×100 of normalised disparity per seed, options interleaved.
"""
from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import inspect
import os
import statistics
import sys
import time

import torch

sys.path.insert(0, os.path.dirname(__file__))
from bench_fit import case, cpu_summary  # noqa: E402
from _common import parse_args, positive_int, seed_int, existing_folder  # noqa: E402

OPTIONS = {"float32": {}, "bf16": dict(bf16=True), "channels_last": dict(channels_last=True),
           "pad zeros": dict(pad="zeros"), "bf16+zeros": dict(bf16=True, pad="zeros"),
           "bf16+channels_last": dict(bf16=True, channels_last=True),
           "warp occlusion": dict(warp_occlusion=True)}  # the warp term's occlusion test (method.kit.visibility)
SIZES = {"96x128": ((96, 128), (32, 64, 128, 256, 512), 8), "48x64": ((48, 64), (16, 32, 64, 128), 30)}


def load_package(path: str, name: str):
    """Import the ddp_lite package at ``path`` under another name (its own fit loop and losses)."""
    spec = importlib.util.spec_from_file_location(name, os.path.join(path, "__init__.py"),
                                                  submodule_search_locations=[path])
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def prepare(package, size, channels, variant: str, options: dict, compile_mode=None):
    """Build one fit's pieces with ``package.complete_depth`` and return a function that runs n iterations."""
    package.complete_depth  # imports the fit; its module is .fit (flat packages) or .method.fit
    fit = sys.modules.get(package.__name__ + ".method.fit") or sys.modules.get(package.__name__ + ".fit")
    rgb, depth, ref, nbrs = case(*size)
    as_own = lambda cam: package.Camera(cam.K, cam.cam_from_world, cam.width, cam.height)  # noqa: E731
    ref, nbrs = as_own(ref), [(image, as_own(cam)) for image, cam in nbrs]
    kwargs = dict(camera=ref, neighbors=nbrs) if variant == "rgbd+warp" else {}
    config, run_kwargs = split_options(package, options, channels=channels, lr=1e-2, eval_every=10 ** 9, iterations=1)
    # the loop is ddp_lite.method.loop.run (ddp_lite.loop.run in flat packages; ddp_lite.fit._run before that)
    owner = sys.modules.get(package.__name__ + ".method.loop") or sys.modules.get(package.__name__ + ".loop")
    owner, name = (owner, "run") if owner is not None else (fit, "_run")
    pieces, run = {}, getattr(owner, name)

    def capture(net, noise, loss_fn, config, iterations, *args, **kw):
        pieces.update(net=net, noise=noise, loss_fn=loss_fn, config=config,
                      run_options={k: v for k, v in kw.items() if k == "options"})
        return run(net, noise, loss_fn, config, iterations, *args, **kw)

    setattr(owner, name, capture)
    try:
        package.complete_depth(rgb, depth, variant=variant, config=config, **kwargs, **run_kwargs)
    finally:
        setattr(owner, name, run)
    net = pieces["net"]
    if compile_mode is not None:
        net = torch.compile(net, mode=compile_mode)

    # the loop takes its progress hook from its caller (older packages made their own bar)
    hook = (sys.modules[package.__name__ + ".core.progress"].FitBar
            if "progress" in inspect.signature(run).parameters else None)

    def step(n: int) -> float:
        quiet = {} if hook is None else {"progress": hook(n, enabled=False)}
        start = time.perf_counter()
        run(net, pieces["noise"], pieces["loss_fn"], pieces["config"], n, **quiet, **pieces["run_options"])
        return (time.perf_counter() - start) / n

    return step


def split_options(package, options: dict, **fields):
    """(``package.FitConfig``, keyword arguments of its ``complete_depth``) for ``options`` after ``fields``, no
    progress bar: a run option goes to ``options=RunOptions(...)`` where the package has them, else (an
    older tree) every name to its FitConfig."""
    run_options = getattr(package, "RunOptions", None)
    if run_options is None:
        return package.FitConfig(progress=False, **fields, **options), {}
    names = {f.name for f in dataclasses.fields(run_options)}
    config = package.FitConfig(**fields, **{k: v for k, v in options.items() if k not in names})
    return config, {"options": run_options(progress=False, **{k: v for k, v in options.items() if k in names})}


ERROR_OPTIONS = ("float32", "bf16", "pad zeros", "bf16+zeros")


def hole_errors(scenes=("house", "desk"), seeds=(0, 1, 2)) -> None:
    """Print hole RMSE ×100 per scene, seed and option, and each fit's s/it (options run in turn)."""
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.complete import complete_depth
    from ddp_lite.method.runtime.options import RunOptions
    from ddp_lite.evaluation.experiments import make_case
    print(f"\n== hole RMSE ×100 (final iteration), rgbd, ci profile 48×64, UNet 16-32-64-128, holes='sgm'")
    print(f"{'scene':<7} {'seed':>4} " + " ".join(f"{o:>11}" for o in ERROR_OPTIONS) + "   s/it per option")
    for scene in scenes:
        case_ = make_case(scene, "ci", holes="sgm")
        errors = {o: [] for o in ERROR_OPTIONS}
        for seed in seeds:
            row, speed = [], []
            for option in ERROR_OPTIONS:
                config = FitConfig.for_profile("ci", variant="rgbd", seed=seed, **OPTIONS[option])  # config fields only
                result = complete_depth(case_.rgb, case_.depth, case_.camera, (), variant="rgbd", config=config,
                                        gt_depth=case_.scored_gt, options=RunOptions(progress=False))
                errors[option].append(result.history["hole_rmse"][-1] * 100)
                row.append(errors[option][-1])
                speed.append(result.seconds / result.iterations)
            print(f"{scene:<7} {seed:>4} " + " ".join(f"{e:11.3f}" for e in row) + "   "
                  + " ".join(f"{t:.4f}" for t in speed), flush=True)
        print(f"{scene:<7} {'mean':>4} " + " ".join(f"{sum(v) / len(v):11.3f}" for v in errors.values()))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=positive_int, default=7)
    parser.add_argument("--variant", default="rgbd+warp", choices=("d", "rgbd", "rgbd+warp"))
    parser.add_argument("--threads", type=positive_int, default=1)
    parser.add_argument("--only", choices=sorted(SIZES))
    parser.add_argument("--options", nargs="*", default=list(OPTIONS), choices=list(OPTIONS), help=f"from {list(OPTIONS)}")
    parser.add_argument("--compile", action="store_true", help="also torch.compile (default, max-autotune-no-cudagraphs)")
    parser.add_argument("--baseline", type=existing_folder, help="path of another ddp_lite package, timed as 'baseline'")
    parser.add_argument("--errors", action="store_true", help="hole error of bf16 / zero padding over seeds instead")
    parser.add_argument("--seeds", type=seed_int, nargs="+", default=[0, 1, 2], help="seeds of --errors")
    args = parse_args(parser, argv)
    torch.set_num_threads(args.threads)
    import ddp_lite
    print(cpu_summary())
    if args.errors:
        return hole_errors(seeds=args.seeds)
    print(f"torch {torch.__version__}, {torch.get_num_threads()} thread(s), {args.variant}, {args.rounds} interleaved rounds")
    baseline = load_package(os.path.abspath(args.baseline), "ddp_lite_baseline") if args.baseline else None
    for name, (size, channels, n) in SIZES.items():
        if args.only and name != args.only:
            continue
        steps, setup = {}, {}
        if baseline is not None:
            steps["baseline"] = prepare(baseline, size, channels, args.variant, {})
        for option in args.options:
            steps[option] = prepare(ddp_lite, size, channels, args.variant, OPTIONS[option])
        for mode in (("default", "max-autotune-no-cudagraphs") if args.compile else ()):
            key = f"compile {mode}"
            steps[key] = prepare(ddp_lite, size, channels, args.variant, {}, compile_mode=mode)
            start = time.perf_counter()
            steps[key](1)  # compiles forward and backward
            setup[key] = time.perf_counter() - start
        for step in steps.values():
            step(2)  # warm-up: allocator, oneDNN primitives
        times = {key: [] for key in steps}
        for _ in range(args.rounds):
            for key, step in steps.items():
                times[key].append(step(n))
        ref = statistics.median(times["float32"]) if "float32" in times else None
        print(f"\n== {args.variant} {name} UNet {'-'.join(map(str, channels))}: median of {args.rounds} rounds × {n} it")
        print(f"{'option':<36} {'s/it':>7} {'min':>7} {'max':>7} {'× fp32':>7} {'setup s':>8}")
        for key, values in times.items():
            median = statistics.median(values)
            ratio = f"{median / ref:7.2f}" if ref else "      -"
            extra = f"{setup[key]:8.1f}" if key in setup else ""
            print(f"{key:<36} {median:7.4f} {min(values):7.4f} {max(values):7.4f} {ratio} {extra}", flush=True)


if __name__ == "__main__":
    main()
