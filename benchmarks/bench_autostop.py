"""How much does auto-stop give away? Simulated early stopping against the hole-error oracle.

    python benchmarks/bench_autostop.py                 # class size 96×128, UNet 32–512 (slow on a CPU)
    python benchmarks/bench_autostop.py --size 48 64    # 4× less work, same net

For each named scene and DDP variant (holes="edge"), ONE long fit runs for ``--factor`` × the
profile's iterations at the profile's learning rate *without* decay, holding out 5 % of the
valid pixels (auto_stop=True) but with patience = iterations, so it never stops. From the
recorded held-out and hole-error curves the auto-stop rule is replayed with the profile's
patience: "kept" is the hole error at the best held-out evaluation before patience first runs
out, "oracle" the lowest hole error of the whole run, "final" the error at its end (drift).
Errors are RMSE ×100 of normalised disparity in the (non-sky) holes. Prints a table; asserts nothing.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from ddp_lite import FitConfig, complete_depth, get_profile  # noqa: E402
from ddp_lite.experiments import make_case  # noqa: E402

SCENES = ("house", "desk", "room", "street")
VARIANTS = ("d", "rgbd", "rgbd+warp")


def replay_auto_stop(eval_iteration, heldout, patience: int, eval_every: int):
    """The auto-stop rule of ``fit._run`` on recorded curves: (index kept, index stopped at)."""
    best_error, best_index, since_best = float("inf"), 0, 0
    for i, error in enumerate(heldout):
        if error < best_error:
            best_error, best_index, since_best = error, i, 0
        else:
            since_best += eval_every
        if since_best >= patience:
            return best_index, i
    return best_index, len(heldout) - 1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, nargs=2, metavar=("H", "W"), help="image size (default: the profile's)")
    parser.add_argument("--profile", default="class")
    parser.add_argument("--iterations", type=int, help="long-run length (default: --factor × the profile's)")
    parser.add_argument("--factor", type=float, default=2.0)
    parser.add_argument("--patience", type=int, help="replayed patience (default: the profile's)")
    parser.add_argument("--scenes", nargs="+", default=list(SCENES))
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS))
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    profile = get_profile(args.profile)
    if args.size:
        profile = dataclasses.replace(profile, size=tuple(args.size))
    patience = args.patience or profile.patience
    print(f"torch {torch.__version__}, {torch.get_num_threads()} thread(s); {profile.describe()}")
    rows = []
    for scene in args.scenes:
        case = make_case(scene, profile, holes="edge")
        for variant in args.variants:
            base = FitConfig.for_profile(profile, variant=variant)
            iterations = args.iterations or int(round(args.factor * base.iterations))
            config = base.replace(iterations=iterations, lr_milestones=(), auto_stop=True, patience=iterations,
                                  eval_every=10, progress=False)
            neighbors = case.neighbors if variant == "rgbd+warp" else ()
            start = time.perf_counter()
            result = complete_depth(case.rgb, case.depth, case.camera, neighbors, variant=variant, config=config,
                                    gt_depth=case.scored_gt, transform=case.transform)
            wall = time.perf_counter() - start
            h = result.history
            its, heldout, hole = h["eval_iteration"], h["heldout"], 100 * h["hole_rmse"]
            kept, stopped = replay_auto_stop(its, heldout, patience, config.eval_every)
            oracle = int(np.argmin(hole))
            rows.append(dict(scene=scene, variant=variant, oracle=hole[oracle], oracle_it=its[oracle], kept=hole[kept],
                             kept_it=its[kept], stop_it=its[stopped], final=hole[-1], iterations=iterations,
                             s_per_it=result.seconds / result.iterations, wall=wall))
            r = rows[-1]
            print(f"  ran {scene}/{variant}: {iterations} it in {wall:.0f} s ({r['s_per_it']:.3f} s/it)", flush=True)
    print(f"\nhole RMSE ×100 (normalised disparity), {profile.size[0]}×{profile.size[1]}, lr {profile.lr:g} "
          f"no decay, replayed patience {patience}")
    head = (f"{'scene':<7} {'variant':<10} {'oracle':>7} {'@it':>5} {'kept':>7} {'@it':>5} {'gap %':>6} "
            f"{'stop it':>7} {'final':>7} {'final-oracle %':>14}")
    print(head)
    print("-" * len(head))
    for r in rows:
        print(f"{r['scene']:<7} {r['variant']:<10} {r['oracle']:7.2f} {r['oracle_it']:5d} {r['kept']:7.2f} "
              f"{r['kept_it']:5d} {100 * (r['kept'] / r['oracle'] - 1):6.1f} {r['stop_it']:7d} {r['final']:7.2f} "
              f"{100 * (r['final'] / r['oracle'] - 1):14.1f}")
    for variant in args.variants:
        sel = [r for r in rows if r["variant"] == variant]
        gaps = [100 * (r["kept"] / r["oracle"] - 1) for r in sel]
        print(f"mean gap {variant:<10} {np.mean(gaps):6.1f} %   mean stop it {np.mean([r['stop_it'] for r in sel]):.0f}")


if __name__ == "__main__":
    main()
