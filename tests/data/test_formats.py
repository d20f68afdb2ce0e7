"""ddp_lite.data.formats: TUM RGB-D, COLMAP and saved-scene readers, round trips against the scene they were
written from, and refusals of malformed files that name the file and the line."""
import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ddp_lite.core.camera import Camera
from ddp_lite.data.tum import associate, read_tum, read_tum_list, read_tum_trajectory, write_tum
from ddp_lite.data.formats import load_sequence, read_scene
from ddp_lite.data.colmap import read_colmap, read_colmap_cameras, read_colmap_images, write_colmap
from ddp_lite.data.fileio import read_colmap_depth
from ddp_lite.data.file_writers import write_colmap_depth
from ddp_lite.classical.holes import random_holes
from ddp_lite.world.scenes import make_scene


@pytest.fixture(scope="module")
def scene():
    return make_scene("desk", size=(24, 32), n_views=3, seed=0)


@pytest.fixture(scope="module")
def holed(scene):
    return [random_holes(v.depth, fraction=0.2, seed=i)[0] for i, v in enumerate(scene)]


def _same_cameras(a, b):
    for va, vb in zip(a, b):
        np.testing.assert_allclose(vb.camera.K, va.camera.K, atol=1e-9)
        np.testing.assert_allclose(vb.camera.cam_from_world, va.camera.cam_from_world, atol=1e-9)


def test_tum_round_trip(tmp_path, scene, holed):
    before = [d.copy() for d in holed]
    write_tum(scene, tmp_path / "tum", depths=holed)
    back = read_tum(tmp_path / "tum")  # K from the intrinsics.txt the writer adds
    assert len(back) == len(scene) and back.size == scene.size
    _same_cameras(scene, back)
    for depth, view in zip(holed, back):
        # the independent reference: TUM stores round(metres × 5000) as uint16
        quantised = (np.round(depth.astype(np.float64) * 5000.0) / 5000.0).astype(np.float32)
        np.testing.assert_array_equal(np.isnan(view.depth), np.isnan(depth))
        np.testing.assert_allclose(view.depth, quantised, atol=1e-5)
    for a, b in zip(scene, back):
        assert np.abs(a.rgb - b.rgb).max() <= 0.5 / 255 + 1e-6  # 8-bit PNG
    for d, b in zip(holed, before):
        np.testing.assert_array_equal(d, b)  # the caller's arrays are untouched


def test_tum_user_intrinsics_and_every(tmp_path, scene):
    write_tum(scene, tmp_path / "tum")
    (tmp_path / "tum" / "intrinsics.txt").unlink()
    with pytest.raises(ValueError, match="intrinsics.txt"):
        read_tum(tmp_path / "tum")
    back = read_tum(tmp_path / "tum", intrinsics=scene[0].camera.K, every=2)
    assert [v.name for v in back] == [f"{1e9 + k / 30.0:.6f}" for k in (0, 2)]
    _same_cameras([scene[0], scene[2]], back)


def test_tum_association_is_nearest_first_and_one_to_one():
    # 0.004 ↔ 0.0 is the closest pair; 0.03 then takes 0.033, and 0.066 ↔ 0.07
    assert associate([0.0, 0.033, 0.066], [0.004, 0.03, 0.07]) == [(0, 0), (1, 1), (2, 2)]
    assert associate([0.0, 0.001], [0.0005]) == [(0, 0)]  # tie: the lower index; one depth frame, used once
    assert associate([0.0], [0.5]) == []


def test_tum_pose_is_interpolated_between_ground_truth_samples(tmp_path, scene):
    write_tum(scene, tmp_path / "tum", fps=30.0)
    stamps, poses = read_tum_trajectory(tmp_path / "tum" / "groundtruth.txt")
    # keep only views 0 and 2 in the ground truth, so view 1's pose must be interpolated halfway
    lines = (tmp_path / "tum" / "groundtruth.txt").read_text().splitlines()
    (tmp_path / "tum" / "groundtruth.txt").write_text("\n".join([lines[0], lines[1], lines[3]]) + "\n")
    back = read_tum(tmp_path / "tum", max_difference=0.04)
    a, b = scene[0].camera.world_from_cam, scene[2].camera.world_from_cam
    middle = back[1].camera.world_from_cam
    w = (stamps[1] - stamps[0]) / (stamps[2] - stamps[0])  # ≈ 0.5: the stamps are written to the microsecond
    np.testing.assert_allclose(middle[:3, 3], (1 - w) * a[:3, 3] + w * b[:3, 3], atol=1e-9)
    relative = Rotation.from_matrix(a[:3, :3]).inv() * Rotation.from_matrix(middle[:3, :3])
    full = Rotation.from_matrix(a[:3, :3]).inv() * Rotation.from_matrix(b[:3, :3])
    assert abs(relative.magnitude() - w * full.magnitude()) < 1e-9  # slerp: the same axis, w of the angle
    np.testing.assert_allclose(relative.as_rotvec() / relative.magnitude(), full.as_rotvec() / full.magnitude(),
                               atol=1e-6)


