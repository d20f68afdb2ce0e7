"""Seconds per iteration, peak memory and FLOP efficiency of the fit loop, per variant and size.

    python benchmarks/bench_fit.py            # all variants at 48×64 and 96×128, UNet 32–512
    python benchmarks/bench_fit.py --narrow   # also the ci profile's narrow net
    python benchmarks/bench_fit.py --set bf16=True --set pad='zeros'   # FitConfig overrides
    python benchmarks/bench_fit.py --isa avx2  # held to AVX2 kernels, as on most laptops (isa.py)

Prints a table; asserts nothing. Each configuration runs in a fresh subprocess so that its
peak resident memory (ru_maxrss) is its own. "bound" is the iteration's floating-point work
(torch.utils.flop_counter, forward + backward) divided by this machine's dense matrix-multiply
rate measured in the same run with the same thread count; "ratio" = time / bound. "conv" is the
floor below the loop: the iteration's convolution calls (forward and backward, as recorded in one
iteration) replayed one by one on fresh tensors of the same shapes, nothing else; "conv ratio" =
conv / bound. A loop can get no nearer its bound than its convolutions do.
"""
from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
from isa import ISA_ENV, cpu_flags, reexec_with_isa  # noqa: E402  benchmarks/ is on the path: the scripts run from there

if __name__ == "__main__":
    reexec_with_isa()  # before torch is imported

import argparse  # noqa: E402
import ast  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import torch  # noqa: E402

from ddp_lite.method.paper.variants import VARIANTS  # noqa: E402
from _common import parse_args, positive_int  # noqa: E402


CPU_FLAGS = ("avx512f", "avx512_bf16", "amx_bf16", "avx512_vnni")


def cpu_summary() -> str:
    """The CPU model and whether it has the flags that decide bf16 / int8 speed (Linux /proc/cpuinfo)."""
    model, flags = cpu_flags()
    marks = ", ".join(f"{flag} {'yes' if flag in flags else 'no'}" for flag in CPU_FLAGS)
    return f"CPU: {model}; {marks}"


def parse_overrides(items) -> dict:
    """``["bf16=True", "pad='zeros'"]`` → ``{"bf16": True, "pad": "zeros"}`` (values as Python literals,
    else as strings)."""
    overrides = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--set expects KEY=VALUE, got {item!r}")
        try:
            overrides[key.strip()] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            overrides[key.strip()] = value
    return overrides


def matmul_rate(n: int = 2048, repeats: int = 5) -> float:
    """Dense float32 matrix-multiply rate (FLOP/s) with the current thread count."""
    a, b = torch.rand(n, n), torch.rand(n, n)
    torch.mm(a, b)
    start = time.perf_counter()
    for _ in range(repeats):
        torch.mm(a, b)
    return 2 * n ** 3 * repeats / (time.perf_counter() - start)


def convolution_seconds(run, repeats: int = 10) -> float:
    """Seconds the convolutions of ``run()`` (one fit iteration) take replayed alone: every
    ``aten.convolution`` and ``aten.convolution_backward`` call is recorded with its arguments' shapes,
    strides and dtypes, then each is called ``repeats`` times (after two warm-up calls) on fresh random
    tensors of that layout; the sum of the per-call means."""
    from torch.utils._python_dispatch import TorchDispatchMode
    wanted = (torch.ops.aten.convolution.default, torch.ops.aten.convolution_backward.default)
    calls = []

    class Recorder(TorchDispatchMode):
        def __torch_dispatch__(self, func, types, args=(), kwargs=None):
            if func in wanted:
                calls.append((func, [(a.shape, a.stride(), a.dtype) if isinstance(a, torch.Tensor) else a for a in args]))
            return func(*args, **(kwargs or {}))

    def fresh(arg):  # a tensor of the recorded layout (strides of 0 included), else the argument itself
        if not (isinstance(arg, tuple) and len(arg) == 3 and isinstance(arg[0], torch.Size)):
            return arg
        shape, stride, dtype = arg
        extent = 1 + sum((n - 1) * step for n, step in zip(shape, stride))
        return torch.randn(max(extent, 1), dtype=dtype).as_strided(shape, stride)

    with Recorder():
        run()
    total = 0.0
    for func, recorded in calls:
        args = [fresh(arg) for arg in recorded]
        for _ in range(2):
            func(*args)
        start = time.perf_counter()
        for _ in range(repeats):
            func(*args)
        total += (time.perf_counter() - start) / repeats
    return total


def case(height: int, width: int, seed: int = 0):
    """A slanted plane with a textured image, 20 % holes and two shifted neighbours."""
    from ddp_lite.core.camera import Camera, look_at
    rng = np.random.default_rng(seed)
    ref = Camera.from_fov(width, height, 60.0)
    u = np.arange(width, dtype=np.float32)
    depth = np.broadcast_to(2.0 + 2.0 * u / width, (height, width)).astype(np.float32).copy()
    depth[rng.random((height, width)) < 0.2] = np.nan
    rgb = rng.random((height, width, 3)).astype(np.float32)
    nbrs = [(rgb, Camera(ref.K, look_at([dx, 0, 0], [dx, 0, 3.0]), width, height)) for dx in (-0.1, 0.1)]
    return rgb, depth, ref, nbrs


