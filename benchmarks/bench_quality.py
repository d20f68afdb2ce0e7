"""Does DDP beat the classical fills? Hole error of DDP recipes vs every fill in ``ddp_lite.classical.baselines``.

    python benchmarks/bench_quality.py --quick                           # a few cases, the profile's recipe
    python benchmarks/bench_quality.py --recipes default ens3 --seeds 0 1 --out q.jsonl --lane 0/2 &
    python benchmarks/bench_quality.py --recipes default ens3 --seeds 0 1 --out q.jsonl --lane 1/2
    python benchmarks/bench_quality.py --report q.jsonl                  # the table, from recorded rows

The suite is fixed (cases are never dropped because DDP loses on them):
- the four named scenes (piecewise planar: linear interpolation is exact in disparity on a plane),
  each with OpenCV SGM holes of both parameter sets and with large Depthcomp-like blob holes;
- the curved, photo-textured scenes of ``ddp_lite.world.organic`` (when present), with the same holes;
- notebook 09's Middlebury-format fixture: SGM holes on the left view, the right view as the
  warp loss's neighbour;
- the real Middlebury Motorcycle pair (``ddp_lite.studies.real_cases``) pooled to 125×185 (``motorcycle-4``)
  and 250×370 (``motorcycle-2``): three blob patterns, real SGBM holes, left-right-check (occlusion)
  holes; the right view as the warp loss's neighbour. These keep their own size whatever the profile.
- with ``--suite middlebury [--data DIR]``, every Middlebury scene with ground truth under DIR (default: the data
  root data_fetch installs into, else the shipped samples) and Motorcycle
  (``benchmarks/bench_real.py``: DepthComp's holes, blobs, SGBM holes, the truth's occlusions; eighth or quarter size);
- with ``--middlebury FOLDER ...``, the same five hole kinds on other Middlebury 2014 pairs (``data_fetch``
  fetches them; ``middlebury:FOLDER-F/holes``), pooled by F to about twice the profile's pixels.
SGM runs at 3× the working size below 96 rows and keeps each block's centre (as the notebooks do).
``--suite synthetic`` (the default), ``real`` (motorcycle-4), ``real-half`` (motorcycle-2), ``all``
(synthetic and motorcycle-4). The report prints each size apart, then every recipe over all its cases.

Every classical fill works on disparity in pixels (d = f·B/Z, where linear is exact on planes).
DDP's transform is the default one a user gets (from the input depth). A recipe is a set of
``FitConfig`` overrides on top of the profile's config; ``name:key=value,key=value`` adds one
on the command line. A real case's fits are told where its depth came from (``RealCase.depth_source``:
``"stereo"`` for SGBM's depth) unless the recipe sets ``depth_source`` itself. Scores: hole RMSE in
disparity pixels (sky and unknown truth excluded); "ratio" = DDP / the best classical fill of that case; mean and worst over the cases, per seed
and for the mean over seeds. Rows go to ``--out`` as JSON lines (one per fit), so lanes can run
in parallel (one thread each) and ``--report`` prints the tables. Asserts nothing.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from ddp_lite.classical.stereo import sgm_depth  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402
from ddp_lite.method.paper.disparity import DisparityTransform  # noqa: E402
from ddp_lite.classical import baselines  # noqa: E402
from ddp_lite.evaluation.experiments import Case, make_case, sgm_depth_at_scale  # noqa: E402
from ddp_lite.classical.holes import random_holes  # noqa: E402
from ddp_lite.data.middlebury import load_middlebury, make_middlebury_fixture  # noqa: E402
from ddp_lite.studies.real_cases import REAL_HOLES, factor_for_profile, make_real_case  # noqa: E402
from ddp_lite.method.kit.recipes import RECIPES as KIT_RECIPES  # noqa: E402
from ddp_lite.data.resample import resize_scene  # noqa: E402
from ddp_lite.world.scenes import SCENES  # noqa: E402
from _common import (RowsFile, add_profile_args, check_configs, check_output_folder, check_rows_in,  # noqa: E402
                     check_rows_out, positive_int, data_root, lane, parse_args, profile_from_args, read_rows,
                     recipe_overrides, seed_int, split_top)
from study_recipes import STUDY  # noqa: E402

NAMED = ("house", "desk", "room", "street")
HOLES = ("sgm-dense", "sgm-sparse", "blobs")
QUICK = ("desk/sgm-dense", "house/blobs", "fixture/sgm-dense")

# name → FitConfig overrides on top of the profile's config: the default (the kit), the paper's
# method, the photo recipe (the kit's fit refined by an image-guided bilateral solve), and the study's other recipes (study_recipes.STUDY, each with its one-line why)
RECIPES = {"default": {}, "paper": KIT_RECIPES["paper"].overrides, "photo": KIT_RECIPES["photo"].overrides, **STUDY}


def organic_scenes() -> tuple[str, ...]:
    """The curved scenes registered by ``ddp_lite.world.organic`` (empty if it is not there)."""
    return tuple(name for name in SCENES if name not in NAMED)


def suite(quick: bool = False, kind: str = "synthetic") -> list[str]:
    """The case names of a suite: ``synthetic``, ``real`` (125×185), ``real-half`` (250×370), ``all`` or ``none``."""
    real = {factor: [f"motorcycle-{factor}/{holes}" for holes in REAL_HOLES] for factor in (4, 2)}
    if kind == "none":
        return []
    if kind in ("real", "real-half"):
        return real[4 if kind == "real" else 2]
    names = [f"{scene}/{holes}" for scene in NAMED + organic_scenes() for holes in HOLES] + ["fixture/sgm-dense"]
    if quick:  # QUICK plus one curved scene with SGM holes
        chosen = set(QUICK) | {f"{scene}/sgm-dense" for scene in organic_scenes()[:1]}
        names = [n for n in names if n in chosen]
    return names + (real[4] if kind == "all" else [])


MIDDLEBURY = "middlebury:"  # the prefix of the cases of other Middlebury pairs: middlebury:FOLDER-F/holes


def middlebury_cases(folders, profile) -> list[str]:
    """The real cases of other Middlebury 2014 pairs: each folder's ``REAL_HOLES``, pooled by the factor
    that brings its image to about twice the profile's pixels."""
    return [f"{MIDDLEBURY}{folder}-{factor_for_profile(profile, load_middlebury(folder)[0].depth.shape)}/{holes}"
            for folder in folders for holes in REAL_HOLES]