def test_tum_fr1_images_are_undistorted(tmp_path, scene):
    from ddp_lite.core.views import Scene, View
    from ddp_lite.data.tum import TUM_INTRINSICS
    folder = tmp_path / "rgbd_dataset_freiburg1_xyz"
    (fx, fy, cx, cy), _ = TUM_INTRINSICS["fr1"]  # fr1's K belongs to 640×480 images: write those
    K = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    rgb = cv2.resize(np.random.default_rng(0).random((60, 80, 3)).astype(np.float32), (640, 480))
    views = [View(rgb, np.full((480, 640), 2.0, np.float32), Camera(K, np.eye(4), 640, 480), str(i)) for i in range(2)]
    write_tum(Scene("fr1", views), folder)
    (folder / "intrinsics.txt").unlink()  # so the folder name picks fr1 and its distortion
    undistorted = read_tum(folder)
    raw = read_tum(folder, undistort=False)
    assert undistorted[0].camera.K[0, 0] == pytest.approx(517.306408)
    assert not np.array_equal(undistorted[0].rgb, raw[0].rgb)
    # OpenCV as the reference: the same remap, done here independently
    K, dist = undistorted[0].camera.K, np.array([0.262383, -0.953104, -0.005358, 0.002628, 1.163314])
    expected = cv2.undistort(raw[0].rgb, K, dist, None, K)
    inner = (slice(4, -4), slice(4, -4))
    np.testing.assert_allclose(undistorted[0].rgb[inner], expected[inner], atol=2e-2)


@pytest.mark.parametrize("depth_format", ["bin", "png", "npy", "pfm"])
def test_colmap_round_trip(tmp_path, scene, holed, depth_format):
    write_colmap(scene, tmp_path / "ws", depths=holed, depth_format=depth_format)
    back = read_colmap(tmp_path / "ws", depth_scale=0.001 if depth_format == "png" else None)
    assert [v.name for v in back] == [f"{v.name}.png" for v in scene]
    _same_cameras(scene, back)
    for depth, view in zip(holed, back):
        reference = (np.round(depth.astype(np.float64) * 1000.0) / 1000.0).astype(np.float32) \
            if depth_format == "png" else depth
        np.testing.assert_array_equal(np.isnan(view.depth), np.isnan(depth))
        np.testing.assert_allclose(view.depth, reference, atol=1e-5)


def test_colmap_principal_point_is_shifted_half_a_pixel(tmp_path, scene):
    write_colmap(scene, tmp_path / "ws", model="SIMPLE_PINHOLE")
    line = [l for l in (tmp_path / "ws" / "sparse" / "cameras.txt").read_text().splitlines() if not l.startswith("#")][0]
    f, cx, cy = (float(v) for v in line.split()[4:])
    # COLMAP: the top-left pixel's centre is (0.5, 0.5); the kit: (0, 0). A centred 32×24 camera has cx = 16.
    assert (cx, cy) == (16.0, 12.0) and scene[0].camera.K[0, 2] == 15.5
    assert read_colmap_cameras(tmp_path / "ws" / "sparse" / "cameras.txt")[1].K[0, 2] == 15.5


def test_colmap_dense_bin_layout_is_column_major(tmp_path):
    depth = np.arange(6, dtype=np.float32).reshape(2, 3) + 1  # H = 2, W = 3
    write_colmap_depth(tmp_path / "d.bin", depth)
    data = (tmp_path / "d.bin").read_bytes()
    assert data.startswith(b"3&2&1&")
    # column by column: (0,0), (1,0), (0,1), (1,1), ...: COLMAP's read_array (reshape (W, H), order F)
    np.testing.assert_array_equal(np.frombuffer(data[6:], "<f4"), [1, 4, 2, 5, 3, 6])
    np.testing.assert_array_equal(read_colmap_depth(tmp_path / "d.bin"), depth)


def test_scene_folder_round_trip(tmp_path, scene):
    scene.save(tmp_path / "s" / "desk.npz")
    for path in (tmp_path / "s", tmp_path / "s" / "desk.npz"):
        back = load_sequence(path, "scene")
        _same_cameras(scene, back)
        for a, b in zip(scene, back):
            np.testing.assert_array_equal(a.depth, b.depth)


# ------------------------------------------------------------------------------------------------
# refusals: the file and the line
# ------------------------------------------------------------------------------------------------

