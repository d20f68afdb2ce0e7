"""Full-resolution refinement: a working-size fit, up-sampled, made sharp at the photo's own resolution.

A DDP fit runs at a working size (``sequences.working_size``: ~96×128 at ``class``) and its completed depth,
up-sampled into the holes of a full-size photo, is blurred across every depth edge the holes hold (each
working pixel spans several full-size ones). Here that up-sampled fit becomes the *target* of one
edge-aware solve at full size, guided by the full-size colour image, in disparity (1/Z):

    minimise   Σ_i c_i (x_i − t_i)²  +  λ · Σ_ij w_ij(colour) (x_i − x_j)²

with t = the valid input where it is valid (confidence c = 1) and the up-sampled fit in the holes
(confidence c = ``hole_confidence`` < 1), the fit first corrected by its own error on the valid pixels
(input − fit), carried into the holes by the same solve (``residual``). The valid depth around a hole is then carried into it along
surfaces of one colour and stops at colour edges, while the fit still decides where no valid pixel of
the same surface is near. The valid input pixels are returned exactly as given; only the holes change.

Solvers (``method``), chosen by ``benchmarks/bench_full_resolution.py`` on Motorcycle's blob and SGBM
holes and six Middlebury HalfSize scenes (the figures: ``docs/studies/real_suite.md``; the residual step
is what takes the default below the best classical fill):

- ``bilateral-solver`` (default, c = 0.01 in the holes): Barron & Poole's fast bilateral solver with the
  confidence c, on the kit's bilateral grid (``classical.guided_fills``).
- ``fgs``: the fast global smoother (Min et al. 2014, OpenCV ``ximgproc``), normalised:
  x = FGS(c·t) / FGS(c), the weighted least-squares solve above by separable 1-D passes.
- ``guided-filter``: He et al.'s guided filter with the confidence as each pixel's weight in every
  window's affine colour model (``classical.guided_fills``): local (window ``radius``).

:func:`refine_over_smoothness` averages the bilateral solver's solve over four (``sigma_xy``, ``lam``)
settings: the ``refine`` of the ``photo`` recipe at a fit's own size, where it beats the one default
solve on the real suite. At a photo's full size the one solve is as good, at a quarter of the time, and
``complete`` runs it (the studies: ``docs/studies/real_suite.md``).

The solves' reach (``sigma_xy``) is tuned in pixels at one size: at a fit's own size on the eighth-size real
suite (``SMOOTHNESS_TUNED_SHORT_SIDE``), at a photo's full size on ≤ 555-row photos
(``FULL_SIZE_TUNED_SHORT_SIDE``). On a larger image the kit's steps scale it with the short side
(:func:`smoothness_at`, :func:`full_size_solve`), so the solve reaches as far across the surfaces there;
:func:`refine_full_resolution` itself takes pixels as given.
"""
from __future__ import annotations

import cv2
import numpy as np

from .depth_fills import check_fill_input, nearest_values
from .holes import hole_rim
from ..core.checks import check_int
from ..core.pixel_lengths import PixelLength

__all__ = ["REFINEMENTS", "SMOOTHNESS_MEAN", "SMOOTHNESS_STEREO", "SMOOTHNESS_TUNED_SHORT_SIDE", "FULL_SIZE_SOLVE",
           "FULL_SIZE_TUNED_SHORT_SIDE", "smoothness_at", "full_size_solve", "refine_full_resolution",
           "refine_over_smoothness", "hole_confidence_map"]

REFINEMENTS = ("fgs", "bilateral-solver", "guided-filter")

_DEFAULTS = {
    "fgs": {"lam": 300.0, "sigma_color": 8.0},
    "bilateral-solver": {"lam": 4.0, "sigma_xy": 8.0, "sigma_luma": 8.0, "sigma_chroma": 8.0},
    "guided-filter": {"radius": 8, "eps": 1e-3},
}


def _check_positive(value, name: str) -> float:
    if isinstance(value, bool) or not np.isscalar(value) or not np.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a positive number, got {value!r}")
    return float(value)


def hole_confidence_map(valid, hole_confidence: float) -> np.ndarray:
    """(H, W) float64 confidence of the target: 1 on ``valid`` (H, W) bool pixels, ``hole_confidence`` in the holes."""
    return np.where(valid, 1.0, float(hole_confidence))


def _fgs(guide: np.ndarray, values: np.ndarray, confidence: np.ndarray, lam: float, sigma_color: float):
    """Normalised fast global smoother: FGS(c·t) / FGS(c), guide (H, W, 3) uint8."""
    smooth = cv2.ximgproc.fastGlobalSmootherFilter
    num = smooth(guide, (confidence * values).astype(np.float32), lam, sigma_color)
    den = smooth(guide, confidence.astype(np.float32), lam, sigma_color)
    return num.astype(np.float64) / np.maximum(den.astype(np.float64), 1e-12)


