"""Offline tests of ddp_lite.data.datasets: PFM, Middlebury calib/loader/fixture, KITTI, TnT cams, NYU depth."""
import struct

import cv2
import numpy as np
import pytest

from ddp_lite.data.datasets import (NYU_K, load_kitti, load_nyu, load_tnt, read_kitti_calib, read_kitti_disparity,
                                    read_mvsnet_cam)
from ddp_lite.data.middlebury import load_middlebury, make_middlebury_fixture, parse_middlebury_calib
from ddp_lite.data.fileio import read_depth_image, read_pfm
from ddp_lite.data.resample import resize_scene
from ddp_lite.data.file_writers import write_pfm
from ddp_lite.core.camera import Camera
from ddp_lite.world.scenes import make_scene
from ddp_lite.classical.stereo import disparity_to_depth
from ddp_lite.core.views import Scene, View


@pytest.mark.parametrize("shape", [(5, 7), (5, 7, 3)])
def test_pfm_round_trip_is_exact_and_leaves_the_input_alone(tmp_path, shape):
    array = np.random.default_rng(0).normal(size=shape).astype(np.float32)
    array[0, 0] = np.inf
    array[1, 2] = -1e30
    before = array.copy()
    write_pfm(tmp_path / "a.pfm", array)
    back = read_pfm(tmp_path / "a.pfm")
    assert back.dtype == np.float32 and back.shape == shape
    np.testing.assert_array_equal(back, array)
    np.testing.assert_array_equal(array, before)
    assert not list(tmp_path.glob("*.tmp"))


def test_pfm_single_channel_with_trailing_axis(tmp_path):
    array = np.arange(12, dtype=np.float64).reshape(3, 4, 1)
    write_pfm(tmp_path / "a.pfm", array)
    np.testing.assert_array_equal(read_pfm(tmp_path / "a.pfm"), array[:, :, 0])


@pytest.mark.parametrize("channels", [1, 3])
def test_pfm_big_endian_written_by_hand(tmp_path, channels):
    H, W = 2, 3
    top_first = np.arange(H * W * channels, dtype=np.float32).reshape((H, W, channels) if channels == 3 else (H, W))
    rows_bottom_up = top_first[::-1].ravel()
    header = (b"PF" if channels == 3 else b"Pf") + b"\n3 2\n1.0\n"
    (tmp_path / "be.pfm").write_bytes(header + struct.pack(f">{rows_bottom_up.size}f", *rows_bottom_up))
    np.testing.assert_array_equal(read_pfm(tmp_path / "be.pfm"), top_first)


def test_pfm_bad_input(tmp_path):
    with pytest.raises(ValueError, match="array"):
        write_pfm(tmp_path / "a.pfm", np.zeros((2, 3, 2)))
    (tmp_path / "bad.pfm").write_bytes(b"P6\n1 1\n255\nxxx")
    with pytest.raises(ValueError, match="PFM"):
        read_pfm(tmp_path / "bad.pfm")
    (tmp_path / "short.pfm").write_bytes(b"Pf\n4 4\n-1.0\n" + b"\0" * 8)
    with pytest.raises(ValueError, match="truncated"):
        read_pfm(tmp_path / "short.pfm")


CALIB = """cam0=[1000 0 300.5; 0 1000 200; 0 0 1]
cam1=[1000 0 340.5; 0 1000 200; 0 0 1]
doffs=40
baseline=200.0
width=640
height=480
ndisp=128
isint=0
vmin=10
vmax=120
"""


def test_middlebury_calib_by_hand():
    calib = parse_middlebury_calib(CALIB)
    np.testing.assert_array_equal(calib.K0, [[1000, 0, 300.5], [0, 1000, 200], [0, 0, 1]])
    assert calib.K1[0, 2] == 340.5 and calib.doffs == 40.0
    assert calib.baseline == pytest.approx(0.2)  # 200 mm
    assert (calib.width, calib.height, calib.ndisp) == (640, 480, 128)
    assert calib.extra["vmax"] == 120.0
    left, right = calib.cameras()
    np.testing.assert_allclose(left.center, [0, 0, 0])
    np.testing.assert_allclose(right.center, [0.2, 0, 0])
    # Z = f·B/(d + doffs): 1000·0.2/(60 + 40) = 2 m; 1000·0.2/(10 + 40) = 4 m; inf → NaN; d + doffs ≤ 0 → NaN
    depth = calib.depth(np.array([[60.0, 10.0], [np.inf, -40.0]], dtype=np.float32))
    np.testing.assert_allclose(depth[0], [2.0, 4.0])
    assert np.isnan(depth[1]).all() and depth.dtype == np.float32
    # a right-camera point projects with x1 = x0 - d: check the geometry agrees with the formula
    X = np.array([0.3, -0.1, 2.0, 1.0])
    x0 = left.K @ (left.cam_from_world @ X)[:3]
    x1 = right.K @ (right.cam_from_world @ X)[:3]
    d = x0[0] / x0[2] - x1[0] / x1[2]
    assert 1000 * 0.2 / (d + 40) == pytest.approx(2.0)


