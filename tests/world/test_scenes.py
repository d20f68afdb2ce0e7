"""Synthetic scenes: exact depth, the camera model, multi-view photo-consistency, the stereo rig,
view selection, determinism, save/load and input checks, each against an independent reference."""
import cv2
import numpy as np
import pytest
from scipy import ndimage

from ddp_lite.core.camera import Camera, look_at
from ddp_lite.world.neighbors import select_neighbors
from ddp_lite.world.render import Box, Plane, Sphere, render
from ddp_lite.world.scenes import list_scenes, make_scene
from ddp_lite.world.textures import Texture
from ddp_lite.core.views import LABELS, Scene, View

NOISE = Texture("noise", (0.9, 0.6, 0.3), (0.1, 0.2, 0.4), 0.05)


@pytest.fixture(scope="module")
def desk():
    return make_scene("desk", size=(48, 64), n_views=3, seed=0)


def test_fronto_parallel_plane_renders_its_exact_depth():
    camera = Camera.from_fov(40, 30, 60.0)
    rgb, depth, labels = render([Plane((0, 0, 3.25), (0, 0, -1), (1, 0, 0), NOISE)], camera)
    assert depth.dtype == np.float32 and rgb.shape == (30, 40, 3) and rgb.dtype == np.float32
    np.testing.assert_allclose(depth, 3.25, rtol=1e-7)
    assert np.all(labels == 3) and 0.0 <= rgb.min() and rgb.max() <= 1.0


def test_ground_plane_seen_by_a_pitched_camera_matches_the_closed_form():
    # camera h metres above the ground (y down), pitched down by a: the ray through row v has world
    # y-slope sin a + cos a · (v - cy) / f, so it meets the ground at depth h / (that slope)
    h, a, f_deg = 1.5, np.radians(20.0), 70.0
    eye = np.array([0.3, -h, 0.0])
    camera = Camera.from_fov(64, 48, f_deg, look_at(eye, eye + 10 * np.array([0.0, np.sin(a), np.cos(a)])))
    _, depth, _ = render([Plane((0, 0, 0), (0, -1, 0), (1, 0, 0), NOISE)], camera)
    f, cy = camera.K[0, 0], camera.K[1, 2]
    slope = np.sin(a) + np.cos(a) * (np.arange(48) - cy) / f  # (48,)
    expected = np.where(slope > 0, h / np.where(slope > 0, slope, 1.0), np.inf)
    np.testing.assert_allclose(depth, np.broadcast_to(expected[:, None], depth.shape), rtol=1e-5)


def test_sphere_centre_projects_where_the_camera_model_says():
    pose = look_at((0.4, -0.2, -0.5), (0.0, 0.1, 4.0))
    camera = Camera.from_fov(96, 72, 60.0, pose)
    X, r = np.array([0.5, 0.3, 4.0]), 0.35
    R, t = camera.cam_from_world[:3, :3], camera.cam_from_world[:3, 3]
    x_cam = R @ X + t
    u, v, w = camera.K @ x_cam
    u, v = u / w, v / w
    _, depth, labels = render([Sphere(tuple(X), r, NOISE), Plane((0, 0, 30), (0, 0, -1), (1, 0, 0),
                                                                  Texture("sky"))], camera)
    rows, cols = np.nonzero(labels == 3)
    assert abs(cols.mean() - u) < 0.3 and abs(rows.mean() - v) < 0.3  # silhouette centroid
    # a sphere exactly centred on pixel (uc, vc): the ray through it enters at |X - C| - r
    uc, vc = 50, 30
    ray = np.linalg.inv(camera.K) @ np.array([uc, vc, 1.0])  # camera frame, z = 1
    X2 = camera.world_from_cam[:3, :3] @ (4.0 * ray) + camera.center
    _, depth2, _ = render([Sphere(tuple(X2), r, NOISE), Plane((0, 0, 30), (0, 0, -1), (1, 0, 0), NOISE)], camera)
    assert depth2[vc, uc] == pytest.approx(4.0 - r / np.linalg.norm(ray), rel=1e-6)


def test_box_front_face_and_background_depth():
    camera = Camera.from_fov(64, 48, 60.0)
    prims = [Box((0.0, 0.0, 2.5), (0.4, 0.3, 0.5), NOISE), Plane((0, 0, 6), (0, 0, -1), (1, 0, 0), NOISE)]
    _, depth, _ = render(prims, camera)
    f, cx, cy = camera.K[0, 0], camera.K[0, 2], camera.K[1, 2]
    v, u = np.mgrid[0:48, 0:64]
    x, y = (u - cx) / f * 2.0, (v - cy) / f * 2.0  # where the pixel's ray crosses the face z = 2
    on_face = (np.abs(x) < 0.39) & (np.abs(y) < 0.29)
    clear = (np.abs(x) > 0.41) | (np.abs(y) > 0.31)  # outside the front face's outline: misses the box
    np.testing.assert_allclose(depth[on_face], 2.0, rtol=1e-6)
    np.testing.assert_allclose(depth[clear], 6.0, rtol=1e-6)


