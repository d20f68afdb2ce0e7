"""`ddp-lite complete` at a photo's own resolution: DDP fitted at the working size, brought back to full
size (a) by up-sampling alone and (b) by the full-resolution refinement (``classical.full_resolution``), against
every classical fill of ``baselines.BASELINES`` computed at that full size.

    python benchmarks/bench_full_resolution.py --data DIR --isa avx2 --out benchmarks/results/full_resolution.jsonl
    python benchmarks/bench_full_resolution.py --data DIR --cache /tmp/fits --fits-only     # the fits alone, cached
    python benchmarks/bench_full_resolution.py --data DIR --scenes Plastic/depthcomp --no-sgbm --seeds 0 1 2
    python benchmarks/bench_full_resolution.py --data DIR --scenes Plastic Baby1 Bowling1 Art Books Dolls --isa avx2 --recipe photo
    python benchmarks/bench_full_resolution.py --data DIR --scenes Plastic Baby1 Bowling1 --cache DIR --smoothness   # means of solves

Cases (each at full size, scored in the holes where the truth is known, RMSE of disparity in the image's own
pixels, f·B/Z):
  motorcycle/blobs   scikit-image's Middlebury 2014 Motorcycle (500×741), blob holes
                     (``random_holes(gt, 0.2, seed=1, blob_size=min(H, W)/10)``) over its unknown pixels;
  motorcycle/sgbm    the same photo with SGBM's own holes and SGBM's depth elsewhere
                     (``real_cases.make_real_case("sgbm", factor=1)``, 500×740);
  <scene>/blobs      Middlebury 2005/2006 scenes at HalfSize read from ``--data`` (``2006-Plastic/`` ...),
                     view1 and its truth, blob holes as above;
  plastic/depthcomp  ``--scenes Plastic/depthcomp``: Plastic at HalfSize with the paper's own Table 6 holes
                     (DepthComp's ``plastic-disp-hole.png`` under ``--data``, pooled from FullSize by 2×2 blocks).

The fit runs as ``complete`` runs it (``working_size.shrink``, ``complete_depth``, rgbd, ``--recipe``: the
``kit`` recipe by default; ``photo`` fits without the kit's hole terms, and its own solve runs once, at full
size, as in ``complete``). ``--cache DIR`` keeps each fit's working-size depth (an .npz per case, profile, recipe,
seed and ISA), so that the refinement and the fills can be measured again without fitting. A classical fill
that takes more than ``--fill-limit`` seconds (60) on a case runs in a child process and is stopped and
reported as skipped. Timings are printed with the CPU's vector flags; nothing here reads a fixed data path.
"""
from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
from isa import reexec_with_isa  # noqa: E402

if __name__ == "__main__":
    reexec_with_isa()  # before torch is imported

import argparse  # noqa: E402
import json  # noqa: E402
import multiprocessing  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from _common import (add_profile_args, check_output_folder, check_rows_out, existing_folder, parse_args,  # noqa: E402
                     positive_float, profile_from_args, seed_int)
from isa import isa_summary  # noqa: E402
from ddp_lite.method.profiles import get_profile  # noqa: E402

SCENES = ("Plastic", "Baby1", "Bowling1", "Art", "Books", "Dolls")


class Case:
    """One full-size case: ``rgb`` (H, W, 3), ``depth`` (H, W) metres NaN = hole, ``gt`` (H, W) metres NaN =
    unknown, ``fb`` px·m (disparity px = fb / Z − doffs; doffs cancels in a difference)."""

    def __init__(self, name, rgb, depth, gt, fb):
        self.name, self.rgb, self.depth, self.gt, self.fb = name, rgb, depth, gt, float(fb)
        self.scored = ~np.isfinite(depth) & np.isfinite(gt)

    def rmse_px(self, filled) -> float:
        s = self.scored
        return float(np.sqrt(np.mean((self.fb / filled[s] - self.fb / self.gt[s]) ** 2)))


def blob_holes(gt):
    from ddp_lite.classical.holes import random_holes
    H, W = gt.shape
    return random_holes(gt, fraction=0.2, seed=1, blob_size=min(H, W) / 10)[0]