def test_middlebury_calib_bad_input():
    with pytest.raises(ValueError, match="baseline"):
        parse_middlebury_calib(CALIB.replace("baseline=200.0\n", ""))
    with pytest.raises(ValueError, match="cam0"):
        parse_middlebury_calib(CALIB.replace("0 0 1]\ncam1", "0 1]\ncam1"))
    with pytest.raises(ValueError, match="focal"):
        disparity_to_depth(np.ones((2, 2)), 0.0, 0.1)


def test_middlebury_fixture_round_trip(tmp_path):
    folder = make_middlebury_fixture(tmp_path / "Toy-perfect", size=(48, 64), seed=0)
    assert sorted(p.name for p in folder.iterdir()) == ["calib.txt", "disp0.pfm", "disp1.pfm", "im0.png", "im1.png"]
    assert np.isinf(read_pfm(folder / "disp0.pfm")).any()
    scene = load_middlebury(folder)
    ref = make_scene("desk", size=(48, 64), n_views=1, seed=0)
    assert isinstance(scene, Scene) and scene.name == "Toy-perfect" and len(scene.right) == 1
    valid = np.isfinite(scene[0].depth)
    assert 0.8 < valid.mean() < 0.97  # the inf disparities became NaN
    np.testing.assert_allclose(scene[0].depth[valid], ref[0].depth[valid], rtol=1e-6)
    np.testing.assert_allclose(scene.right[0].depth, ref.right[0].depth, rtol=1e-6)
    np.testing.assert_allclose(scene[0].rgb, ref[0].rgb, atol=1 / 255)
    np.testing.assert_allclose(scene[0].camera.K, ref[0].camera.K)
    np.testing.assert_allclose(scene.right[0].camera.center, [ref.meta["baseline"], 0, 0])
    assert scene.meta["baseline"] == pytest.approx(ref.meta["baseline"])
    small = load_middlebury(folder, size=(24, 32))
    assert small.size == (24, 32) and small[0].camera.K[0, 0] == pytest.approx(ref[0].camera.K[0, 0] / 2)
    scene.save(tmp_path / "s.npz")  # notebooks' save/load path accepts it
    assert Scene.load(tmp_path / "s.npz").meta == scene.meta