def _inverse_warp(nbr_rgb, ref_depth, ref_cam, nbr_cam):
    """Independent NumPy/cv2 inverse warp: nbr image sampled at the reference pixels' projections."""
    H, W = ref_depth.shape
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    rays = np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(ref_cam.K).T  # (H, W, 3)
    pts = rays * ref_depth[..., None]
    T = nbr_cam.cam_from_world @ np.linalg.inv(ref_cam.cam_from_world)
    q = pts @ T[:3, :3].T + T[:3, 3]
    uvw = q @ nbr_cam.K.T
    mu, mv = (uvw[..., 0] / uvw[..., 2]).astype(np.float32), (uvw[..., 1] / uvw[..., 2]).astype(np.float32)
    warped = cv2.remap(nbr_rgb, mu, mv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return warped, mu, mv, q[..., 2]


def _consistent_pixels(ref, nbr, mu, mv, z):
    """Pixels seen by both views, away from the border and from depth edges."""
    H, W = ref.depth.shape
    inside = (mu >= 1) & (mu <= W - 2) & (mv >= 1) & (mv <= H - 2)
    nbr_z = cv2.remap(nbr.depth, mu, mv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    visible = np.abs(nbr_z - z) < 0.02 * z  # not occluded in the neighbour
    return inside & visible & ~_near_depth_edges(ref.depth)


def _near_depth_edges(depth, jump=0.06, iterations=2):
    log = np.log(depth)
    edge = np.zeros(depth.shape, bool)
    edge[:, 1:] |= np.abs(np.diff(log, axis=1)) > jump
    edge[1:] |= np.abs(np.diff(log, axis=0)) > jump
    return ndimage.binary_dilation(edge, iterations=iterations)


def test_warping_a_neighbour_with_true_depth_reproduces_the_reference(desk):
    ref, nbr = desk[0], desk[1]
    warped, mu, mv, z = _inverse_warp(nbr.rgb, ref.depth, ref.camera, nbr.camera)
    ok = _consistent_pixels(ref, nbr, mu, mv, z)
    assert ok.mean() > 0.5
    error = np.abs(warped - ref.rgb).mean(-1)[ok]
    assert np.median(error) < 0.02 and error.mean() < 0.03
    # sanity: on the textured surfaces, a wrong depth breaks photo-consistency
    textured = ok & (desk.labels[0] == 3)
    wrong, *_ = _inverse_warp(nbr.rgb, ref.depth * 0.6, ref.camera, nbr.camera)
    right_error = np.abs(warped - ref.rgb).mean(-1)[textured].mean()
    assert np.abs(wrong - ref.rgb).mean(-1)[textured].mean() > 2 * right_error


def test_warp_module_agrees_on_the_scene(desk):
    from ddp_lite.method.paper.warp import warp_to_reference
    ref, nbr = desk[0], desk[2]
    warped, valid = warp_to_reference(nbr.rgb, ref.depth, ref.camera, nbr.camera)
    _, mu, mv, z = _inverse_warp(nbr.rgb, ref.depth, ref.camera, nbr.camera)
    ok = _consistent_pixels(ref, nbr, mu, mv, z) & valid
    error = np.abs(warped - ref.rgb).mean(-1)[ok]
    assert ok.mean() > 0.5 and np.median(error) < 0.02 and error.mean() < 0.03


def test_right_view_is_a_rectified_pair(desk):
    B = desk.meta["baseline"]
    for left, right in zip(desk.views, desk.right):
        np.testing.assert_array_equal(left.camera.K, right.camera.K)
        np.testing.assert_allclose(right.camera.cam_from_world[:3, :3], left.camera.cam_from_world[:3, :3])
        offset = left.camera.cam_from_world[:3, :3] @ (right.camera.center - left.camera.center)
        np.testing.assert_allclose(offset, [B, 0.0, 0.0], atol=1e-12)  # along the left camera's x axis
    # the left image is the right image shifted by the disparity f·B/z, row by row
    left, right = desk[0], desk.right[0]
    H, W = left.depth.shape
    disparity = (left.camera.K[0, 0] * B / left.depth).astype(np.float32)
    v, u = np.mgrid[0:H, 0:W].astype(np.float32)
    warped = cv2.remap(right.rgb, u - disparity, v, cv2.INTER_LINEAR)
    ok = (u - disparity >= 1) & ~_near_depth_edges(left.depth, iterations=3)
    assert np.median(np.abs(warped - left.rgb).mean(-1)[ok]) < 0.02


def test_every_named_scene_is_finite_labelled_and_described():
    names = list_scenes()
    assert {"house", "desk", "room", "street"} <= set(names) and "house" in repr(names)
    for name in names:
        scene = make_scene(name, size=(24, 32), n_views=2, supersample=1)
        assert len(scene) == 2 and len(scene.right) == 2 and len(scene.labels) == 2
        for view in scene.views + scene.right:
            assert np.all(np.isfinite(view.depth)) and view.depth.min() > 0
            assert view.rgb.dtype == np.float32 and 0 <= view.rgb.min() and view.rgb.max() <= 1
        assert set(np.unique(scene.labels[0])) <= set(LABELS)
        assert all(isinstance(v, float) for v in scene.meta.values())
        assert scene.meta["d_min"] <= min(v.depth.min() for v in scene.views)
        assert scene.meta["d_max"] >= max(v.depth.max() for v in scene.views)
    house = make_scene("house", size=(48, 64), n_views=1)
    sky = house.labels[0] == 0
    assert sky.mean() > 0.05 and np.allclose(house[0].depth[sky], house[0].depth[sky].max(), rtol=0.2)
    assert (house.labels[0] == 2).mean() > 0.1  # the planks


def test_select_neighbors_prefers_five_degrees():
    # a textured wall 4 m ahead; views whose baseline to view 0 makes ~1°, ~5° and ~15° at the wall
    wall = [Plane((0, 0, 4.0), (0, 0, -1), (1, 0, 0), NOISE)]
    views = []
    for angle in (0.0, 15.0, 1.0, 5.0):
        eye = np.array([4.0 * np.tan(np.radians(angle)), 0.0, 0.0])
        camera = Camera.from_fov(32, 24, 60.0, look_at(eye, (0.0, 0.0, 4.0)))
        rgb, depth, _ = render(wall, camera, supersample=1)
        views.append(View(rgb, depth, camera))
    scene = Scene("angles", views)
    assert select_neighbors(scene, 0, n=3) == [3, 1, 2]
    assert select_neighbors(scene, 0, n=1) == [3]


def test_select_neighbors_on_a_named_scene(desk):
    chosen = select_neighbors(desk, 0, 2)
    assert sorted(chosen) == [1, 2]


def test_same_seed_same_bytes_other_seed_other_texture():
    a = make_scene("house", size=(24, 32), n_views=2, seed=3, supersample=1)
    b = make_scene("house", size=(24, 32), n_views=2, seed=3, supersample=1)
    c = make_scene("house", size=(24, 32), n_views=2, seed=4, supersample=1)
    for x, y in zip(a.views + a.right, b.views + b.right):
        assert x.rgb.tobytes() == y.rgb.tobytes() and x.depth.tobytes() == y.depth.tobytes()
        assert x.camera.cam_from_world.tobytes() == y.camera.cam_from_world.tobytes()
    assert a.meta == b.meta
    assert np.abs(a[0].rgb - c[0].rgb).mean() > 0.01  # new textures and colours
    np.testing.assert_array_equal(a[0].depth, c[0].depth)  # same geometry


def test_save_load_round_trip(tmp_path, desk):
    path = tmp_path / "desk.npz"
    desk.save(path)
    back = Scene.load(path)
    assert back.name == desk.name and back.meta == desk.meta and len(back.right) == len(desk.right)
    for x, y in zip(desk.views + desk.right, back.views + back.right):
        np.testing.assert_array_equal(x.rgb, y.rgb)
        np.testing.assert_array_equal(x.depth, y.depth)
        np.testing.assert_array_equal(x.camera.cam_from_world, y.camera.cam_from_world)
        assert x.name == y.name
    for x, y in zip(desk.labels, back.labels):
        np.testing.assert_array_equal(x, y)
    assert [p.name for p in tmp_path.iterdir()] == ["desk.npz"]  # no temporary left behind


@pytest.mark.parametrize("kwargs, word", [
    (dict(name="castle"), "name"), (dict(name="house", size=(0, 10)), "size"),
    (dict(name="house", size="big"), "size"), (dict(name="house", n_views=0), "n_views"),
    (dict(name="house", seed=-1), "seed"), (dict(name="house", fov_x_deg=179.0), "fov_x_deg"),
    (dict(name="house", supersample=2), "supersample"),
])
def test_make_scene_rejects_bad_input(kwargs, word):
    with pytest.raises(ValueError, match=word):
        make_scene(**{"size": (16, 16), "n_views": 1, **kwargs})


def test_select_neighbors_rejects_bad_input(desk):
    with pytest.raises(ValueError, match="ref"):
        select_neighbors(desk, 7)
    with pytest.raises(ValueError, match="n"):
        select_neighbors(desk, 0, n=3)


def test_a_view_as_a_warp_neighbour():
    view = make_scene("desk", size=(16, 16), n_views=1)[0]
    rgb, camera = view.as_neighbor()
    assert rgb is view.rgb and camera is view.camera
    assert view.neighbor == view.as_neighbor()  # the old name

