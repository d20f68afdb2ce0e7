"""Classical fills that see the depth alone: nearest, interpolation over a triangulation, inpainting,
the biharmonic surface (the colour-guided ones: :mod:`ddp_lite.classical.guided_fills`).

Every fill has the signature of :mod:`ddp_lite.classical.baselines`, ``fn(depth, rgb=None) -> depth``
(``rgb`` unused here).

- ``nearest``: the value of the nearest valid pixel (Euclidean distance transform).
- ``linear`` / ``cubic``: piecewise-linear / Clough-Tocher interpolation over a Delaunay
  triangulation of the valid pixels (``scipy.interpolate``), the cubic clamped to the range of its
  triangle's corners; outside their convex hull, where they are undefined, the nearest valid value.
- ``telea`` / ``navier-stokes``: OpenCV's image inpainting (fast marching, Telea 2004; fluid
  dynamics, Bertalmío et al. 2001). Both are written for 8-bit images: Telea adds a normalised
  gradient term worth up to ~1.4 *grey levels*, which on float metres is ~1.4 *metres*. We
  therefore quantise depth to uint16 levels spanning the valid range, inpaint, and map back, so
  that term is worth a fraction of a millimetre (see ``_inpaint_uint16``).
- ``biharmonic``: the smoothest (biharmonic) surface through the valid pixels (scikit-image), clamped
  to the range of the valid depth around each hole.
- ``ebi`` / ``fbf``: stand-ins for the EBI and FBF rows of the paper's Table 6 from ``cv2.xphoto.inpaint``:
  shift-map inpainting (patches of valid depth pasted at offsets chosen by graph cuts) and
  frequency-selective reconstruction (a sparse Fourier basis fitted around each hole, extrapolated into
  it). Neither is the paper's method, and on the real Motorcycle pair both are worse than ``linear``
  (``docs/studies/real_data.md``, "The stand-ins for the paper's EBI and FBF rows").
"""
from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

from ..core.checks import check_depth, check_image

__all__ = ["fill_nearest", "fill_linear", "fill_linear_from_rim", "fill_cubic", "fill_telea", "fill_navier_stokes",
           "fill_biharmonic", "fill_ebi", "fill_fbf", "check_fill_input", "nearest_values"]


def check_fill_input(depth, rgb=None, min_valid: int = 1, need_rgb: bool = False):
    """A float64 copy of ``depth`` (H, W), its valid mask, and ``rgb`` as float64 (or None)."""
    array = check_depth(depth, "depth", min_valid=min_valid, dtype=np.float64)  # a copy: the caller's is never written
    valid = np.isfinite(array)
    if rgb is None:
        if need_rgb:
            raise ValueError("rgb is required: an (H, W, 3) image in [0, 1] guides this method")
        return array, valid, None
    # the kit's one colour rule (check_image): (H, W, 3) in [0, 1] or uint8; 0–255 floats are refused, since
    # every fill's colour weights (sigmas, eps, the colorization's variance) are set for [0, 1]
    image = check_image(rgb, "rgb", array.shape).astype(np.float64)
    return array, valid, image