def is_real(name: str) -> bool:
    """Whether a case is a real photograph (Motorcycle or another Middlebury pair)."""
    return name.startswith(("motorcycle", MIDDLEBURY))


def build_case(name: str, profile) -> tuple[Case, float]:
    """The case ``scene/holes`` at the profile's size and its f·B (px · m) for disparity in pixels."""
    scene_name, holes = name.rsplit("/", 1)
    H, W = profile.size
    if scene_name.startswith(("motorcycle-", MIDDLEBURY)):
        folder, factor = scene_name.rsplit("-", 1)
        case = make_real_case(holes, factor=int(factor),
                              scene=folder[len(MIDDLEBURY):] if folder.startswith(MIDDLEBURY) else None)
        return case, case.fb
    if scene_name == "fixture":
        with tempfile.TemporaryDirectory(prefix="ddp-quality-") as tmp:
            full = load_middlebury(make_middlebury_fixture(Path(tmp) / "Fixture-perfect", size=(3 * H, 3 * W), seed=0))
        scene, matching = resize_scene(full, profile.size), resize_scene(full, (3 * H, 3 * W))
        depth = np.ascontiguousarray(sgm_depth(matching, 0, holes.split("-")[1])[0][1::3, 1::3])
        view = scene[0]
        case = Case(name, view.rgb, depth.astype(np.float32), view.depth, view.camera, [scene.right[0]],
                    DisparityTransform.from_depth(view.depth, margin=1.0), scene, 0, None)
        return case, view.camera.focal * scene.meta["baseline"]
    if holes == "blobs":  # Depthcomp-like: large smooth blobs cut into the complete depth
        case = make_case(scene_name, profile, holes="random")
        case.depth, _ = random_holes(case.gt, fraction=0.2, seed=1, blob_size=min(H, W) / 10)
    else:
        case = make_case(scene_name, profile, holes="sgm", sgm_params=holes.split("-")[1])
    return case, case.camera.K[0, 0] * case.scene.meta["baseline"]