def check_args(args) -> None:
    """Before any work (``ValueError`` naming the option): each of ``--scenes`` a folder under ``--data`` with
    holes it has, the cache folder and the rows file writable."""
    for entry in args.scenes if args.data else ():
        check_scene(args.data, entry)
    if args.cache:
        check_output_folder(args.cache, "--cache")
    if args.out:
        check_rows_out(args.out)


def check_scene(data, entry: str) -> tuple[str, str, list]:
    """``entry`` (``name`` or ``name/holes``) of ``--scenes``: (its folder under ``data``, the holes, DepthComp's
    hole files); ``ValueError`` naming ``--scenes`` otherwise."""
    from ddp_lite.data.installed import DEPTHCOMP_FILE
    name, _, holes = entry.partition("/")
    matches = [f for f in sorted(os.listdir(data)) if f.split("-", 1)[-1] == name]
    if not matches:
        raise ValueError(f"--scenes {entry!r}: --data {os.fspath(data)!r} has no folder for scene {name!r} "
                         f"(e.g. 2006-{name})")
    if holes not in ("", "blobs", "depthcomp"):
        raise ValueError(f"--scenes {entry!r}: the holes must be blobs (the default) or depthcomp")
    hole_files = sorted(Path(data).rglob(DEPTHCOMP_FILE)) if holes == "depthcomp" else []
    if holes == "depthcomp" and (name != "Plastic" or not hole_files):
        raise ValueError(f"--scenes {entry!r}: DepthComp's holes exist for Plastic only, in {DEPTHCOMP_FILE} under --data")
    return matches[0], holes, hole_files


def make_cases(data: str | None, scenes, sgbm: bool = True) -> list:
    """The cases named in the module's docstring, Motorcycle's first."""
    from ddp_lite.data.middlebury import load_motorcycle
    from ddp_lite.data.middlebury_rail import load_rail_scene
    cases = []
    scene = load_motorcycle()
    gt = scene[0].depth
    cases.append(Case("motorcycle/blobs", scene[0].rgb, blob_holes(gt), gt,
                      scene[0].camera.focal * scene.meta["baseline"]))
    if sgbm:
        from ddp_lite.studies.real_cases import make_real_case
        real = make_real_case("sgbm", factor=1)
        cases.append(Case("motorcycle/sgbm", real.rgb, real.depth, real.gt, real.fb))
    from ddp_lite.data.samples import read_depthcomp_holes
    for entry in scenes if data else ():
        name = entry.partition("/")[0]
        folder, holes, hole_files = check_scene(data, entry)
        rail = load_rail_scene(os.path.join(data, folder))
        gt = rail[0].depth
        if holes == "depthcomp":
            depth = np.where(read_depthcomp_holes(hole_files[0], gt.shape), np.nan, gt).astype(np.float32)
        else:
            depth = blob_holes(gt)
        cases.append(Case(f"{name.lower()}/{holes or 'blobs'}", rail[0].rgb, depth, gt,
                          rail[0].camera.focal * rail.meta["baseline"]))
    return cases


def fit_small(case: Case, profile, seed: int, cache: str | None, isa: str, recipe: str = "kit"):
    """DDP at the working size as ``complete`` fits it → (working-size completed depth, fit seconds, shape)."""
    from ddp_lite.method.complete import complete_depth
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.runtime.options import RunOptions
    from ddp_lite.sequences.working_size import shrink, working_shape
    shape = working_shape(case.depth.shape, max(profile.size))
    path = None
    if cache:
        os.makedirs(cache, exist_ok=True)
        tag = "" if recipe == "kit" else f"_{recipe}"  # the kit's fits keep the names they were cached under
        if tuple(profile.size) != tuple(get_profile(profile.name).size):  # --size: a fit at another working size
            tag += f"_{profile.size[0]}x{profile.size[1]}"
        path = os.path.join(cache, f"{case.name.replace('/', '_')}_{profile.name}{tag}_s{seed}_{isa}.npz")
        if os.path.exists(path):
            stored = np.load(path)
            return stored["depth"], float(stored["seconds"]), shape
    small_rgb, small_depth = shrink(case.rgb, case.depth, shape)
    # the recipe's own solve (photo) runs at full size in evaluate, as complete runs it: not also here
    config = FitConfig.for_profile(profile, variant="rgbd", recipe=recipe, seed=seed).replace(refine=False)
    start = time.perf_counter()
    result = complete_depth(small_rgb, small_depth, variant="rgbd", config=config, options=RunOptions(progress=False))
    seconds = time.perf_counter() - start
    if path:
        np.savez(path + ".tmp.npz", depth=result.depth, seconds=seconds)
        os.replace(path + ".tmp.npz", path)
    return result.depth, seconds, shape


