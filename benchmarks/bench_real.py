"""The real suite: every fill and DDP (kit, paper, photo; rgbd and rgbd+warp) on every Middlebury scene.

    python benchmarks/bench_quality.py --suite middlebury --data DIR                    # eighth size, seed 0
    python benchmarks/bench_quality.py --suite middlebury --data DIR --real-size quarter --seeds 0 1 2
    python benchmarks/bench_quality.py --suite middlebury --data DIR --report           # the tables only
    python benchmarks/bench_quality.py --suite middlebury --data DIR --variants rgbd+warp \
        --recipes kit kit:warp_combine=min --cases Art/sgbm Art/occlusion                  # a lever, on some cases

``DIR`` is a folder of Middlebury scenes with ground truth (default: the data root, where ``python -m data_fetch
fetch middlebury2006 …`` and its siblings install them, else the kit's shipped samples; the first line says
which), or any folder laid out like it; the cases are
``ddp_lite.studies.real_suite``'s: DepthComp's own holes on Plastic, seeded blobs, OpenCV SGBM's holes and
the truth's occlusions on every scene, and Motorcycle. ``--real-size eighth`` (≈ 160×140, about 40 s a fit on
one core) is for iterating, ``quarter`` (≈ 320×280, minutes a fit) for confirming.

It prints its expected wall time before it starts, fits the recipes of a case side by side (one torch
thread each), appends one JSON row per fill or fit to ``--out`` (default
``benchmarks/results/real_suite_<size>.jsonl``) and skips what is already there, so a stopped run resumes: a
row is reused only at the same size and profile (``ROW_FIELDS``), and a last line cut short is moved aside.
Scores: hole RMSE in disparity px of the working size; per case the ratio of each DDP row to the best of
all fills and to the best of the paper's Table 6 methods present in the kit (``baselines.PAPER_TABLE6``).
Then the per-scene table, the means per hole kind and over all cases, and how long it took. Asserts nothing.
"""
from __future__ import annotations

import json
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from ddp_lite.classical import baselines
from ddp_lite.method.config import FitConfig
from ddp_lite.method.runtime.options import RunOptions
from ddp_lite.studies.real_cases import _fit_reusing, _plain_fits, _planned
from ddp_lite.data.installed import data_line, data_root, installed_scenes
from ddp_lite.data.samples import SAMPLES, sample_scene
from ddp_lite.studies.real_suite import SUITE_HOLES, find_scenes, make_suite_case, suite_case_names
from _common import RowsFile, read_rows, recipe_overrides

RESULTS = Path(__file__).resolve().parent / "results"
SECONDS_PER_FIT = {"eighth": 45.0, "quarter": 240.0}  # one class fit on one core, when no fit of that size is recorded
# two fits side by side on two cores, one thread each, against one alone: a case's pair 80 s, one fit 45 s (eighth
# size, docs/studies/real_suite.md)
SIDE_BY_SIDE = 80.0 / 45.0
FILLS_PER_CASE = 5.0  # s, every fill of one eighth-size case (median of the 61 cases of real_suite_eighth.jsonl: 4.8)
_TABLE6_FALLBACK = ("linear", "cubic", "telea", "guided-filter")


def table6_fills() -> tuple[str, ...]:
    """The kit's fills that are rows of the paper's Table 6."""
    names = tuple(getattr(baselines, "PAPER_TABLE6", {}).values()) or _TABLE6_FALLBACK
    return tuple(n for n in names if n in baselines.BASELINES)


def suite_data(data=None) -> tuple[Path, str, bool]:
    """The folder of scenes the suite reads: ``data`` if given, else the data root when ``data_fetch`` installed a
    Middlebury scene there, else the kit's shipped samples → (folder, the line that says which, and for the
    samples the command that installs the real scenes, whether it is the samples)."""
    if data:
        scenes = find_scenes(data)
        return Path(data), data_line([f"{len(scenes)} scenes under {data} ({', '.join(scenes)})"]), False
    installed = installed_scenes()
    if installed:
        listed = ", ".join(f"{name} ({copy.dataset} {copy.size})" for name, copy in installed.items())
        return data_root(), data_line([f"{len(installed)} scenes installed in {data_root()}: {listed}"]), False
    return sample_scene(SAMPLES[0]).parent, data_line(
        [], f"the shipped quarter-size samples ({', '.join(SAMPLES)}; rows go to a file of their own)",
        "middlebury2006", why=f"no Middlebury scene installed in {data_root()}"), True


