"""Real completion cases: the Middlebury *Motorcycle* pair (``middlebury.load_motorcycle``), or any other
Middlebury 2014 pair (``middlebury.load_middlebury``), with holes.

The synthetic scenes flatter DDP: their colour edges are depth edges and their surfaces are clean.
A real photograph has texture everywhere, soft shading, and depth edges without colour edges. These
cases put the real image, its real ground truth and real stereo failures in front of every fill.

The pair is pooled from 500×740 (one column cropped) by an integer ``factor`` (8: 62×92, 4: 125×185,
2: 250×370, 1: full size; ``factor_for_profile`` picks the one nearest a profile's size):
colour by the block mean, depth by the block mean of *inverse* depth (so of disparity: the block's
mean disparity), valid where at least 3/4 of the block is known. Pooling, not sub-sampling, keeps the
colour and the depth of a pixel averaged over the same block. Hole kinds (``REAL_HOLES``):

- ``blobs-1``, ``blobs-2``, ``blobs-3``: Depthcomp-style smooth blobs (20 % of the pixels, three fixed
  patterns) cut into the ground truth;
- ``sgbm``: OpenCV SGBM (``stereo.sgm_disparity``, dense parameters, left-right checked) on the
  full-size pair, pooled: the input is SGBM's own depth, with its errors, where it answered;
- ``occlusion``: the ground truth with holes where SGBM's left-right check fails (pixels the right
  view does not see, mostly), pooled as a hole wherever a block has one.

The truth's unknown pixels are holes in every input and are never scored (``RealCase.scored_holes``).
Another pair (``make_real_case(..., scene=folder)``) is cut the same way: cropped to a multiple of 4
rows and columns, pooled, holed; judge a method on several, not on Motorcycle alone.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from ..classical.baselines import BASELINES
from ..evaluation.experiments import Case
from ..method.config import FitConfig
from ..method.complete import complete_depth
from ..method.kit.combine import blend_members, blended_result, mixed_with_fill, refined
from ..classical.holes import random_holes
from ..data.middlebury import load_middlebury, load_motorcycle
from ..method.profiles import get_profile
from ..method.runtime.options import RunOptions
from ..method.runtime.side_by_side import run_fits
from ..classical.stereo import sgm_disparity, sgm_left_right_failures
from ..core.views import Scene, View

__all__ = ["REAL_HOLES", "REAL_FACTORS", "make_real_case", "pool_scene", "RealCase", "factor_for_profile", "factor_for_pixels",
           "compare_fills", "compare_fills_on"]

REAL_HOLES = ("blobs-1", "blobs-2", "blobs-3", "sgbm", "occlusion")
REAL_FACTORS = {8: "62x92", 4: "125x185", 2: "250x370", 1: "500x740"}  # Motorcycle's pooled sizes
_CROP_MULTIPLE = 4  # rows and columns cropped to a multiple of 4 (Motorcycle: 741 → 740 columns)


@dataclass
class RealCase(Case):
    """A :class:`~ddp_lite.evaluation.experiments.Case` on a real image: ``gt`` has NaN where the truth is unknown,
    ``fb`` = f·B (px · m) at the working size, so disparity (px) = fb / depth − doffs. ``depth_source``: where the
    input depth came from, as a caller would declare it to ``FitConfig(depth_source=...)``: ``"stereo"`` for
    SGBM's depth, ``"clean"`` for the truth with holes cut."""

    fb: float = 1.0
    depth_source: str = "clean"

    @property
    def scored_holes(self) -> np.ndarray:
        """(H, W) bool: holes of the input where the truth is known, the only pixels scored."""
        return ~np.isfinite(self.depth) & np.isfinite(self.gt)

    def rmse_px(self, depth, mask=None) -> float:
        """Hole RMSE of ``depth`` (H, W) metres against the truth, in disparity pixels of the working size,
        over the scored holes (or the part ``mask`` (H, W) bool of them; NaN if that is empty)."""
        mask = self.scored_holes if mask is None else mask & self.scored_holes
        if not mask.any():
            return float("nan")
        return float(np.sqrt(np.mean((self.fb / depth[mask] - self.fb / self.gt[mask]) ** 2)))

    def regions(self) -> dict[str, np.ndarray]:
        """Where in the scored holes an error comes from, (H, W) bool each: ``edges`` (within 2 px of a
        depth edge of the truth: a disparity step > 1 px), ``textured`` / ``smooth`` (grey-level standard
        deviation over 5×5 above / below 0.03), ``near`` / ``far`` (≤ / > 6 px from the nearest valid
        input pixel)."""
        disparity = np.nan_to_num(self.fb / self.gt, nan=0.0)
        step = np.zeros(disparity.shape, bool)
        step[:, 1:] |= np.abs(np.diff(disparity, axis=1)) > 1.0
        step[1:] |= np.abs(np.diff(disparity, axis=0)) > 1.0
        edges = ndimage.binary_dilation(step, iterations=2)
        grey = self.rgb.mean(axis=2)
        local_std = np.sqrt(np.maximum(ndimage.uniform_filter(grey ** 2, 5) - ndimage.uniform_filter(grey, 5) ** 2, 0))
        distance = ndimage.distance_transform_edt(~np.isfinite(self.depth))
        scored = self.scored_holes
        return {"edges": scored & edges, "textured": scored & (local_std > 0.03), "smooth": scored & (local_std <= 0.03),
                "near": scored & (distance <= 6), "far": scored & (distance > 6)}