def _fill_child(queue, name, disparity, rgb):
    from ddp_lite.classical import baselines
    start = time.perf_counter()
    out = baselines.BASELINES[name](disparity, rgb)
    queue.put((out, time.perf_counter() - start))


def classical_fill(name: str, case: Case, limit: float):
    """``BASELINES[name]`` on ``case`` at full size, in disparity as ``bench_quality`` does → (depth or None, s).
    None: it ran past ``limit`` seconds (stopped)."""
    disparity = case.fb / case.depth
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_fill_child, args=(queue, name, disparity, case.rgb))
    start = time.perf_counter()
    child.start()
    try:
        out, seconds = queue.get(timeout=limit)
    except Exception:  # queue.Empty: past the limit
        child.terminate()
        child.join()
        return None, time.perf_counter() - start
    child.join()
    return case.fb / out, seconds


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_profile_args(parser)
    parser.add_argument("--isa", default="native", choices=("native", "avx2"), help="native or avx2 (benchmarks/isa.py)")
    parser.add_argument("--data", type=existing_folder, help="a folder of Middlebury 2005/2006 scenes (2006-Plastic/ ...)")
    parser.add_argument("--scenes", nargs="+", default=list(SCENES[:3]),
                        help="scene names under --data (Plastic/depthcomp: the paper's own holes)")
    parser.add_argument("--no-sgbm", action="store_true", help="skip Motorcycle's SGBM holes")
    parser.add_argument("--seeds", type=seed_int, nargs="+", default=[0], help="the fit's seeds")
    from ddp_lite.method.kit.recipes import RECIPES
    parser.add_argument("--recipe", choices=tuple(RECIPES), default="kit", help="the fit's recipe")
    parser.add_argument("--cache", help="keep (and reuse) each fit's working-size depth in this folder")
    parser.add_argument("--fits-only", action="store_true", help="only run (and cache) the fits")
    parser.add_argument("--fill-limit", type=positive_float, default=60.0, help="seconds a classical fill may take")
    parser.add_argument("--sweep", action="store_true", help="try every refinement setting of SWEEP")
    parser.add_argument("--smoothness", action="store_true",
                        help="also the refinement averaged over the solves of each SMOOTHNESS_SWEEP setting")
    parser.add_argument("--out", help="append one JSON line per case and seed here")
    args = parse_args(parser, argv, check_args)
    profile = profile_from_args(args)
    print(isa_summary(), f"; torch threads {args.threads}", flush=True)
    cases = make_cases(args.data, args.scenes, sgbm=not args.no_sgbm)
    for case in cases:
        for seed in args.seeds:
            small, seconds, shape = fit_small(case, profile, seed, args.cache, args.isa, args.recipe)
            print(f"{case.name} seed {seed}: fit at {shape[0]}×{shape[1]} {seconds:.1f} s", flush=True)
    if args.fits_only:
        return
    sweep = {"default": {}, **(SWEEP if args.sweep else {}),
             **({k: {"settings": v} for k, v in SMOOTHNESS_SWEEP.items()} if args.smoothness else {})}
    rows = []
    for case in cases:
        fills = {name: cached_fill(name, case, args.fill_limit, args.cache) for name in FILL_NAMES}
        for seed in args.seeds:
            small, seconds, shape = fit_small(case, profile, seed, args.cache, args.isa, args.recipe)
            row = evaluate(case, small, sweep, fills)
            row.update(case=case.name, seed=seed, profile=profile.name, recipe=args.recipe, isa=args.isa,
                       threads=args.threads, shape=list(case.depth.shape), working=list(shape), fit_seconds=seconds,
                       holes=float((~np.isfinite(case.depth)).mean()), scored=int(case.scored.sum()))
            row["fills"] = {name: (None if out is None else case.rmse_px(out)) for name, (out, _) in fills.items()}
            row["fill_seconds"] = {name: s for name, (_, s) in fills.items()}
            scored = {k: v for k, v in row["fills"].items() if v is not None}
            row["best_fill"] = min(scored, key=scored.get)
            rows.append(row)
            if args.out:
                with open(args.out, "a") as out:
                    out.write(json.dumps(row) + "\n")
            report(row)
    print(f"\nhole RMSE at full size (disparity px), '{profile.name}', {args.recipe} recipe, rgbd; seconds taken with "
          f"{args.threads} torch thread(s), ISA {args.isa} (see the CPU line)")
    print(f"{'case':<18}{'seed':>5}{'full-res':>10}{'upsampled':>11}  {'best fill':<26}{'ratio':>7}{'refine s':>10}{'fit s':>8}")
    for r in rows:
        best = r["best_fill"]
        print(f"{r['case']:<18}{r['seed']:>5}{r['refined']['default']:>10.3f}{r['DDP-upsampled']:>11.3f}  "
              f"{best + ' ' + format(r['fills'][best], '.3f'):<26}{r['refined']['default'] / r['fills'][best]:>7.3f}"
              f"{r['refine_seconds']['default']:>10.2f}{r['fit_seconds']:>8.1f}")
    if rows and rows[0]["mixed"]:
        print("\nthe refined fit mixed with a share of a full-size fill: hole RMSE (px) per case, mean ratio to the best fill")
        for key in rows[0]["mixed"]:
            ratios = [r["mixed"][key] / r["fills"][r["best_fill"]] for r in rows]
            print(f"{key:<28}" + "".join(f"{r['mixed'][key]:>8.3f}" for r in rows) + f"   ratio {np.mean(ratios):.3f} "
                  f"(below 1 on {sum(x < 1 for x in ratios)} of {len(ratios)})")
    if args.sweep or args.smoothness:
        print("\nsweep: hole RMSE (px) per case, and the mean of each setting's ratio to the best fill")
        for key in [k for k in sweep if k != "default"]:
            ratios = [r["refined"][key] / r["fills"][r["best_fill"]] for r in rows]
            print(f"{key:<48}" + "".join(f"{r['refined'][key]:>8.3f}" for r in rows) + f"   ratio {np.mean(ratios):.3f}")


