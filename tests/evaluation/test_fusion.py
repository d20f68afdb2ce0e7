"""Multi-view fusion on exact synthetic depth: fused points lie on the true surface, a corrupted
view is voted out, TSDF agrees, and clouds survive a .ply round trip and a headless render."""
import os

# open3d is imported inside the tests that use it: loading it takes ~3 s, which every test worker paid at collection
import numpy as np
import pytest

from ddp_lite.core.camera import Camera
from ddp_lite.evaluation.fusion import fuse_depths, points_from_depth, render_point_cloud, save_ply, tsdf_fuse
from ddp_lite.evaluation.metrics import point_cloud_prf
from ddp_lite.world.scenes import make_scene


@pytest.fixture(scope="module")
def desk():
    scene = make_scene("desk", size=(48, 64), n_views=4, seed=0)
    return [v.depth for v in scene], [v.camera for v in scene], [v.rgb for v in scene]


def _surface_error(points, depths, cameras):
    """(N,) relative depth error of each world point against the ground truth of the view that sees
    it best: project into every view, compare with that view's depth at the nearest pixel, keep
    the smallest. A point on the true surface is seen by at least one view (the one it came from)
    with error ~0; occluded views only give larger errors, so the minimum is the right one."""
    best = np.full(len(points), np.inf)
    for depth, cam in zip(depths, cameras):
        local = points @ cam.cam_from_world[:3, :3].T + cam.cam_from_world[:3, 3]
        uvw = local @ cam.K.T
        col, row = np.floor(uvw[:, 0] / uvw[:, 2] + 0.5), np.floor(uvw[:, 1] / uvw[:, 2] + 0.5)
        ok = (local[:, 2] > 0) & (col >= 0) & (col < cam.width) & (row >= 0) & (row < cam.height)
        truth = np.full(len(points), np.nan)
        truth[ok] = depth[row[ok].astype(int), col[ok].astype(int)]
        best = np.fmin(best, np.abs(local[:, 2] - truth) / truth)
    return np.where(np.isfinite(best), best, np.inf)


def test_points_from_depth_round_trips_through_the_camera(desk):
    depths, cameras, images = desk
    depth = depths[1].copy()
    depth[10:20, 30:40] = np.nan
    before = depth.copy()
    points, colours = points_from_depth(depth, cameras[1], images[1])
    mask = np.isfinite(depth)
    assert points.shape == (mask.sum(), 3) and colours.shape == (mask.sum(), 3)
    np.testing.assert_array_equal(colours, images[1][mask])
    cam = cameras[1]
    local = points @ cam.cam_from_world[:3, :3].T + cam.cam_from_world[:3, 3]
    uvw = local @ cam.K.T
    v, u = np.nonzero(mask)
    np.testing.assert_allclose(uvw[:, 0] / uvw[:, 2], u, atol=1e-6)
    np.testing.assert_allclose(uvw[:, 1] / uvw[:, 2], v, atol=1e-6)
    np.testing.assert_allclose(local[:, 2], depth[mask], rtol=1e-6)
    np.testing.assert_array_equal(depth, before)
    assert points_from_depth(depth, cam).shape == points.shape  # without rgb: just the points


def test_fusing_ground_truth_gives_points_on_the_surface(desk):
    depths, cameras, images = desk
    before = [d.copy() for d in depths]
    cloud = fuse_depths(depths, cameras, images, min_views=2)
    points = np.asarray(cloud.points)
    assert len(points) > 0.5 * depths[0].size  # measured: 3204 points from 4 × 3072 pixels
    assert cloud.has_colors() and np.asarray(cloud.colors).shape == points.shape
    error = _surface_error(points, depths, cameras)
    assert np.median(error) < 1e-3 and np.percentile(error, 99) < 0.02  # measured 0.04 %, 1.0 %
    for d, b in zip(depths, before):
        np.testing.assert_array_equal(d, b)
    # Fusibile marks merged pixels as used: every surface is output about once, not once per view
    assert len(points) < 1.5 * max(np.isfinite(d).sum() for d in depths)


def test_a_corrupted_view_is_voted_out(desk):
    depths, cameras, _ = desk
    corrupted = list(depths)
    corrupted[1] = depths[1] * 1.2  # view 1 is 20 % too far everywhere
    unchecked = _surface_error(np.asarray(fuse_depths(corrupted, cameras, min_views=0).points), depths, cameras)
    assert (unchecked > 0.1).sum() > 1000  # with no check, view 1's wrong points are in the cloud
    fused = _surface_error(np.asarray(fuse_depths(corrupted, cameras, min_views=2).points), depths, cameras)
    assert len(fused) > 2000 and fused.max() < 0.05  # with C = 2 they are all rejected


def test_tsdf_fusion_is_non_empty_and_on_the_surface(desk):
    depths, cameras, images = desk
    cloud = tsdf_fuse(depths, cameras, images, voxel_length=0.01)
    points = np.asarray(cloud.points)
    assert len(points) > 1000 and cloud.has_colors()  # measured: 45575 points
    error = _surface_error(points, depths, cameras)
    assert np.median(error) < 0.005 and np.percentile(error, 90) < 0.02  # measured 0.05 %, 0.9 %
    assert not tsdf_fuse(depths, cameras, voxel_length=0.02).has_colors()