def _guided(image: np.ndarray, values: np.ndarray, confidence: np.ndarray, radius: int, eps: float):
    """Confidence-weighted guided filter: per window, the affine colour model fitted to c-weighted
    targets (``guided_fills.masked_guided_filter``), averaged over the windows covering a pixel."""
    from .guided_fills import masked_guided_filter
    q, _ = masked_guided_filter(image, values, confidence, int(radius), float(eps))
    return q


def _bilateral_system(image: np.ndarray, lam: float, sigma_xy: float, sigma_luma: float, sigma_chroma: float):
    """Barron & Poole's bilateral grid of ``image`` (H, W, 3) (``guided_fills``) and its smoothness term:
    (S vertices × pixels, lam · the bistochastic grid Laplacian); one per image and setting, for every solve on it."""
    from scipy import sparse

    from .guided_fills import bilateral_grid, bistochastic
    S, blur = bilateral_grid(np.clip(image, 0.0, 1.0), sigma_xy, sigma_luma, sigma_chroma)
    _, n = bistochastic(S, blur)
    Dn = sparse.diags(n)
    affinity = Dn @ blur @ Dn
    laplacian = sparse.diags(np.asarray(affinity.sum(axis=1)).ravel()) - affinity
    return S, lam * laplacian


def _bilateral_solver(system, values: np.ndarray, confidence: np.ndarray, initial=None):
    """The solve with confidence c on a :func:`_bilateral_system`; conjugate gradients start from the grid's
    mean of ``initial`` (H, W) (default: of c·t / c), which is also what a part of the grid that no confident
    pixel reaches keeps."""
    from scipy import sparse
    from scipy.sparse.linalg import cg

    S, smoothness = system
    c, t = confidence.ravel(), values.ravel()
    A = (smoothness + sparse.diags(S @ c)).tocsr()
    b = S @ (c * t)
    start = b / np.maximum(S @ c, 1e-12) if initial is None else (S @ initial.ravel()) / np.asarray(S.sum(axis=1)).ravel()
    y, _ = cg(A, b, x0=start, rtol=1e-6, maxiter=500, M=sparse.diags(1.0 / np.maximum(A.diagonal(), 1e-10)))
    return (S.T @ y).reshape(values.shape)


