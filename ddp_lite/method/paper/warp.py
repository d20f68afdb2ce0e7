"""Differentiable inverse warping: a neighbour's image seen through the reference depth.

For each reference pixel p = (u, v, 1) with predicted depth D, the 3D point in the reference
camera is ``D · K_ref⁻¹ p``; the neighbour sees it at ``K_nbr (R · D · K_ref⁻¹ p + t)`` where
``(R, t)`` is ``nbr_from_ref``. Everything except D is fixed during a fit, so we fold it into a
per-pixel ray ``M p`` with ``M = K_nbr R K_ref⁻¹`` and an offset ``K_nbr t``, computed once:

    q = D · (M p) + K_nbr t,      (u', v') = (q_x / q_z, q_y / q_z)

and sample the neighbour bilinearly at (u', v') with ``grid_sample(align_corners=True)``, which
maps -1 and +1 to the *centres* of the first and last pixel, matching the convention that
pixel (0, 0) is the centre of the top-left pixel. A pixel is invalid when the point is behind
the neighbour (q_z ≤ 0) or lands outside its image; invalid pixels are excluded from the loss.

An occlusion test passed in as ``visibility`` (the kit's, not the paper's:
:class:`~ddp_lite.method.kit.visibility.Visibility`) also marks invalid the pixels where the reference
surface hides the point from the neighbour.
"""
from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from ...core.camera import Camera, pixel_grid, relative_pose
from ...core.checks import unmask

__all__ = ["Warper", "warp_to_reference"]


class Warper(torch.nn.Module):
    """Precomputed inverse warp from one neighbour camera into a reference camera.

    Example:
        >>> cam = Camera.from_fov(32, 24, 60.0)
        >>> image = torch.rand(1, 3, 24, 32)
        >>> warped, valid = Warper(cam, cam)(image, torch.full((1, 1, 24, 32), 2.0))
        >>> bool(torch.allclose(warped, image, atol=1e-5)), bool(valid.all())
        (True, True)
    """

    def __init__(self, ref_cam: Camera, nbr_cam: Camera, dtype=torch.float32, device=None,
                 visibility: torch.nn.Module | None = None):
        """``visibility``: None (the paper's warp), or an occlusion test, depth (B, 1, H, W) → hidden (B, 1, H, W)
        bool, applied every ``VISIBILITY_EVERY`` calls."""
        super().__init__()
        self.visibility = visibility
        self.hidden, self.calls = None, 0  # the last occlusion mask and the calls since (see VISIBILITY_EVERY)
        nbr_from_ref = relative_pose(ref_cam, nbr_cam)
        K_nbr = torch.tensor(nbr_cam.K, dtype=torch.float64)
        rotation = torch.tensor(nbr_from_ref[:3, :3], dtype=torch.float64)
        translation = torch.tensor(nbr_from_ref[:3, 3], dtype=torch.float64)
        M = K_nbr @ rotation @ torch.linalg.inv(torch.tensor(ref_cam.K, dtype=torch.float64))
        pixels = pixel_grid(ref_cam.height, ref_cam.width, torch.float64)  # (3, H·W)
        rays = (M @ pixels).reshape(1, 3, ref_cam.height, ref_cam.width)  # (1, 3, H, W)
        self.register_buffer("rays", rays.to(dtype=dtype, device=device))
        self.register_buffer("offset", (K_nbr @ translation).reshape(1, 3, 1, 1).to(dtype=dtype, device=device))
        # pixel → grid_sample's [-1, 1] with align_corners=True
        scale = torch.tensor([2.0 / max(nbr_cam.width - 1, 1), 2.0 / max(nbr_cam.height - 1, 1)])
        self.register_buffer("to_grid", scale.reshape(1, 2, 1, 1).to(dtype=dtype, device=device))
        self.nbr_size = (nbr_cam.height, nbr_cam.width)
        self.eps = 1e-6
        self.edge = 1e-3  # px of slack at the image border, against round-off

    def forward(self, nbr_image: torch.Tensor, ref_depth: torch.Tensor):
        """``nbr_image`` (B, C, H', W'), ``ref_depth`` (B, 1, H, W) metres → warped image (B, C, H, W)
        and validity mask (B, 1, H, W) bool (False: behind the neighbour or outside its image)."""
        q = ref_depth * self.rays + self.offset  # (B, 3, H, W), neighbour's homogeneous pixels
        z = q[:, 2:3]
        uv = q[:, :2] / z.clamp(min=self.eps)  # (B, 2, H, W) neighbour pixel coordinates
        grid = uv * self.to_grid - 1.0
        warped = F.grid_sample(nbr_image, grid.permute(0, 2, 3, 1), mode="bilinear",
                               padding_mode="border", align_corners=True)
        with torch.no_grad():
            height, width = self.nbr_size
            lo, u, v = -self.edge, uv[:, :1], uv[:, 1:]
            valid = ((z > self.eps) & (u >= lo) & (u <= width - 1 - lo) & (v >= lo) & (v <= height - 1 - lo)
                     & torch.isfinite(ref_depth))
            if self.visibility is not None:
                valid = valid & ~self.hidden_pixels(ref_depth)
        return warped, valid

    VISIBILITY_EVERY = 10  # calls between two occlusion tests: a fit's depth moves little in 10 steps

    def hidden_pixels(self, ref_depth: torch.Tensor) -> torch.Tensor:
        """(B, 1, H, W) bool: the occlusion mask of ``ref_depth``, recomputed every ``VISIBILITY_EVERY``
        calls (the test marches 32 px per pixel: about 7 ms at 125×185 on two threads) and whenever the
        shape changes."""
        if self.hidden is None or self.calls % self.VISIBILITY_EVERY == 0 or self.hidden.shape != ref_depth.shape:
            self.hidden, self.calls = self.visibility(ref_depth.detach()), 0
        self.calls += 1
        return self.hidden