def nearest_values(depth: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Holes take the value of the nearest valid pixel (ties: whichever the EDT picks)."""
    _, (rows, cols) = ndimage.distance_transform_edt(~valid, return_indices=True)
    return depth[rows, cols]


def fill_nearest(depth, rgb=None) -> np.ndarray:
    """Nearest-valid-pixel fill: (H, W) metres, NaN holes → (H, W) float32 metres.

    Example:
        >>> fill_nearest(np.array([[1.0, np.nan, np.nan, 4.0]])).tolist()
        [[1.0, 1.0, 4.0, 4.0]]
    """
    depth, valid, _ = check_fill_input(depth, rgb)
    return nearest_values(depth, valid).astype(np.float32)


def _griddata(depth, rgb, method: str) -> np.ndarray:
    depth, valid, _ = check_fill_input(depth, rgb, min_valid=3)
    holes = ~valid
    if not holes.any():
        return depth.astype(np.float32)
    from scipy import interpolate  # here, not above: ~0.4 s of import that a fill without it never needs
    from scipy.spatial import QhullError

    known, wanted = np.argwhere(valid), np.argwhere(holes)  # (N, 2), (M, 2) rows, cols
    try:
        if method == "linear":
            values = interpolate.griddata(known, depth[valid], wanted, method="linear")
        else:
            values = _clough_tocher_within_triangles(known, depth[valid], wanted)
    except QhullError as error:
        raise ValueError(f"depth's valid pixels must not all lie on one line for {method} interpolation") from error
    out = depth.copy()
    out[holes] = values
    outside = ~np.isfinite(out)  # outside the convex hull of the valid pixels
    if outside.any():
        out[outside] = nearest_values(depth, valid)[outside]
    return out.astype(np.float32)


def _clough_tocher_within_triangles(known: np.ndarray, values: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """Clough-Tocher values at ``wanted`` (M, 2), each clamped to the range of its Delaunay triangle's three
    vertices (NaN outside the hull). The cubic's gradients are estimated from far-off pixels: across a
    depth edge they overshoot by several times the step (``docs/studies/real_data.md``, "The classical fills
    bounded on real photos")."""
    from scipy import interpolate

    interpolant = interpolate.CloughTocher2DInterpolator(known, values)
    out = interpolant(wanted)
    simplex = interpolant.tri.find_simplex(wanted)
    inside = simplex >= 0
    corners = values[interpolant.tri.simplices[simplex[inside]]]  # (M_inside, 3)
    out[inside] = np.clip(out[inside], corners.min(axis=1), corners.max(axis=1))
    return out


def _hole_rim_range(depth: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi), each (H, W): the least and greatest valid depth on the rim of the hole (8-connected) a pixel
    lies in (the valid pixels touching it); ±inf where no valid pixel touches a hole, and at valid pixels."""
    eight = np.ones((3, 3), bool)
    labels, count = ndimage.label(~valid, structure=eight)
    lo, hi = np.full(count + 1, np.inf), np.full(count + 1, -np.inf)
    # a rim pixel may touch several holes: the largest and the smallest label around it cover two of them,
    # and a pixel between three holes is rare enough that a missing bound there only loosens the clamp
    rim = valid & ndimage.binary_dilation(~valid, structure=eight)
    for around in (ndimage.maximum_filter(labels, 3), ndimage.minimum_filter(np.where(labels > 0, labels, count + 1), 3)):
        touching = rim & (around > 0) & (around <= count)
        np.minimum.at(lo, around[touching], depth[touching])
        np.maximum.at(hi, around[touching], depth[touching])
    lo[0], hi[0] = -np.inf, np.inf
    return lo[labels], hi[labels]


def fill_linear(depth, rgb=None) -> np.ndarray:
    """Linear interpolation on a Delaunay triangulation (nearest outside the hull): (H, W) → (H, W) float32.

    Exact on planar (affine in u, v) depth. Needs ≥ 3 valid pixels, not all on one line.
    """
    return _griddata(depth, rgb, "linear")


def fill_linear_from_rim(depth, rgb=None) -> np.ndarray:
    """:func:`fill_linear` triangulating only the valid pixels that touch a hole (8-neighbours): (H, W) →
    (H, W) float32. A hole pixel's triangle has its corners on the hole's rim, so this is the same fill
    up to the ties a regular grid leaves to the triangulation (cocircular pixels), and much faster on a
    full-size photo, where `ddp-lite complete` compares against it (only the rim is triangulated;
    ``docs/studies/real_data.md``, "The stand-ins for the paper's EBI and FBF rows").

    Example:
        >>> depth = np.tile(np.arange(6, dtype=np.float32) + 1, (4, 1))
        >>> depth[1:3, 2:4] = np.nan
        >>> fill_linear_from_rim(depth)[1].tolist()
        [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    """
    depth, valid, _ = check_fill_input(depth, rgb, min_valid=3)
    holes = ~valid
    rim = valid & ndimage.binary_dilation(holes, structure=np.ones((3, 3), bool))
    if not holes.any():
        return depth.astype(np.float32)
    from scipy import interpolate
    from scipy.spatial import QhullError

    try:
        values = interpolate.griddata(np.argwhere(rim), depth[rim], np.argwhere(holes), method="linear")
    except QhullError:  # a rim on one line: the whole valid set decides
        return _griddata(depth, rgb, "linear")
    out = depth.copy()
    out[holes] = values
    outside = ~np.isfinite(out)  # outside the rim's hull: the nearest valid pixel, which is on the rim
    if outside.any():
        out[outside] = nearest_values(depth, valid)[outside]
    return out.astype(np.float32)


def fill_cubic(depth, rgb=None) -> np.ndarray:
    """Clough-Tocher cubic interpolation, each value within its triangle's corners (nearest outside the hull):
    (H, W) metres → (H, W) float32."""
    return _griddata(depth, rgb, "cubic")


def _inpaint_uint16(depth, rgb, flag: int, radius: float = 5.0) -> np.ndarray:
    """``cv2.inpaint`` on depth quantised to uint16 levels spanning its valid range, mapped back.

    OpenCV's Telea adds ``(Jx + Jy) / |J|`` to each filled value: up to ±√2 in the image's own
    units, harmless in 8-bit grey levels but metres-sized on float metres. Mapping the valid
    range [lo, hi] onto levels [1024, 64511] (a margin for slight over/undershoot) makes one
    level ≤ (hi - lo) / 63487: 0.02 mm for a 1.3 m range, 1.6 mm for a 100 m range.
    """
    depth, valid, _ = check_fill_input(depth, rgb)
    if valid.all():
        return depth.astype(np.float32)
    lo, hi = float(depth[valid].min()), float(depth[valid].max())
    scale = 63487.0 / (hi - lo) if hi > lo else 1000.0  # levels per metre
    levels = np.where(valid, (depth - lo) * scale + 1024.0, 0.0)
    levels = np.clip(np.round(levels), 0, 65535).astype(np.uint16)
    holes = (~valid).astype(np.uint8)  # cv2: non-zero = to inpaint
    filled = cv2.inpaint(levels, holes, float(radius), flag).astype(np.float64)
    out = np.where(valid, depth, (filled - 1024.0) / scale + lo)  # valid pixels keep their exact value
    return out.astype(np.float32)


def fill_telea(depth, rgb=None) -> np.ndarray:
    """OpenCV Telea (fast-marching) inpainting, radius 5 px, on uint16-quantised depth: (H, W) → (H, W) float32."""
    return _inpaint_uint16(depth, rgb, cv2.INPAINT_TELEA)


def fill_navier_stokes(depth, rgb=None) -> np.ndarray:
    """OpenCV Navier-Stokes inpainting, radius 5 px, on uint16-quantised depth: (H, W) → (H, W) float32."""
    return _inpaint_uint16(depth, rgb, cv2.INPAINT_NS)


def fill_biharmonic(depth, rgb=None) -> np.ndarray:
    """Biharmonic inpainting (``skimage.restoration.inpaint_biharmonic``): (H, W) metres → (H, W) float32.

    Each hole's values are clamped to the range of the valid pixels touching it (the surface has no maximum
    principle and overshoots a depth edge: ``docs/studies/real_data.md``, "The classical fills bounded on real
    photos"). Exact on planar depth away from the image border.
    """
    from skimage.restoration import inpaint_biharmonic

    depth, valid, _ = check_fill_input(depth, rgb)
    if valid.all():
        return depth.astype(np.float32)
    start = np.where(valid, depth, 0.0)  # the hole values are ignored, but must be finite
    out = inpaint_biharmonic(start, ~valid)
    lo, hi = _hole_rim_range(depth, valid)  # the biharmonic surface has no maximum principle: it overshoots
    return np.where(valid, depth, np.clip(out, lo, hi)).astype(np.float32)


def fill_ebi(depth, rgb=None) -> np.ndarray:
    """Exemplar-based inpainting, the kit's stand-in for the EBI row of the paper's Table 6: OpenCV's shift-map
    inpainting (``cv2.xphoto.inpaint``, ``INPAINT_SHIFTMAP``; He & Sun 2012) on the float32 depth → (H, W)
    float32 metres.

    Every hole pixel copies the depth of a valid pixel at an offset (a label) chosen by graph cuts so that
    neighbouring copies agree: whole patches of the valid depth are pasted into the holes. EBI (Arias et al.
    2011) is a variational exemplar method (patch weights and a patch error minimised together, values
    blended from many patches); shift-map pastes single offsets and does not see the colour image (given
    Lab colour as extra channels it was no better overall). The float32 depth is used as it is: quantised
    to uint16 levels the same fill was worse (its costs are scaled for 8-bit levels). On the real
    Motorcycle pair it is well behind the linear fill, takes seconds a fill, and is fragile: the offsets
    it picks move with the input's last digits (``docs/studies/real_data.md``, "The stand-ins for the
    paper's EBI and FBF rows"). For one input it is deterministic.
    Valid pixels keep their input value.
    """
    depth, valid, _ = check_fill_input(depth, rgb)
    if valid.all():
        return depth.astype(np.float32)
    offset = float(depth[valid].mean())
    src = np.where(valid, depth - offset, 0.0).astype(np.float32)
    dst = np.zeros_like(src)
    cv2.xphoto.inpaint(src, valid.astype(np.uint8), dst, cv2.xphoto.INPAINT_SHIFTMAP)  # mask: non-zero = known
    out = np.where(valid, depth, dst.astype(np.float64) + offset)
    return out.astype(np.float32)


_FSR_LEVELS = 63  # the valid range is mapped onto levels 0–63 for the Fourier fill (see fill_fbf)


def fill_fbf(depth, rgb=None) -> np.ndarray:
    """A Fourier-basis fill, the kit's stand-in for the FBF row of the paper's Table 6: OpenCV's
    frequency-selective reconstruction (``cv2.xphoto.inpaint``, ``INPAINT_FSR_FAST``; Seiler & Kaup 2015,
    Genser et al. 2018) on the depth quantised to 64 levels → (H, W) float32 metres.

    Block by block, FSR models the known pixels around a hole as a sparse sum of 2-D Fourier basis functions,
    picked one at a time (the one that most reduces the weighted residual), and extrapolates that sum into
    the hole. FBF (Atapour-Abarghouei et al. 2016) also fills with a Fourier basis but filters the depth's
    spectrum with a Butterworth filter and iterates; this is the closest library method, not FBF.
    OpenCV's FSR takes 8-bit images only (16-bit input comes back unfilled), and its stopping rule is in
    grey levels: the more levels the valid range spans, the longer it runs. The FAST mode on 64 levels was
    both better and faster than on 256 levels, and the BEST mode too slow for a class
    (``docs/studies/real_data.md``, "The stand-ins for the paper's EBI and FBF rows").
    One level is 1/63 of the valid range, a quantisation the valid pixels do not see (they keep their value).
    """
    depth, valid, _ = check_fill_input(depth, rgb)
    if valid.all():
        return depth.astype(np.float32)
    lo, hi = float(depth[valid].min()), float(depth[valid].max())
    scale = _FSR_LEVELS / (hi - lo) if hi > lo else 1.0  # levels per metre
    levels = np.clip(np.round(np.where(valid, (depth - lo) * scale, 0.0)), 0, 255).astype(np.uint8)
    dst = np.zeros_like(levels)
    cv2.xphoto.inpaint(levels, valid.astype(np.uint8), dst, cv2.xphoto.INPAINT_FSR_FAST)  # mask: non-zero = known
    out = np.where(valid, depth, dst.astype(np.float64) / scale + lo)
    return out.astype(np.float32)
