"""An ensemble of K fits at once: K nets stepped in one Python loop vs one batched pass (torch.func.vmap).

    python benchmarks/bench_ensemble.py               # 48×64 (ci net, 32–512) and 96×128 (32–512), K = 1, 2, 4, 8
    python benchmarks/bench_ensemble.py --threads 2
    python benchmarks/bench_ensemble.py --fits --threads 2   # whole ensemble fits: members in turn vs side by side

Per iteration, for K members with their own weights and noise:
- ``loop``: K UNets called one after another, one loss (the sum), one backward, one fused Adam
  over all K nets' parameters;
- ``vmap``: the K nets' parameters stacked (``torch.func.stack_module_state``), one
  ``vmap(functional_call)`` over the member axis, BatchNorm without running statistics
  (``torch.func.replace_all_batch_norm_modules_``; a fit uses batch statistics anyway), one fused Adam
  over the K-stacked parameters.
The loss is a plain L1 against a fixed target (the same in both modes), so the table is the
networks' cost; DDP's loss adds its own per-member cost on top. Modes and K are interleaved in one
process (rounds of loop, vmap, ...); the table gives medians. ``× one`` = s/it ÷ (K × s/it of one net).

``--fits`` times what ``complete_depth(config=FitConfig(ensemble=K))`` does (the `class` net and
variant, a fixed iteration count so that every member does the same work): the K members one
after another with all threads (``in turn``), or one member per thread side by side, each on one
thread (``side by side``, what an ensemble does on a CPU with ≥ 2 threads).
"""
from __future__ import annotations

import argparse
import copy
import os
import statistics
import sys
import time

import torch
from torch.func import functional_call, replace_all_batch_norm_modules_, stack_module_state, vmap

sys.path.insert(0, os.path.dirname(__file__))
from bench_fit import cpu_summary  # noqa: E402
from _common import parse_args, positive_int  # noqa: E402

CASES = (((48, 64), (16, 32, 64, 128), 10), ((48, 64), (32, 64, 128, 256, 512), 4),
         ((96, 128), (32, 64, 128, 256, 512), 2))  # (size, UNet widths, iterations per timed round at K = 1)


def stepper(size, channels, K: int, mode: str):
    """A function running n Adam iterations of K members; returns seconds per iteration."""
    from ddp_lite.method.paper.nets import UNet
    nets = []
    for k in range(K):
        torch.manual_seed(k)
        nets.append(UNet(16, 4, channels))
    generator = torch.Generator().manual_seed(0)
    noise = torch.rand(K, 16, *size, generator=generator) * 0.1
    target = torch.rand(K, 4, *size, generator=generator)
    if mode == "loop":
        optimizer = torch.optim.Adam([p for net in nets for p in net.parameters()], lr=1e-2, fused=True)

        def loss():
            return sum((net(noise[k:k + 1]) - target[k:k + 1]).abs().mean() for k, net in enumerate(nets))
    else:
        for net in nets:
            replace_all_batch_norm_modules_(net)
        params, buffers = stack_module_state(nets)  # {name: (K, ...)}
        skeleton = copy.deepcopy(nets[0]).to("meta")
        batched = vmap(lambda p, b, x: functional_call(skeleton, (p, b), (x[None],))[0])
        optimizer = torch.optim.Adam(list(params.values()), lr=1e-2, fused=True)

        def loss():  # the mean over (K, 4, H, W) × K = the sum of the members' means, as in "loop"
            return (batched(params, buffers, noise) - target).abs().mean() * K

    def step(n: int) -> float:
        start = time.perf_counter()
        for _ in range(n):
            total = loss()
            optimizer.zero_grad(set_to_none=True)
            total.backward()
            optimizer.step()
        return (time.perf_counter() - start) / n

    return step


