"""How much does auto-stop give away? The automatic stop against the hole-error oracle.

    python benchmarks/bench_autostop.py                 # class size 96×128, UNet 32–512 (~45 min on one core)
    python benchmarks/bench_autostop.py --size 48 64    # 4× less work, same net
    python benchmarks/bench_autostop.py --seeds 0 1 --scenes house desk

For each named scene and DDP variant (holes="edge"), ONE long fit runs for ``--iterations``
with the profile's recipe (held-out pixels, lr cut on every held-out plateau) but is never
allowed to stop. Because a fit is deterministic (same seed, same thread count), the run with
the profile's ``plateau_decays`` would have followed the same curve up to its stop; the stop
rule (:class:`ddp_lite.method.stopping.PlateauStopper`) is therefore replayed exactly on the recorded
held-out curve. "kept" is the hole error of the output auto-stop returns, "oracle" the lowest
hole error of the whole long run (known only through the ground truth), "final" the error at
its end (drift). "plain" replays the same curve with no lr cut (stop at the first plateau).
"near %" is the share of evaluations from iteration 100 on that lie within 5 % of the oracle:
how lucky a stop must be.
``--constant-lr`` runs Deep Image Prior's recipe instead (no lr cut ever; "kept" = plain stop).
Errors are RMSE ×100 of normalised disparity in the (non-sky) holes. Prints a table; asserts nothing.
"""
from __future__ import annotations

import argparse
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.evaluation.experiments import make_case  # noqa: E402
from ddp_lite.method.stopping import PlateauStopper  # noqa: E402
from ddp_lite.method.paper.variants import VARIANTS, get_variant  # noqa: E402
from ddp_lite.method.kit.recipes import get_recipe  # noqa: E402
from _common import add_profile_args, profile_from_args, parse_args, positive_int, seed_int  # noqa: E402

SCENES = ("house", "desk", "room", "street")


def replay(held_out, patience: int, eval_every: int, decays: int):
    """The auto-stop of ``ddp_lite.method.loop.run`` on a recorded held-out curve: (index kept, index stopped at)."""
    stopper, kept = PlateauStopper(patience, eval_every, decays), 0
    for i, error in enumerate(held_out):
        event = stopper.update(error)
        if event == "improved":
            kept = i
        elif event == "stop":
            return kept, i
    return kept, len(held_out) - 1


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_profile_args(parser)
    parser.add_argument("--iterations", type=positive_int, default=800, help="long-run length")
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=SCENES)
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=VARIANTS)
    parser.add_argument("--seeds", type=seed_int, nargs="+", default=[0])
    parser.add_argument("--constant-lr", action="store_true", help="never cut the lr (DIP's recipe)")
    args = parse_args(parser, argv)
    profile = profile_from_args(args)
    print(f"torch {torch.__version__}, {torch.get_num_threads()} thread(s); {profile.describe(get_recipe())}")
    rows = []
    for scene in args.scenes:
        case = make_case(scene, profile, holes="edge")
        for variant in args.variants:
            for seed in args.seeds:
                config = FitConfig.for_profile(profile, variant=variant, seed=seed)
                long_config = config.replace(iterations=args.iterations, plateau_decays=10 ** 6)
                if args.constant_lr:
                    config = config.replace(plateau_decays=0)
                    long_config = long_config.replace(lr_gamma=1.0)
                neighbors = case.neighbors if get_variant(variant).needs_neighbors else ()
                result = complete_depth(case.rgb, case.depth, case.camera, neighbors, variant=variant,
                                        config=long_config, gt_depth=case.scored_gt, transform=case.transform,
                                        options=RunOptions(progress=False))
                h = result.history
                its, held_out, hole = h["eval_iteration"], h["held_out"], 100 * h["hole_rmse"]
                stopping = config.stopping
                kept, stopped = replay(held_out, stopping.patience, stopping.eval_every, stopping.plateau_decays)
                plain, _ = replay(held_out, stopping.patience, stopping.eval_every, 0)
                oracle = int(np.argmin(hole))
                near = 100 * np.mean(hole[its >= 100] <= 1.05 * hole[oracle])
                rows.append(dict(scene=scene, variant=variant, seed=seed, oracle=hole[oracle], oracle_it=its[oracle],
                                 kept=hole[kept], kept_it=its[kept], stop_it=its[stopped], plain=hole[plain],
                                 final=hole[-1], near=near, s_per_it=result.seconds / result.iterations))
                print(f"  ran {scene}/{variant} seed {seed}: {result.iterations} it in {result.seconds:.0f} s "
                      f"({rows[-1]['s_per_it']:.3f} s/it)", flush=True)
    print(f"\nhole RMSE ×100 (normalised disparity), {profile.size[0]}×{profile.size[1]}, lr {profile.lr:g}, "
          f"patience {config.stopping.patience}, "
          + ("constant lr, stop at the first plateau, " if args.constant_lr else
             f"{config.stopping.plateau_decays} lr cut(s) ×{config.paper.lr_gamma:g} then stop, ") +
          f"held-out {config.stopping.held_out_fraction:.0%} of the valid pixels")
    head = (f"{'scene':<7} {'variant':<10} {'seed':>4} {'oracle':>7} {'@it':>5} {'kept':>7} {'@it':>5} {'gap %':>6} "
            f"{'stop it':>7} {'plain gap %':>11} {'final gap %':>11} {'near %':>6}")
    print(head)
    print("-" * len(head))
    gap = lambda r, key: 100 * (r[key] / r["oracle"] - 1)  # noqa: E731
    for r in rows:
        print(f"{r['scene']:<7} {r['variant']:<10} {r['seed']:4d} {r['oracle']:7.2f} {r['oracle_it']:5d} "
              f"{r['kept']:7.2f} {r['kept_it']:5d} {gap(r, 'kept'):6.1f} {r['stop_it']:7d} {gap(r, 'plain'):11.1f} "
              f"{gap(r, 'final'):11.1f} {r['near']:6.0f}")
    print()
    for variant in args.variants:
        sel = [r for r in rows if r["variant"] == variant]
        gaps = [gap(r, "kept") for r in sel]
        print(f"{variant:<10} gap mean {np.mean(gaps):5.1f} %  median {np.median(gaps):5.1f} %  max {np.max(gaps):5.1f} %"
              f"  ≤5 %: {sum(g <= 5 for g in gaps)}/{len(gaps)}  mean stop it {np.mean([r['stop_it'] for r in sel]):.0f}"
              f"  | plain stop: mean gap {np.mean([gap(r, 'plain') for r in sel]):5.1f} %"
              f"  | run to the end: mean gap {np.mean([gap(r, 'final') for r in sel]):5.1f} %")
    gaps = [gap(r, "kept") for r in rows]
    print(f"{'all':<10} gap mean {np.mean(gaps):5.1f} %  median {np.median(gaps):5.1f} %  ≤5 %: "
          f"{sum(g <= 5 for g in gaps)}/{len(gaps)}  | evaluations within 5 % of the oracle (it ≥ 100): "
          f"median {np.median([r['near'] for r in rows]):.0f} %")


if __name__ == "__main__":
    main()