def scored(case: Case) -> np.ndarray:
    return case.holes & np.isfinite(case.gt)


def rmse_px(depth, case: Case, fb: float) -> float:
    mask = scored(case)
    return float(np.sqrt(np.mean((fb / depth[mask] - fb / case.gt[mask]) ** 2)))


def region_errors(case, depth) -> dict:
    """A real case's hole RMSE (px) by region (``RealCase.regions``) as ``{"px_<region>": ...}``; {} otherwise."""
    if not hasattr(case, "regions"):
        return {}
    return {f"px_{region}": case.rmse_px(depth, mask) for region, mask in case.regions().items()}


def parse_recipe(text: str) -> tuple[str, dict]:
    """``name`` (from RECIPES) or ``name:key=value,key=value`` (RECIPES' ``name``, or the default's, with those
    ``FitConfig`` overrides) → (name, overrides); ``ValueError`` naming what is wrong (``_common.recipe_overrides``)."""
    name, overrides = recipe_overrides(text)
    if ":" not in text and name not in RECIPES:
        raise ValueError(f"--recipes: unknown recipe {text!r}; known: {', '.join(sorted(RECIPES))} "
                         f"(or name:key=value,...)")
    return name, {**RECIPES.get(name, {}), **overrides}


_split_top = split_top  # bench_real and the studies read recipes with it

# what changes a row's numbers: a resumed run reuses a row only when all of these match
ROW_FIELDS = ("case", "method", "variant", "seed", "size", "profile", "overrides")


def check_case_name(name: str) -> None:
    """``ValueError`` unless ``name`` is a case this script builds: ``scene/holes`` of a named or curved scene
    (holes ``HOLES``), ``fixture/sgm-dense|sgm-sparse``, ``motorcycle-F/holes`` or ``middlebury:FOLDER-F/holes``
    (holes ``REAL_HOLES``, F a pooling factor ≥ 1)."""
    scene, slash, holes = name.rpartition("/")
    if not slash:
        raise ValueError(f"--cases {name!r}: a case is scene/holes, e.g. desk/blobs or motorcycle-4/sgbm")
    if scene.startswith(("motorcycle-", MIDDLEBURY)):
        folder, _, factor = scene.rpartition("-")
        if not factor.isdigit() or int(factor) < 1:
            raise ValueError(f"--cases {name!r}: the pooling factor after '-' must be a whole number ≥ 1")
        if folder.startswith(MIDDLEBURY) and not Path(folder[len(MIDDLEBURY):]).is_dir():
            raise ValueError(f"--cases {name!r}: no such folder {folder[len(MIDDLEBURY):]!r}")
        if holes not in REAL_HOLES:
            raise ValueError(f"--cases {name!r}: a real case's holes are one of {', '.join(REAL_HOLES)}")
    elif scene == "fixture":
        if holes != "sgm-dense" and holes != "sgm-sparse":
            raise ValueError(f"--cases {name!r}: the fixture's holes are sgm-dense or sgm-sparse")
    elif scene not in SCENES:
        raise ValueError(f"--cases {name!r}: no scene {scene!r}; known: {', '.join(sorted(SCENES))}, fixture, "
                         f"motorcycle-F, middlebury:FOLDER-F")
    elif holes not in HOLES:
        raise ValueError(f"--cases {name!r}: holes are one of {', '.join(HOLES)}")


def run(args) -> None:
    profile = profile_from_args(args)
    names = (args.cases or suite(args.quick, args.suite)) + middlebury_cases(args.middlebury, profile)
    index_of_lane, lanes = args.lane
    recipes = [parse_recipe(r) for r in args.recipes]
    rows = RowsFile(args.out, ROW_FIELDS)
    try:
        for index, name in enumerate(names):
            if index % lanes == index_of_lane:
                _run_case(name, profile, recipes, args, rows)
    finally:
        rows.close()


