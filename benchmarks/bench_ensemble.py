"""An ensemble of K fits at once: K nets stepped in one Python loop vs one batched pass (torch.func.vmap).

    python benchmarks/bench_ensemble.py               # 48×64 (ci net, 32–512) and 96×128 (32–512), K = 1, 2, 4, 8
    python benchmarks/bench_ensemble.py --threads 2

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

CASES = (((48, 64), (16, 32, 64, 128), 10), ((48, 64), (32, 64, 128, 256, 512), 4),
         ((96, 128), (32, 64, 128, 256, 512), 2))  # (size, UNet widths, iterations per timed round at K = 1)


def stepper(size, channels, K: int, mode: str):
    """A function running n Adam iterations of K members; returns seconds per iteration."""
    from ddp_lite.nets import UNet
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--members", type=int, nargs="+", default=[1, 2, 4, 8])
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    print(cpu_summary())
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
