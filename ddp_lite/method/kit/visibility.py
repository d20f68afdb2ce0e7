"""Which reference pixels a neighbour cannot see: the occlusion test of the kit's warp term.

Not in the paper. The paper's L_warp compares every reference pixel that lands inside the
neighbour's image with the colour found there. Beside a foreground edge, a band of the background
is hidden from the neighbour by the foreground; the colour found there is the foreground's, so
L_warp pulls the band's depth towards a wrong answer. On stereo pairs those bands are where
left-right checks fail, the commonest real hole. ``WarpConfig.occlusion`` (``warp_occlusion``) leaves them out.

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

from ...core.camera import Camera, pixel_grid, relative_pose

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
        height, width = ref_cam.height, ref_cam.width
        centre = torch.tensor(np.linalg.inv(relative_pose(ref_cam, nbr_cam))[:3, 3], dtype=torch.float64)  # C, ref frame
        epipole = torch.tensor(ref_cam.K, dtype=torch.float64) @ centre  # e = K C, homogeneous
        pixels = pixel_grid(height, width, torch.float64)[:2].reshape(2, height, width)  # (2, H, W) p
        # P + tD (D = C - P) projects from p along depth·(e_xy - p·e_z), whatever the depth: the
        # epipolar line's direction, the same every call, and so are the marched pixels s_k = p + k·dir
        velocity = epipole[:2, None, None] - pixels * epipole[2]  # (2, H, W)
        speed = velocity.norm(dim=0, keepdim=True)  # (1, H, W) |e_xy - p·e_z|
        steps = torch.arange(1, self.REACH + 1, dtype=torch.float64).reshape(-1, 1, 1, 1)  # (N, 1, 1, 1)
        at = pixels + steps * velocity / speed.clamp_min(1e-12)  # (N, 2, H, W)
        inside = (at[:, 0] >= 0) & (at[:, 0] <= width - 1) & (at[:, 1] >= 0) & (at[:, 1] <= height - 1)  # (N, H, W)
        scale = torch.tensor([2.0 / max(width - 1, 1), 2.0 / max(height - 1, 1)], dtype=torch.float64).reshape(1, 2, 1, 1)
        grid = (at * scale - 1.0).permute(0, 2, 3, 1).reshape(1, -1, width, 2)  # (1, N·H, W, 2) for grid_sample
        as_buffer = dict(dtype=dtype, device=device)
        self.register_buffer("speed", speed[None].to(**as_buffer))  # (1, 1, H, W)
        self.register_buffer("steps", steps[None, :, 0].to(**as_buffer))  # (1, N, 1, 1)
        self.register_buffer("centre_z", centre[2].reshape(1, 1, 1, 1).to(**as_buffer))  # C_z
        self.register_buffer("grid", grid.to(**as_buffer))
        self.register_buffer("inside", inside[None].to(device=device))  # (1, N, H, W)
        self.size = (height, width)

    @torch.no_grad()
    def forward(self, depth: torch.Tensor) -> torch.Tensor:
        """``depth`` (B, 1, H, W) metres, finite → (B, 1, H, W) bool: True where the neighbour cannot see."""
        batch, (height, width) = depth.shape[0], self.size
        # with D_z = C_z - P_z, the segment reaches s_k at t_k = k P_z / (|e_xy - p·e_z| - k D_z) (none where
        # that is ≤ 0), at depth z_k = P_z + t_k D_z
        towards_z = self.centre_z - depth  # (B, 1, H, W) D_z
        denominator = self.speed - self.steps * towards_z  # (B, N, H, W)
        t = self.steps * depth / denominator.clamp_min(1e-12)
        z = depth + t * towards_z
        surface = F.grid_sample(depth, self.grid.expand(batch, -1, -1, -1), mode="bilinear", padding_mode="border",
                                align_corners=True).reshape(batch, -1, height, width)  # (B, N, H, W) the depth at s_k
        behind = self.inside & (denominator > 0) & (t <= 1) & (surface < z * (1.0 - self.MARGIN))
        return behind.any(dim=1, keepdim=True)