def test_resize_scene_by_hand():
    # 27×24 → 9×8: a factor of exactly 3, so each small pixel covers one 3×3 block whose centre is (3i+1, 3j+1)
    rows, cols = np.mgrid[0:27, 0:24]
    depth = (1.0 + rows + 100.0 * cols).astype(np.float32)
    depth[4, 7] = np.nan  # the centre of block (1, 2): the small pixel must be a hole
    depth[0, 0] = np.nan  # a corner of block (0, 0): nearest-by-centre must not see it
    block = (rows // 3 + 10 * (cols // 3)).astype(np.float32) / 100.0  # constant on every 3×3 block
    rgb = np.stack([block, 0.5 * block, np.full_like(block, 0.25)], axis=2)
    K = np.array([[30.0, 0.0, 11.5], [0.0, 30.0, 13.0], [0.0, 0.0, 1.0]])
    right_pose = np.eye(4)
    right_pose[0, 3] = -0.1
    labels = [(rows % 2).astype(np.uint8)]
    scene = Scene("toy", [View(rgb, depth, Camera(K, np.eye(4), 24, 27), "l")],
                  [View(rgb[:, ::-1], depth[:, ::-1], Camera(K, right_pose, 24, 27), "r")],
                  {"baseline": 0.1, "doffs": 6.0, "ndisp": 30.0, "focal": 30.0, "d_min": 0.5, "d_max": 3000.0}, labels)
    before = depth.copy()
    small = resize_scene(scene, (9, 8))
    assert small.size == (9, 8) and small.name == "toy" and len(small.right) == 1
    expected = depth[1::3, 1::3]
    np.testing.assert_array_equal(small[0].depth, expected)
    assert np.isnan(small[0].depth[1, 2]) and small[0].depth[0, 0] == depth[1, 1]
    np.testing.assert_allclose(small[0].rgb, rgb[1::3, 1::3], atol=1e-6)  # area of a constant block
    np.testing.assert_array_equal(small.right[0].depth, depth[:, ::-1][1::3, 1::3])
    np.testing.assert_array_equal(small.labels[0], labels[0][1::3, 1::3])
    # K: f/3, c' = (c + 0.5)/3 - 0.5; the pose is kept
    np.testing.assert_allclose(small[0].camera.K, [[10.0, 0.0, 3.5], [0.0, 10.0, 4.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(small.right[0].camera.center, [0.1, 0.0, 0.0])
    assert small.meta == {"baseline": 0.1, "doffs": 2.0, "ndisp": 10.0, "focal": 10.0, "d_min": 0.5, "d_max": 3000.0}
    np.testing.assert_array_equal(scene[0].depth, before)  # the input is untouched
    assert scene.size == (27, 24) and scene.meta["doffs"] == 6.0
    with pytest.raises(ValueError, match="size"):
        resize_scene(scene, (4, 4))
    with pytest.raises(TypeError, match="scene"):
        resize_scene("scene", (9, 8))


def test_load_middlebury_size_equals_resize_scene(tmp_path):
    folder = make_middlebury_fixture(tmp_path / "Toy-perfect", size=(48, 64), seed=1)
    direct, later = load_middlebury(folder, size=(24, 32)), resize_scene(load_middlebury(folder), (24, 32))
    assert direct.meta == later.meta
    for a, b in zip(direct.views + direct.right, later.views + later.right):
        np.testing.assert_array_equal(a.depth, b.depth)
        np.testing.assert_array_equal(a.rgb, b.rgb)
        np.testing.assert_array_equal(a.camera.K, b.camera.K)


def test_kitti_disparity_and_loader(tmp_path):
    raw = np.array([[0, 2688], [65535, 256]], dtype=np.uint16)
    cv2.imwrite(str(tmp_path / "d.png"), raw)
    d = read_kitti_disparity(tmp_path / "d.png")
    assert np.isnan(d[0, 0]) and d[0, 1] == 10.5 and d[1, 1] == 1.0 and d[1, 0] == pytest.approx(255.996, abs=1e-3)
    cv2.imwrite(str(tmp_path / "u8.png"), raw.astype(np.uint8))
    with pytest.raises(ValueError, match="16-bit"):
        read_kitti_disparity(tmp_path / "u8.png")
    base = tmp_path / "training"
    for sub in ("image_2", "image_3", "disp_occ_0", "calib_cam_to_cam"):
        (base / sub).mkdir(parents=True)
    image = np.full((16, 24, 3), 128, np.uint8)
    cv2.imwrite(str(base / "image_2" / "000000_10.png"), image)
    cv2.imwrite(str(base / "image_3" / "000000_10.png"), image)
    disp = np.zeros((16, 24), np.uint16)
    disp[4, 5] = 40 * 256
    cv2.imwrite(str(base / "disp_occ_0" / "000000_10.png"), disp)
    (base / "calib_cam_to_cam" / "000000.txt").write_text(
        "P_rect_02: 700 0 12 44.8 0 700 8 0.2 0 0 1 0.003\nP_rect_03: 700 0 12 -339.2 0 700 8 2.2 0 0 1 0.003\n")
    K, baseline = read_kitti_calib(base / "calib_cam_to_cam" / "000000.txt")
    assert baseline == pytest.approx(384.0 / 700) and K[0, 0] == 700
    scene = load_kitti(tmp_path, 0)
    assert scene[0].depth[4, 5] == pytest.approx(700 * baseline / 40) and np.isfinite(scene[0].depth).sum() == 1
    assert scene.meta["baseline"] == pytest.approx(baseline)


CAM = """extrinsic
0.970263 0.00747983 0.241939 -0.191742
-0.0147429 0.999493 0.0282234 0.284341
-0.241605 -0.030951 0.969881 0.65308
0.0 0.0 0.0 1.0

intrinsic
1169.62 0.0 646.295
0.0 1167.11 489.927
0.0 0.0 1.0

0.44 0.0055 192 1.49
"""


def test_mvsnet_cam_and_tnt_loader(tmp_path):
    (tmp_path / "cams").mkdir()
    (tmp_path / "images").mkdir()
    small = CAM.replace("1169.62 0.0 646.295\n0.0 1167.11 489.927", "27.4 0.0 15.1\n0.0 24.3 10.2")  # K of 30×20
    for i in range(2):
        (tmp_path / "cams" / f"{i:08d}_cam.txt").write_text(small)
        cv2.imwrite(str(tmp_path / "images" / f"{i:08d}.jpg"), np.full((20, 30, 3), 90, np.uint8))
    (tmp_path / "big_cam.txt").write_text(CAM)
    camera, info = read_mvsnet_cam(tmp_path / "big_cam.txt", 1280, 960)
    assert camera.K[0, 0] == pytest.approx(1169.62) and camera.cam_from_world[1, 3] == pytest.approx(0.284341)
    R = camera.cam_from_world[:3, :3]
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)  # printed digits re-orthonormalised
    assert info == {"depth_min": 0.44, "depth_interval": 0.0055, "depth_num": 192.0, "depth_max": 1.49}
    scene = load_tnt(tmp_path, indices=[0, 1])
    assert len(scene) == 2 and np.isnan(scene[0].depth).all() and scene.meta == {"d_min": 0.44, "d_max": 1.49}
    # a depth map at 3/5 of the image size is upsampled by pixel centres: image column u takes
    # depth column floor((u + 0.5)·3/5), i.e. 0 0 1 2 2 | 3 3 4 5 5 ... (plain nearest gives 0 0 1 1 2)
    (tmp_path / "depth").mkdir()
    for i in range(2):
        write_pfm(tmp_path / "depth" / f"{i:08d}.pfm", np.tile(np.arange(1, 19, dtype=np.float32), (12, 1)))
    scene = load_tnt(tmp_path, indices=[0], depth_dir=tmp_path / "depth")
    expected = 1 + np.concatenate([[0, 0, 1, 2, 2]] * 6) + np.repeat(np.arange(6) * 3, 5)
    np.testing.assert_array_equal(scene[0].depth[7], expected)
    with pytest.raises(ValueError, match=r"big_cam\.txt.*principal point \(646.295"):
        read_mvsnet_cam(tmp_path / "big_cam.txt", 30, 20)  # a 1280×960 camera for 30×20 images
    (tmp_path / "cams" / "00000000_cam.txt").write_text(CAM.replace("intrinsic", "intrinsics_missing"))
    with pytest.raises(ValueError, match="MVSNet"):
        read_mvsnet_cam(tmp_path / "cams" / "00000000_cam.txt", 10, 10)


def test_nyu_depth_in_millimetres(tmp_path):
    depth_mm = np.zeros((480, 640), np.uint16)
    depth_mm[100:200, 100:300] = 2500
    cv2.imwrite(str(tmp_path / "depth.png"), depth_mm)
    np.save(tmp_path / "depth.npy", depth_mm)
    cv2.imwrite(str(tmp_path / "rgb.png"), np.zeros((480, 640, 3), np.uint8))
    for file in ("depth.png", "depth.npy"):
        depth = read_depth_image(tmp_path / file)
        assert depth[150, 150] == pytest.approx(2.5) and np.isnan(depth[0, 0])
    scene = load_nyu(tmp_path / "rgb.png", depth_path=tmp_path / "depth.png")
    np.testing.assert_allclose(scene[0].camera.K, NYU_K)
    assert scene.meta["d_max"] == pytest.approx(2.5) and scene[0].mask.sum() == 100 * 200
    with pytest.raises(ValueError, match="depth_path"):
        load_nyu(tmp_path / "rgb.png")


def test_nyu_labelled_mat(tmp_path):
    """The labelled .mat is MATLAB v7.3 (HDF5): MATLAB's H×W×3×N is stored N×3×W×H (axes reversed)."""
    import h5py  # pinned in environment.txt
    H, W = 4, 6
    rgb = np.arange(2 * H * W * 3, dtype=np.uint8).reshape(2, H, W, 3)
    raw = np.full((2, H, W), 1.5, np.float32)
    raw[1, 0, :2] = 0.0  # Kinect holes are stored as 0
    filled = np.full((2, H, W), 2.0, np.float32)
    with h5py.File(tmp_path / "nyu.mat", "w") as f:
        f["images"] = rgb.transpose(0, 3, 2, 1)
        f["rawDepths"] = raw.transpose(0, 2, 1)
        f["depths"] = filled.transpose(0, 2, 1)
    K = np.array([[5.0, 0, 2.5], [0, 5.0, 1.5], [0, 0, 1]])
    scene = load_nyu(tmp_path / "nyu.mat", index=1, K=K)
    np.testing.assert_allclose(scene[0].rgb, rgb[1] / 255.0, atol=1e-7)
    assert np.isnan(scene[0].depth[0, :2]).all() and scene[0].depth[3, 5] == 1.5 and scene[0].mask.sum() == H * W - 2
    assert scene.name == "nyu0001-raw"
    assert np.all(load_nyu(tmp_path / "nyu.mat", index=1, raw=False, K=K)[0].depth == 2.0)
    with pytest.raises(ValueError, match="index"):
        load_nyu(tmp_path / "nyu.mat", index=2, K=K)
    with pytest.raises(ValueError, match="K must be given"):
        load_nyu(tmp_path / "nyu.mat")