MIX_SHARES = (0.25, 0.5, 0.6, 0.7, 0.8)  # shares of a full-size fill mixed into the refined fit
FILL_NAMES = ("nearest", "linear", "cubic", "telea", "navier-stokes", "biharmonic", "colorization", "guided-filter",
              "bilateral-solver", "cross-bilateral")

# settings the sweep tries: name → refine_full_resolution keywords (a first, wider sweep chose the FGS and
# guided-filter settings below and showed that the residual correction is what beats the best fill)
SWEEP = {}
for _residual in (False, True):
    for _conf in (0.003, 0.01, 0.03):
        SWEEP[f"bs c={_conf} residual={_residual}"] = dict(method="bilateral-solver", hole_confidence=_conf,
                                                          residual=_residual)
    SWEEP[f"fgs lam=100 c=0.03 residual={_residual}"] = dict(method="fgs", lam=100, hole_confidence=0.03,
                                                             residual=_residual)
    SWEEP[f"gf r=8 c=0.03 residual={_residual}"] = dict(method="guided-filter", radius=8, hole_confidence=0.03,
                                                        residual=_residual)

# the refinement as `photo` runs it at its working size: the mean (in disparity) of the bilateral solver's solves
# over (sigma_xy px, lam) settings; at full size the image is 3.5-4x the working size, so the reach is scaled too
SMOOTHNESS_SWEEP = {
    "one (8, 16)": ((8.0, 16.0),),
    "one (16, 4)": ((16.0, 4.0),),
    "mean (4|8 x 4|16)": ((4.0, 4.0), (4.0, 16.0), (8.0, 4.0), (8.0, 16.0)),
    "mean (8|16 x 4|16)": ((8.0, 4.0), (8.0, 16.0), (16.0, 4.0), (16.0, 16.0)),
    "mean (16|32 x 4|16)": ((16.0, 4.0), (16.0, 16.0), (32.0, 4.0), (32.0, 16.0)),
    "mean (8|16|32 x 4|16)": ((8.0, 4.0), (8.0, 16.0), (16.0, 4.0), (16.0, 16.0), (32.0, 4.0), (32.0, 16.0)),
}


