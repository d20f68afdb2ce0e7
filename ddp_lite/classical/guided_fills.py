"""Classical fills guided by the colour image: depth edges are taken where colour edges are (the fills
that see the depth alone: :mod:`ddp_lite.classical.depth_fills`).

Every fill has the signature of :mod:`ddp_lite.classical.baselines`, ``fn(depth, rgb=None) -> depth``;
``rgb`` (H, W, 3) in [0, 1] is required.

- ``colorization``: Levin, Lischinski & Weiss, "Colorization using optimization" (2004), as the
  NYU Depth v2 toolbox's ``fill_depth_colorization.m`` uses it: each pixel's depth is a weighted
  average of its 3×3 neighbours', weights high where the grey levels are alike, so depth
  follows colour edges. One sparse linear system (scipy.sparse, spsolve).
- ``guided-filter``: He, Sun & Tang's guided filter (2010) as a hole fill (the GIF row of the paper's
  Table 6): in every window the depth is an affine function of the colour, fitted to the window's
  valid pixels only; a hole pixel averages the affine models of the windows that cover it, weighted
  by how much valid depth each saw, within the range of the depth they saw. Holes beyond a window's
  reach take the linear fill, which the colour model refines at the holes' rims. Written here, not
  ``cv2.ximgproc.guidedFilter``: that filter has no per-pixel weights, and its ratio on [valid·depth,
  valid] is a ratio of two affine models, not a model fitted to the valid pixels (Motorcycle 250×370
  blobs-1: 11.3 px against 2.2 in the reached holes). With all weights 1 the two agree (a test checks it).
- ``bilateral-solver``: Barron & Poole's fast bilateral solver (2016; not a row of Table 6): the smoothest depth
  in a bilateral grid over (x, y, luma, chroma), pulled to the input where it is valid; a sparse
  system on the grid's vertices, solved by preconditioned conjugate gradients (scipy.sparse). OpenCV's
  ``cv2.ximgproc.fastBilateralSolverFilter`` is in the contrib wheel but built without Eigen, and refuses to run.
- ``cross-bilateral``: the NYU Depth v2 toolbox's ``fill_depth_cross_bf``: a joint bilateral filter of
  the valid depth guided by the grey image (``cv2.ximgproc.jointBilateralFilter``, normalised by the
  valid pixels), at three scales from coarse to fine.
- ``fast-global-smoother``: Min et al.'s fast global smoother (2014, ``cv2.ximgproc``) as a normalised
  sparse-data interpolation: valid depth spread along the image, stopped by colour edges.
"""
from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage, sparse

from ..core.checks import check_image, check_int, check_real
from .depth_fills import check_fill_input, fill_linear, nearest_values

__all__ = ["fill_colorization", "colorization_affinities", "colorization_weights", "NEIGHBOUR_OFFSETS",
           "fill_guided_filter", "fill_bilateral_solver", "joint_bilateral_fill", "fill_cross_bilateral", "fill_fast_global_smoother"]


# 3×3 window minus its centre, (dy, dx)
_OFFSETS = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]
NEIGHBOUR_OFFSETS = tuple(_OFFSETS)