def test_fused_ground_truth_scores_high_against_ground_truth_points(desk):
    depths, cameras, _ = desk
    cloud = fuse_depths(depths, cameras, min_views=2)
    truth = np.concatenate([points_from_depth(d, c) for d, c in zip(depths, cameras)])
    # a pixel spans ~z/f = 2 m / 55 px ≈ 3.6 cm on the far wall, so τ = 2 cm is "small" here
    result = point_cloud_prf(cloud, truth, tau=0.02)
    assert result["precision"] > 0.95 and result["fscore"] > 0.85  # measured P 0.99, R 0.88, F 0.93


def test_save_ply_round_trip(desk, tmp_path):
    import open3d as o3d
    depths, cameras, images = desk
    cloud = fuse_depths(depths, cameras, images, min_views=1)
    path = tmp_path / "fused.ply"
    save_ply(cloud, path)
    back = o3d.io.read_point_cloud(str(path))
    np.testing.assert_allclose(np.asarray(back.points), np.asarray(cloud.points), atol=1e-6)
    np.testing.assert_allclose(np.asarray(back.colors), np.asarray(cloud.colors), atol=1 / 255 + 1e-6)
    assert os.listdir(tmp_path) == ["fused.ply"]  # no temporary file left behind
    with pytest.raises(ValueError, match=r"\.ply"):
        save_ply(cloud, tmp_path / "fused.txt")
    with pytest.raises(TypeError, match="PointCloud"):
        save_ply(np.zeros((3, 3)), path)


def test_render_point_cloud_reproduces_a_view_from_its_own_points(desk):
    import open3d as o3d
    import matplotlib.pyplot as plt

    depths, cameras, images = desk
    points, colours = points_from_depth(depths[0], cameras[0], images[0])
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    cloud.colors = o3d.utility.Vector3dVector(colours.astype(np.float64))
    image = render_point_cloud(cloud, cameras[0])  # each point lands back on its own pixel
    np.testing.assert_allclose(image, images[0], atol=1e-6)
    fig, ax = plt.subplots()
    default = render_point_cloud(fuse_depths(depths, cameras, min_views=1), ax=ax, point_size=2)
    assert default.shape == (96, 128, 3) and default.dtype == np.float32
    assert 0.2 < (default < 1).any(axis=2).mean() < 1.0  # framed: the cloud covers part of the image
    plt.close(fig)


def test_nearest_point_wins_in_the_render():
    import open3d as o3d
    cam = Camera.from_fov(width=9, height=7, fov_x_deg=60.0)  # principal point on pixel (4, 3)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.array([[0.0, 0.0, 2.0], [0.0, 0.0, 1.0]])))
    cloud.colors = o3d.utility.Vector3dVector(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    image = render_point_cloud(cloud, cam)
    centre = image[3, 4]
    np.testing.assert_array_equal(centre, [0.0, 0.0, 1.0])  # blue is nearer than red


def test_fusion_inputs_are_checked(desk):
    depths, cameras, images = desk
    with pytest.raises(ValueError, match="same length"):
        fuse_depths(depths, cameras[:3])
    with pytest.raises(ValueError, match="min_views"):
        fuse_depths(depths, cameras, min_views=4)
    with pytest.raises(ValueError, match=r"depth\[2\]"):
        fuse_depths([depths[0], depths[1], depths[2][:, :10], depths[3]], cameras)
    with pytest.raises(ValueError, match="positive"):
        points_from_depth(-depths[0], cameras[0])
    with pytest.raises(TypeError, match="Camera"):
        points_from_depth(depths[0], np.eye(3))
    with pytest.raises(ValueError, match=r"image\[0\]"):
        fuse_depths(depths, cameras, [im[:, :, :2] for im in images])
    with pytest.raises(ValueError, match="voxel_length"):
        tsdf_fuse(depths, cameras, images, voxel_length=0.0)


def test_depth_coloured_renders_share_a_given_scale_and_draw_a_colour_bar():
    import matplotlib
    import matplotlib.pyplot as plt

    cam = Camera.from_fov(width=9, height=7, fov_x_deg=60.0)
    near, far = np.array([[0.0, 0.0, 2.0]]), np.array([[0.0, 0.0, 4.0]])
    colour = lambda z: matplotlib.colormaps["viridis_r"]((z - 1.0) / (5.0 - 1.0))[:3]  # the scale 1-5 m, by hand
    fig, axes = plt.subplots(1, 2)
    for ax, points, z in ((axes[0], near, 2.0), (axes[1], far, 4.0)):
        image = render_point_cloud(points, cam, ax=ax, depth_range=(1.0, 5.0))
        np.testing.assert_allclose(image[3, 4], colour(z), atol=1e-6)  # not each cloud's own percentiles
    assert len(fig.axes) == 4 and "depth" in fig.axes[2].get_ylabel()  # one colour bar per render
    plt.close(fig)
    with pytest.raises(ValueError, match="depth_range"):
        render_point_cloud(near, cam, depth_range=(5.0, 1.0))
