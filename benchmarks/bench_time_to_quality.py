"""Time to quality: wall seconds until the hole error comes within 5 % of the best reached.

    python benchmarks/bench_time_to_quality.py                # class size 96×128, UNet 32–512
    python benchmarks/bench_time_to_quality.py --size 48 64   # 4× less work, same net
    python benchmarks/bench_time_to_quality.py --parts main c2f

Variant rgbd+warp, holes="edge", errors are hole RMSE ×100 of normalised disparity (sky excluded).
Parts:

- ``main``: per named scene, three recipes: the kit's default (``FitConfig.for_profile``: lr 1e-2,
  ×0.3 at 60 %/85 %, auto-stop), Deep Image Prior's usual one (Adam lr 0.01, a fixed
  ``--budget`` iterations, no schedule, no auto-stop) and the paper's (lr 5e-5, ×0.01 at 75 %
  and 94 % of the same budget, so the same wall time). The target is 1.05 × the best hole
  error any recipe reached; "to target" is the first evaluation (every 10 iterations) at or
  under it. "kept" is the error of what the fit returns (the best held-out output with
  auto-stop, the last one without).
- ``warm``: views 0, 1, 2 of one scene; view k+1 from scratch vs from view k's weights (with the
  default recipe, and with a tenth of its learning rate and no decay).
- ``precision``: float32 vs bf16 autocast vs channels_last (s/it and kept error).
- ``c2f``: :func:`complete_depth_coarse_to_fine` (half the iterations at half size) vs plain,
  both with the default recipe; only full-size evaluations count towards the target.

Seconds at an evaluation are interpolated linearly within a run (or within each stage of a
coarse-to-fine run) from its total time. Prints tables; asserts nothing.
"""
from __future__ import annotations

import argparse
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.evaluation.experiments import make_case  # noqa: E402
from ddp_lite.method.coarse_to_fine import complete_depth_coarse_to_fine  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402
from ddp_lite.method.kit.recipes import get_recipe  # noqa: E402
from _common import add_profile_args, profile_from_args, parse_args, positive_int, seed_int, positive_float  # noqa: E402

SCENES = ("house", "desk", "room", "street")
VARIANT = "rgbd+warp"


def curve(result):
    """(eval iterations, eval seconds, hole RMSE ×100, full-size mask) of a result."""
    h = result.history
    its = np.asarray(h["eval_iteration"], float)
    if "stage_seconds" in h:  # coarse-to-fine: per-stage linear time
        (n1, n2), (s1, s2) = h["stage_iterations"], h["stage_seconds"]
        seconds = np.where(its <= n1, its * s1 / n1, s1 + (its - n1) * s2 / n2)
        full = np.asarray(h["eval_scale"]) == 1
    else:
        seconds = its * result.seconds / result.iterations
        full = np.ones(len(its), bool)
    return its.astype(int), seconds, 100 * np.asarray(h["hole_rmse"]), full


def kept_error(result) -> float:
    its, _, hole, full = curve(result)
    index = np.nonzero(its == result.best_iteration)[0]
    return float(hole[index[-1]]) if len(index) else float("nan")


def to_target(result, target: float):
    """(iterations, seconds) of the first full-size evaluation with hole error ≤ target, or None."""
    its, seconds, hole, full = curve(result)
    hit = np.nonzero((hole <= target) & full)[0]
    return (int(its[hit[0]]), float(seconds[hit[0]])) if len(hit) else None


def best(result) -> float:
    _, _, hole, full = curve(result)
    return float(hole[full].min())


def fit(case, config, coarse_to_fine=False, init=None, options=RunOptions(progress=False), **kwargs):
    if coarse_to_fine:
        return complete_depth_coarse_to_fine(case.rgb, case.depth, case.camera, case.neighbors, variant=VARIANT,
                                             config=config, gt_depth=case.scored_gt, transform=case.transform,
                                             options=options, **kwargs)
    return complete_depth(case.rgb, case.depth, case.camera, case.neighbors, variant=VARIANT, config=config,
                          gt_depth=case.scored_gt, transform=case.transform, init=init, options=options)


def recipes(profile, budget: int, seed: int = 0) -> dict[str, FitConfig]:
    default = FitConfig.for_profile(profile, variant=VARIANT, eval_every=10, seed=seed)
    dip = default.replace(lr=0.01, iterations=budget, lr_milestones=(), auto_stop=False)
    paper = default.replace(lr=5e-5, iterations=budget, lr_milestones=(round(0.75 * budget), round(0.94 * budget)),
                            lr_gamma=0.01, auto_stop=False)
    return {"default": default, "DIP": dip, "paper": paper}


def row(name, result, target) -> str:
    hit = to_target(result, target)
    reach = f"{hit[0]:>6d} {hit[1]:8.1f}" if hit else f"{'never':>6} {'-':>8}"
    return (f"{name:<22} {reach} {best(result):7.2f} {kept_error(result):7.2f} {result.iterations:6d} "
            f"{result.seconds:7.1f} {result.seconds / result.iterations:6.3f}")


