"""ddp-lite: Depth completion with a view-constrained Deep Depth Prior (Ghosh et al., 3DV 2020).

    >>> import ddp_lite as ddp
    >>> result = ddp.complete_depth(rgb, depth_with_nans, camera, neighbors, variant="rgbd+warp")
    >>> result.depth  # (H, W) metres, holes filled

Units and conventions: images float32 (H, W, 3) in [0, 1]; depth float32 (H, W) metres with NaN
holes; cameras in the OpenCV convention (x right, y down, z forward), pixel (0, 0) = centre of the
top-left pixel. ``DDP_PROFILE`` (ci / class / paper) sets sizes and schedules.
"""
# What a notebook or a user calls: completion, its config and profiles, scenes and cameras, the
# transform DDP fits in, SGM input. ``from ddp_lite import *`` gives exactly these.
__all__ = ["complete_depth", "DepthResult", "merge", "FitConfig", "VARIANTS", "fit_image", "ImageResult",
           "get_profile", "Profile", "PROFILES", "make_scene", "list_scenes", "Scene", "View", "Camera", "look_at",
           "DisparityTransform", "sgm_depth", "random_holes"]

from .camera import Camera, look_at
from .disparity import DisparityTransform
from .fit import DepthResult, FitConfig, ImageResult, complete_depth, fit_image, merge
from .holes import random_holes
from .profiles import PROFILES, Profile, get_profile
from .scenes import list_scenes, make_scene
from .stereo import sgm_depth
from .variants import VARIANTS
from .views import Scene, View
from . import organic  # registers the curved, photo-textured scenes in SCENES

# Building blocks, importable from here as before; new code imports them from their modules
# (ddp_lite.losses, ddp_lite.nets, ddp_lite.warp, ...), where their documentation lives.
from .camera import backproject, pixel_grid, project, relative_pose
from .coarse_to_fine import complete_depth_coarse_to_fine
from .holes import edge_band_holes, kinect_noise
from .losses import disparity_loss, masked_l1, rgb_loss, ssim, warp_loss
from .nets import SkipNet, UNet, build_net, make_noise
from .neighbors import select_neighbors
from .scenes import register_scene
from .stereo import sgm_disparity
from .warp import Warper, warp_to_reference
from . import baselines, datasets, fusion, metrics

__version__ = "0.1.0"
