"""The notebooks' shared experiment plumbing: one scene → inputs → DDP variants → error table.

A notebook tells a story; the bookkeeping behind it (which view, which holes, which neighbours,
which disparity range, which error in which region) lives here so that every notebook measures
the same way. Errors are RMSE of *normalised disparity* ×100 (the representation DDP fits and
the unit the paper's Middlebury table uses), inside the holes, and inside the holes' part of the
band around depth edges, where depth-only filling bleeds (paper Fig. 3).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.camera import Camera
from ..method.paper.disparity import DisparityTransform
from ..method.config import FitConfig
from ..method.complete import complete_depth
from ..method.result import DepthResult
from ..method.runtime.options import RunOptions
from ..method.runtime.side_by_side import run_fits
from .fusion import points_from_depth
from ..classical.holes import edge_band_holes, random_holes
from .metrics import cloud_scores, disparity_rmse, edge_band
from ..method.profiles import Profile, get_profile
from ..world.neighbors import select_neighbors
from ..world.scenes import make_scene
from ..classical.stereo import sgm_depth_subsampled
from ..method.paper.variants import get_variant
from ..core.views import LABEL_SKY

__all__ = ["Case", "make_case", "sgm_depth_at_scale", "run_variants", "run_cases", "run_jobs", "error_table",
           "format_table", "format_ranking", "format_mean_spread", "ablation", "TABLE2_CONFIGS"]


@dataclass
class Case:
    """One reference view prepared for depth completion, with its ground truth."""

    name: str
    rgb: np.ndarray  # (H, W, 3) [0, 1]
    depth: np.ndarray  # (H, W) metres, NaN holes: the input
    gt: np.ndarray  # (H, W) metres, finite: the truth
    camera: Camera
    neighbors: list = field(default_factory=list)  # Views used by the warp loss
    transform: DisparityTransform | None = None
    scene: object = None
    ref: int = 0
    labels: np.ndarray | None = None  # (H, W) uint8 texture classes (views.LABEL_*), see views.LABELS

    @property
    def scored(self) -> np.ndarray:
        """(H, W) bool: where ground truth is scored (everything but the sky)."""
        return np.ones(self.gt.shape, bool) if self.labels is None else self.labels != LABEL_SKY

    @property
    def scored_gt(self) -> np.ndarray:
        """(H, W) metres: the ground truth with NaN where it is not scored (pass as ``gt_depth``)."""
        return np.where(self.scored, self.gt, np.nan).astype(np.float32)

    @property
    def holes(self) -> np.ndarray:
        """(H, W) bool: pixels to be filled (NaN in the input) and scored (not sky)."""
        return ~np.isfinite(self.depth) & self.scored

    def edge_holes(self, width: int = 3) -> np.ndarray:
        """(H, W) bool: holes within ``width`` px of a ground-truth depth edge."""
        return self.holes & edge_band(self.gt, width)


def sgm_depth_at_scale(scene_name: str, size, n_views: int, seed: int, ref=0, params="sparse",
                       scale: int | None = None):
    """SGM depth (H, W) metres with NaN holes for a scene rendered at ``size``, matched at ``scale``× size;
    ``ref`` an int (one map) or a sequence of view indices (a list of maps, one render).

    Semi-global matching needs texture detail that a 48×64 image does not have: there it fails
    almost everywhere, and what it returns is mostly wrong. So small images are matched at 3×
    the size and every 3rd pixel is kept, the centre one of each 3×3 block. With pinhole
    intrinsics scaled by 3 (f' = 3f, c' = 3c + 1, pixel (0, 0) at the centre of the top-left
    pixel) that pixel's ray is *exactly* the small pixel's ray, so the kept depth belongs to the
    small image's geometry. ``scale=None`` → 3 below 96 rows, else 1.
    """
    H, W = size
    scale = (3 if H < 96 else 1) if scale is None else int(scale)
    if scale < 1 or scale % 2 == 0:
        raise ValueError(f"scale must be an odd positive integer (so a pixel has a centre sample), got {scale}")
    scene = make_scene(scene_name, size=(H * scale, W * scale), n_views=n_views, seed=seed)
    refs = [ref] if np.isscalar(ref) else list(ref)
    depths = [sgm_depth_subsampled(scene, i, scale, params) for i in refs]  # each (H, W)
    return depths[0] if np.isscalar(ref) else depths


def make_case(scene_name: str = "house", profile: Profile | str | None = None, ref: int = 0, holes: str = "sgm",
              seed: int = 0, n_neighbors: int = 2, sgm_params: str = "sparse") -> Case:
    """Render a named scene at the profile's size and cut holes into view ``ref``'s depth.

    ``holes``: ``"sgm"`` (real OpenCV SGM holes), ``"random"`` (seeded blobs) or ``"edge"`` (a band
    across a depth edge plus random blobs).
    """
    profile = get_profile(profile)
    scene = make_scene(scene_name, size=profile.size, n_views=profile.n_views, seed=seed)
    view = scene[ref]
    if holes == "sgm":
        depth = sgm_depth_at_scale(scene_name, profile.size, profile.n_views, seed, ref, sgm_params)
    elif holes == "random":
        depth, _ = random_holes(view.depth, seed=seed)
    elif holes == "edge":
        banded, _ = edge_band_holes(view.depth, seed=seed)
        depth, _ = random_holes(banded, seed=seed)
    else:
        raise ValueError(f"holes must be 'sgm', 'random' or 'edge', got {holes!r}")
    neighbors = [scene[i] for i in select_neighbors(scene, ref, n_neighbors)] if n_neighbors else []
    meta = scene.meta
    if "d_min" in meta and "d_max" in meta:
        transform = DisparityTransform(meta["d_min"], meta["d_max"], meta.get("constant", 0.0))
    else:
        transform = DisparityTransform.from_depth(depth)
    labels = scene.labels[ref] if scene.labels else None
    return Case(scene_name, view.rgb, depth.astype(np.float32), view.depth, view.camera, neighbors, transform,
                scene, ref, labels)


def run_variants(case: Case, variants=("d", "rgbd", "rgbd+warp"), profile=None, net: str = "unet", *,
                 options: RunOptions | None = None, **config_overrides) -> dict[str, DepthResult]:
    """Fit each DDP variant on ``case`` with the profile's config for a notebook (``Profile.notebook_settings``:
    at ``ci`` a shorter run; ``config_overrides`` win); {variant: DepthResult}. The fits are independent and run
    side by side (:mod:`ddp_lite.method.runtime.side_by_side`)."""
    overrides = {**get_profile(profile).notebook_settings(), **config_overrides}
    results = run_jobs([(case, variant, net, overrides) for variant in variants], profile, options)
    return dict(zip(variants, results))


def run_cases(cases, variant: str = "rgbd", profile=None, net: str = "unet", *, options: RunOptions | None = None,
              **config_overrides) -> list[DepthResult]:
    """Fit ``variant`` on each of ``cases`` with the profile's config for a notebook (``Profile.notebook_settings``;
    ``config_overrides`` win), side by side → one DepthResult per case."""
    overrides = {**get_profile(profile).notebook_settings(), **config_overrides}
    return run_jobs([(case, variant, net, overrides) for case in cases], profile, options)


def run_jobs(jobs, profile=None, options: RunOptions | None = None) -> list[DepthResult]:
    """Each ``(case, variant, net, {FitConfig field: value})`` of ``jobs`` fitted with the profile's config
    (the case's ground truth for the fit's history), run with ``options`` (:class:`RunOptions`; None →
    ``RunOptions()``) → DepthResults in the same order. The fits are
    independent: on a CPU they run side by side, one torch thread each, as many at once as torch has
    threads (:mod:`ddp_lite.method.runtime.side_by_side`); a fit gives the numbers of one thread."""
    options = RunOptions() if options is None else options
    configs = [FitConfig.for_profile(profile, variant=variant, net=net, **options) for _, variant, net, options in jobs]
    partners = [case.neighbors if get_variant(variant).needs_neighbors else () for case, variant, *_ in jobs]

    def fit(k: int) -> DepthResult:
        case, variant = jobs[k][0], jobs[k][1]
        return complete_depth(case.rgb, case.depth, case.camera, partners[k], variant=variant, config=configs[k],
                              gt_depth=case.scored_gt, transform=case.transform, options=options)
    return run_fits(fit, [(config, variant, case.depth.shape, len(neighbors))
                          for config, (case, variant, *_), neighbors in zip(configs, jobs, partners)], options)


def error_table(case: Case, estimates: dict, band: int = 3) -> dict[str, dict[str, float]]:
    """{method: {"holes": RMSE×100, "edge band": RMSE×100}} of normalised disparity for depth maps
    or :class:`DepthResult` values in ``estimates``."""
    table = {}
    for name, estimate in estimates.items():
        depth = estimate.depth if isinstance(estimate, DepthResult) else estimate
        table[name] = {"holes": disparity_rmse(depth, case.gt, case.holes, case.transform),
                       "edge band": disparity_rmse(depth, case.gt, case.edge_holes(band), case.transform)}
    return table


def format_table(table: dict[str, dict[str, float]], digits: int = 2, title: str = "") -> str:
    """A plain-text table of ``{row: {column: value}}``, rows in the given order; each column at least
    12 characters wide and 2 wider than its name, so that long names stay apart.

    Example:
        >>> print(format_table({"DDP": {"depth PSNR": 16.7, "reproj. PSNR": 21.0}}, digits=1))
               depth PSNR  reproj. PSNR
        DDP          16.7          21.0
    """
    columns = list(next(iter(table.values())).keys())
    width = max(len(str(r)) for r in table) + 2
    widths = [max(12, len(str(c)) + 2) for c in columns]
    lines = [title] if title else []
    lines.append(" " * width + "".join(f"{c:>{w}}" for c, w in zip(columns, widths)))
    for row, values in table.items():
        lines.append(f"{str(row):<{width}}" + "".join(f"{values[c]:>{w}.{digits}f}" for c, w in zip(columns, widths)))
    return "\n".join(lines)


def format_ranking(table: dict[str, dict[str, float]], digits: int = 3) -> str:
    """``table`` {case: {method: error}} → the methods ranked by their mean error over the cases, one
    line each: the error per case, the mean and the rank (1 = best). Every case must have every method.

    Example:
        >>> print(format_ranking({"a": {"x": 1.0, "y": 3.0}, "b": {"x": 2.0, "y": 1.0}}, digits=1))
        method                        a        b  average  rank
        x                           1.0      2.0      1.5     1
        y                           3.0      1.0      2.0     2
    """
    cases = list(table)
    methods = list(table[cases[0]])
    average = {m: float(np.mean([table[c][m] for c in cases])) for m in methods}
    lines = [f"{'method':<22}" + "".join(f"{c:>9}" for c in cases) + f"{'average':>9}{'rank':>6}"]
    for rank, m in enumerate(sorted(methods, key=average.get), 1):
        lines.append(f"{m:<22}" + "".join(f"{table[c][m]:>9.{digits}f}" for c in cases)
                     + f"{average[m]:>9.{digits}f}{rank:>6}")
    return "\n".join(lines)


def format_mean_spread(runs: list[dict[str, dict[str, float]]], digits: int = 2, title: str = "") -> str:
    """A plain-text table of "mean ± std" over several ``{row: {column: value}}`` tables (same rows
    and columns, e.g. one per scene and seed), rows in the order of the first; std is the sample
    std. A single run has no spread: its values alone."""
    rows, columns = list(runs[0]), list(next(iter(runs[0].values())))
    width = max(len(str(r)) for r in rows) + 2
    cell = 2 * (digits + 5) + 3
    lines = [title] if title else []
    lines.append(" " * width + "".join(f"{c:>{cell}}" for c in columns))
    for row in rows:
        text = f"{str(row):<{width}}"
        for column in columns:
            values = np.array([run[row][column] for run in runs], dtype=float)
            mean = f"{values.mean():.{digits}f}"
            text += f"{f'{mean} ± {values.std(ddof=1):.{digits}f}' if len(values) > 1 else mean:>{cell}}"
        lines.append(text)
    return "\n".join(lines)


TABLE2_CONFIGS = {  # Table 2's rows: (network, variant)
    "UNet + D": ("unet", "d"),
    "UNet + RGBD": ("unet", "rgbd"),
    "UNet + RGBD + warp": ("unet", "rgbd+warp"),
    "SkipNet + RGBD + warp": ("skip", "rgbd+warp"),
}


# How many (scene, seed) cases notebook 05 runs live at each profile: ci and class the first scene's first seed
# (one fit per row; ci checks the flow, class fits in a lab's minutes), paper every scene × seed. The full
# table with its spread at any profile: benchmarks/bench_ablation.py.
LIVE_ABLATION_CASES = {"ci": 1, "class": 1, "paper": None}


def ablation_cases(scenes, profile=None) -> list[tuple[str, int]]:
    """The (scene, seed) cases notebook 05 runs live at ``profile`` (a name, a Profile or None:
    ``DDP_PROFILE``): every scene in ``scenes`` × the profile's seeds, cut to the first
    ``LIVE_ABLATION_CASES[profile]`` of them (None: all), scene by scene, seed by seed."""
    if isinstance(scenes, str):
        raise TypeError(f"scenes must be a sequence of scene names, not one name: got {scenes!r}")
    profile = get_profile(profile)
    scenes = tuple(scenes)
    if not scenes or not all(isinstance(scene, str) for scene in scenes):
        raise ValueError(f"scenes must be a non-empty sequence of scene names, got {scenes!r}")
    cases = [(scene, seed) for scene in scenes for seed in profile.seeds]
    return cases[:LIVE_ABLATION_CASES.get(profile.name)]


def ablation(cases, configs: dict | None = None, profile=None, holes: str = "edge", tau: float = 0.01, log=print,
             **config_overrides):
    """Notebook 05's ablation (Table 2): every config ``{row: (net, variant)}`` or ``{row: (net, variant,
    {FitConfig field: value})}`` on every (scene, seed) case.

    Returns ``(runs, examples)``: ``runs`` holds one ``{row: {"holes", "edge band", "P", "R", "F"}}``
    per case (RMSE ×100 of normalised disparity; P/R/F % of the completed view's cloud at
    ``tau`` × the median depth, "SGM+DDP" style, sky not scored); ``examples`` is
    ``{scene: (case, {row: DepthResult})}`` for the first case of each scene, so that a figure draws
    each fit against the holes and ground truth it was fitted on. ``config_overrides`` go to every
    fit (e.g. ``gammas=(0.5, 0.5)``), after ``Profile.notebook_settings`` (at ``ci`` a shorter run).
    """
    configs = TABLE2_CONFIGS if configs is None else configs
    short = get_profile(profile).notebook_settings()
    if short and "iterations" not in config_overrides:
        log(f"each fit {short['iterations']} iterations (the profile's notebook_iterations)")
    config_overrides = {**short, **config_overrides}
    runs, examples = [], {}
    made = [(scene, seed, make_case(scene, profile, holes=holes, seed=seed)) for scene, seed in cases]
    jobs = [(case, variant, net, {**config_overrides, **(extra[0] if extra else {}), "seed": seed})
            for _, seed, case in made for net, variant, *extra in configs.values()]
    fitted = iter(run_jobs(jobs, profile, RunOptions(progress=False)))  # every fit of the table side by side, in the table's order
    for scene, seed, case in made:
        gt_points = points_from_depth(case.scored_gt, case.camera)
        distance = tau * float(np.nanmedian(case.scored_gt))
        run, results = {}, {}
        for row, result in zip(configs, fitted):
            merged = np.where(case.scored, result.merged(case.depth), np.nan)  # "SGM+DDP", sky not scored
            run[row] = {**error_table(case, {row: result})[row],
                        **cloud_scores(points_from_depth(merged, case.camera), gt_points, distance)}
            results[row] = result
        examples.setdefault(scene, (case, results))
        runs.append(run)
        log(f"{scene} seed {seed}: " + ", ".join(f"{row} {v['holes']:.2f}" for row, v in run.items()))
    return runs, examples