def colorization_weights(image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Levin et al.'s affinities of ``image`` (H, W, 3) float64 in [0, 1], as ``check_image`` leaves it (not
    checked again here): weights (8, H, W) over the 3×3 neighbours in ``NEIGHBOUR_OFFSETS`` order, summing to
    1 per pixel (0 outside the image), and the flat index (8, H, W) of each neighbour (-1 outside)."""
    H, W = image.shape[:2]
    gray = image @ np.array([0.2989, 0.5870, 0.1140])  # MATLAB's rgb2gray weights, (H, W)
    index = np.arange(H * W).reshape(H, W)
    gray_pad = np.pad(gray, 1, constant_values=np.nan)  # NaN: outside the image
    index_pad = np.pad(index, 1, constant_values=-1)
    nbr_gray = np.stack([gray_pad[1 + dy:1 + dy + H, 1 + dx:1 + dx + W] for dy, dx in _OFFSETS])  # (8, H, W)
    nbr_index = np.stack([index_pad[1 + dy:1 + dy + H, 1 + dx:1 + dx + W] for dy, dx in _OFFSETS])  # (8, H, W)
    inside = nbr_index >= 0

    window = np.concatenate([nbr_gray, gray[None]])  # (9, H, W), the centre included as in the toolbox
    variance = np.nanvar(window, axis=0)
    diff2 = (nbr_gray - gray[None]) ** 2  # (8, H, W), NaN outside
    sigma2 = np.maximum(0.6 * variance, -np.nanmin(diff2, axis=0) / np.log(0.01))
    sigma2 = np.maximum(sigma2, 2e-6)  # a flat window: equal weights
    weights = np.where(inside, np.exp(-np.nan_to_num(diff2) / sigma2[None]), 0.0)
    return weights / weights.sum(axis=0, keepdims=True), nbr_index


def colorization_affinities(rgb) -> np.ndarray:
    """The affinities of the colorization fill, (8, H, W) float32 for ``rgb`` (H, W, 3) in [0, 1]: the
    weight of each of a pixel's 3×3 neighbours (``NEIGHBOUR_OFFSETS`` (dy, dx) order; 0 outside the
    image), high where the grey levels are alike *relative to the local variance*, so that texture
    of one surface still links its pixels while an edge between two surfaces does not. Each pixel's
    eight weights sum to 1."""
    image = check_image(rgb, "rgb")
    return colorization_weights(image.astype(np.float64))[0].astype(np.float32)


def fill_colorization(depth, rgb=None, alpha: float = 1.0) -> np.ndarray:
    """Levin et al. colorization fill (NYU v2's ``fill_depth_colorization.m``): depth, rgb → (H, W) float32.

    ``depth`` (H, W) metres with NaN holes; ``rgb`` (H, W, 3) in [0, 1] (required).

    Solves one sparse system, for every pixel p: z_p - Σ_q w_pq z_q + α·[p valid]·(z_p - d_p) = 0,
    q over p's 3×3 neighbours: each depth is a weighted mean of its neighbours', pulled to the input
    d where that is valid. Weights w_pq ∝ exp(-(g_q - g_p)² / σ_p²) on the grey image g, with
    σ_p² = max(0.6·var(window), -min_q (g_q - g_p)² / ln 0.01, 2e-6), normalised so Σ_q w_pq = 1.
    Valid pixels keep their input value in the output (as the toolbox does).
    """
    depth, valid, image = check_fill_input(depth, rgb, need_rgb=True)
    if not (np.isscalar(alpha) and np.isfinite(alpha) and alpha > 0):
        raise ValueError(f"alpha must be a positive number, got {alpha!r}")
    if valid.all():
        return depth.astype(np.float32)
    H, W = depth.shape
    weights, nbr_index = colorization_weights(image)
    inside = nbr_index >= 0
    index = np.arange(H * W).reshape(H, W)

    # A = I - W + α·diag(valid), b = α·valid·depth
    rows = np.broadcast_to(index, nbr_index.shape)[inside]
    A = sparse.csr_matrix((-weights[inside], (rows, nbr_index[inside])), shape=(H * W, H * W))
    A = A + sparse.diags(1.0 + alpha * valid.ravel())
    b = alpha * np.where(valid, depth, 0.0).ravel()
    from scipy.sparse.linalg import spsolve  # on first use, as cg below: a kernel that never solves skips its import

    solution = spsolve(A.tocsc(), b).reshape(H, W)
    return np.where(valid, depth, solution).astype(np.float32)


def _box_mean(x: np.ndarray, radius: int) -> np.ndarray:
    """The mean over the (2r+1)² window around each pixel of (H, W, ...) ``x``, reflecting at the border."""
    size = (2 * radius + 1, 2 * radius + 1) + (1,) * (x.ndim - 2)
    return ndimage.uniform_filter(x, size=size, mode="reflect")


def masked_guided_filter(guide: np.ndarray, target: np.ndarray, weight: np.ndarray, radius: int,
                          eps: float) -> tuple[np.ndarray, np.ndarray]:
    """One guided filter (He et al. 2010, colour guide) fitted to the pixels where ``weight`` > 0.

    ``guide`` (H, W, C), ``target`` (H, W), ``weight`` (H, W) in [0, 1]. Per window k, (a_k, b_k) minimise
    Σ_i w_i (a_k·I_i + b_k − p_i)² / Σ_i w_i + eps·|a_k|²; pixel i gets Σ_k ω_k (a_k·I_i + b_k) / Σ_k ω_k
    over the windows k covering it, ω_k = the window's mean weight. Returns that (H, W) and Σ_k ω_k.
    """
    C = guide.shape[2]
    w = _box_mean(weight, radius)  # (H, W): each window's mean weight
    safe = np.maximum(w, 1e-12)
    mean_I = _box_mean(weight[..., None] * guide, radius) / safe[..., None]  # (H, W, C)
    mean_p = _box_mean(weight * target, radius) / safe  # (H, W)
    outer = guide[..., :, None] * guide[..., None, :]  # (H, W, C, C)
    cov_II = _box_mean(weight[..., None, None] * outer, radius) / safe[..., None, None] \
        - mean_I[..., :, None] * mean_I[..., None, :]
    cov_Ip = _box_mean(weight[..., None] * guide * target[..., None], radius) / safe[..., None] \
        - mean_I * mean_p[..., None]
    a = np.linalg.solve(cov_II + eps * np.eye(C), cov_Ip[..., None])[..., 0]  # (H, W, C)
    b = mean_p - np.einsum("hwc,hwc->hw", a, mean_I)
    a, b = a * w[..., None], b * w  # windows weighted by the valid depth they saw
    total = _box_mean(w, radius)
    q = (np.einsum("hwc,hwc->hw", _box_mean(a, radius), guide) + _box_mean(b, radius)) / np.maximum(total, 1e-12)
    return q, total


def fill_guided_filter(depth, rgb=None, radius: int = 2, eps: float = 1e-4) -> np.ndarray:
    """Guided-filter fill: depth (H, W) with NaN holes, rgb (H, W, 3) in [0, 1] → (H, W) float32.

    Each (2·radius+1)² window models depth as an affine function of the colour, fitted by ridge
    regression (``eps`` on the colour's [0, 1] scale: a larger one follows colour less) to its valid
    pixels; a hole pixel that such windows reach averages their models, each weighted by its share
    of valid pixels, and is clamped to the range of the valid depth those windows saw (the
    (4·radius+1)² square around it): an affine model fitted to a few pixels at a hole's rim
    extrapolates the colour's variation far beyond the depth it saw. Deeper hole pixels, which no
    window of that radius reaches, take the linear fill (``fill_linear``, the fill the colour model
    improves on): windows grown to reach them span several surfaces (Motorcycle 250×370 blobs: 6.0 px
    with doubled radii against nearest's 5.3 and linear's 3.7). Valid pixels keep their input value.

    Example:
        >>> rgb = np.linspace(0, 1, 12).reshape(3, 4, 1).repeat(3, axis=2)
        >>> depth = 1.0 + 2.0 * rgb[..., 0]; depth[1, 1] = np.nan      # depth affine in the colour
        >>> round(float(fill_guided_filter(depth, rgb, radius=1, eps=1e-9)[1, 1]), 4), round(float(1 + 2 * rgb[1, 1, 0]), 4)
        (1.9091, 1.9091)
    """
    depth, valid, image = check_fill_input(depth, rgb, need_rgb=True)
    for name, value, low in (("radius", radius, 1), ("eps", eps, 0.0)):
        if isinstance(value, bool) or not np.isscalar(value) or not np.isfinite(value) or value < low \
                or (name == "radius" and int(value) != value) or (name == "eps" and value <= 0):
            raise ValueError(f"{name} must be a {'positive integer' if name == 'radius' else 'positive number'}, "
                             f"got {value!r}")
    holes = ~valid
    if not holes.any():
        return depth.astype(np.float32)
    r = int(radius)
    q, reach = masked_guided_filter(image, np.where(valid, depth, 0.0), valid.astype(np.float64), r, float(eps))
    seen = 4 * r + 1  # the windows covering a pixel together span this square around it
    lo = ndimage.minimum_filter(np.where(valid, depth, np.inf), seen, mode="nearest")
    hi = ndimage.maximum_filter(np.where(valid, depth, -np.inf), seen, mode="nearest")
    reached = holes & (reach > 1e-9)
    out = depth.copy()
    out[reached] = np.clip(q, lo, hi)[reached]
    deeper = holes & ~reached
    if deeper.any():
        try:
            base = fill_linear(depth)
        except ValueError:  # fewer than 3 valid pixels, or all on one line: no triangle to interpolate in
            base = nearest_values(depth, valid)
        out[deeper] = base[deeper]
    return out.astype(np.float32)


def bilateral_grid(image: np.ndarray, sigma_xy: float, sigma_luma: float, sigma_chroma: float):
    """Barron & Poole's simplified bilateral grid of ``image`` (H, W, 3) in [0, 1]: every pixel falls on
    the vertex at its rounded (x/σ_xy, y/σ_xy, Y/σ_l, U/σ_c, V/σ_c) (YUV on a 0–255 scale). Returns the
    splat matrix S (vertices × pixels, one 1 per column) and the blur B = Σ over the five axes of the
    ±1-vertex neighbours (a [1 2 1] blur without its centre, which ``bistochastic`` adds back)."""
    H, W = image.shape[:2]
    yuv = cv2.cvtColor(image.astype(np.float32), cv2.COLOR_RGB2YUV).reshape(-1, 3) * 255.0  # (N, 3)
    yy, xx = np.mgrid[0:H, 0:W]
    coords = np.column_stack([xx.ravel() / sigma_xy, yy.ravel() / sigma_xy, yuv[:, 0] / sigma_luma,
                              yuv[:, 1] / sigma_chroma, yuv[:, 2] / sigma_chroma])
    coords = np.round(coords).astype(np.int64)
    coords -= coords.min(axis=0)
    vertices, pixel_vertex = np.unique(coords, axis=0, return_inverse=True)  # (M, 5), (N,)
    M, N = len(vertices), H * W
    S = sparse.csr_matrix((np.ones(N), (pixel_vertex.ravel(), np.arange(N))), shape=(M, N))
    extent = vertices.max(axis=0) + 2
    keys = np.ravel_multi_index(vertices.T, extent)  # sorted, as np.unique sorted the rows
    blur = sparse.csr_matrix((M, M))
    for axis in range(5):
        for step in (-1, 1):
            shifted = vertices.copy()
            shifted[:, axis] += step
            ok = shifted[:, axis] >= 0
            shifted_keys = np.ravel_multi_index(shifted[ok].T, extent)
            where = np.searchsorted(keys, shifted_keys)
            found = (where < M) & (keys[np.minimum(where, M - 1)] == shifted_keys)
            rows = np.flatnonzero(ok)[found]
            blur = blur + sparse.csr_matrix((np.ones(len(rows)), (rows, where[found])), shape=(M, M))
    return S, blur


def bistochastic(S, blur, iterations: int = 20):
    """Diagonals (m, n) with diag(n)·B̄·diag(n) having row sums m = S·1, B̄ = B + 10·I (Barron & Poole)."""
    m = np.asarray(S.sum(axis=1)).ravel()
    n = np.ones_like(m)
    for _ in range(iterations):
        n = np.sqrt(n * m / (blur @ n + 10.0 * n))
    return m, n


def fill_bilateral_solver(depth, rgb=None, lam: float = 4.0, sigma_xy: float = 8.0, sigma_luma: float = 8.0,
                          sigma_chroma: float = 8.0, tol: float = 1e-6) -> np.ndarray:
    """Fast bilateral solver fill (Barron & Poole 2016): depth (H, W) NaN holes, rgb (H, W, 3) → (H, W) float32.

    Minimises λ/2 · Σ_ij Ŵ_ij (x_i − x_j)² + Σ_i c_i (x_i − t_i)² with t the input, c = 1 where it is
    valid and 0 in the holes, and Ŵ the bistochastised bilateral affinity of the colour image
    (σ_xy px, σ_luma and σ_chroma on a 0–255 scale). In grid space: (λ(D_m − D_n B̄ D_n) + diag(S c)) y
    = S(c·t), x = Sᵀ y; conjugate gradients, Jacobi-preconditioned, from the grid's mean of a
    nearest-valid fill (which is also what a grid region with no valid depth keeps). Valid pixels
    keep their input value.
    """
    from scipy.sparse.linalg import cg

    depth, valid, image = check_fill_input(depth, rgb, need_rgb=True)
    for name, value in (("lam", lam), ("sigma_xy", sigma_xy), ("sigma_luma", sigma_luma),
                        ("sigma_chroma", sigma_chroma), ("tol", tol)):
        if isinstance(value, bool) or not np.isscalar(value) or not np.isfinite(value) or value <= 0:
            raise ValueError(f"{name} must be a positive number, got {value!r}")
    if valid.all():
        return depth.astype(np.float32)
    S, blur = bilateral_grid(np.clip(image, 0.0, 1.0), sigma_xy, sigma_luma, sigma_chroma)
    _, n = bistochastic(S, blur)
    m = np.asarray(S.sum(axis=1)).ravel()
    c = valid.ravel().astype(np.float64)
    t = np.where(valid, depth, 0.0).ravel()
    Dn = sparse.diags(n)
    affinity = Dn @ blur @ Dn  # B̄'s centre 10·I cancels in the Laplacian below
    # diag(affinity·1 + 10n²) is D_m once the bistochastisation has converged; taking it from the affinity
    # itself keeps the smoothness term a graph Laplacian (positive semi-definite) when it has not
    laplacian = sparse.diags(np.asarray(affinity.sum(axis=1)).ravel()) - affinity
    A = lam * laplacian + sparse.diags(S @ c)
    b = S @ (c * t)
    start = (S @ nearest_values(depth, valid).ravel()) / m
    diagonal = np.maximum(A.diagonal(), 1e-10)
    y, _ = cg(A.tocsr(), b, x0=start, rtol=tol, maxiter=500, M=sparse.diags(1.0 / diagonal))
    solution = (S.T @ y).reshape(depth.shape)
    return np.where(valid, depth, solution).astype(np.float32)


# a pixel whose window weights sum below this (the centre pixel alone weighs 1) counts as unreached: OpenCV
# tabulates the range kernel in float32, so far in its tail (sums ~1e-30) the weighted mean is noise; above
# 1e-6 it is the float64 mean to 1e-3 px (Motorcycle 250×370 blobs, disparities 19–45 px)
_MIN_BILATERAL_WEIGHT = 1e-6


def joint_bilateral_fill(depth, guide, sigma_s: float, sigma_r: float, radius: int = 5) -> np.ndarray:
    """One joint (cross) bilateral pass (``cv2.ximgproc.jointBilateralFilter``): (H, W) depth with NaN =
    unusable, (H, W) grey ``guide`` in [0, 1] → (H, W) float64, every pixel the weighted mean of the usable
    depths within ``radius`` px of it (a disc, as OpenCV's window), weights
    exp(−|Δxy|² / 2σ_s²) · exp(−(g_q − g_p)² / 2σ_r²); NaN where those weights sum below 1e-6 (no usable
    pixel, or only ones of far-off grey).

    OpenCV's filter has no mask: it is run on [usable·depth, usable] and the first divided by the second,
    which is exactly the mean over the usable pixels (the weights' own normalisation cancels); no pixel
    outside the image counts.
    """
    depth = np.asarray(depth, dtype=np.float64)
    if depth.ndim != 2:
        raise ValueError(f"depth must be (H, W) metres with NaN holes, got shape {depth.shape}")
    guide = np.asarray(guide)
    if guide.shape != depth.shape or not np.issubdtype(guide.dtype, np.number) or not np.all(np.isfinite(guide)):
        raise ValueError(f"guide must be a finite (H, W) grey image like depth {depth.shape}, got {guide.dtype} {guide.shape}")
    if guide.min() < -1e-6 or guide.max() > 1 + 1e-6:  # sigma_r is in [0, 1] grey levels
        raise ValueError(f"guide must lie in [0, 1] (grey levels; sigma_r is set for that range), got range "
                         f"[{guide.min():.3g}, {guide.max():.3g}]")
    check_real(sigma_s, "sigma_s", low=0.0, low_open=True), check_real(sigma_r, "sigma_r", low=0.0, low_open=True)
    radius = check_int(radius, "radius", minimum=1)
    usable = np.isfinite(depth)
    if not usable.any():
        return np.full(depth.shape, np.nan)
    offset = float(depth[usable].mean())  # filtered about the mean: float32 keeps the differences' digits
    src = np.dstack([np.where(usable, depth - offset, 0.0), usable, np.zeros(depth.shape)]).astype(np.float32)
    # padded here with unusable pixels: OpenCV's own border (whatever borderType) lets outside pixels count.
    # The guide's padding spans 0 to 1: OpenCV tabulates the range kernel over the guide's own range, and a
    # guide of one grey (a zero range) gets a wrong table; padding never weighs, so its grey is free
    src = np.pad(src, ((radius, radius), (radius, radius), (0, 0)))
    padded_guide = np.pad(guide.astype(np.float32), radius, constant_values=0.0)
    padded_guide[0, 0] = 1.0
    out = cv2.ximgproc.jointBilateralFilter(padded_guide, src, 2 * radius + 1, float(sigma_r), float(sigma_s))
    out = out[radius:-radius, radius:-radius].astype(np.float64)
    weight = out[..., 1]
    reached = weight > _MIN_BILATERAL_WEIGHT
    return np.where(reached, out[..., 0] / np.where(reached, weight, 1.0) + offset, np.nan)


def fill_cross_bilateral(depth, rgb=None, space_sigmas=(12.0, 5.0, 8.0), range_sigmas=(0.2, 0.08, 0.02),
                         radius: int = 5) -> np.ndarray:
    """The NYU toolbox's ``fill_depth_cross_bf.m``: a multi-scale joint bilateral fill guided by the grey
    image → (H, W) float32 metres. ``depth`` (H, W) metres with NaN holes, ``rgb`` (H, W, 3) (required).

    Scale s (0 = full size) samples the images every 2^s px (nearest). From the coarsest scale to the
    finest, each hole pixel becomes the ``joint_bilateral_fill`` mean (a disc of ``radius`` px, σ_s and σ_r
    ``space_sigmas[s]`` px and ``range_sigmas[s]`` grey levels in [0, 1]) of the pixels usable at
    that scale (valid, or filled by the coarser one); a hole pixel of a finer scale starts from its
    coarse pixel's value. As the toolbox (its ``cbf`` mex file), but in float metres where the toolbox
    quantises depth to 256 levels of its maximum, and with the nearest valid depth where no scale
    reached a hole (the toolbox leaves 0 there), and OpenCV's disc window where the toolbox's is the 11×11
    square (Motorcycle 250×370, four hole kinds: hole RMSE −6 % to +4 %, mean 3.51 → 3.49 px).
    Valid pixels keep their value.
    """
    depth, valid, image = check_fill_input(depth, rgb, need_rgb=True)
    space_sigmas, range_sigmas = tuple(space_sigmas), tuple(range_sigmas)
    if len(space_sigmas) != len(range_sigmas) or not space_sigmas:
        raise ValueError(f"space_sigmas and range_sigmas must be non-empty and the same length, got "
                         f"{len(space_sigmas)} and {len(range_sigmas)}")
    if not all(np.isfinite(s) and s > 0 for s in space_sigmas + range_sigmas):
        raise ValueError(f"space_sigmas and range_sigmas must be positive, got {space_sigmas}, {range_sigmas}")
    if isinstance(radius, bool) or int(radius) != radius or radius < 1:
        raise ValueError(f"radius must be a positive integer (px), got {radius!r}")
    if valid.all():
        return depth.astype(np.float32)
    grey = image @ np.array([0.2989, 0.5870, 0.1140])  # MATLAB's rgb2gray, as the toolbox
    H, W = depth.shape
    known = np.where(valid, depth, np.nan)
    sizes = [(max(1, H >> s), max(1, W >> s)) for s in range(len(space_sigmas))]
    coarse = None  # (values, filled) of the previous, coarser scale, NaN = not reached
    for s in reversed(range(len(space_sigmas))):
        h, w = sizes[s]
        rows, cols = (np.arange(h) * H // h)[:, None], (np.arange(w) * W // w)[None, :]
        level = known[rows, cols]  # the toolbox's nearest sampling: pixel floor(y·H/h)
        if coarse is not None:
            ch, cw = coarse.shape
            start = coarse[np.arange(h)[:, None] * ch // h, np.arange(w)[None, :] * cw // w]
            level = np.where(np.isfinite(level), level, start)
        filtered = joint_bilateral_fill(level, grey[rows, cols], space_sigmas[s], range_sigmas[s], int(radius))
        missing = ~np.isfinite(known[rows, cols])
        coarse = np.where(missing, np.where(np.isfinite(filtered), filtered, level), level)
    out = np.where(valid, depth, coarse)
    unreached = ~np.isfinite(out)
    if unreached.any():
        out[unreached] = nearest_values(depth, valid)[unreached]
    return out.astype(np.float32)


def fill_fast_global_smoother(depth, rgb=None, lam: float = 100.0, sigma_color: float = 8.0) -> np.ndarray:
    """Fast global smoother fill (Min et al. 2014, ``cv2.ximgproc.fastGlobalSmootherFilter``): depth (H, W)
    with NaN holes, rgb (H, W, 3) in [0, 1] → (H, W) float32.

    The smoother solves (I + λ·L) x = f with L an edge-aware Laplacian of the colour image (neighbour
    weights exp(−|ΔI| / σ_color), colour on a 0–255 scale), approximately, by 1-D passes along the rows and
    the columns (three iterations, λ shrinking each time). As the paper's sparse-data interpolation, it is
    run on [valid·depth, valid] and the first divided by the second: each hole pixel becomes a weighted mean
    of the valid depth, the weights spreading along the image and stopping at colour edges, so the fill
    stays within the valid depth's range. Where the spread weight is below 1e-4 (no valid depth reachable
    without crossing strong edges) the nearest valid pixel's value. Valid pixels keep their input value.
    """
    depth, valid, image = check_fill_input(depth, rgb, need_rgb=True)
    for name, value in (("lam", lam), ("sigma_color", sigma_color)):
        if isinstance(value, bool) or not np.isscalar(value) or not np.isfinite(value) or value <= 0:
            raise ValueError(f"{name} must be a positive number, got {value!r}")
    if valid.all():
        return depth.astype(np.float32)
    offset = float(depth[valid].mean())  # smoothed about the mean: float32 keeps the differences' digits
    src = np.dstack([np.where(valid, depth - offset, 0.0), valid]).astype(np.float32)
    guide = np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)  # the smoother's guide must be 8-bit
    out = cv2.ximgproc.fastGlobalSmootherFilter(guide, src, float(lam), float(sigma_color)).astype(np.float64)
    weight = out[..., 1]
    reached = weight > 1e-4
    filled = np.where(reached, out[..., 0] / np.where(reached, weight, 1.0) + offset, nearest_values(depth, valid))
    return np.where(valid, depth, filled).astype(np.float32)