def _pool_mean(array: np.ndarray, factor: int) -> np.ndarray:
    """Block means of (H·f, W·f, ...) → (H, W, ...), NaN-aware; NaN where < 3/4 of a block is finite."""
    H, W = array.shape[0] // factor, array.shape[1] // factor
    blocks = array[:H * factor, :W * factor].reshape(H, factor, W, factor, *array.shape[2:])
    finite = np.isfinite(blocks)
    total = np.where(finite, blocks, 0.0).sum(axis=(1, 3))
    count = finite.sum(axis=(1, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = total / count
    return np.where(count >= 0.75 * factor * factor, mean, np.nan).astype(np.float32)


def _pool_depth(depth: np.ndarray, factor: int) -> np.ndarray:
    """Depth (H·f, W·f) metres → (H, W): the block mean of inverse depth, inverted (NaN where unknown)."""
    with np.errstate(divide="ignore"):
        inverse = _pool_mean(1.0 / depth, factor)
    return (1.0 / inverse).astype(np.float32)


def pool_scene(scene: Scene, factor: int) -> Scene:
    """A stereo ``scene`` pooled by an integer ``factor``: colour by block means, depth by block means of
    inverse depth (valid where ≥ 3/4 of the block is), cameras and pixel ``meta`` scaled. The input is not
    modified. Pixel (0, 0) stays the centre of the top-left (pooled) pixel: ``Camera.resized``."""
    def pooled(view: View) -> View:
        H, W = view.depth.shape[0] // factor, view.depth.shape[1] // factor
        cropped = view.camera.__class__(view.camera.K, view.camera.cam_from_world, W * factor, H * factor)
        return View(_pool_mean(view.rgb, factor), _pool_depth(view.depth, factor), cropped.resized(W, H), view.name)
    meta = {k: (float(v) / factor if k in ("doffs", "ndisp", "focal") else v) for k, v in scene.meta.items()}
    return Scene(scene.name, [pooled(v) for v in scene.views], [pooled(v) for v in scene.right], meta)


def make_real_case(holes: str = "sgbm", factor: int = 4, scene=None, hole_mask=None) -> RealCase:
    """A real stereo pair pooled by ``factor`` with holes of kind ``holes`` (one of ``REAL_HOLES``) →
    :class:`RealCase` named ``"<scene>/<holes>"`` (the right view as the warp loss's neighbour). Deterministic.

    ``scene``: None for the Motorcycle pair (``REAL_FACTORS`` gives its pooled sizes), or another
    Middlebury 2014 pair: a folder (``middlebury.load_middlebury``) or a loaded one-view stereo
    :class:`~ddp_lite.core.views.Scene` with a right view and ``meta`` ``baseline`` (m), ``doffs`` (px)
    and ``ndisp``, at the size SGBM should run at. ``factor``: a positive integer. A scene with more than
    one view (``middlebury_rail.load_rail_scene``) gives its other views as the warp loss's neighbours
    (view0 and view2 of the rail), one with a single view its right view.

    ``hole_mask``: (H, W) bool at the scene's full size, True = hole (DepthComp's own holes, the truth's
    occluded pixels): then ``holes`` only names the kind, and the mask is pooled as a hole where at
    least half of a block is one.

    Example:
        >>> case = make_real_case("blobs-1", factor=4)
        >>> case.name, case.depth.shape, round(float(np.isnan(case.depth).mean()), 2) >= 0.2
        ('motorcycle/blobs-1', (125, 185), True)
    """
    if hole_mask is None and holes not in REAL_HOLES:
        raise ValueError(f"holes must be one of {REAL_HOLES}, got {holes!r}")
    if hole_mask is not None and (not isinstance(holes, str) or not holes or "/" in holes):
        raise ValueError(f"holes must name the kind of hole_mask (a word without '/'), got {holes!r}")
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ValueError(f"factor must be a positive integer, got {factor!r}")
    if scene is None:
        full, name = load_motorcycle(), "motorcycle"
    else:
        full = scene if isinstance(scene, Scene) else load_middlebury(scene)
        if not full.right or not {"baseline", "doffs"} <= set(full.meta):
            raise ValueError("scene must be a Middlebury stereo pair: a right view and meta 'baseline' and 'doffs' "
                             f"(load_middlebury gives them), got right views {len(full.right)}, meta {sorted(full.meta)}")
        name = full.name
    if hole_mask is not None:
        hole_mask = np.asarray(hole_mask)
        if hole_mask.dtype != bool or hole_mask.shape != full[0].depth.shape:
            raise ValueError(f"hole_mask must be a bool (H, W) = {full[0].depth.shape} array like the scene, got "
                             f"{hole_mask.dtype} {hole_mask.shape}")
    full = _cropped(full)
    scene = pool_scene(full, factor)
    view, gt = scene[0], scene[0].depth
    H, W = gt.shape
    if hole_mask is not None:
        blocks = hole_mask[:H * factor, :W * factor].reshape(H, factor, W, factor)
        depth = np.where(blocks.mean(axis=(1, 3)) >= 0.5, np.nan, gt).astype(np.float32)
    elif holes.startswith("blobs"):
        depth, _ = random_holes(gt, fraction=0.2, seed=int(holes.split("-")[1]), blob_size=min(H, W) / 10)
    elif holes == "sgbm":
        disparity, _ = sgm_disparity(_stereo_pair(full), 0, "dense")  # (H·f, W·f) px, NaN holes
        shifted = disparity + float(full.meta["doffs"])
        with np.errstate(invalid="ignore", divide="ignore"):
            sgbm = np.where(shifted > 0, float(full[0].camera.focal * full.meta["baseline"]) / shifted, np.nan)
        depth = _pool_depth(sgbm.astype(np.float32), factor)
    else:  # occlusion
        failed = sgm_left_right_failures(_stereo_pair(full), 0, "dense")  # (H·f, W·f) bool
        blocks = failed[:H * factor, :W * factor].reshape(H, factor, W, factor).any(axis=(1, 3))
        depth = np.where(blocks, np.nan, gt).astype(np.float32)
    fb = float(view.camera.focal * scene.meta["baseline"])
    neighbors = list(scene.views[1:]) or [scene.right[0]]
    return RealCase(f"{name}/{holes}", view.rgb, depth, gt, view.camera, neighbors, None, scene, 0, None, fb=fb,
                    depth_source="stereo" if holes == "sgbm" and hole_mask is None else "clean")


def _stereo_pair(scene: Scene) -> Scene:
    """The reference view and its stereo partner alone (a rail scene also holds its neighbours)."""
    return Scene(scene.name, scene.views[:1], scene.right[:1], dict(scene.meta))


def factor_for_profile(profile=None, shape=(500, 741)) -> int:
    """The pooling factor of a real pair of full size ``shape`` (H, W; Motorcycle's by default) for a
    profile: the smallest whose image has at most twice the profile's pixels (Motorcycle: ``ci`` 48×64 → 8,
    ``class`` 96×128 → 4, ``paper`` → 1)."""
    H, W = get_profile(profile).size
    rows, columns = (n - n % _CROP_MULTIPLE for n in shape)
    factor = 1
    while (rows // factor) * (columns // factor) > 2 * H * W:
        factor *= 2
    return factor


def factor_for_pixels(shape, pixels: int) -> int:
    """The smallest integer pooling factor that brings a pair of full size ``shape`` (H, W), cropped as
    :func:`make_real_case` crops it, to at most ``pixels`` pixels.

    Example:
        >>> factor_for_pixels((277, 316), 96 * 128)  # a quarter-size Middlebury 2006 view at class's pixels
        3
    """
    rows, columns = (n - n % _CROP_MULTIPLE for n in shape)
    factor = 1
    while (rows // factor) * (columns // factor) > pixels:
        factor += 1
    return factor


def compare_fills(case: RealCase, profile=None, recipes=("paper", "kit"), variant: str = "rgbd", seed: int = 0,
                  options: RunOptions = RunOptions(progress=False)) -> dict[str, np.ndarray]:
    """Every classical fill (``baselines.BASELINES``) and DDP under each of ``recipes`` on ``case``
    → {name: (H, W) disparity in px of the working size}, the input kept where it is valid.

    The classical fills fill the disparity map (d = f·B/Z); DDP fits its own normalised disparity,
    from the input depth's range, with the profile's size and budget (``rgbd+warp`` warps the right
    view), told the case's ``depth_source``. Names: the fills' keys, then ``"DDP <recipe>"``. A blend of two
    recipes listed before it (of ``paper`` and ``kit``), or a recipe whose fit is one listed before it with
    only the refinement or the fill's share changed, is built from the fits it reuses: the same method, fewer
    fits (``photo`` fits without the kit's hole terms: a fit of its own).
    The fits run side by side (:mod:`ddp_lite.method.runtime.side_by_side`), as ``options`` say (no progress bars
    by default).
    """
    return compare_fills_on([case], profile, recipes, variant, seed, options)[0]


def compare_fills_on(cases: list, profile=None, recipes=("paper", "kit"), variant: str = "rgbd", seed: int = 0,
                     options: RunOptions = RunOptions(progress=False), **config_overrides) -> list[dict[str, np.ndarray]]:
    """:func:`compare_fills` of each of ``cases``, the fits of every case side by side in one pool (case by
    case, three fits on two cores leave one idle for the third) → one {name: (H, W) px} per case.
    ``config_overrides`` (``FitConfig`` fields) go to every fit, e.g. a shorter run (``Profile.cut_short``)."""
    configs = [[FitConfig.for_profile(profile, variant=variant, recipe=recipe, seed=seed,
                                      depth_source=case.depth_source, **config_overrides) for recipe in recipes]
               for case in cases]
    fitted = _plain_fits_on(list(zip(cases, configs)), variant, options)  # per case: (config, result) pairs
    outs = []
    for case, case_configs, case_fitted in zip(cases, configs, fitted):
        disparity_in = case.fb / case.depth  # (H, W) px (plus doffs: a constant, it cancels in every error)
        out = {name: fill(disparity_in, case.rgb) for name, fill in BASELINES.items()}
        for recipe, config in zip(recipes, case_configs):
            out[f"DDP {recipe}"] = case.fb / _fit_reusing(case, variant, config, case_fitted, options).merged(case.depth)
        outs.append(out)
    return outs


def _planned(configs: list) -> list:
    """The plain fits the recipes ``configs`` need: each without its fill's share and its refinement; a blend
    of two fits listed before it needs none of its own, nor a recipe whose share is chosen on held-out depth."""
    planned = []
    for config in configs:
        if config.combination.blend_fill is None:
            continue  # its share is chosen on depth held out of the fit: a fit of its own
        base = config.replace(blend_fill=0.0, refine=False, depth_source="clean")
        blend = base.combination
        if blend.blend_paper and blend.blend_weight is not None and all(m in planned for m in blend_members(base)):
            continue
        if base not in planned:
            planned.append(base)
    return planned


def _plain_fits(case: RealCase, variant: str, configs: list, options: RunOptions) -> list:
    """The plain fits (:func:`_planned`) of the recipes ``configs`` on ``case``, side by side → [(config, DepthResult)]."""
    return _plain_fits_on([(case, configs)], variant, options)[0]


def _plain_fits_on(items: list, variant: str, options: RunOptions) -> list:
    """:func:`_plain_fits` of each ``(case, configs)`` in ``items``, all their fits in one side-by-side pool
    → one [(config, DepthResult)] per item."""
    jobs = [(item, case, config) for item, (case, configs) in enumerate(items) for config in _planned(configs)]

    def neighbors(case):
        return case.neighbors if variant == "rgbd+warp" else ()

    def fit(k: int):
        _, case, config = jobs[k]
        return complete_depth(case.rgb, case.depth, case.camera, neighbors(case), variant=variant, config=config,
                              options=options)
    results = run_fits(fit, [(config, variant, case.depth.shape, len(neighbors(case))) for _, case, config in jobs],
                       options)
    grouped = [[] for _ in items]
    for (item, _, config), result in zip(jobs, results):
        grouped[item].append((config, result))
    return grouped


def _fit_reusing(case: RealCase, variant: str, config: FitConfig, fitted: list, options: RunOptions):
    """``complete_depth`` of ``case`` under ``config``, from the plain fits in ``fitted`` (:func:`_plain_fits`):
    one of them, or a blend of two (a recipe with ``blend_paper`` after ``kit`` and ``paper``, same seed),
    refined when the config asks (``photo`` after ``kit``), with the config's share of the fill mixed in after."""
    share = config.combination.blend_fill
    if share is None:  # the share is chosen on depth held out of the fit: a fit of its own
        neighbors = case.neighbors if variant == "rgbd+warp" else ()
        return complete_depth(case.rgb, case.depth, case.camera, neighbors, variant=variant, config=config,
                              options=options)
    base = config.replace(blend_fill=0.0, refine=False, depth_source="clean")
    same = [result for c, result in fitted if c == base]
    if same:
        result = same[0]
    else:  # _plain_fits planned no fit of its own: a blend of two it did
        done = [result for wanted in blend_members(base) for c, result in fitted if c == wanted]
        result = blended_result(done, done[0].transform, base.combination.blend_weight)
    if config.combination.refine:
        result = refined(result, case.depth, case.rgb, config.combination.depth_source)
    return mixed_with_fill(result, case.depth, case.rgb, share, config.combination.depth_source) if share else result


def _cropped(scene: Scene) -> Scene:
    """The full-size pair cropped to a multiple of ``_CROP_MULTIPLE`` rows and columns (the bottom and
    right-most dropped; K unchanged)."""
    rows, columns = (n - n % _CROP_MULTIPLE for n in scene[0].depth.shape)

    def crop(view: View) -> View:
        camera = view.camera.__class__(view.camera.K, view.camera.cam_from_world, columns, rows)
        return View(view.rgb[:rows, :columns], view.depth[:rows, :columns], camera, view.name)
    return Scene(scene.name, [crop(v) for v in scene.views], [crop(v) for v in scene.right], dict(scene.meta))