def refine_full_resolution(depth, rgb, target, method: str = "bilateral-solver", hole_confidence: float = 0.01,
                           residual: bool = True, rim: int = 0, **params) -> np.ndarray:
    """The holes of ``depth`` filled by an edge-aware solve toward ``target`` → (H, W) float32 metres.

    Args:
        depth: (H, W) metres at full size, NaN (or ≤ 0) = hole; its valid pixels are kept exactly.
        rgb: (H, W, 3) in [0, 1] (or uint8), the full-size photo that guides the solve.
        target: (H, W) metres, finite and > 0: the fit up-sampled to full size everywhere
            (``working_size.fill_holes_at_full_size(depth, small, raw=True)``); without ``residual``
            only its holes are read.
        method: one of ``REFINEMENTS``.
        hole_confidence: the target's weight in the holes, in (0, 1]; the valid input's is 1.
        residual: first correct the target by its own error on the valid pixels (input − fit, in
            disparity), carried into the holes by the same edge-aware solve: where the fit is off at a
            hole's rim (a blurred edge, a biased surface), it is off the same way inside.
        rim: px of valid pixels around each hole the solve does not read (``classical.holes.hole_rim``; a stereo
            matcher's rim, often wrong); they are returned as given, like every valid pixel.
        params: the solver's own settings (``fgs``: ``lam``, ``sigma_color`` on a 0–255 scale;
            ``bilateral-solver``: ``lam``, ``sigma_xy`` px, ``sigma_luma``, ``sigma_chroma``;
            ``guided-filter``: ``radius`` px, ``eps``).

    Returns:
        (H, W) float32 metres, equal to ``depth`` on its valid pixels; the inputs are not modified.

    Example:
        >>> depth = np.full((40, 60), 2.0, np.float32); depth[10:30, 20:40] = np.nan
        >>> out = refine_full_resolution(depth, np.full((40, 60, 3), 0.5, np.float32), np.full((40, 60), 3.0))
        >>> bool(np.all(out[~np.isnan(depth)] == 2.0)), bool(2.0 <= out[20, 30] <= 3.0)
        (True, True)
    """
    if method not in REFINEMENTS:
        raise ValueError(f"method must be one of {REFINEMENTS}, got {method!r}")
    hole_confidence = _check_positive(hole_confidence, "hole_confidence")
    check_int(rim, "rim", minimum=0)
    if hole_confidence > 1:
        raise ValueError(f"hole_confidence must be in (0, 1] (the valid input's confidence is 1), got {hole_confidence!r}")
    unknown = set(params) - set(_DEFAULTS[method])
    if unknown:
        raise ValueError(f"method {method!r} takes {sorted(_DEFAULTS[method])}, got {sorted(unknown)}")
    settings = {**_DEFAULTS[method], **params}
    for name, value in settings.items():
        _check_positive(value, name)
    if method == "guided-filter" and int(settings["radius"]) != settings["radius"]:
        raise ValueError(f"radius must be a positive integer (px), got {settings['radius']!r}")
    depth_in = np.asarray(depth)
    if depth_in.ndim == 2 and np.issubdtype(depth_in.dtype, np.number):
        depth_in = np.where(np.asarray(depth_in, np.float64) > 0, depth_in, np.nan)  # ≤ 0 is a hole, as NaN
    array, valid, image = check_fill_input(depth_in, rgb, need_rgb=True)
    target = np.asarray(target)
    if target.shape != array.shape or not np.issubdtype(target.dtype, np.number):
        raise ValueError(f"target must be a numeric (H, W) depth like depth {array.shape}, got "
                         f"{target.dtype} {target.shape}")
    target = target.astype(np.float64)
    if valid.all():
        return array.astype(np.float32)
    kept = valid  # what comes back as given; the solve reads it less the rim
    valid = valid & ~hole_rim(valid, int(rim))
    holes = ~valid
    read = np.ones_like(holes) if residual else holes
    if not np.all(np.isfinite(target[read]) & (target[read] > 0)):
        raise ValueError("target must be finite and > 0 (metres) in every " + ("pixel" if residual else "hole of depth")
                         + ": the completed depth up-sampled to full size" + (" (or residual=False)" if residual else ""))
    measured = 1.0 / np.where(valid, array, 1.0)
    fitted = 1.0 / np.where(read, target, 1.0)
    scale = float(np.median(np.where(valid, measured, fitted)))  # the solvers see values near 1, whatever the unit
    measured, fitted = measured / scale, fitted / scale

    system = (_bilateral_system(image, settings["lam"], settings["sigma_xy"], settings["sigma_luma"],
                                settings["sigma_chroma"]) if method == "bilateral-solver" else None)

    def solve(values, confidence):
        if method == "fgs":
            guide = np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)
            return _fgs(guide, values, confidence, settings["lam"], settings["sigma_color"])
        if method == "guided-filter":
            return _guided(image, values, confidence, int(settings["radius"]), settings["eps"])
        return _bilateral_solver(system, values, confidence)

    if residual:  # the fit's error where it is known, carried into the holes
        error = np.where(valid, measured - fitted, 0.0)
        if method == "bilateral-solver":  # as the bilateral-solver fill: no pull in the holes, from the nearest error
            carried = _bilateral_solver(system, error, valid.astype(np.float64), initial=nearest_values(error, valid))
        else:  # a normalised filter needs some weight everywhere: 0 error where no valid pixel reaches
            carried = solve(error, np.where(valid, 1.0, 1e-6))
        fitted = fitted + np.where(holes, carried, 0.0)
    values = np.where(valid, measured, fitted)
    solved = solve(values, hole_confidence_map(valid, hole_confidence))
    low, high = values.min(), values.max()  # a solve of positive weights stays within its inputs; rounding may not
    solved = np.clip(np.where(np.isfinite(solved), solved, values), low, high) * scale
    return np.where(kept, array, 1.0 / solved).astype(np.float32)


# the largest short side (px) of the images the solves at a fit's own size were chosen on: the eighth-size real
# suite (115-138 rows); a larger image gets their reach in proportion (core.pixel_lengths)
SMOOTHNESS_TUNED_SHORT_SIDE = 138
# the bilateral solver's (sigma_xy px at that size, lam) whose solves `refine_over_smoothness` averages: chosen on
# half the real suite's scenes at its working size (~160×140) and confirmed on the other half
# (docs/studies/real_suite.md)
SMOOTHNESS_MEAN = ((4.0, 4.0), (4.0, 16.0), (8.0, 4.0), (8.0, 16.0))
# ... for a stereo matcher's depth, whose holes lie where the image gave the matcher too little to go on
# (textureless, occluded) and whose rim is often off: twice the reach (chosen and confirmed likewise)
SMOOTHNESS_STEREO = ((8.0, 4.0), (8.0, 16.0), (16.0, 4.0), (16.0, 16.0))
# the largest short side (px) of the photos the full-size solve was chosen on (bench_full_resolution.py:
# Motorcycle 500×741, the 2005/2006 scenes at HalfSize, 555 rows)
FULL_SIZE_TUNED_SHORT_SIDE = 555
# the one solve `ddp-lite complete` runs at a photo's full size, by the depth's source (sigma_xy px at that size):
# twice the reach for a stereo matcher's, its rim not read (the study on Motorcycle's SGBM depth:
# docs/studies/real_suite.md)
FULL_SIZE_SOLVE = {"clean": {"sigma_xy": 8.0}, "stereo": {"sigma_xy": 16.0}}