# what changes a row's numbers: a resumed run reuses a row only when all of these match (a fill's profile is None)
ROW_FIELDS = ("case", "method", "variant", "seed", "size", "profile")


def _rows(path: Path) -> list[dict]:
    return read_rows(path)


QUIET = RunOptions(progress=False)  # how every fit here runs


def recipe_config(profile: str, variant: str, recipe: str, seed: int) -> FitConfig:
    """The config of one fit: ``recipe`` a kit recipe's name (kit, paper, photo) or that name with
    ``FitConfig`` overrides, ``kit:warp_combine=min,gammas=(0.96,0.02)`` (bare words are read as strings)."""
    name, overrides = recipe_overrides(recipe)  # ValueError naming what is wrong
    return FitConfig.for_profile(profile, variant=variant, recipe=name, seed=seed, **overrides)


def run(data, size: str, recipes, variants, seeds, out: Path, profile: str = "class", cases=None) -> None:
    """Fill and fit every case of the suite under ``data`` (or those named in ``cases``) not yet in ``out``;
    rows appended as they finish. ``recipes``: see :func:`recipe_config`."""
    names = suite_case_names(data)
    if cases:
        unknown = sorted(set(cases) - set(names))
        if unknown:
            raise ValueError(f"--cases: {unknown} not in the suite under {data}")
        names = [n for n in names if n in set(cases)]
    for recipe in recipes:  # every config checked before the first row
        for variant in variants:
            for seed in seeds:
                recipe_config(profile, variant, recipe, seed).validate()
    rows = RowsFile(out, ROW_FIELDS)
    fill_key = lambda name, method: dict(case=name, method=method, variant=None, seed=None, size=size, profile=None)  # noqa: E731
    fit_key = lambda name, recipe, variant, seed: dict(case=name, method=f"DDP {recipe}", variant=variant,  # noqa: E731
                                                       seed=seed, size=size, profile=profile)
    print(expected_time(names, size, recipes, variants, seeds, rows.rows, profile) + f"; rows to {out}", flush=True)
    start = time.perf_counter()
    try:
        for name in names:
            case = None
            for method, fill in baselines.BASELINES.items():
                if rows.done(fill_key(name, method)):
                    continue
                case = case or make_suite_case(data, name, size)
                began = time.perf_counter()
                disparity = fill(case.fb / case.depth, case.rgb)
                rows.record(dict(fill_key(name, method), px=case.rmse_px(case.fb / disparity),
                                 seconds=time.perf_counter() - began))
            for variant in variants:
                for seed in seeds:
                    wanted = [r for r in recipes if not rows.done(fit_key(name, r, variant, seed))]
                    if not wanted:
                        continue
                    case = case or make_suite_case(data, name, size)
                    began = time.perf_counter()
                    configs = [recipe_config(profile, variant, r, seed) for r in wanted]
                    fitted = _plain_fits(case, variant, configs, QUIET)
                    seconds = (time.perf_counter() - began) / max(1, len(fitted))
                    for recipe, config in zip(wanted, configs):
                        result = _fit_reusing(case, variant, config, fitted, QUIET)
                        rows.record(dict(fit_key(name, recipe, variant, seed),
                                         px=case.rmse_px(result.merged(case.depth)), seconds=seconds,
                                         iterations=int(getattr(result, "iterations", 0) or 0)))
                    print(f"{name:<24} {variant:<10} seed {seed}: {time.perf_counter() - began:.0f} s "
                          f"({(time.perf_counter() - start) / 60:.1f} min in all)", flush=True)
    finally:
        rows.close()
    print(f"done in {(time.perf_counter() - start) / 60:.1f} min", flush=True)