def _run_case(name: str, profile, recipes, args, rows: RowsFile) -> None:
    """Every fill and every fit of ``recipes`` × ``args.variants`` × ``args.seeds`` on one case not yet in ``rows``."""
    case, fb = build_case(name, profile)
    size = f"{case.depth.shape[0]}x{case.depth.shape[1]}"
    here = dict(case=name, size=size, profile=profile.name)
    disparity_in = fb / case.depth
    for method, fill in baselines.BASELINES.items():
        key = dict(here, method=method, variant=None, seed=None, overrides=None)
        if not rows.done(key):  # a fill added since the file was written runs too
            start = time.perf_counter()
            filled = fill(disparity_in, case.rgb)
            rows.record(dict(key, px=rmse_px(fb / filled, case, fb), seconds=time.perf_counter() - start,
                             **region_errors(case, fb / filled)))
    for recipe, overrides in recipes:
        for variant in args.variants:
            if variant == "rgbd+warp" and not case.neighbors:
                continue
            for seed_ in args.seeds:
                key = dict(here, method=recipe, variant=variant, seed=seed_, overrides=repr(overrides))
                if rows.done(key):
                    continue
                source = {"depth_source": case.depth_source} if hasattr(case, "depth_source") else {}
                config = FitConfig.for_profile(profile, variant=variant, **{"seed": seed_, **source, **overrides})
                neighbors = case.neighbors if variant == "rgbd+warp" else ()
                start = time.perf_counter()
                result = complete_depth(case.rgb, case.depth, case.camera, neighbors, variant=variant,
                                        config=config, options=RunOptions(progress=False))
                row = dict(key, px=rmse_px(result.merged(case.depth), case, fb),
                           seconds=time.perf_counter() - start, iterations=result.iterations,
                           **region_errors(case, result.merged(case.depth)))
                rows.record(row)
                if args.save_fits:  # the fit's disparity (1/m): members of any ensemble, averaged later
                    save_fit(Path(args.save_fits), row, result.merged(case.depth))
                print(f"{name:<22} {recipe:<14} {variant:<10} seed {seed_}: {row['px']:.3f} px "
                      f"({row['seconds']:.0f} s)", flush=True)


def fit_path(folder: Path, case: str, recipe: str, variant: str, seed: int, size: str) -> Path:
    """Where ``--save-fits`` keeps one fit's output: one ``.npy`` per (case, recipe, variant, seed, size)."""
    return folder / f"{case.replace('/', '~')}__{recipe}__{variant}__{seed}__{size}.npy"


def save_fit(folder: Path, row: dict, depth: np.ndarray) -> None:
    """The fit's merged depth as inverse depth (1/m), float32, written atomically."""
    folder.mkdir(parents=True, exist_ok=True)
    path = fit_path(folder, row["case"], row["method"], row["variant"], row["seed"], row["size"])
    temporary = path.with_suffix(".tmp.npy")
    np.save(temporary, (1.0 / depth).astype(np.float32))
    temporary.replace(path)


def averaged_rows(rows: list[dict], folder: Path, profile, name: str, members) -> list[dict]:
    """Rows for the mean of saved fits (their inverse depths averaged, as ``FitConfig.ensemble`` averages
    its members' disparities): ``members(method, seed)`` lists the (method, seed) pairs averaged for a
    row anchored at a fit of ``method`` with ``seed``, or None to skip it; the row's method is
    ``name(method)`` and ``px`` its hole RMSE on the case. Rows whose members are not all saved are left out."""
    seconds = {(r["case"], r["method"], r["variant"], r["size"], r["seed"]): r["seconds"] for r in rows if r.get("variant")}
    cases, out = {}, []
    for case_name, method, variant, size, seed in sorted(seconds, key=str):
        chosen = members(method, seed)
        paths = [fit_path(folder, case_name, m, variant, s, size) for m, s in chosen or ()]
        if not chosen or not all(p.exists() for p in paths):
            continue
        if case_name not in cases:
            cases[case_name] = build_case(case_name, profile)
        case, fb = cases[case_name]
        inverse = np.mean([np.load(p) for p in paths], axis=0)  # (H, W) 1/m
        out.append(dict(case=case_name, method=name(method), variant=variant, seed=seed, size=size,
                        px=rmse_px(1.0 / inverse, case, fb),
                        seconds=sum(seconds.get((case_name, m, variant, size, s), np.nan) for m, s in chosen)))
    return out