REFUSALS = [  # (file, reader, its text, the line the error must name, what it must say)
    ("rgb.txt", read_tum_list, "# t f\n1.0 rgb/1.png\n2.0\n", 3, "expected 'timestamp filename'"),
    ("rgb.txt", read_tum_list, "1.0 rgb/1.png\nabc rgb/2.png\n", 2, "timestamp must be numbers"),
    ("groundtruth.txt", read_tum_trajectory, "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n", 2, "8 numbers"),
    ("groundtruth.txt", read_tum_trajectory, "1.0 0 0 0 0 0 0 0\n", 1, "unit length"),
    ("groundtruth.txt", read_tum_trajectory, "# header\n1.0 0 0 nan 0 0 0 1\n", 2, "finite"),
    ("cameras.txt", read_colmap_cameras, "1 PINHOLE 32 24 30 30 16\n", 1,
     r"PINHOLE needs 4 parameters \(fx fy cx cy\), got 3"),
    ("cameras.txt", read_colmap_cameras, "# c\n1 FISHEYE 32 24 30 16 12 0.1\n", 2,
     "camera model 'FISHEYE' is not supported"),
    ("cameras.txt", read_colmap_cameras, "1 PINHOLE 32 x 30 30 16 12\n", 1, "positive integers"),
    ("cameras.txt", read_colmap_cameras, "1 PINHOLE 32 24 30 30 16 12\n1 PINHOLE 32 24 30 30 16 12\n", 2,
     "appears twice"),
    ("images.txt", read_colmap_images, "1 1 0 0 0 0 0 0 1 a.png\n\n2 1 0 0 0 0 0 1 a.png\n", 3,
     "expected 'IMAGE_ID QW"),
    ("images.txt", read_colmap_images, "1 2 0 0 0 0 0 0 1 a.png\n\n", 1, "unit length"),
    ("images.txt", read_colmap_images, "1 1 0 0 0 0 0 0 x a.png\n\n", 1, "must be integers"),
]


@pytest.mark.parametrize("name, reader, text, line, match", REFUSALS)
def test_malformed_files_are_refused_naming_file_and_line(tmp_path, name, reader, text, line, match):
    (tmp_path / name).write_text(text)
    with pytest.raises(ValueError, match=rf"{name}, line {line}: .*{match}"):
        reader(tmp_path / name)


def test_colmap_refuses_distortion_unless_asked_and_unknown_cameras(tmp_path, scene):
    write_colmap(scene, tmp_path / "ws")
    cameras = tmp_path / "ws" / "sparse" / "cameras.txt"
    K = scene[0].camera.K
    text = cameras.read_text().replace("PINHOLE", "OPENCV", 1)
    first = [l for l in text.splitlines() if l.startswith("1 ")][0]
    cameras.write_text(text.replace(first, first + " 0.05 0 0 0"))
    with pytest.raises(ValueError, match=r"cameras.txt: camera 1 is OPENCV with lens distortion"):
        read_colmap(tmp_path / "ws")
    undistorted = read_colmap(tmp_path / "ws", undistort=True)
    np.testing.assert_allclose(undistorted[0].camera.K, K, atol=1e-9)
    images = tmp_path / "ws" / "sparse" / "images.txt"
    images.write_text(images.read_text().replace(" 1 desk0.png", " 9 desk0.png"))
    with pytest.raises(ValueError, match=r"images.txt, line 4: CAMERA_ID 9 is not in"):
        read_colmap(tmp_path / "ws", undistort=True)


def test_colmap_refuses_truncated_depth_and_png_without_scale(tmp_path, scene):
    (tmp_path / "bad.bin").write_bytes(b"3&2&1&" + b"\0" * 20)
    with pytest.raises(ValueError, match=r"bad.bin: holds 20 data bytes, expected 24"):
        read_colmap_depth(tmp_path / "bad.bin")
    (tmp_path / "bad2.bin").write_bytes(b"P6\n3 2\n")
    with pytest.raises(ValueError, match=r"bad2.bin, line 1: not a COLMAP dense map"):
        read_colmap_depth(tmp_path / "bad2.bin")
    write_colmap(scene, tmp_path / "ws", depth_format="png")
    with pytest.raises(ValueError, match=r"desk0.png stores integers; give depth_scale"):
        read_colmap(tmp_path / "ws")


def test_tum_writer_refuses_depth_a_16_bit_png_cannot_hold(tmp_path, scene):
    far = [np.full(scene.size, 20.0, np.float32)] * len(scene)
    with pytest.raises(ValueError, match=r"does not fit a 16-bit PNG"):
        write_tum(scene, tmp_path / "tum", depths=far)


def test_scene_reader_refusals(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="exactly one saved scene"):
        read_scene(tmp_path / "empty")
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(ValueError, match="other.npz is not a scene written by Scene.save"):
        read_scene(tmp_path / "other.npz")
    with pytest.raises(ValueError, match="format must be one of"):
        load_sequence(tmp_path, "kitti")
