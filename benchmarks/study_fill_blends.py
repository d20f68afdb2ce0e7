"""How much of a classical fill should DDP mix in, and which fill? Rules judged on the real suite, chosen on one
half of the scenes and confirmed on the other.

    python benchmarks/study_fill_blends.py --data DIR fit [--seeds 0 1] [--cases Art/sgbm ...]   # the fits (slow)
    python benchmarks/study_fill_blends.py --data DIR fit --channels 8 16 32 64 128 --fits DIR2   # the narrow net
    python benchmarks/study_fill_blends.py --data DIR fit --set fill_input=1 --fits DIR3          # other settings
    python benchmarks/study_fill_blends.py --data DIR fit --set warp_confidence=true --fits DIR4   # (true/false)
    python benchmarks/study_fill_blends.py --data DIR report --fits DIR3 --core --out R3 --against R  # paired
    python benchmarks/study_fill_blends.py --data DIR report [--seeds 0 1]                        # the rules (minutes)
    python benchmarks/study_fill_blends.py --data DIR report --seeds 0 1 2 --from-rows a.jsonl b.jsonl  # their tables
    python benchmarks/study_fill_blends.py --data DIR stereo-grid --seeds 0 1 2 --out R4           # a matcher's depth
    python benchmarks/study_fill_blends.py --data DIR answer-rules --seeds 0 1 2 --out R5          # other answers
    python benchmarks/study_fill_blends.py --data DIR warp-scenes --from-rows R R_rgbd             # the warp term, per scene
    python benchmarks/study_fill_blends.py --data DIR per-case --from-rows R R_rgbd                # the per-scene table
    python benchmarks/study_fill_blends.py --data DIR per-case --from-rows R R_rgbd P P_rgbd       # ... photo's own fits

The best classical fill differs from case to case (the bilateral solver on most, colorization on
occlusions, the guided filter on Plastic's strokes), so "DDP over the best fill" compares DDP with an
oracle. A method may only choose from what the input shows. Here every choice is made on **held-out
valid depth**: 5 % of the valid pixels in hole-like blobs (``kit.blend.fill_held_out_mask``) are taken out of
the input before DDP fits and before every fill runs, and the rule picks what predicts them best.

``fit``: one ``kit`` DDP fit per case and seed on the held-out input, without the fill's share
(``blend_fill=0``), ``class`` at the suite's size; its depth and the held-out mask are saved to
``--fits`` (one ``.npz`` per case and seed; a saved one is skipped, so a stopped run resumes).

``report``: per case, every fill of the held-out input (scored on the held-out blobs) and of the whole
input (scored in the holes), and these rules for the answer in the holes (disparity, ``(1 − f)·DDP +
f·fill``):

- ``fit``: DDP alone (f = 0); ``kit``: f = ¼ of the mean of colorization and the bilateral solver (the
  ``kit`` recipe today);
- ``fixed f``: f of that mean, f = 0.1 … 1 (1: the mean fill alone);
- ``chosen share``: f ∈ {0, 0.1, …, 1} that best predicts the held-out blobs, of that mean;
- ``chosen fill``: the fill that best predicts the held-out blobs, alone (no DDP);
- ``chosen fill + share``: that fill, and the share of it that best predicts the blobs;
- ``refined c=…``: DDP's fit as the target of the edge-aware solve ``complete`` runs at a photo's full size
  (``classical.full_resolution``: the bilateral solver guided by the image, confidence 1 on the valid input
  and c on the fit in the holes, after the fit's own error on the valid pixels is carried into them);
  ``refined + f``: that (c = 0.01) with f of the mean fill mixed in after; ``f, refined``: f of the mean fill
  mixed into the fit first, then refined;
- ``solve s,λ + ¼``: the refinement with the bilateral solver's spatial reach ``sigma_xy`` = s px and
  smoothness ``lam`` = λ (the default is 8, 4), then ¼ of the mean fill; ``chosen solve + ¼``: the (s, λ) that
  best predicts the held-out blobs (the refinement run on the held-out input); ``mean of 4 / 9 solves + ¼``:
  the refinements over s ∈ {4, 8} × λ ∈ {4, 16} (or all nine) averaged in disparity, then ¼ of the fill;
- ``stereo solves + 0.25``: ``depth_source="stereo"``, for a matcher's depth: the solves and the fill
  read the input without the 1 px rim of its holes (``kit.blend.trusted_depth``), the solves over s ∈ {8, 16}
  × λ ∈ {4, 16} (``SMOOTHNESS_STEREO``); ``photo by source``: that rule where the input is SGBM's
  depth, the mean of 4 where it is the ground truth with holes (blobs, occlusions, Plastic's strokes).

Each rule's hole RMSE over the best fill of the case (the suite's yardstick), means per hole kind, per
half (A: Art, Dolls, Moebius, Baby1, Baby3, Bowling2, Adirondack, Jadeplant, Pipes, Playtable;
B: Books, Laundry, Reindeer, Baby2, Bowling1, Plastic, ArtL, Piano, Playroom, Motorcycle) and over seeds.
Rows (one per case, seed and rule) to ``--out``. Asserts nothing.
"""
from __future__ import annotations

import argparse
import json
import os
import time
from collections import defaultdict
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy import ndimage  # noqa: E402