def smoothness_at(settings, shape, tuned_short_side: int = SMOOTHNESS_TUNED_SHORT_SIDE) -> tuple:
    """(sigma_xy, lam) ``settings`` stated at the size they were tuned on (short side up to ``tuned_short_side``
    px) → the same for an image of ``shape`` (H, W, ...): each reach a
    :class:`~ddp_lite.core.pixel_lengths.PixelLength`, the tuned px up to that size, in proportion to the short
    side above it.

    Example:
        >>> smoothness_at(((4.0, 4.0), (8.0, 16.0)), (276, 346))
        ((8.0, 4.0), (16.0, 16.0))
    """
    return tuple((PixelLength(float(sigma_xy), tuned_short_side).at(shape), lam) for sigma_xy, lam in settings)


def full_size_solve(source: str, shape) -> dict:
    """The bilateral solver's settings ``ddp-lite complete`` runs at a photo's full size ``shape`` (H, W, ...) for
    a ``source``'s depth (``FULL_SIZE_SOLVE``; its reach scaled by :func:`smoothness_at` above the size it was
    tuned on, ``FULL_SIZE_TUNED_SHORT_SIDE``)."""
    if source not in FULL_SIZE_SOLVE:
        raise ValueError(f"source must be one of {tuple(FULL_SIZE_SOLVE)}, got {source!r}")
    settings = FULL_SIZE_SOLVE[source]
    (sigma_xy, _), = smoothness_at(((settings["sigma_xy"], None),), shape, FULL_SIZE_TUNED_SHORT_SIDE)
    return {**settings, "sigma_xy": sigma_xy}


def refine_over_smoothness(depth, rgb, target, settings=SMOOTHNESS_MEAN, rim: int = 0) -> np.ndarray:
    """The bilateral-solver refinement averaged, in disparity (1/Z), over several smoothness settings.

    How far a hole's valid rim should be carried, and how smooth the surface between, differs from hole to
    hole (holes cut into clean depth want a sharp, short-reach solve; a stereo matcher's holes, whose rim
    is itself off, a smooth one), and the valid depth cannot tell which (held-out valid pixels choose the
    sharpest setting nearly always). The mean of a few settings is steadier than any one of them.

    Args:
        depth, rgb, target: as :func:`refine_full_resolution` (metres, NaN holes; colour; the fit).
        settings: a non-empty sequence of (sigma_xy px, lam) pairs for the bilateral solver.
        rim: as :func:`refine_full_resolution`: px of valid rim the solves do not read.
    Returns:
        (H, W) float32 metres, equal to ``depth`` on its valid pixels.
    Example:
        >>> depth = np.full((40, 60), 2.0, np.float32); depth[10:30, 20:40] = np.nan
        >>> out = refine_over_smoothness(depth, np.full((40, 60, 3), 0.5, np.float32), np.full((40, 60), 3.0))
        >>> bool(np.all(out[~np.isnan(depth)] == 2.0)), bool(2.0 <= out[20, 30] <= 3.0)
        (True, True)
    """
    pairs = list(settings) if isinstance(settings, (list, tuple)) else []
    if not pairs or not all(isinstance(pair, (list, tuple)) and len(pair) == 2 for pair in pairs):
        raise ValueError(f"settings must be a non-empty sequence of (sigma_xy, lam) pairs, got {settings!r}")
    for sigma_xy, lam in pairs:
        _check_positive(sigma_xy, "settings' sigma_xy")
        _check_positive(lam, "settings' lam")
    solves = [refine_full_resolution(depth, rgb, target, sigma_xy=float(sigma_xy), lam=float(lam), rim=rim)
              for sigma_xy, lam in pairs]  # (H, W) metres each, the valid input kept exactly
    disparity = np.mean([1.0 / solve.astype(np.float64) for solve in solves], axis=0)  # (H, W) 1/m
    valid = np.all([solve == solves[0] for solve in solves], axis=0)  # where every solve returned the input
    return np.where(valid, solves[0], 1.0 / disparity).astype(np.float32)