def ensemble_seconds(K: int, side_by_side: bool, iterations: int, size=(96, 128), variant: str = "rgbd") -> float:
    """Wall seconds of one ``complete_depth`` ensemble of K members (bench_fit's textured plane)."""
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.complete import complete_depth
    from ddp_lite.method.runtime.options import RunOptions
    from ddp_lite.method import complete
    from bench_fit import case
    rgb, depth, ref, nbrs = case(*size)
    config = FitConfig.for_profile("class", variant=variant, iterations=iterations, auto_stop=False, ensemble=K)
    members = complete.side_by_side_workers
    if not side_by_side:
        complete.side_by_side_workers = lambda *args, **kwargs: 1
    try:
        start = time.perf_counter()
        complete_depth(rgb, depth, ref, nbrs if variant == "rgbd+warp" else (), variant=variant, config=config,
                       options=RunOptions(progress=False))
        return time.perf_counter() - start
    finally:
        complete.side_by_side_workers = members


def main_fits(args) -> None:
    print(f"whole ensembles: class net and recipe, {args.iterations} iterations per member, 96x128, "
          f"{torch.get_num_threads()} thread(s), median of {args.rounds} interleaved rounds")
    print(f"{'variant':>9} {'K':>2} {'in turn s':>10} {'side by side s':>14} {'ratio':>6} {'s per fit':>10}")
    for variant in ("rgbd", "rgbd+warp"):
        for K in args.members:
            ensemble_seconds(K, True, 5, variant=variant)  # warm-up
            times = {True: [], False: []}
            for _ in range(args.rounds):
                for side in (False, True):
                    times[side].append(ensemble_seconds(K, side, args.iterations, variant=variant))
            turn, side = statistics.median(times[False]), statistics.median(times[True])
            print(f"{variant:>9} {K:>2} {turn:10.2f} {side:14.2f} {side / turn:6.2f} {side / K:10.2f}", flush=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", type=positive_int, default=1)
    parser.add_argument("--rounds", type=positive_int, default=5)
    parser.add_argument("--members", type=positive_int, nargs="+", default=None, help="K values (default 1 2 4 8; --fits: 2 3 4)")
    parser.add_argument("--fits", action="store_true", help="whole ensemble fits: members in turn vs side by side")
    parser.add_argument("--iterations", type=positive_int, default=60, help="--fits: iterations per member")
    args = parse_args(parser, argv)
    torch.set_num_threads(args.threads)
    print(cpu_summary())
    if args.fits:
        args.members = args.members or [2, 3, 4]
        return main_fits(args)
    args.members = args.members or [1, 2, 4, 8]
    print(f"torch {torch.__version__}, {torch.get_num_threads()} thread(s), median of {args.rounds} interleaved rounds")
    print(f"{'size':>7} {'net':>18} {'K':>2} {'loop s/it':>10} {'vmap s/it':>10} {'vmap/loop':>9} "
          f"{'loop × one':>10} {'vmap × one':>10}")
    for size, channels, n in CASES:
        for K in args.members:
            steps = {mode: stepper(size, channels, K, mode) for mode in ("loop", "vmap")}
            steps["one"] = stepper(size, channels, 1, "loop")  # one net, in the same rounds: same load
            iterations = max(1, round(n / K))
            for step in steps.values():
                step(2)  # warm-up
            times = {mode: [] for mode in steps}
            for _ in range(args.rounds):
                for mode, step in steps.items():
                    times[mode].append(step(iterations if mode != "one" else max(1, n // 2)))
            median = {mode: statistics.median(values) for mode, values in times.items()}
            one = median["one"]
            print(f"{size[0]}x{size[1]:<4} {'-'.join(map(str, channels)):>18} {K:>2} {median['loop']:10.4f} "
                  f"{median['vmap']:10.4f} {median['vmap'] / median['loop']:9.2f} {median['loop'] / (K * one):10.2f} "
                  f"{median['vmap'] / (K * one):10.2f}", flush=True)


if __name__ == "__main__":
    main()