def ensemble_rows(rows: list[dict], folder: Path, k: int, profile) -> list[dict]:
    """The mean of ``k`` saved fits of one recipe with seeds s, s+1, ..., s+k-1 (what ``FitConfig(ensemble=k,
    seed=s)`` computes), named ``<recipe>×k``."""
    return averaged_rows(rows, folder, profile, lambda method: f"{method}×{k}",
                         lambda method, seed: [(method, seed + j) for j in range(k)])


def mix_rows(rows: list[dict], folder: Path, recipes: list[str], profile) -> list[dict]:
    """The mean of one saved fit of each of ``recipes`` with the same seed (members that differ in
    method, not only in seed), named ``a+b``."""
    return averaged_rows(rows, folder, profile, lambda method: "+".join(recipes),
                         lambda method, seed: [(r, seed) for r in recipes] if method == recipes[0] else None)


def paired_difference(ratios: np.ndarray, baseline: np.ndarray) -> dict:
    """A recipe against a baseline on the same fits: ``ratios`` and ``baseline`` (N,) hold the
    ratio to the best fill of N (case, seed) fits each, in the same order. Returns the mean
    difference and its standard error, the same for the log ratio, and how many got better.

    The difference of two recipes is far less noisy on the same fits than their means are apart:
    the cases' own spread (0.4× to 1.3× the best fill) cancels.

    Example:
        >>> d = paired_difference(np.array([0.9, 1.0, 0.7]), np.array([1.0, 1.0, 1.0]))
        >>> round(d["mean"], 3), round(d["se"], 3), d["better"]
        (-0.133, 0.088, 2)
    """
    diff, log = ratios - baseline, np.log(ratios / baseline)
    n = len(diff)
    se = (lambda x: float(x.std(ddof=1) / np.sqrt(n)) if n > 1 else float("nan"))
    return dict(n=n, mean=float(diff.mean()), se=se(diff), log_mean=float(log.mean()), log_se=se(log),
                better=int((diff < 0).sum()))


def print_paired(fits: dict, best: dict) -> None:
    """Each recipe against ``default`` of its variant, on the (case, seed) fits both have."""
    lines = []
    for (recipe, variant), per_case in sorted(fits.items()):
        base = fits.get(("default", variant))
        if recipe == "default" or base is None:
            continue
        pairs = [(c, s) for c in sorted(per_case) if c in base for s in sorted(per_case[c]) if s in base[c]]
        if len(pairs) < 2:
            continue
        ratio = lambda fits_, c, s: fits_[c][s]["px"] / best[c]
        d = paired_difference(np.array([ratio(per_case, c, s) for c, s in pairs]),
                              np.array([ratio(base, c, s) for c, s in pairs]))
        lines.append(f"{recipe:<18}{variant:<11}{d['n']:>6}{d['mean']:>+9.3f} ± {d['se']:.3f}"
                     f"{d['log_mean']:>+9.3f} ± {d['log_se']:.3f}{d['better']:>5}/{d['n']}")
    if lines:
        header = f"{'paired vs default':<29}{'fits':>6}{'ratio diff ± se':>17}{'log diff ± se':>17}{'better':>9}"
        print("\n" + header + "\n" + "-" * len(header) + "\n" + "\n".join(lines))


def _ratios(rows: list[dict]) -> dict:
    """{(recipe, variant): {case: mean ratio over the seeds every case has}} over ``rows`` of any sizes,
    each case's ratio to its own best classical fill."""
    classical, fits = {}, {}
    for r in rows:
        key = (r["case"], r["size"])
        if r["variant"] is None:
            classical.setdefault(key, {})[r["method"]] = r["px"]
    for r in rows:
        key = (r["case"], r["size"])
        if r["variant"] is not None and key in classical:
            fits.setdefault((r["method"], r["variant"]), {}).setdefault(key, {})[r["seed"]] = r["px"]
    out = {}
    for recipe_variant, per_case in fits.items():
        seeds = set.intersection(*(set(v) for v in per_case.values()))
        if seeds:
            out[recipe_variant] = {c: np.mean([v[s] for s in seeds]) / min(classical[c].values())
                                   for c, v in per_case.items()}
    return out