def warp_to_reference(nbr_image, ref_depth, ref_cam: Camera, nbr_cam: Camera):
    """Resample a neighbour image into the reference view through the reference depth.

    Args:
        nbr_image: (H', W', 3) NumPy float in [0, 1], or a (B, C, H', W') tensor.
        ref_depth: (H, W) NumPy metres (NaN = unknown → invalid), or a (B, 1, H, W) tensor;
            differentiable w.r.t. this when it is a tensor.
        ref_cam, nbr_cam: the two cameras (``nbr_cam`` matches ``nbr_image``'s size).
    Returns:
        ``(warped, valid)``: (H, W, 3) array and (H, W) bool for NumPy input; (B, C, H, W) tensor
        and (B, 1, H, W) bool tensor for tensor input.
    """
    if not isinstance(ref_cam, Camera) or not isinstance(nbr_cam, Camera):
        raise TypeError("ref_cam and nbr_cam must be ddp_lite.Camera instances")
    as_numpy = not isinstance(nbr_image, torch.Tensor)
    if as_numpy:
        image = np.asarray(unmask(nbr_image, "nbr_image", holes=False), dtype=np.float32)
        depth = np.asarray(unmask(ref_depth, "ref_depth", holes=True), dtype=np.float32)  # masked = unknown
        if image.ndim != 3 or image.shape[2] < 1:
            raise ValueError(f"nbr_image must be (H, W, C), got shape {image.shape}")
        if depth.ndim != 2:
            raise ValueError(f"ref_depth must be (H, W), got shape {depth.shape}")
        image_t = torch.from_numpy(image.copy()).permute(2, 0, 1)[None]
        depth_t = torch.from_numpy(depth.copy())[None, None]
    else:
        image_t, depth_t = nbr_image, ref_depth
        if image_t.ndim != 4 or depth_t.ndim != 4 or depth_t.shape[1] != 1:
            raise ValueError(f"expected nbr_image (B, C, H, W) and ref_depth (B, 1, H, W), "
                             f"got {tuple(image_t.shape)} and {tuple(depth_t.shape)}")
    if tuple(depth_t.shape[-2:]) != (ref_cam.height, ref_cam.width):
        raise ValueError(f"ref_depth is {tuple(depth_t.shape[-2:])} but ref_cam is {ref_cam.height}×{ref_cam.width}")
    if tuple(image_t.shape[-2:]) != (nbr_cam.height, nbr_cam.width):
        raise ValueError(f"nbr_image is {tuple(image_t.shape[-2:])} but nbr_cam is {nbr_cam.height}×{nbr_cam.width}")
    warper = Warper(ref_cam, nbr_cam, dtype=image_t.dtype, device=image_t.device)
    finite = torch.isfinite(depth_t)
    warped, valid = warper(image_t, torch.where(finite, depth_t, torch.ones_like(depth_t)))
    valid = valid & finite
    if as_numpy:
        return warped[0].permute(1, 2, 0).numpy(), valid[0, 0].numpy()
    return warped, valid