from ddp_lite.classical.baselines import BASELINES  # noqa: E402
from ddp_lite.core.files import atomic_path, write_bytes_atomic  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402
from ddp_lite.classical.full_resolution import SMOOTHNESS_STEREO, refine_full_resolution, refine_over_smoothness  # noqa: E402
from ddp_lite.method.kit.blend import FILL_MEMBERS, best_fill_share, fill_held_out_mask, trusted_depth  # noqa: E402
from bench_real import table6_fills  # noqa: E402
from ddp_lite.studies.real_suite import (SUITE_HALF_A, SUITE_HOLES, make_suite_case, suite_case_names,  # noqa: E402
                                         suite_half)
from _common import (check_configs, check_output_folder, check_rows_out, data_root, existing_file,  # noqa: E402
                     parse_args, positive_int, read_rows, seed_int)

RESULTS = Path(__file__).resolve().parent / "results"
HALF_A = SUITE_HALF_A  # the scenes rules are chosen on (ddp_lite.studies.real_suite)
SHARES = tuple(round(0.1 * k, 1) for k in range(11))
KIT_SHARE = 0.25
REFINE_CONFIDENCES = (0.01, 0.1)
REFINED_SHARES = (0.25, 0.5, 0.7)
SMOOTHNESS = tuple((s, lam) for s in (4.0, 8.0, 16.0) for lam in (1.0, 4.0, 16.0))  # the solve's (sigma_xy px, lam)
STEREO_RULE = "stereo solves + 0.25"  # depth_source="stereo": the rim not read, SMOOTHNESS_STEREO
BY_SOURCE_RULE = "photo by source"  # the stereo rule on a matcher's depth (sgbm), the mean of 4 elsewhere
STEREO_KINDS = ("sgbm",)  # the hole kinds whose input is a stereo matcher's depth
SOLVE_MEANS = {"mean of 4 solves": ((4.0, 4.0), (4.0, 16.0), (8.0, 4.0), (8.0, 16.0)), "mean of 9 solves": SMOOTHNESS}


def half(case: str) -> str:
    """"A" or "B": the half of the suite the case's scene is in."""
    return suite_half(case)


