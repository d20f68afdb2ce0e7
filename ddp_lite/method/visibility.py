"""Which reference pixels a neighbour cannot see: the occlusion test of the kit's warp term.

Not in the paper. The paper's L_warp compares every reference pixel that lands inside the
neighbour's image with the colour found there. Beside a foreground edge, a band of the background
is hidden from the neighbour by the foreground; the colour found there is the foreground's, so
L_warp pulls the band's depth towards a wrong answer. On stereo pairs those bands are where
left-right checks fail, the commonest real hole. ``FitConfig.warp_occlusion`` leaves them out.

The test, for a reference point P (pixel p, depth z) and the neighbour's centre C: P is hidden
when the segment from P to C passes behind the reference surface, i.e. some point S of it
projects to a reference pixel s where the surface is nearer than S. The segment projects onto
the epipolar line through p, so the test marches along that line 1 px at a time (up to
``REACH`` px) and compares each segment point's depth with the depth map there: screen-space
ray marching, as in shadow mapping. A plane both cameras see from the same side hides nothing of
itself, however steep it is in depth, which a z-buffer of points in the neighbour's pixels gets
wrong.

Conventions: pixel (0, 0) is the centre of the top-left pixel; depth is along the reference's
optical axis, in metres; C is expressed in the reference camera's frame.
"""
from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from ..core.camera import Camera, pixel_grid, relative_pose

__all__ = ["Visibility"]


class Visibility(torch.nn.Module):
    """The reference pixels hidden from one neighbour, for a depth map that changes every call.

    Example:
        >>> K = np.array([[40.0, 0.0, 16.0], [0.0, 40.0, 4.0], [0.0, 0.0, 1.0]])
        >>> pose = np.eye(4); pose[0, 3] = -0.2  # the neighbour 0.2 m to the right
        >>> depth = torch.full((1, 1, 8, 32), 2.0)  # a wall: disparity 40 · 0.2 / 2 = 4 px
        >>> depth[..., 16:24] = 1.0  # a box in front of it: 8 px, 4 px more than the wall
        >>> Visibility(Camera(K, np.eye(4), 32, 8), Camera(K, pose, 32, 8))(depth)[0, 0, 0].nonzero().flatten().tolist()
        [13, 14, 15]
    """

    REACH = 32  # px marched along the epipolar line: wider than the widest occluded band expected
    MARGIN = 0.03  # relative depth by which the surface must be nearer than the segment

    def __init__(self, ref_cam: Camera, nbr_cam: Camera, dtype=torch.float32, device=None):
        super().__init__()
        ref_from_nbr = np.linalg.inv(relative_pose(ref_cam, nbr_cam))
        K = torch.tensor(ref_cam.K, dtype=torch.float64)
        K_inv = torch.linalg.inv(K)
        rays = (K_inv @ pixel_grid(ref_cam.height, ref_cam.width, torch.float64))  # (3, H·W), z = 1
        self.register_buffer("K", K.to(dtype=dtype, device=device))
        self.register_buffer("K_inv_xy", K_inv[:, :2].to(dtype=dtype, device=device))  # (3, 2): pixel steps → ray steps
        self.register_buffer("rays", rays.reshape(1, 3, ref_cam.height, ref_cam.width).to(dtype=dtype, device=device))
        self.register_buffer("pixels", pixel_grid(ref_cam.height, ref_cam.width, torch.float64)[:2]
                             .reshape(1, 2, ref_cam.height, ref_cam.width).to(dtype=dtype, device=device))
        centre = torch.tensor(ref_from_nbr[:3, 3], dtype=torch.float64)
        self.register_buffer("centre", centre.reshape(1, 3, 1, 1).to(dtype=dtype, device=device))
        self.register_buffer("steps", torch.arange(1, self.REACH + 1, dtype=dtype, device=device).reshape(1, -1, 1, 1, 1))
        scale = torch.tensor([2.0 / max(ref_cam.width - 1, 1), 2.0 / max(ref_cam.height - 1, 1)], dtype=dtype)
        self.register_buffer("to_grid", scale.reshape(1, 1, 2, 1, 1).to(device=device))
        self.size = (ref_cam.height, ref_cam.width)

    @torch.no_grad()
    def forward(self, depth: torch.Tensor) -> torch.Tensor:
        """``depth`` (B, 1, H, W) metres, finite → (B, 1, H, W) bool: True where the neighbour cannot see."""
        batch, (height, width) = depth.shape[0], self.size
        point = depth * self.rays  # (B, 3, H, W) P, with P_z = depth
        towards = self.centre - point  # (B, 3, H, W) D = C - P
        # P + tD projects to h(t) / h_z(t) with h(t) = K P + t K D; at t = 0 that is p, moving along
        # velocity = (K D)_xy P_z - (K P)_xy D_z (up to a positive factor): the epipolar line's direction
        q, dq = torch.einsum("ij,bjhw->bihw", self.K, point), torch.einsum("ij,bjhw->bihw", self.K, towards)
        velocity = dq[:, :2] * depth - q[:, :2] * towards[:, 2:]  # (B, 2, H, W)
        speed = velocity.norm(dim=1, keepdim=True)  # (B, 1, H, W)
        direction = velocity / speed.clamp_min(1e-12)
        # the segment reaches k px from p at t_k = k P_z² / (|velocity| - k P_z D_z) (none where ≤ 0),
        # at depth z_k = P_z + t_k D_z
        steps = self.steps[:, :, 0]  # (1, N, 1, 1)
        denominator = speed - steps * depth * towards[:, 2:]  # (B, N, H, W)
        t = steps * depth * depth / denominator.clamp_min(1e-12)
        z = depth + t * towards[:, 2:]
        at = self.pixels[:, None] + self.steps * direction[:, None]  # (B, N, 2, H, W) s_k = p + k·dir, pixels
        grid = (at * self.to_grid - 1.0).permute(0, 1, 3, 4, 2).reshape(batch, -1, width, 2)  # (B, N·H, W, 2)
        surface = F.grid_sample(depth, grid, mode="bilinear", padding_mode="border", align_corners=True)
        surface = surface.reshape(batch, -1, height, width)  # (B, N, H, W) the depth map at s_k
        inside = (at[:, :, 0] >= 0) & (at[:, :, 0] <= width - 1) & (at[:, :, 1] >= 0) & (at[:, :, 1] <= height - 1)
        behind = inside & (denominator > 0) & (t <= 1) & (surface < z * (1.0 - self.MARGIN))
        return behind.any(dim=1, keepdim=True)