def report_together(rows: list[dict]) -> None:
    """Every recipe over its synthetic and real cases together (each at its own size)."""
    ratios = _ratios(rows)
    if len({r["size"] for r in rows}) < 2 or not ratios:
        return
    header = f"{'recipe':<18}{'variant':<11}{'synthetic':>10}{'n':>4}{'real':>8}{'n':>4}{'real max':>9}{'all':>8}"
    print("\n=== together: mean ratio to the best classical fill (each case at its own size) ===\n"
          + header + "\n" + "-" * len(header))
    for (recipe, variant), per_case in sorted(ratios.items()):
        real = [v for (c, _), v in per_case.items() if is_real(c)]
        synthetic = [v for (c, _), v in per_case.items() if not is_real(c)]
        mean = lambda x: np.mean(x) if x else np.nan
        print(f"{recipe:<18}{variant:<11}{mean(synthetic):>10.3f}{len(synthetic):>4}{mean(real):>8.3f}{len(real):>4}"
              f"{(max(real) if real else np.nan):>9.3f}{mean(synthetic + real):>8.3f}")


def report(path: str, size: str | None = None, extra=None) -> None:
    """Print the tables of a results file; ``extra(rows)`` may return more rows (saved fits' ensembles)."""
    rows = read_rows(path)
    rows += extra(rows) if extra else []
    # rows of one size and profile are one table: a profile's fits are never scored against another's
    groups = sorted({(r["size"], r.get("profile") or "") for r in rows if size is None or r["size"] == size})
    for size_here, profile in groups:
        here = [r for r in rows if r["size"] == size_here and (r.get("profile") or "") == profile]
        classical = {}
        for r in here:
            if r["variant"] is None:
                classical.setdefault(r["case"], {})[r["method"]] = r["px"]
        fits = {}
        for r in here:
            if r["variant"] is not None and r["case"] in classical:
                fits.setdefault((r["method"], r["variant"]), {}).setdefault(r["case"], {})[r["seed"]] = r
        print(f"\n=== {size_here}{f', profile {profile}' if profile else ''}: hole RMSE (disparity px); "
              f"ratio = DDP / best classical fill of the case ===")
        cases = sorted(classical)
        best = {c: min(classical[c].values()) for c in cases}
        winner = {c: min(classical[c], key=classical[c].get) for c in cases}
        wins = {}
        for c in cases:
            wins[winner[c]] = wins.get(winner[c], 0) + 1
        print("best classical fill per case: " + ", ".join(f"{k} {v}" for k, v in sorted(wins.items(), key=lambda x: -x[1])))
        header = f"{'recipe':<18}{'variant':<11}{'cases':>6}{'seeds':>6}{'mean':>7}{'worst':>7}{'mean/seed':>10}" \
                 f"{'curved':>10}{'curved max':>11}{'wins':>6}{'s/fit':>7}"
        print(header)
        print("-" * len(header))
        for (recipe, variant), per_case in sorted(fits.items()):
            common = sorted(per_case)
            seeds = sorted(set.intersection(*(set(per_case[c]) for c in common)))
            if not seeds:
                continue
            mean_px = {c: np.mean([per_case[c][s]["px"] for s in seeds]) for c in common}
            ratios = np.array([mean_px[c] / best[c] for c in common])
            per_seed = [np.mean([per_case[c][s]["px"] / best[c] for c in common]) for s in seeds]
            real = np.array([mean_px[c] / best[c] for c in common if c.split("/")[0] not in NAMED])  # curved + fixture
            seconds = np.mean([per_case[c][s]["seconds"] for c in common for s in seeds])
            print(f"{recipe:<18}{variant:<11}{len(common):>6}{len(seeds):>6}{ratios.mean():>7.3f}{ratios.max():>7.3f}"
                  f"{np.mean(per_seed):>10.3f}{(real.mean() if real.size else np.nan):>10.3f}"
                  f"{(real.max() if real.size else np.nan):>11.3f}{int((ratios < 1).sum()):>6}{seconds:>7.1f}")
        print_paired(fits, best)
        if os.environ.get("QUALITY_PER_CASE"):
            for (recipe, variant), per_case in sorted(fits.items()):
                print(f"\n{recipe} {variant}")
                for c in sorted(per_case):
                    vals = [per_case[c][s]["px"] for s in sorted(per_case[c])]
                    print(f"  {c:<24} best {winner[c]:<13} {best[c]:.3f}  ddp " + " ".join(f"{v:.3f}" for v in vals)
                          + f"  ratio {np.mean(vals) / best[c]:.2f}")
    if size is None:
        report_together(rows)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_profile_args(parser)
    parser.add_argument("--quick", action="store_true", help="a small subset of the suite, for iterating")
    parser.add_argument("--cases", nargs="+", help="case names (scene/holes); default: the whole suite")
    parser.add_argument("--suite", choices=("synthetic", "real", "real-half", "all", "none", "middlebury"),
                        default="synthetic",
                        help="which cases (the real ones: the Middlebury Motorcycle pair at 125×185 or 250×370; "
                             "none: only --cases and --middlebury; middlebury: every scene under --data and "
                             "Motorcycle, benchmarks/bench_real.py)")
    parser.add_argument("--data", metavar="DIR", help="with --suite middlebury: the folder of Middlebury scenes "
                                                      "(default: the data root, else the shipped samples)")
    parser.add_argument("--real-size", choices=("eighth", "quarter"), default="eighth",
                        help="with --suite middlebury: ≈ 160×140 to iterate on, ≈ 320×280 to confirm")
    parser.add_argument("--refill", action="store_true",
                        help="with --suite middlebury: compute every fill's rows again (after a fill changed)")
    parser.add_argument("--middlebury", nargs="+", default=[], metavar="FOLDER",
                        help="other Middlebury 2014 pairs (im0/im1.png, disp0.pfm, calib.txt): their five real hole "
                             "kinds join the suite")
    parser.add_argument("--recipes", nargs="+", default=["default"])
    parser.add_argument("--variants", nargs="+", default=["rgbd", "rgbd+warp"], choices=("d", "rgbd", "rgbd+warp"))
    parser.add_argument("--seeds", type=seed_int, nargs="+", default=[0, 1])
    parser.add_argument("--lane", type=lane, default=(0, 1), help="i/n: run every n-th case starting at i (parallel lanes)")
    parser.add_argument("--out", help="append one JSON line per fit here (and skip fits already in it)")
    parser.add_argument("--report", metavar="JSONL", nargs="?", const=True,
                        help="print the tables of a results file and exit (alone: of --out, or with --suite "
                             "middlebury of the size's default file)")
    parser.add_argument("--save-fits", metavar="DIR", help="keep each DDP fit's output here (inverse depth, .npy)")
    parser.add_argument("--ensembles", type=positive_int, nargs="+", default=[], metavar="K",
                        help="with --report and --save-fits: also report the mean of K saved fits (seeds s..s+K-1)")
    parser.add_argument("--mixes", nargs="+", default=[], metavar="A+B",
                        help="with --report and --save-fits: also report the mean of one fit of each recipe (same seed)")
    return parser