def held_out_input(case, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The case's input with ``fill_held_out_mask``'s blobs of valid depth taken out, and those blobs (H, W) bool."""
    held_out = fill_held_out_mask(np.isfinite(case.depth), seed)
    return np.where(held_out, np.nan, case.depth).astype(np.float32), held_out


def fit(data, names, seeds, fits: Path, variant: str, size: str, channels: tuple | None = None,
        settings: dict | None = None) -> None:
    """One kit fit per case and seed on the held-out input, saved to ``fits`` (``channels``: the net's
    encoder widths, None → the profile's; ``settings``: other ``FitConfig`` fields, e.g. ``fill_input``)."""
    fits.mkdir(parents=True, exist_ok=True)
    # what changes a saved fit besides its case, variant and seed (its name): a resumed run reuses only its own
    made_with = json.dumps(dict(size=size, channels=list(channels) if channels else None, settings=settings or {}),
                           sort_keys=True)
    start = time.perf_counter()
    for seed in seeds:
        for name in names:
            path = fits / f"{name.replace('/', '__')}__{variant}__{seed}.npz"
            if path.exists():
                with np.load(path) as saved:
                    made = str(saved["made_with"]) if "made_with" in saved.files else None
                if made is not None and made != made_with:
                    raise ValueError(f"--fits {fits}: {path.name} was fitted with {made}, this run fits with "
                                     f"{made_with}; give another --fits folder")
                continue
            case = make_suite_case(data, name, size)
            depth, held_out = held_out_input(case, seed)
            config = FitConfig.for_profile("class", variant=variant, recipe="kit", seed=seed, blend_fill=0.0,
                                           **({"channels": channels} if channels else {}), **(settings or {}))
            began = time.perf_counter()
            neighbors = case.neighbors if variant == "rgbd+warp" else ()
            result = complete_depth(case.rgb, depth, case.camera, neighbors, variant=variant, config=config,
                                    options=RunOptions(progress=False))
            seconds = time.perf_counter() - began
            with atomic_path(path) as temporary:
                np.savez_compressed(temporary, depth=result.depth, held_out=held_out, seconds=seconds,
                                    made_with=np.array(made_with))
            print(f"{name:<24} seed {seed}: {seconds:.0f} s ({(time.perf_counter() - start) / 60:.1f} min in all)",
                  flush=True)


def _saved_depth(saved, path: Path, case) -> np.ndarray:
    """A saved fit's depth (H, W) metres; ``ValueError`` when it was fitted at another size than ``case``'s."""
    depth = saved["depth"]
    if depth.shape != case.depth.shape:
        raise ValueError(f"--fits: {path} is {depth.shape[0]}×{depth.shape[1]}, the case at this --size "
                         f"{case.depth.shape[0]}×{case.depth.shape[1]}: fitted at another size; give its --size or "
                         f"another --fits folder")
    return depth


def _rmse(estimate: np.ndarray, truth: np.ndarray, mask: np.ndarray) -> float:
    return float(np.sqrt(np.mean((estimate[mask] - truth[mask]) ** 2)))


def rules(case, fit_depth: np.ndarray, held_out: np.ndarray, seed: int, core: bool = False) -> dict[str, float]:
    """{rule: hole RMSE in disparity px} for one case and its saved fit (module docstring); ``core``: only
    the fills, ``fit``, ``kit``, ``fixed 1.0``, ``refined + 0.25`` and ``mean of 4 solves + 0.25`` (a
    fifth of the time, enough to compare two sets of fits)."""
    held_depth = np.where(held_out, np.nan, case.depth)
    truth_in = case.fb / case.depth  # (H, W) px disparity of the input, NaN in its holes
    fit_px = case.fb / fit_depth
    fills_all = {n: f(truth_in, case.rgb) for n, f in BASELINES.items()}  # (H, W) px each
    mean_all = np.mean([fills_all[n] for n in FILL_MEMBERS], axis=0)
    holes = case.scored_holes

    def score(px):  # the input where it is valid, px in its holes
        return case.rmse_px(case.fb / np.where(np.isfinite(case.depth), truth_in, px), holes)

    trusted = trusted_depth(case.depth, "stereo")  # the input without the 1 px rim of its holes
    stereo_fill = np.mean([BASELINES[n](case.fb / trusted, case.rgb) for n in FILL_MEMBERS], axis=0)
    stereo = case.fb / refine_over_smoothness(trusted, case.rgb, fit_depth, SMOOTHNESS_STEREO)
    stereo_rule = {STEREO_RULE: score((1 - KIT_SHARE) * stereo + KIT_SHARE * stereo_fill)}
    if core:
        out = {f"fill {n}": score(px) for n, px in fills_all.items()}
        out.update(stereo_rule)
        out["fit"] = score(fit_px)
        out["kit"] = score((1 - KIT_SHARE) * fit_px + KIT_SHARE * mean_all)
        out["fixed 1.0"] = score(mean_all)
        refined = {k: case.fb / refine_full_resolution(case.depth, case.rgb, fit_depth, sigma_xy=k[0], lam=k[1])
                   for k in SOLVE_MEANS["mean of 4 solves"]}
        out["refined + 0.25"] = score((1 - KIT_SHARE) * refined[8.0, 4.0] + KIT_SHARE * mean_all)
        out["mean of 4 solves + 0.25"] = score((1 - KIT_SHARE) * np.mean(list(refined.values()), axis=0)
                                               + KIT_SHARE * mean_all)
        return out
    fills_held = {n: f(case.fb / held_depth, case.rgb) for n, f in BASELINES.items()}
    mean_held = np.mean([fills_held[n] for n in FILL_MEMBERS], axis=0)

    def chosen_share(fill_held):  # the kit's own held-out choice, over shares up to the fill alone
        return best_fill_share(fit_px, fill_held, truth_in, held_out, SHARES)[0]

    out = {f"fill {n}": score(px) for n, px in fills_all.items()}
    out.update(stereo_rule)
    out["fit"] = score(fit_px)
    out["kit"] = score((1 - KIT_SHARE) * fit_px + KIT_SHARE * mean_all)
    for f in SHARES[1:]:
        out[f"fixed {f:.1f}"] = score((1 - f) * fit_px + f * mean_all)
    f = chosen_share(mean_held)
    out["chosen share"], out["chosen share: f"] = score((1 - f) * fit_px + f * mean_all), f
    best = min(fills_held, key=lambda n: _rmse(fills_held[n], truth_in, held_out))
    out["chosen fill"] = score(fills_all[best])
    f = chosen_share(fills_held[best])
    out["chosen fill + share"], out["chosen fill + share: f"] = score((1 - f) * fit_px + f * fills_all[best]), f
    out["chosen fill: name"] = best
    for confidence in REFINE_CONFIDENCES:  # the fit as the target of the edge-aware solve complete runs at full size
        refined = refine_full_resolution(case.depth, case.rgb, fit_depth, hole_confidence=confidence)
        out[f"refined c={confidence:g}"] = score(case.fb / refined)
    refined_px = case.fb / refine_full_resolution(case.depth, case.rgb, fit_depth)
    for f in REFINED_SHARES:
        out[f"refined + {f:g}"] = score((1 - f) * refined_px + f * mean_all)
        mixed = case.fb / ((1 - f) * fit_px + f * mean_all)  # (H, W) metres
        out[f"{f:g}, refined"] = score(case.fb / refine_full_resolution(case.depth, case.rgb, mixed))
    solves, predicted = {}, {}  # (s, λ) → (H, W) px of the whole input's refinement; → held-out RMSE
    for s, lam in SMOOTHNESS:
        solves[s, lam] = case.fb / refine_full_resolution(case.depth, case.rgb, fit_depth, sigma_xy=s, lam=lam)
        held_refined = case.fb / refine_full_resolution(held_depth, case.rgb, fit_depth, sigma_xy=s, lam=lam)
        predicted[s, lam] = _rmse(held_refined, truth_in, held_out)
        out[f"solve {s:g},{lam:g} + 0.25"] = score((1 - KIT_SHARE) * solves[s, lam] + KIT_SHARE * mean_all)
    chosen = min(SMOOTHNESS, key=predicted.get)
    out["chosen solve + 0.25"] = score((1 - KIT_SHARE) * solves[chosen] + KIT_SHARE * mean_all)
    out["chosen solve: s,lam"] = f"{chosen[0]:g},{chosen[1]:g}"
    for name, settings in SOLVE_MEANS.items():
        out[f"{name} + 0.25"] = score((1 - KIT_SHARE) * np.mean([solves[k] for k in settings], axis=0)
                                      + KIT_SHARE * mean_all)
    return out


def report(data, names, seeds, fits: Path, variant: str, size: str, out: Path, from_rows: list[Path],
           other_fits: Path | None = None, core: bool = False) -> None:
    rows = [row for path in from_rows for row in read_rows(path)]
    rows = [r for r in rows if r["seed"] in seeds and r["case"] in names]
    for seed in seeds if not from_rows else ():
        for name in names:
            path = fits / f"{name.replace('/', '__')}__{variant}__{seed}.npz"
            if not path.exists():
                continue
            case = make_suite_case(data, name, size)
            with np.load(path) as saved:
                scores = rules(case, _saved_depth(saved, path, case), saved["held_out"], seed, core)
                seconds = float(saved["seconds"])
            rows.append(dict(case=name, seed=seed, variant=variant, size=size, half=half(name), fit_seconds=seconds,
                             **scores))
    if not rows:
        print(f"no fits in {fits}")
        return
    if not from_rows:
        write_bytes_atomic(out, "".join(json.dumps(r) + "\n" for r in rows).encode())
    fills = [k for k in rows[0] if k.startswith("fill ")]
    ratio_keys = ["fit", "kit"] + [f"fixed {f:.1f}" for f in SHARES[1:]] + [
        "chosen share", "chosen fill", "chosen fill + share"] + [f"refined c={c:g}" for c in REFINE_CONFIDENCES] + [
        f"refined + {f:g}" for f in REFINED_SHARES] + [f"{f:g}, refined" for f in REFINED_SHARES] + [
        f"solve {s:g},{lam:g} + 0.25" for s, lam in SMOOTHNESS] + ["chosen solve + 0.25"] + [
        f"{name} + 0.25" for name in SOLVE_MEANS] + [STEREO_RULE, BY_SOURCE_RULE]
    table6 = [f"fill {n}" for n in table6_fills()]
    for r in rows:
        r["best"] = min(r[k] for k in fills)
        by_source(r)
        r["best Table 6"] = min(r[k] for k in table6 if k in r)
    ratio_keys = [k for k in ratio_keys if all(k in r for r in rows)]  # core rows hold a few
    groups = [("A", lambda r: r["half"] == "A"), ("B", lambda r: r["half"] == "B")] + [
        (kind, lambda r, k=kind: r["case"].endswith("/" + k)) for kind in SUITE_HOLES] + [("all", lambda r: True)]
    for against in ("best", "best Table 6"):
        print(f"\n{len(rows)} case-seeds ({variant}, {size}, seeds {sorted({r['seed'] for r in rows})}); "
              f"rule's hole RMSE / the {against} fill's, mean over cases (on how many below 1.0)")
        print(f"{'rule':<26}" + "".join(f"{g:>16}" for g, _ in groups))
        for key in ratio_keys:
            cells = []
            for _, keep in groups:
                chosen = [r[key] / r[against] for r in rows if keep(r)]
                cells.append(f"{np.mean(chosen):.3f} ({sum(x < 1 for x in chosen)}/{len(chosen)})" if chosen else "-")
            print(f"{key:<26}" + "".join(f"{c:>16}" for c in cells))
    for label, pool in (("fill", fills), ("Table 6 method", table6)):
        print(f"\nagainst the strongest single {label} of each group (the one nearest the best fill of each case "
              f"on the group's mean): rule's hole RMSE / that {label}'s, mean over cases (on how many below 1.0)")
        strongest = {g: min((f for f in pool if all(f in r for r in rows)), key=lambda f: np.mean(
            [r[f] / r["best"] for r in rows if keep(r)] or [np.inf])) for g, keep in groups}
        print(f"{'':<26}" + "".join(f"{strongest[g][5:]:>18}" for g, _ in groups))
        for key in [k for k in ("kit", "refined + 0.25", "mean of 4 solves + 0.25", BY_SOURCE_RULE) if k in ratio_keys]:
            cells = []
            for g, keep in groups:
                chosen = [r[key] / r[strongest[g]] for r in rows if keep(r)]
                cells.append(f"{np.mean(chosen):.3f} ({sum(x < 1 for x in chosen)}/{len(chosen)})" if chosen else "-")
            print(f"{key:<26}" + "".join(f"{c:>18}" for c in cells))
    print(f"\npaired against `photo` (refined + 0.25): mean change of the hole RMSE (lower on how many)")
    for key in ratio_keys:
        cells = []
        for _, keep in groups:
            change = [r[key] / r["refined + 0.25"] - 1 for r in rows if keep(r)]
            cells.append(f"{100 * np.mean(change):+.1f}% ({sum(x < 0 for x in change)}/{len(change)})" if change else "-")
        print(f"{key:<26}" + "".join(f"{c:>16}" for c in cells))
    if not from_rows:
        print(f"rows to {out}")
    if other_fits:
        compare(rows, read_rows(other_fits), groups)
    if "chosen share: f" not in rows[0]:
        return
    shares = defaultdict(list)
    for r in rows:
        shares[r["case"].split("/")[1]].append(r["chosen share: f"])
    print("chosen share of the mean fill, per hole kind: " + ", ".join(
        f"{k} {np.mean(v):.2f}" for k, v in shares.items()))
    names_chosen = defaultdict(int)
    for r in rows:
        names_chosen[r["chosen fill: name"]] += 1
    print("fill chosen on the held-out blobs: " + ", ".join(f"{k} {v}" for k, v in sorted(
        names_chosen.items(), key=lambda kv: -kv[1])))
    solves_chosen = defaultdict(lambda: defaultdict(int))
    for r in rows:
        solves_chosen[r["case"].split("/")[1]][r["chosen solve: s,lam"]] += 1
    print("solve (sigma_xy, lam) chosen on the held-out blobs, per hole kind: " + "; ".join(
        f"{kind} " + ", ".join(f"({k}) {v}" for k, v in sorted(c.items(), key=lambda kv: -kv[1])[:3])
        for kind, c in solves_chosen.items()))


STEREO_GRID = {"mean of 4": None, "one (16, 16)": ((16.0, 16.0),), "stereo 4": SMOOTHNESS_STEREO}  # None: the mean
RIMS = (0, 1, 2)  # px of the rim not read


def stereo_grid(data, names, seeds, fits: Path, variant: str, size: str, out: Path) -> None:
    """How a stereo matcher's depth was chosen for: on the cases whose input is SGBM's, the solves of
    ``STEREO_GRID`` on the input without a rim of ``RIMS`` px (the fill read likewise), then ¼ of that fill;
    each over the best fill of the case, per half. Rows to ``out``."""
    from ddp_lite.classical.full_resolution import SMOOTHNESS_MEAN
    rows = []
    for seed in seeds:
        for name in names:
            path = fits / f"{name.replace('/', '__')}__{variant}__{seed}.npz"
            if name.split("/")[1] not in STEREO_KINDS or not path.exists():
                continue
            case = make_suite_case(data, name, size)
            with np.load(path) as saved:
                fit_depth = _saved_depth(saved, path, case)
            valid = np.isfinite(case.depth)
            truth_in = case.fb / case.depth

            def score(px):
                return case.rmse_px(case.fb / np.where(valid, truth_in, px), case.scored_holes)
            row = dict(case=name, seed=seed, half=half(name),
                       best=min(score(f(truth_in, case.rgb)) for f in BASELINES.values()))
            for rim in RIMS:
                depth = np.where(ndimage.binary_dilation(~valid, iterations=rim), np.nan, case.depth) if rim else case.depth
                fill = np.mean([BASELINES[n](case.fb / depth, case.rgb) for n in FILL_MEMBERS], axis=0)
                for label, settings in STEREO_GRID.items():
                    solve = case.fb / refine_over_smoothness(depth, case.rgb, fit_depth, settings or SMOOTHNESS_MEAN)
                    row[f"rim {rim}, {label}"] = score((1 - KIT_SHARE) * solve + KIT_SHARE * fill)
            rows.append(row)
            print(f"{name:<22} seed {seed}", flush=True)
    write_bytes_atomic(out, "".join(json.dumps(r) + "\n" for r in rows).encode())
    keys = [k for k in rows[0] if k.startswith("rim ")]
    print(f"\n{len(rows)} case-seeds of a matcher's depth; hole RMSE / the best fill's, mean (on how many below 1.0)")
    for key in keys:
        cells = []
        for h in ("A", "B"):
            ratios = [r[key] / r["best"] for r in rows if r["half"] == h]
            cells.append(f"{np.mean(ratios):.3f} ({sum(x < 1 for x in ratios)}/{len(ratios)})")
        print(f"{key:<26}" + "".join(f"{c:>16}" for c in cells))
    print(f"rows to {out}")


ANSWER_RULES = ("photo by source", "rim share 0.75, 1 px", "median of fit, solve, colorization",
                "mean of the seeds' solves + 0.25")


def answer_rules(data, names, seeds, fits: Path, variant: str, size: str, out: Path) -> None:
    """What else the answer could be made of, from the saved fits, against ``photo`` by source (S: its solves,
    F: its fill, both reading the input as its source says; the answer (1 − f)·S + f·F, f = ¼):

    - ``rim share 0.75, 1 px``: f per pixel, 0.25 + 0.5·exp(−(d − 1) / 1 px), d the distance (px) into the
      hole from the nearest valid pixel read: more of the fill beside the rim, where it interpolates;
    - ``median of fit, solve, colorization``: per pixel, the median of the fit, S and the colorization fill;
    - ``mean of the seeds' solves + 0.25``: S averaged over the fits of every seed (an ensemble of fits).

    Per case and seed, hole RMSE over the best fill of the case; rows to ``out``."""
    rows, solves = [], defaultdict(list)
    for name in names:
        case = make_suite_case(data, name, size)
        source = case.depth_source  # "stereo" for SGBM's depth
        trusted = trusted_depth(case.depth, source)
        truth_in = case.fb / case.depth
        fills = {n: f(case.fb / trusted, case.rgb) for n, f in BASELINES.items()}  # (H, W) px each
        fill = np.mean([fills[n] for n in FILL_MEMBERS], axis=0)
        best = min(case.rmse_px(case.fb / np.where(np.isfinite(case.depth), truth_in, f(truth_in, case.rgb)))
                   for f in BASELINES.values())
        into_hole = ndimage.distance_transform_edt(~np.isfinite(trusted))  # (H, W) px

        def score(px):
            return case.rmse_px(case.fb / np.where(np.isfinite(case.depth), truth_in, px))
        for seed in seeds:
            path = fits / f"{name.replace('/', '__')}__{variant}__{seed}.npz"
            if not path.exists():
                continue
            with np.load(path) as saved:
                fit_depth = _saved_depth(saved, path, case)
            solve = case.fb / refine_over_smoothness(trusted, case.rgb, fit_depth,
                                                     SMOOTHNESS_STEREO if source == "stereo" else SOLVE_MEANS["mean of 4 solves"])
            solves[name].append(solve)
            share = KIT_SHARE + 0.5 * np.exp(-(into_hole - 1.0))
            rows.append({"case": name, "seed": seed, "half": half(name), "best": best,
                         ANSWER_RULES[0]: score((1 - KIT_SHARE) * solve + KIT_SHARE * fill),
                         ANSWER_RULES[1]: score((1 - share) * solve + share * fill),
                         ANSWER_RULES[2]: score(np.median([case.fb / fit_depth, solve, fills["colorization"]], axis=0))})
        ensemble = (1 - KIT_SHARE) * np.mean(solves[name], axis=0) + KIT_SHARE * fill if solves[name] else None
        for row in rows:
            if row["case"] == name and len(solves[name]) == len(seeds) > 1:
                row[ANSWER_RULES[3]] = score(ensemble)
        print(f"{name:<22} {len(solves[name])} seeds", flush=True)
    write_bytes_atomic(out, "".join(json.dumps(r) + "\n" for r in rows).encode())
    groups = [("A", lambda r: r["half"] == "A"), ("B", lambda r: r["half"] == "B")] + [
        (kind, lambda r, k=kind: r["case"].endswith("/" + k)) for kind in SUITE_HOLES] + [("all", lambda r: True)]
    print(f"\n{len(rows)} case-seeds; hole RMSE / the best fill's, mean (on how many below 1.0); "
          "then paired against photo by source (lower on how many)")
    print(f"{'rule':<36}" + "".join(f"{g:>16}" for g, _ in groups))
    for key in ANSWER_RULES:
        for label, value in (("", lambda r: r[key] / r["best"]), ("  paired", lambda r: r[key] / r[ANSWER_RULES[0]] - 1)):
            cells = []
            for _, keep in groups:
                x = [value(r) for r in rows if keep(r) and key in r]
                cells.append("-" if not x else f"{np.mean(x):.3f} ({sum(v < 1 for v in x)})" if not label else
                             f"{100 * np.mean(x):+.1f}% ({sum(v < 0 for v in x)})")
            print(f"{(label or key):<36}" + "".join(f"{c:>16}" for c in cells))
    print(f"rows to {out}")


ONE_VIEW = ("Adirondack", "ArtL", "Jadeplant", "Piano", "Pipes", "Playroom", "Playtable", "Motorcycle")  # right view only


def warp_scenes(warp_rows: Path, rgbd_rows: Path, residual: Path) -> None:
    """Where the warp term helps ``photo`` by source and where it does not, per scene, beside how far the warp
    term's own photometric minimum lies from the truth inside that case's holes (the share of hole pixels
    more than 2 px off and the median, for the mean of the rail's two neighbours or the 2014 pair's right
    view: ``study_warp_residual.py``'s ``residual`` file). Paired rows of the same case and seed from
    ``report --core`` of rgbd+warp fits (``warp_rows``) and of rgbd fits (``rgbd_rows``)."""
    def load(path):
        rows = {}
        for r in read_rows(path):
            by_source(r)
            rows[r["case"], r["seed"]] = r
        return rows
    warp, rgbd = load(warp_rows), load(rgbd_rows)
    far = {}
    for line in residual.read_text().splitlines():
        parts = line.split()
        if len(parts) > 2 and (parts[1:4] == ["mean", "of", "2"] or parts[1].endswith("-right")):
            far[parts[0]] = (float(line.split("median")[1].split()[0]), float(line.rsplit("> 2 px", 1)[1]))
    pairs = [(key, rgbd[key][BY_SOURCE_RULE] / warp[key][BY_SOURCE_RULE] - 1, rgbd[key]["fit"] / warp[key]["fit"] - 1)
             for key in sorted(rgbd) if key in warp]
    print(f"{len(pairs)} case-seeds; the warp term's gain: rgbd's hole RMSE / rgbd+warp's − 1 (> 0: the term helps)")
    print(f"{'holes':<10} {'neighbours':<17} {'n':>3} {'photo by source':>16} {'(median)':>9} {'fit alone':>10} "
          f"{'minimum > 2 px off':>19} {'median off':>11}")
    for kind in SUITE_HOLES:
        for label, one_view in (("the right view", True), ("view0 and view2", False)):
            chosen = [(k, g, f) for k, g, f in pairs if k[0].endswith("/" + kind) and (k[0].split("/")[0] in ONE_VIEW) == one_view]
            if not chosen:
                continue
            off = [far[k[0]] for k, _, _ in chosen if k[0] in far]
            print(f"{kind:<10} {label:<17} {len(chosen):>3} {100 * np.mean([g for _, g, _ in chosen]):>+15.1f}% "
                  f"{100 * np.median([g for _, g, _ in chosen]):>+8.1f}% "
                  f"{100 * np.mean([f for _, _, f in chosen]):>+9.1f}% "
                  + (f"{np.mean([o[1] for o in off]):>19.2f} {np.mean([o[0] for o in off]):>8.2f} px" if off else ""))
    for kind in SUITE_HOLES:
        known = [(far[k[0]][1], g) for k, g, _ in pairs if k[0].endswith("/" + kind) and k[0] in far]
        if len(known) > 2:
            print(f"{kind}: correlation of the minimum's share > 2 px off with photo's gain, over case-seeds: "
                  f"{np.corrcoef(np.array(known).T)[0, 1]:+.2f}")
    print("\nper case (gain of photo by source, of the fit alone; the minimum's share > 2 px off, its median)")
    for (name, seed), gain, fit_gain in sorted(pairs, key=lambda p: (p[0][0].split("/")[1], p[0][0])):
        off = far.get(name)
        print(f"{name:<22} seed {seed}  {100 * gain:+6.1f}%  {100 * fit_gain:+6.1f}%"
              + (f"  {off[1]:.2f}  {off[0]:.2f} px" if off else ""))


def _variant_rows(warp_rows: Path, rgbd_rows: Path) -> dict:
    """{"rgbd+warp": {(case, seed): row}, "rgbd": ...} from two rows files of ``report --core``, each row with the
    ``photo by source`` rule added."""
    variants = {}
    for label, path in (("rgbd+warp", warp_rows), ("rgbd", rgbd_rows)):
        rows = read_rows(path)
        for r in rows:
            by_source(r)
        variants[label] = {(r["case"], r["seed"]): r for r in rows}
    return variants


def per_case(warp_rows: Path, rgbd_rows: Path, photo_rows: tuple[Path, Path] | None = None) -> None:
    """The per-scene table: per case, its best fill and best Table 6 method (px), and ``kit`` and ``photo`` by
    source with and without the warp term over each (mean over the seeds both variants have); then the
    means per hole kind. Rows of ``report --core`` for rgbd+warp fits (``warp_rows``) and rgbd fits of the ``kit``
    recipe; ``photo_rows``: the same two for the ``photo`` recipe's own fits (without the kit's hole terms), whose
    ``photo`` columns then replace those read from the ``kit`` fits (means over the seeds both of them have)."""
    table6 = [f"fill {n}" for n in table6_fills()]
    sources = {"kit": _variant_rows(warp_rows, rgbd_rows)}
    sources["photo"] = _variant_rows(*photo_rows) if photo_rows else sources["kit"]
    keys = {name: sorted(set(v["rgbd+warp"]) & set(v["rgbd"])) for name, v in sources.items()}
    cases = sorted({case for case, _ in keys["kit"]} & {case for case, _ in keys["photo"]},
                   key=lambda c: (c.split("/")[1], c))
    columns = [(recipe, v, rule) for recipe, rule in (("kit", "kit"), ("photo", BY_SOURCE_RULE))
               for v in ("rgbd", "rgbd+warp")]
    print(f"{len(cases)} cases: hole RMSE (disparity px) of the best fill and the best Table 6 method, and each "
          "DDP rule's over them, best fill (best Table 6), mean over the seeds both variants have (kit's, then "
          "photo's" + (" own fits" if photo_rows else "") + ")")
    print(f"{'case':<22} {'seeds':<12} {'best fill (px)':<28} {'best Table 6 (px)':<22}"
          + "".join(f"{recipe}/{v:<10}".rjust(22) for recipe, v, _ in columns))
    means = defaultdict(lambda: defaultdict(list))
    for case in cases:
        first = sources["kit"]["rgbd"][next(k for k in keys["kit"] if k[0] == case)]
        fills = {k: first[k] for k in first if k.startswith("fill ")}
        best, best6 = min(fills, key=fills.get), min((k for k in table6 if k in fills), key=fills.get)
        cells = []
        for recipe, v, rule in columns:
            rows = [sources[recipe][v][key] for key in keys[recipe] if key[0] == case]
            over = np.mean([r[rule] / r[best] for r in rows]), np.mean([r[rule] / r[best6] for r in rows])
            means[recipe, v][case.split("/")[1]].append(over)
            means[recipe, v]["all"].append(over)
            cells.append(f"{over[0]:.2f} ({over[1]:.2f})".rjust(22))
        seeds = "/".join(",".join(str(seed) for c, seed in keys[name] if c == case) for name in sources)
        print(f"{case:<22} {seeds:<12} {best[5:] + f' {fills[best]:.3f}':<28} "
              f"{best6[5:] + f' {fills[best6]:.3f}':<22}" + "".join(cells))
    for kind in list(SUITE_HOLES) + ["all"]:
        overs = [means[recipe, v][kind] for recipe, v, _ in columns]  # per column: (over best, over Table 6) per case
        if not overs[0]:  # a hole kind these rows do not have
            continue
        cells = [f"{np.mean([o[0] for o in over]):.2f} ({np.mean([o[1] for o in over]):.2f})".rjust(22) for over in overs]
        print(f"{'mean: ' + kind + f' (n={len(overs[0])})':<87}" + "".join(cells))


def by_source(row: dict) -> None:
    """Add the ``photo by source`` rule to a row that has the stereo rule: that rule where the case's input is a
    stereo matcher's depth, the mean of 4 solves elsewhere."""
    if STEREO_RULE in row:
        stereo_input = row["case"].split("/")[1] in STEREO_KINDS
        row[BY_SOURCE_RULE] = row[STEREO_RULE] if stereo_input else row["mean of 4 solves + 0.25"]


def compare(rows: list[dict], others: list[dict], groups) -> None:
    """Paired: each rule's hole RMSE in ``rows`` against the same case and seed in ``others`` (other fits)."""
    for row in others:
        by_source(row)
    other = {(r["case"], r["seed"]): r for r in others}
    pairs = [(r, other[r["case"], r["seed"]]) for r in rows if (r["case"], r["seed"]) in other]
    print(f"\npaired against the other fits ({len(pairs)} case-seeds): mean change of the hole RMSE (lower on how many)")
    print(f"{'rule':<26}" + "".join(f"{g:>16}" for g, _ in groups))
    for key in [k for k in ("fit", "kit", "refined + 0.25", "mean of 4 solves + 0.25", BY_SOURCE_RULE)
                if all(k in r and k in o for r, o in pairs)]:
        cells = []
        for _, keep in groups:
            change = [r[key] / o[key] - 1 for r, o in pairs if keep(r)]
            cells.append(f"{100 * np.mean(change):+.1f}% ({sum(x < 0 for x in change)}/{len(change)})" if change else "-")
        print(f"{key:<26}" + "".join(f"{c:>16}" for c in cells))
    timed = [(r["fit_seconds"], o["fit_seconds"]) for r, o in pairs if "fit_seconds" in r and "fit_seconds" in o]
    if timed:
        print(f"fit seconds: {np.median([t for t, _ in timed]):.0f} against {np.median([t for _, t in timed]):.0f} "
              f"(median of {len(timed)}, as they ran)")


def _setting(item: str) -> tuple[str, object]:
    """``"fill_input=1"`` → ("fill_input", 1); ``"warp_confidence=true"`` → ("warp_confidence", True); a value
    that is neither a number nor true/false stays a word."""
    field_name, sep, value = item.partition("=")
    if not sep or not field_name:
        raise ValueError(f"--set: expected FIELD=VALUE, got {item!r}")
    if value.lower() in ("true", "false"):
        return field_name, value.lower() == "true"
    try:
        number = float(value)
    except ValueError:
        return field_name, value
    return field_name, int(number) if number.is_integer() and "." not in value else number


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("fit", "report", "stereo-grid", "answer-rules", "warp-scenes", "per-case"))
    parser.add_argument("--data", required=True, type=data_root, help="a folder of Middlebury scenes with ground truth")
    parser.add_argument("--seeds", type=seed_int, nargs="+", default=[0])
    parser.add_argument("--cases", nargs="+", help="scene/holes names; default: the whole suite")
    parser.add_argument("--variant", default="rgbd+warp", choices=("rgbd", "rgbd+warp"))
    parser.add_argument("--size", default="eighth", choices=("eighth", "quarter"))
    parser.add_argument("--fits", type=Path, default=RESULTS / "fill_blend_fits")
    parser.add_argument("--channels", type=positive_int, nargs="+",
                        help="fit: the net's encoder widths (default: the profile's; 8 16 32 64 128 is the narrow net)")
    parser.add_argument("--set", nargs="+", default=[], metavar="FIELD=VALUE",
                        help="fit: other FitConfig fields of the fits, e.g. fill_input=1 (numbers or words)")
    parser.add_argument("--core", action="store_true",
                        help="report: only the rules that compare fits (fit, kit, photo's one and four solves)")
    parser.add_argument("--out", type=Path, default=RESULTS / "fill_blends_eighth.jsonl")
    parser.add_argument("--from-rows", type=existing_file, nargs="+", default=[],
                        help="report: summarise these rows files (written by earlier reports) instead of scoring")
    parser.add_argument("--against", type=existing_file,
                        help="report: also compare, paired, with the rows of other fits (e.g. the narrow net's)")
    def check(args):
        unknown = sorted(set(args.cases or ()) - set(suite_case_names(args.data)))
        if unknown:
            raise ValueError(f"--cases: not in the suite under {args.data}: {unknown}")
        settings = dict(_setting(item) for item in args.set)
        check_configs([("--set / --channels", lambda: FitConfig.for_profile(
            "class", variant=args.variant, recipe="kit", blend_fill=0.0,
            **({"channels": tuple(args.channels)} if args.channels else {}), **settings))])
        if args.what in ("warp-scenes", "per-case") and len(args.from_rows) != 2 and not (
                args.what == "per-case" and len(args.from_rows) == 4):
            raise ValueError(f"{args.what}: --from-rows WARP_ROWS RGBD_ROWS (two files"
                             + ("; per-case: then the photo recipe's own two, optionally)" if args.what == "per-case"
                                else ")"))
        if args.what in ("answer-rules", "stereo-grid", "report"):
            check_rows_out(args.out)
        if args.what == "fit":
            check_output_folder(args.fits, "--fits")
    args = parse_args(parser, argv, check)
    names = suite_case_names(args.data)
    if args.cases:
        names = [n for n in names if n in set(args.cases)]
    if args.what == "fit":
        fit(args.data, names, args.seeds, args.fits, args.variant, args.size,
            tuple(args.channels) if args.channels else None, dict(_setting(item) for item in args.set))
    elif args.what in ("warp-scenes", "per-case"):
        if args.what == "per-case":
            per_case(*args.from_rows[:2], tuple(args.from_rows[2:]) or None)
        else:
            warp_scenes(*args.from_rows, RESULTS / "warp_residual_real_suite_eighth.txt")
    elif args.what == "answer-rules":
        answer_rules(args.data, names, args.seeds, args.fits, args.variant, args.size, args.out)
    elif args.what == "stereo-grid":
        stereo_grid(args.data, names, args.seeds, args.fits, args.variant, args.size, args.out)
    else:
        report(args.data, names, args.seeds, args.fits, args.variant, args.size, args.out, args.from_rows,
               args.against, args.core)


if __name__ == "__main__":
    main()