def _recorded_fit_seconds(size: str) -> list[float]:
    """The seconds of the single ``class`` fits recorded at ``size`` (``study_fill_blends.py fit``: one kit fit
    alone on one thread, rows ``results/fill_blends_<size>*.jsonl``)."""
    seconds = []
    for path in sorted(RESULTS.glob(f"fill_blends_{size}*.jsonl")):
        seconds += [r["fit_seconds"] for r in map(json.loads, path.read_text().splitlines()) if r.get("fit_seconds")]
    return seconds


def expected_time(names, size: str, recipes, variants, seeds, rows: list[dict], profile: str = "class") -> str:
    """One line: the cases, the runs and fits left (not in ``rows``), and the wall time they should take on two
    cores: per case-variant-seed its plain fits (``real_cases._planned``: ``photo`` fits on its own) two at a
    time, each as long as the median fit of ``rows`` at this size (this pass's own, as it ran) or, before there
    is one, of the single fits recorded at ``size`` (:func:`_recorded_fit_seconds`) slowed by ``SIDE_BY_SIDE``;
    plus every fill of a case not yet filled, as long as the median case's fills in ``rows``, or ``FILLS_PER_CASE``
    at eighth size (4× the pixels, 4× the time, at quarter)."""
    done = {(r["case"], r["method"], r["variant"], r["seed"]) for r in rows
            if r.get("size") == size and r.get("profile") == profile}  # what run reuses (ROW_FIELDS)
    plain = {v: len(_planned([recipe_config(profile, v, r, 0) for r in recipes])) for v in variants}
    runs = [(n, v, s) for n in names for v in variants for s in seeds
            if any((n, f"DDP {r}", v, s) not in done for r in recipes)]
    fits = sum(plain[v] for _, v, _ in runs)
    own = [r["seconds"] for r in rows if r["variant"] is not None and (r["case"], r["method"], r["variant"], r["seed"])
           in done and r.get("seconds")]
    recorded = _recorded_fit_seconds(size)
    if own:  # bench_real's rows hold a run's wall time over its fits: per fit, side by side
        per_fit, source = float(np.median(own)), f"the median of this pass's {len(own)} fits"
    elif recorded:
        per_fit = float(np.median(recorded)) * SIDE_BY_SIDE / 2
        source = f"{np.median(recorded):.0f} s a {size}-size class fit alone (median of {len(recorded)} recorded)"
    else:
        per_fit, source = SECONDS_PER_FIT[size] * SIDE_BY_SIDE / 2, f"{SECONDS_PER_FIT[size]:.0f} s a fit (assumed)"
    pairs = sum(-(-plain[v] // 2) for _, v, _ in runs)  # each run's fits two at a time
    fit_seconds = pairs * 2 * per_fit
    filled = {r["case"] for r in rows if r["variant"] is None and r.get("size") == size}
    fill_case = defaultdict(float)
    for r in rows:
        if r["variant"] is None and r.get("size") == size:
            fill_case[r["case"]] += r.get("seconds", 0.0)
    per_case = (float(np.median(list(fill_case.values()))) if fill_case
                else FILLS_PER_CASE * (4 if size == "quarter" else 1))
    fill_seconds = per_case * sum(1 for n in names if n not in filled)
    hours = (fit_seconds + fill_seconds) / 3600
    return (f"{len(names)} cases, {len(runs)} case-variant-seed runs ({fits} fits) left: expect about {hours:.1f} h on "
            f"2 cores ({profile}, {size}; {per_fit:.0f} s a fit side by side, from {source}; "
            f"{fill_seconds / 60:.0f} min of fills)")


def refill(data, size: str, out: Path) -> None:
    """Every fill's rows of ``out`` computed again with today's fills (the DDP rows kept): after a fill changed."""
    kept = [r for r in _rows(out) if r["variant"] is not None]
    temporary = out.with_suffix(".tmp")
    temporary.write_text("".join(json.dumps(r) + "\n" for r in kept))
    temporary.replace(out)
    run(data, size, [], [], [], out)


def ratios(rows: list[dict]) -> dict:
    """{(case, method, variant): [ratio to the best fill, ratio to the best Table 6 fill, px]} over seeds."""
    fills = defaultdict(dict)
    fits = defaultdict(list)
    for r in rows:
        if r["variant"] is None:
            fills[r["case"]][r["method"]] = r["px"]
        else:
            fits[(r["case"], r["method"], r["variant"])].append(r["px"])
    table6 = table6_fills()
    out = {}
    for (case, method, variant), values in fits.items():
        if case not in fills:
            continue
        best = min(fills[case].values())
        best6 = min(fills[case][m] for m in table6 if m in fills[case])
        px = float(np.mean(values))
        out[(case, method, variant)] = [px / best, px / best6, px, len(values)]
    return out


def report(path: Path, size: str | None = None, profile: str | None = None) -> None:
    """The per-scene table and the means per hole kind, from the rows in ``path`` (of one ``size`` and
    ``profile`` where given: a run reports its own rows, not another size's or profile's)."""
    rows = [r for r in _rows(path) if (size is None or r.get("size") == size)
            and (profile is None or r["variant"] is None or r.get("profile") == profile)]
    if not rows:
        print(f"no rows in {path}")
        return
    fills = defaultdict(dict)
    for r in rows:
        if r["variant"] is None:
            fills[r["case"]][r["method"]] = r["px"]
    table = ratios(rows)
    columns = sorted({(m, v) for _, m, v in table}, key=lambda mv: (mv[1], mv[0]))
    table6 = table6_fills()
    print(f"{path.name}: hole RMSE (disparity px) and DDP / best fill (DDP / best of Table 6's {', '.join(table6)})")
    width = max(13, *(len(m) - 3 + len(v) for m, v in columns))
    print(f"{'case':<22} {'best fill (px)':<24} {'best Table 6 (px)':<20}" + "".join(f" {m[4:] + '/' + v:<{width}}"
                                                                                  for m, v in columns))
    for case in sorted(fills, key=lambda c: (c.split("/")[1], c)):
        best = min(fills[case], key=fills[case].get)
        best6 = min((m for m in table6 if m in fills[case]), key=fills[case].get)
        cells = "".join(f" {f'{table[(case, m, v)][0]:.2f} ({table[(case, m, v)][1]:.2f})' if (case, m, v) in table else '-':<{width}}"
                        for m, v in columns)
        print(f"{case:<22} {best + f' {fills[case][best]:.3f}':<24} {best6 + f' {fills[case][best6]:.3f}':<20}{cells}")
    print("\nmeans of the ratios (to the best fill; to the best Table 6 method), per hole kind and over all cases:")
    for holes in SUITE_HOLES + ("all",):
        parts = []
        for m, v in columns:
            chosen = [x for (c, mm, vv), x in table.items() if mm == m and vv == v and (holes == "all" or c.endswith("/" + holes))]
            if chosen:
                parts.append(f"{m[4:]}/{v} {np.mean([x[0] for x in chosen]):.3f}; {np.mean([x[1] for x in chosen]):.3f} "
                             f"(n={len(chosen)})")
        if parts:
            print(f"  {holes:<10} " + " | ".join(parts))
    seconds = sum(r.get("seconds", 0.0) for r in rows if r["variant"] is not None)
    print(f"\n{len(rows)} rows; the fits' own time {seconds / 60:.0f} fit-minutes\n")
    print(markdown_means(path))


def markdown_means(path: Path) -> str:
    """The means per hole kind as a Markdown table (for the README and docs): each DDP row's ratio to the best
    fill and, after the slash, to the best of the paper's Table 6 methods; n = cases."""
    table = ratios(_rows(path))
    columns = sorted({(m, v) for _, m, v in table}, key=lambda mv: (mv[1], mv[0]))
    lines = ["| DDP | " + " | ".join(SUITE_HOLES) + " | all |", "|---" * (len(SUITE_HOLES) + 2) + "|"]
    for m, v in columns:
        cells = []
        for holes in SUITE_HOLES + ("all",):
            chosen = [x for (c, mm, vv), x in table.items() if (mm, vv) == (m, v) and (holes == "all" or c.endswith("/" + holes))]
            cells.append(f"{np.mean([x[0] for x in chosen]):.2f} / {np.mean([x[1] for x in chosen]):.2f} (n={len(chosen)})"
                         if chosen else "–")
        lines.append(f"| `{m[4:]}`, {v} | " + " | ".join(cells) + " |")
    return "\n".join(lines)

