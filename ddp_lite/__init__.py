"""ddp-lite: Depth completion with a view-constrained Deep Depth Prior (Ghosh et al., 3DV 2020).

    >>> import ddp_lite as ddp
    >>> result = ddp.complete_depth(rgb, depth_with_nans, camera, neighbors, variant="rgbd+warp")
    >>> result.depth  # (H, W) metres, holes filled

Units and conventions: images float32 (H, W, 3) in [0, 1]; depth float32 (H, W) metres with NaN
holes; cameras in the OpenCV convention (x right, y down, z forward), pixel (0, 0) = centre of the
top-left pixel. ``DDP_PROFILE`` (ci / class / paper) sets sizes and schedules.
"""
from .camera import Camera, backproject, look_at, pixel_grid, project, relative_pose
from .disparity import DisparityTransform
from .fit import (VARIANTS, DepthResult, FitConfig, ImageResult, complete_depth, complete_depth_coarse_to_fine, fit_image,
                  merge)
from .losses import disparity_loss, masked_l1, rgb_loss, ssim, warp_loss
from .nets import SkipNet, UNet, build_net, make_noise
from .profiles import PROFILES, Profile, get_profile
from . import baselines, datasets, fusion, metrics
from .holes import edge_band_holes, kinect_noise, random_holes, sgm_depth, sgm_disparity
from .scenes import Scene, View, list_scenes, make_scene, register_scene, select_neighbors
from . import organic  # registers the curved, photo-textured scenes in SCENES
from .warp import Warper, warp_to_reference

__version__ = "0.1.0"