def cached_fill(name: str, case: Case, limit: float, cache: str | None):
    """``classical_fill`` once per case (kept in ``cache``): → (depth or None, seconds)."""
    path = os.path.join(cache, f"fill_{case.name.replace('/', '_')}_{name}.npz") if cache else None
    if path and os.path.exists(path):
        stored = np.load(path)
        return (None if stored["depth"].ndim == 0 else stored["depth"]), float(stored["seconds"])
    out, seconds = classical_fill(name, case, limit)
    print(f"  {case.name}: {name} {'skipped, over the limit' if out is None else 'done'} ({seconds:.1f} s)", flush=True)
    if path:
        np.savez(path + ".tmp.npz", depth=np.array(np.nan) if out is None else out, seconds=seconds)
        os.replace(path + ".tmp.npz", path)
    return out, seconds


def evaluate(case: Case, small, sweep: dict, fills: dict | None = None) -> dict:
    """DDP up-sampled into the holes, and refined at full size by each setting of ``sweep`` → RMSEs, seconds;
    and the default refinement mixed, in disparity, with a share of a full-size fill of ``fills`` ({name:
    (depth or None, seconds)}): the bilateral solver alone, and its mean with colorization (the fill the
    ``kit`` recipe mixes in at the working size) → ``row["mixed"]["<fill> <share>"]``."""
    from ddp_lite.classical.full_resolution import refine_full_resolution, refine_over_smoothness
    from ddp_lite.sequences.working_size import fill_holes_at_full_size
    upsampled = fill_holes_at_full_size(case.depth, small)
    target = fill_holes_at_full_size(case.depth, small, raw=True)
    row = {"DDP-upsampled": case.rmse_px(upsampled), "refined": {}, "refine_seconds": {}}
    for key, kwargs in sweep.items():
        start = time.perf_counter()
        if "settings" in kwargs:  # several solves averaged
            refined = refine_over_smoothness(case.depth, case.rgb, target, kwargs["settings"])
        else:
            refined = refine_full_resolution(case.depth, case.rgb, target, **kwargs)
        row["refine_seconds"][key] = time.perf_counter() - start
        assert np.array_equal(refined[~case.scored & np.isfinite(case.depth)],
                              case.depth[~case.scored & np.isfinite(case.depth)])
        row["refined"][key] = case.rmse_px(refined)
        if key == "default":
            default = refined
    row["mixed"] = {}
    partners = {}  # name → (H, W) disparity px
    if fills and fills.get("bilateral-solver", (None,))[0] is not None:
        partners["bilateral-solver"] = case.fb / fills["bilateral-solver"][0]
        if fills.get("colorization", (None,))[0] is not None:
            partners["mean"] = (partners["bilateral-solver"] + case.fb / fills["colorization"][0]) / 2
    for name, fill in partners.items():
        for share in MIX_SHARES:
            mixed = (1 - share) * case.fb / default + share * fill
            row["mixed"][f"{name} {share}"] = case.rmse_px(case.fb / mixed)
    return row


def report(row: dict) -> None:
    refined = row["refined"].get("default")
    fills = {k: v for k, v in row["fills"].items()}
    best = row["best_fill"]
    print(f"{row['case']} seed {row['seed']} ({row['shape'][0]}×{row['shape'][1]}, {row['holes']:.1%} holes, "
          f"fit at {row['working'][0]}×{row['working'][1]} {row['fit_seconds']:.1f} s): "
          + (f"DDP full-res {refined:.3f} px ({row['refine_seconds']['default']:.2f} s), " if refined else "")
          + f"DDP upsampled {row['DDP-upsampled']:.3f}, best fill {best} {fills[best]:.3f}; "
          + ", ".join(f"{k} {'skipped' if v is None else f'{v:.3f}'}" for k, v in fills.items()), flush=True)


if __name__ == "__main__":
    main()
