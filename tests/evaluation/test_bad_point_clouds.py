"""Point clouds: an empty cloud is refused before a file is written, and colours are scaled from 8 bits or refused."""
from __future__ import annotations

import numpy as np
import pytest


def test_an_empty_point_cloud_is_refused_clearly_and_colours_are_scaled_or_refused(tmp_path):
    from ddp_lite.core.camera import Camera
    from ddp_lite.evaluation.fusion import fuse_depths, points_from_depth, save_ply
    camera = Camera.from_fov(8, 6, 60.0)
    empty = fuse_depths([np.full((6, 8), np.nan)], [camera], min_views=0)
    with pytest.raises(ValueError, match="no points"):
        save_ply(empty, tmp_path / "empty.ply")
    assert not (tmp_path / "empty.ply").exists()
    depth = np.full((6, 8), 2.0)
    points, colours = points_from_depth(depth, camera, np.full((6, 8, 3), 255, np.uint8))
    assert np.allclose(colours, 1.0)
    _, half = points_from_depth(depth, camera, np.full((6, 8, 3), 128, np.uint8))
    assert np.allclose(half, 128 / 255)
    with pytest.raises(ValueError, match="divide it by 255"):
        points_from_depth(depth, camera, np.full((6, 8, 3), 200.0))