def _middlebury_rows_path(args) -> Path:
    import bench_real

    if isinstance(args.report, str):
        return Path(args.report)
    samples = not args.data and bench_real.suite_data()[2]  # the shipped samples' rows: a file of their own
    return Path(args.out or bench_real.RESULTS / f"real_suite_{args.real_size}{'_samples' if samples else ''}.jsonl")


def check_args(args) -> None:
    """Every argument checked before any work (``ValueError`` naming the option): the cases, each recipe's
    config at every variant and seed, the data, the rows file and folders."""
    if args.report is True and not args.out and args.suite != "middlebury":
        raise ValueError("--report without a file reports --out's rows: give --report FILE or --out FILE")
    if args.refill and args.suite != "middlebury":
        raise ValueError("--refill acts on nothing without --suite middlebury")
    if (args.ensembles or args.mixes) and not (args.report and args.save_fits):
        raise ValueError("--ensembles and --mixes need --report and --save-fits (they average saved fits)")
    if args.report:
        check_rows_in(_middlebury_rows_path(args) if args.suite == "middlebury" else
                      (args.report if isinstance(args.report, str) else args.out), "--report")
        return
    if args.suite == "middlebury":
        _check_middlebury(args)
        return
    profile = profile_from_args(args)
    for name in args.cases or []:
        check_case_name(name)
    try:
        middlebury_cases(args.middlebury, profile)
    except (OSError, ValueError) as error:
        raise ValueError(f"--middlebury: {error}") from None
    recipes = [parse_recipe(r) for r in args.recipes]
    check_configs((f"--recipes {name}", lambda o=overrides, v=variant, s=seed_: FitConfig.for_profile(
        profile, variant=v, **{"seed": s, **o})) for name, overrides in recipes for variant in args.variants
        for seed_ in args.seeds)
    if args.out:
        check_rows_out(args.out)
    if args.save_fits:
        check_output_folder(args.save_fits, "--save-fits")


