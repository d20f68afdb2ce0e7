"""Independent references for the fills that now call OpenCV's contrib modules: the kit's former NumPy
implementations, kept here to check the library against (tests) and to time it against (benchmarks)."""
import numpy as np


def numpy_joint_bilateral(depth, guide, sigma_s, sigma_r, radius=5, disc=True):
    """The kit's former joint bilateral pass, float64 NumPy: the mean of the usable (finite) depths in the
    window (the (2r+1)² square, or with ``disc`` the pixels within ``radius``, OpenCV's window), weights
    exp(−|Δxy|²/2σ_s²)·exp(−Δg²/2σ_r²), zero outside the image. Returns (mean, weight sum), NaN mean where 0."""
    depth = np.asarray(depth, dtype=np.float64)
    guide = np.asarray(guide, dtype=np.float64)
    H, W = depth.shape
    usable = np.isfinite(depth)
    values = np.pad(np.where(usable, depth, 0.0), radius)
    weights_in = np.pad(usable.astype(np.float64), radius)
    guide_pad = np.pad(guide, radius)
    total, weight = np.zeros((H, W)), np.zeros((H, W))
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            if disc and dx * dx + dy * dy > radius * radius:
                continue
            window = np.s_[radius + dy:radius + dy + H, radius + dx:radius + dx + W]
            w = (np.exp(-(dx * dx + dy * dy) / (2.0 * sigma_s ** 2))
                 * np.exp(-(guide_pad[window] - guide) ** 2 / (2.0 * sigma_r ** 2)) * weights_in[window])
            total += w * values[window]
            weight += w
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(weight > 0, total / weight, np.nan), weight
