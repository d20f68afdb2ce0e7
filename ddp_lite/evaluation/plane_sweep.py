"""Plane-sweep multi-view stereo: the classical counterpart of MVSNet's depth and probability map.

For a reference view and N calibrated neighbours, sweep D fronto-parallel planes z = z_k of the
reference camera, uniform in inverse depth between ``d_min`` and ``d_max`` (so that the planes are
evenly spaced in pixels of disparity), and for each plane:

1. warp every neighbour into the reference through the plane (``warp.Warper``, bilinear);
2. compare the warped grey image with the reference by **ZNCC** over a ``window × window`` box:
   ``ncc = cov(r, w) / √(var r · var w + ε)``, cost ``1 − ncc`` in [0, 2];
3. average the cost over the neighbours that see the pixel through that plane (in front of them,
   inside their image); a pixel no neighbour sees takes the neutral cost 1.

The cost volume C (D, H, W) becomes a probability volume ``P = softmax_k(−C / temperature)``, as
MVSNet's regularised cost volume does; the depth is the winning plane (lowest cost) refined to
sub-plane precision by a parabola through the costs of the winner and its two neighbour planes
(in inverse depth, where the planes are uniform). The per-pixel **probability** is MVSNet's: the
probability mass of the four planes nearest the refined position. Where the photometric cost
does not single out a plane (no texture, occlusion, a surface seen by no neighbour) the mass
spreads over many planes and the probability is low: MVSNet's probability map, and the holes the
paper cuts at probability 0.1 (Table 4).

Units: depth metres along the optical axis, planes (D,) metres near → far; images (H, W, 3) in
[0, 1]; cameras in the OpenCV convention. Runs in torch on the CPU, vectorised over the planes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from ..core.checks import check_image, check_int, check_real
from ..core.views import image_and_camera
from ..method.paper.warp import Warper

__all__ = ["inverse_depth_planes", "SweepResult", "plane_sweep"]

_GREY = (0.2989, 0.5870, 0.1140)  # the luminance weights the kit's colour-guided fills use
_ZNCC_EPS = 1e-5  # (grey levels in [0, 1])²: keeps flat windows from dividing by zero, so their NCC → 0


def inverse_depth_planes(d_min: float, d_max: float, n_planes: int) -> np.ndarray:
    """(D,) plane depths in metres, near → far, uniform in inverse depth from ``d_min`` to ``d_max``.

    Example:
        >>> inverse_depth_planes(1.0, 4.0, 3).tolist()  # 1/z = 1, 0.625, 0.25
        [1.0, 1.6, 4.0]
    """
    d_min = check_real(d_min, "d_min", 0.0, None, low_open=True)
    d_max = check_real(d_max, "d_max", d_min, None, low_open=True)
    n_planes = check_int(n_planes, "n_planes", minimum=3)
    return 1.0 / np.linspace(1.0 / d_min, 1.0 / d_max, n_planes)


@dataclass
class SweepResult:
    """What ``plane_sweep`` returns.

    ``depth`` (H, W) float32 metres (refined, every pixel); ``probability`` (H, W) float32 in [0, 1]
    (the mass of the four planes nearest the depth); ``planes`` (D,) metres; ``cost`` (D, H, W)
    float32, the neighbour-averaged 1 − ZNCC; ``index`` (H, W) int, the winning plane.
    """

    depth: np.ndarray
    probability: np.ndarray
    planes: np.ndarray
    cost: np.ndarray
    index: np.ndarray

    def holes(self, threshold: float) -> np.ndarray:
        """(H, W) depth metres with NaN where the probability is below ``threshold`` (the paper: 0.1)."""
        threshold = check_real(threshold, "threshold", 0.0, 1.0)
        return np.where(self.probability >= threshold, self.depth, np.nan).astype(np.float32)


def _grey(rgb: np.ndarray) -> torch.Tensor:
    """(H, W, 3) → (1, 1, H, W) float32 luminance."""
    return torch.from_numpy(rgb @ np.array(_GREY, np.float32))[None, None]


def _box(x: torch.Tensor, window: int) -> torch.Tensor:
    """Mean over a ``window × window`` box, (B, 1, H, W) → (B, 1, H, W); the border averages what is inside."""
    return F.avg_pool2d(x, window, stride=1, padding=window // 2, count_include_pad=False)


def _zncc_cost(ref: torch.Tensor, warped: torch.Tensor, window: int) -> torch.Tensor:
    """1 − ZNCC of ``ref`` (1, 1, H, W) against each of ``warped`` (D, 1, H, W) → (D, 1, H, W) in [0, 2]."""
    mean_r, mean_w = _box(ref, window), _box(warped, window)
    var_r = (_box(ref * ref, window) - mean_r ** 2).clamp(min=0.0)
    var_w = (_box(warped * warped, window) - mean_w ** 2).clamp(min=0.0)
    cov = _box(ref * warped, window) - mean_r * mean_w
    return 1.0 - (cov / torch.sqrt(var_r * var_w + _ZNCC_EPS ** 2)).clamp(-1.0, 1.0)


def plane_sweep(ref, neighbors, d_min: float, d_max: float, n_planes: int = 64, window: int = 5,
                temperature: float = 0.1) -> SweepResult:
    """Plane-sweep MVS of ``ref`` against ``neighbors`` → :class:`SweepResult` (depth, probability).

    Args:
        ref: the reference ``View`` or ``(rgb (H, W, 3) in [0, 1], Camera)``.
        neighbors: a non-empty list of Views or (rgb, Camera) pairs (any sizes), calibrated in the
            same world frame as ``ref``.
        d_min, d_max: the depth range swept, metres (0 < d_min < d_max).
        n_planes: D ≥ 3 fronto-parallel planes, uniform in inverse depth.
        window: odd side (px) of the ZNCC box.
        temperature: of the softmax over −cost (cost in [0, 2]); smaller is more confident.

    Example:
        >>> from ddp_lite.world.scenes import make_scene
        >>> scene = make_scene("desk", size=(48, 64), n_views=3)
        >>> sweep = plane_sweep(scene[0], [scene[1], scene[2]], scene.meta["d_min"], scene.meta["d_max"])
        >>> sweep.depth.shape, sweep.probability.shape
        ((48, 64), (48, 64))
    """
    ref_rgb, ref_cam = image_and_camera(ref, "ref")
    if isinstance(neighbors, (np.ndarray, str)) or hasattr(neighbors, "camera") or not hasattr(neighbors, "__len__"):
        raise TypeError("neighbors must be a list of Views or (rgb, Camera) pairs; wrap a single view in a list")
    if len(neighbors) == 0:
        raise ValueError("neighbors must hold at least one calibrated view to match against")
    pairs = [image_and_camera(item, f"neighbors[{i}]") for i, item in enumerate(neighbors)]
    planes = inverse_depth_planes(d_min, d_max, n_planes)
    window = check_int(window, "window", minimum=1)
    if window % 2 == 0:
        raise ValueError(f"window must be odd (a box centred on the pixel), got {window}")
    temperature = check_real(temperature, "temperature", 0.0, None, low_open=True)

    H, W = ref_cam.height, ref_cam.width
    D = len(planes)
    with torch.no_grad():
        grey = _grey(ref_rgb)
        plane_depths = torch.tensor(planes, dtype=torch.float32).reshape(D, 1, 1, 1).expand(D, 1, H, W)
        total, seen_by = torch.zeros(D, 1, H, W), torch.zeros(D, 1, H, W)
        for rgb, camera in pairs:
            nbr = _grey(rgb).expand(D, 1, camera.height, camera.width)
            warped, seen = Warper(ref_cam, camera)(nbr, plane_depths)  # (D, 1, H, W) each
            total += torch.where(seen, _zncc_cost(grey, warped, window), torch.zeros(()))
            seen_by += seen
        # the mean over the neighbours that see the pixel through this plane; seen by none: neutral 1
        cost = torch.where(seen_by > 0, total / seen_by.clamp(min=1.0), torch.ones(()))[:, 0]  # (D, H, W)
        probability_volume = torch.softmax(-cost / temperature, dim=0)

        index = cost.argmin(dim=0)  # (H, W)
        inner = index.clamp(1, D - 2)
        c_prev, c_best, c_next = (cost.gather(0, (inner + k)[None])[0] for k in (-1, 0, 1))
        curvature = c_prev - 2.0 * c_best + c_next
        offset = torch.where(curvature > 1e-9, 0.5 * (c_prev - c_next) / curvature.clamp(min=1e-9), torch.zeros(()))
        at_end = (index == 0) | (index == D - 1)  # no parabola at the ends of the sweep
        position = torch.where(at_end, index.float(), inner.float() + offset.clamp(-0.5, 0.5))  # (H, W) fractional plane

        inverse = torch.tensor(1.0 / planes, dtype=torch.float64)
        step = float(inverse[1] - inverse[0])
        depth = 1.0 / (float(inverse[0]) + position.double() * step)

        first = (position.floor().long() - 1).clamp(0, D - 4)  # MVSNet: the four planes around the estimate
        nearest4 = first[None] + torch.arange(4).reshape(4, 1, 1)
        probability = probability_volume.gather(0, nearest4).sum(0)
    return SweepResult(depth.float().numpy(), probability.clamp(0.0, 1.0).numpy(), planes,
                       cost.numpy(), index.numpy())