def _check_middlebury(args) -> None:
    import bench_real
    from ddp_lite.studies.real_suite import suite_case_names

    for given, flag in ((args.size, "--size"), (args.quick, "--quick"), (args.lane != (0, 1), "--lane"),
                        (args.middlebury, "--middlebury"), (args.save_fits, "--save-fits")):
        if given:
            raise ValueError(f"{flag} acts on nothing with --suite middlebury (its sizes are --real-size eighth or "
                             f"quarter; its cases --data's and --cases)")
    try:
        root = data_root(args.data) if args.data else bench_real.suite_data()[0]  # default: the data root, else samples
    except argparse.ArgumentTypeError as error:
        raise ValueError(f"--data: {error}") from None
    if args.cases:
        names = suite_case_names(root)
        unknown = [c for c in args.cases if c not in names]
        if unknown:
            raise ValueError(f"--cases: {', '.join(unknown)} not in the suite under {args.data} "
                             f"(its cases: {', '.join(names[:6])}, ...)")
    recipes = [r for r in args.recipes if r != "default"] or ["kit", "paper", "photo"]
    check_configs((f"--recipes {r}", lambda r=r, v=v, s=s: bench_real.recipe_config(args.profile, v, r, s))
                  for r in recipes for v in args.variants for s in args.seeds)
    check_rows_out(_middlebury_rows_path(args), "--out")


def main(argv=None) -> None:
    parser = build_parser()
    args = parse_args(parser, argv, check_args)
    if args.suite == "middlebury":
        import bench_real

        data, line, _ = bench_real.suite_data(args.data)  # default: the data root, else the shipped samples
        print(line, flush=True)
        out = _middlebury_rows_path(args)
        if not args.report:
            torch_threads = max(2, args.threads)  # the recipes of a case fit side by side, one thread each
            profile_from_args(argparse.Namespace(threads=torch_threads, profile=args.profile, size=None))
            recipes = [r for r in args.recipes if r != "default"] or ["kit", "paper", "photo"]
            if args.refill:
                bench_real.refill(data, args.real_size, out)
            else:
                bench_real.run(data, args.real_size, recipes, args.variants, args.seeds, out, args.profile,
                               args.cases)
            bench_real.report(out, args.real_size, args.profile)  # this run's rows, not another size's or profile's
        else:
            bench_real.report(out)
        return
    if args.report:
        report_path = args.report if isinstance(args.report, str) else args.out
        extra = None
        if (args.ensembles or args.mixes) and args.save_fits:
            profile = profile_from_args(args)
            extra = lambda rows: ([e for k in args.ensembles  # noqa: E731
                                   for e in ensemble_rows(rows, Path(args.save_fits), k, profile)]
                                  + [m for mix in args.mixes
                                     for m in mix_rows(rows, Path(args.save_fits), mix.split("+"), profile)])
        report(report_path, extra=extra)
        return
    run(args)
    if args.out:
        report(args.out)


if __name__ == "__main__":
    main()