HEAD = f"{'':<22} {'it→tgt':>6} {'s→tgt':>8} {'best':>7} {'kept':>7} {'ran':>6} {'total s':>7} {'s/it':>6}"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_profile_args(parser)
    parser.add_argument("--budget", type=positive_int, help="iterations of the fixed-budget recipes (default: 2 × the profile's)")
    parser.add_argument("--tolerance", type=positive_float, default=0.05)
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=SCENES)
    parser.add_argument("--warm-scene", default="house", choices=SCENES)
    parser.add_argument("--parts", nargs="+", default=["main", "warm", "precision", "c2f"],
                        choices=["main", "warm", "precision", "c2f"])
    parser.add_argument("--seed", type=seed_int, default=0, help="fit seed (net init, noise, held-out pixels)")
    args = parse_args(parser, argv)
    profile = profile_from_args(args)
    budget = args.budget or 2 * profile.iterations
    tol = 1 + args.tolerance
    print(f"torch {torch.__version__}, {torch.get_num_threads()} thread(s); {profile.describe(get_recipe())}\n"
          f"fit seed {args.seed}; fixed budget {budget} it; target = {tol:.2f} × best; hole RMSE ×100", flush=True)
    configs = recipes(profile, budget, args.seed)
    cases = {scene: make_case(scene, profile, holes="edge") for scene in args.scenes}
    runs = {}

    if "main" in args.parts or "c2f" in args.parts:
        for scene, case in cases.items():
            for name, config in configs.items():
                if name != "default" and "main" not in args.parts:
                    continue
                runs[scene, name] = fit(case, config)
                print(f"  ran {scene}/{name}: {runs[scene, name].iterations} it, {runs[scene, name].seconds:.0f} s",
                      flush=True)
    if "main" in args.parts:
        print("\n== recipes (rgbd+warp, edge holes)")
        for scene in cases:
            target = tol * min(best(runs[scene, n]) for n in configs)
            print(f"\n{scene}: best over recipes {target / tol:.2f}, target {target:.2f}\n{HEAD}")
            for name in configs:
                print(row(name, runs[scene, name], target))

    if "c2f" in args.parts:
        print("\n== coarse-to-fine (default recipe, scale 2, coarse_fraction 0.5)")
        for scene, case in cases.items():
            plain = runs[scene, "default"]
            c2f = fit(case, configs["default"], coarse_to_fine=True, scale=2, coarse_fraction=0.5)
            pool = [runs[k] for k in runs if k[0] == scene] + [c2f]
            target = tol * min(best(r) for r in pool)
            print(f"\n{scene}: best of all runs {target / tol:.2f}, target {target:.2f}\n{HEAD}")
            print(row("plain", plain, target))
            print(row("coarse-to-fine", c2f, target))
            n1, n2 = c2f.history["stage_iterations"]
            s1, s2 = c2f.history["stage_seconds"]
            print(f"{'':<22} stages: coarse {n1} it {s1:.1f} s ({s1 / n1:.3f} s/it), fine {n2} it {s2:.1f} s")

    if "warm" in args.parts:
        scene = args.warm_scene
        print(f"\n== warm start ({scene}, views 0 → 1 → 2, default recipe)")
        config = configs["default"]
        views = [make_case(scene, profile, ref=k, holes="edge") for k in range(3)]
        previous = fit(views[0], config)
        print(f"view 0 from scratch: kept {kept_error(previous):.2f}, {previous.iterations} it, {previous.seconds:.1f} s")
        for k in (1, 2):
            scratch = fit(views[k], config)
            warm = fit(views[k], config, init=previous)
            gentle = fit(views[k], config.replace(lr=config.paper.lr / 10, lr_milestones=()), init=previous)
            target = tol * min(best(scratch), best(warm), best(gentle))
            print(f"\nview {k}: best {target / tol:.2f}, target {target:.2f}\n{HEAD}")
            print(row("scratch", scratch, target))
            print(row(f"warm from view {k - 1}", warm, target))
            print(row("  same, lr/10 no decay", gentle, target))
            previous = warm

    if "precision" in args.parts:
        scene = args.warm_scene
        case = cases.get(scene) or make_case(scene, profile, holes="edge")
        print(f"\n== precision / memory format ({scene}, default recipe)")
        variants = {"float32": (False, False), "bf16": (True, False), "channels_last": (False, True),
                    "bf16+channels_last": (True, True)}  # (bf16: the config's, channels_last: the run's)
        results = {name: fit(case, configs["default"].replace(bf16=bf16),
                             options=RunOptions(progress=False, channels_last=channels_last))
                   for name, (bf16, channels_last) in variants.items()}
        target = tol * min(best(r) for r in results.values())
        print(f"best {target / tol:.2f}, target {target:.2f}\n{HEAD}")
        for name, result in results.items():
            print(row(name, result, target))


if __name__ == "__main__":
    main()