def config_and_options(overrides: dict, **fields):
    """(FitConfig, RunOptions) of ``--set`` overrides: the run options' names (``channels_last=True``) go to the
    run, which shows no progress bar; the rest, after ``fields``, to the config."""
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.runtime.options import RUN_OPTIONS, RunOptions
    run = {name: value for name, value in overrides.items() if name in RUN_OPTIONS}
    config = FitConfig(**fields, **{name: value for name, value in overrides.items() if name not in RUN_OPTIONS})
    return config, RunOptions(**{"progress": False, **run})


def check_sets(items) -> None:
    """``--set`` items checked before any work: ``ValueError`` naming the option for a bad item, field or value."""
    try:
        config, options = config_and_options(parse_overrides(items))
        config.validate()
        options.validate()
    except (TypeError, ValueError) as error:
        raise ValueError(f"--set: {error}") from None


def run_one(variant: str, height: int, width: int, channels, iterations: int, overrides=None) -> dict:
    from torch.utils.flop_counter import FlopCounterMode
    from ddp_lite.method.complete import complete_depth
    from ddp_lite.method.paper.variants import get_variant
    rgb, depth, ref, nbrs = case(height, width)
    kwargs = dict(camera=ref, neighbors=nbrs) if get_variant(variant).needs_neighbors else {}
    config, kwargs["options"] = config_and_options(overrides or {}, channels=tuple(channels), lr=1e-2,
                                                   eval_every=10 ** 9)
    with FlopCounterMode(display=False) as counter:
        complete_depth(rgb, depth, variant=variant, config=config.replace(iterations=1), **kwargs)
    flops = counter.get_total_flops()
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    short = complete_depth(rgb, depth, variant=variant, config=config.replace(iterations=5), **kwargs)
    long = complete_depth(rgb, depth, variant=variant, config=config.replace(iterations=5 + iterations), **kwargs)
    per_iteration = (long.seconds - short.seconds) / iterations
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    rate = matmul_rate()
    conv = convolution_seconds(lambda: complete_depth(rgb, depth, variant=variant, config=config.replace(iterations=1),
                                                      **kwargs))
    return dict(variant=variant, size=f"{height}x{width}", channels="-".join(map(str, channels)),
                s_per_it=per_iteration, gflop=flops / 1e9, bound=flops / rate, mm_gflops=rate / 1e9, conv_s=conv,
                peak_mb=peak_mb, rss_before_mb=rss_before / 1024)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--isa", default="native", choices=sorted(ISA_ENV),
                        help="native, or avx2: torch, oneDNN and MKL held to AVX2 kernels (isa.py)")
    parser.add_argument("--iterations", type=positive_int, default=20)
    parser.add_argument("--narrow", action="store_true", help="also the ci profile's narrower net")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="FitConfig field or RunOptions override, repeatable: bf16=True, pad='zeros', "
                             "channels_last=True")
    parser.add_argument("--one", nargs=4, metavar=("VARIANT", "H", "W", "CHANNELS"), help=argparse.SUPPRESS)
    args = parse_args(parser, argv, lambda a: check_sets(a.set))
    overrides = parse_overrides(args.set)
    if args.one:
        variant, height, width, channels = args.one
        print(json.dumps(run_one(variant, int(height), int(width), [int(c) for c in channels.split("-")], args.iterations,
                                 overrides)))
        return
    from ddp_lite.method.profiles import PROFILES
    widths = ["32-64-128-256-512"] + (["-".join(map(str, PROFILES["ci"].channels))] if args.narrow else [])
    print(cpu_summary())
    print(f"torch {torch.__version__}, {torch.get_num_threads()} threads, {args.iterations} timed iterations"
          + (f", overrides {overrides}" if overrides else ""))
    print(f"{'variant':<10} {'size':>7} {'net':>18} {'s/it':>7} {'GFLOP':>6} {'bound s':>8} {'ratio':>6} {'conv s':>7} "
          f"{'conv ratio':>10} {'peak MB':>8}")
    for channels in widths:
        for height, width in ((48, 64), (96, 128)):
            for variant in VARIANTS:
                sets = [arg for item in args.set for arg in ("--set", item)]
                out = subprocess.run([sys.executable, __file__, "--iterations", str(args.iterations), *sets, "--one",
                                      variant, str(height), str(width), channels],
                                     capture_output=True, text=True, check=True)
                r = json.loads(out.stdout.strip().splitlines()[-1])
                print(f"{r['variant']:<10} {r['size']:>7} {r['channels']:>18} {r['s_per_it']:7.3f} {r['gflop']:6.2f} "
                      f"{r['bound']:8.3f} {r['s_per_it'] / r['bound']:6.2f} {r['conv_s']:7.3f} {r['conv_s'] / r['bound']:10.2f} "
                      f"{r['peak_mb']:8.0f}", flush=True)


if __name__ == "__main__":
    main()
