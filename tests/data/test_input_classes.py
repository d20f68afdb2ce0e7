"""The input rules every reader and command shares, one function each, tested where they apply.

* one colour reader: pixels as stored (EXIF orientation not applied), and colour/depth of different
  sizes refused with the EXIF rotation named when it is the reason (``fileio.check_same_size``);
* one depth reader (``fileio.read_depth``): 8-bit pictures refused, "no reading" sentinels warned;
* one depth-writer rule (``file_writers.depth_units``, ``file_writers.float_depth``): no depth (NaN, inf, ≤ 0, −1)
  is stored as the format's hole, never wrapped around 16 bits;
* a camera checked against its image (``camera.check_intrinsics``) wherever intrinsics enter;
* nothing left out without a word (``checks.report_skipped``), and ``strict`` / ``--strict`` refuses;
* colour in [0, 1] wherever it is assumed (View, fills, PSNR); masks of the right shape;
* the command line prints one line per refusal, warning or unexpected error, never a traceback.

Every fixture is built here, tiny; nothing fits a net.
"""
from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from ddp_lite.classical.guided_fills import fill_colorization, fill_cross_bilateral, joint_bilateral_fill
from ddp_lite.core.camera import Camera, check_intrinsics
from ddp_lite.core.checks import SkippedWarning
from ddp_lite.core.views import View
from ddp_lite.data import file_writers, fileio
from ddp_lite.data.colmap import read_colmap, read_colmap_cameras, write_colmap
from ddp_lite.data.tum import read_tum, write_tum
from ddp_lite.evaluation import metrics
from ddp_lite.interface.cli import main
from ddp_lite.method.paper.disparity import DisparityTransform
from ddp_lite.world.scenes import make_scene

H, W = 24, 32
K_640x480 = np.array([[525.0, 0.0, 319.5], [0.0, 525.0, 239.5], [0.0, 0.0, 1.0]])  # a 640×480 camera


@pytest.fixture(scope="module")
def scene():
    return make_scene("desk", size=(H, W), n_views=3, seed=0)


def _phone_jpeg(path, rows, columns, orientation):
    """A JPEG stored ``rows × columns`` tagged with EXIF ``orientation`` (6: shown rotated 90°)."""
    from PIL import Image

    image = Image.fromarray(np.random.default_rng(0).integers(0, 255, (rows, columns, 3), dtype=np.uint8))
    exif = Image.Exif()
    exif[0x0112] = orientation
    image.save(path, "JPEG", exif=exif.tobytes())
    return path


def _depth_png(path, rows, columns, value=1500):
    depth = np.full((rows, columns), value, np.uint16)
    depth[2:6, 2:6] = 0  # a hole, so complete has something to fill
    cv2.imwrite(str(path), depth)
    return path


# --------------------------------------------------------------------------- colour: one orientation rule

def test_complete_names_the_exif_rotation_when_colour_and_depth_disagree(tmp_path, capsys):
    """A phone JPEG stored 32 rows × 48 columns, shown rotated (orientation 6), beside a depth saved upright
    (48 × 32): the pixels cannot be registered; refused before any fit, and the message says why."""
    rgb = _phone_jpeg(tmp_path / "phone.jpg", 32, 48, orientation=6)
    depth = _depth_png(tmp_path / "depth.png", 48, 32)
    code = main(["complete", "--rgb", str(rgb), "--depth", str(depth), "--depth-scale", "0.001",
                 "--out", str(tmp_path / "filled.npy"), "--profile", "ci"])
    err = capsys.readouterr().err
    assert code == 2 and "--rgb" in err and "EXIF orientation 6" in err and "as stored" in err, err
    assert "Traceback" not in err and not (tmp_path / "filled.npy").exists()


def test_every_reader_reads_colour_as_stored_and_names_a_rotated_pair(tmp_path):
    """The same rule in the TUM reader: an EXIF-rotated colour frame read as stored beside its depth, and a
    pair whose sizes differ only by that rotation refused naming the frame and the rotation."""
    folder = tmp_path / "capture"
    write_tum(make_scene("desk", size=(H, W), n_views=2, seed=0), folder)
    first = sorted((folder / "rgb").iterdir())[0]
    _phone_jpeg(first, W, H, orientation=6)  # stored 32 rows × 24 columns, its depth 24 × 32
    with pytest.raises(ValueError, match=r"folder: rgb/.*EXIF orientation 6"), pytest.warns(UserWarning, match="EXIF"):
        read_tum(folder)


# --------------------------------------------------------------------------- depth: one reader

def test_complete_refuses_an_8_bit_picture_as_depth(tmp_path, capsys):
    """An 8-bit grey PNG (a depth visualisation) is no depth at any --depth-scale: exit 2 before the fit."""
    cv2.imwrite(str(tmp_path / "rgb.png"), np.zeros((H, W, 3), np.uint8))
    vis = np.full((H, W), 150, np.uint8)
    vis[2:6, 2:6] = 0
    cv2.imwrite(str(tmp_path / "vis.png"), vis)
    code = main(["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "vis.png"),
                 "--depth-scale", "0.01", "--out", str(tmp_path / "filled.npy"), "--profile", "ci"])
    err = capsys.readouterr().err
    assert code == 2 and "--depth" in err and "8-bit" in err and "fitting" not in capsys.readouterr().out, err


@pytest.mark.parametrize("suffix", [".png", ".npy"])
def test_the_depth_reader_refuses_8_bit_in_every_format(tmp_path, suffix):
    path = tmp_path / f"d{suffix}"
    picture = np.full((H, W), 200, np.uint8)
    cv2.imwrite(str(path), picture) if suffix == ".png" else np.save(path, picture)
    for read in (lambda: fileio.read_depth_image(path), lambda: fileio.read_depth(path, 0.001, "--depth")):
        with pytest.raises(ValueError, match="8-bit"):
            read()


def test_16_bit_depth_sentinel_is_warned_with_the_depth_it_becomes(tmp_path):
    """65535 (a camera's "no reading") in a millimetre PNG reads as 65.535 m: said, naming the file."""
    raw = np.full((H, W), 2000, np.uint16)
    raw[:3, :] = 65535
    cv2.imwrite(str(tmp_path / "d.png"), raw)
    with pytest.warns(UserWarning, match=r"d\.png: 96 pixel\(s\) hold 65535.*65\.53 m"):
        depth = fileio.read_depth(tmp_path / "d.png", 0.001)
    assert depth[0, 0] == pytest.approx(65.535) and depth[5, 5] == pytest.approx(2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an ordinary depth map: no warning
        raw[:3, :] = 3000
        cv2.imwrite(str(tmp_path / "ok.png"), raw)
        fileio.read_depth(tmp_path / "ok.png", 0.001)


def test_tum_depth_read_at_a_wrong_scale_is_refused_with_the_scale_that_fits(tmp_path, scene):
    """TUM stores 5000 units per metre; read at 1 per metre a 1 m depth becomes 5 km: refused, the right
    scale named (the same plausibility rule as ``complete --depth-scale``)."""
    folder = write_tum(scene, tmp_path / "capture")
    with pytest.raises(ValueError, match=r"--depth-scale\) 1: folder: depth/.*would range.*1/depth_factor \(CLI: --depth-scale\) 0\.0002"):
        read_tum(folder, depth_factor=1.0)


# --------------------------------------------------------------------------- depth writers: no wrapping

def test_write_tum_stores_minus_one_and_inf_as_holes_not_as_wrapped_depth(tmp_path, scene):
    """−1 ("unknown") at 5000 units per metre wrapped to 65536 − 5000 = 60536, i.e. 12.107 m; it must be 0."""
    depths = [v.depth.copy() for v in scene]
    depths[0][:2, :] = -1.0
    depths[0][2, :] = np.inf
    given = [d.copy() for d in depths]
    write_tum(scene, tmp_path / "tum", depths=depths)
    stored = cv2.imread(str(sorted((tmp_path / "tum" / "depth").iterdir())[0]), cv2.IMREAD_UNCHANGED)
    assert (stored[:3] == 0).all() and (stored[3:] > 0).all()
    back = read_tum(tmp_path / "tum")
    assert np.isnan(back[0].depth[:3]).all()
    np.testing.assert_allclose(back[0].depth[3:], np.round(scene[0].depth[3:] * 5000.0) / 5000.0, atol=1e-6)
    for a, b in zip(depths, given):
        np.testing.assert_array_equal(a, b)  # the caller's maps untouched


def test_every_depth_writer_maps_no_depth_to_its_hole_value(tmp_path):
    depth = np.full((4, 5), 2.0, np.float32)
    depth[0, :4] = [-1.0, np.inf, -np.inf, 0.0]
    units, lost = file_writers.depth_units(depth, 1000.0)
    assert units[0, :4].tolist() == [0, 0, 0, 0] and units[1, 0] == 2000 and lost == 0
    colmap = np.frombuffer(file_writers.colmap_depth_bytes(depth)[len(b"5&4&1&"):], "<f4").reshape(5, 4).T
    assert colmap[0, :4].tolist() == [0.0, 0.0, 0.0, 0.0] and colmap[1, 0] == 2.0
    assert np.isnan(file_writers.float_depth(depth)[0, :4]).all()
    # a valid depth that would be stored as the 65535 sentinel (13.107 m at 5000/m) does not fit
    assert file_writers.depth_units(np.full((2, 2), 13.107), 5000.0)[1] == 4


# --------------------------------------------------------------------------- a camera checked against its image

def test_a_camera_of_another_image_size_is_refused_wherever_intrinsics_enter(tmp_path, scene):
    with pytest.raises(ValueError, match=r"K: the principal point \(319\.5, 239\.5\) px lies outside the 24×32 \(H×W\)"):
        Camera(K_640x480, np.eye(4), W, H)
    assert check_intrinsics(K_640x480, 640, 480).shape == (3, 3)
    with pytest.raises(ValueError, match="fx=5e\\+06 px is implausible"):
        check_intrinsics(np.array([[5e6, 0, 15.5], [0, 5e6, 11.5], [0, 0, 1.0]]), W, H, "--intrinsics")
    # TUM: a 640×480 camera named for 32×24 frames, refused before its distortion blanks them
    folder = write_tum(scene, tmp_path / "rgbd_dataset_freiburg1_desk")
    (folder / "intrinsics.txt").unlink()
    with pytest.raises(ValueError, match=r"intrinsics \('fr1'.*principal point \(318\.643, 255\.314\)"):
        read_tum(folder)
    # COLMAP: a cameras.txt line whose K does not fit its own WIDTH HEIGHT, with the file and line
    write_colmap(scene, tmp_path / "ws")
    cameras = tmp_path / "ws" / "sparse" / "cameras.txt"
    cameras.write_text(cameras.read_text().replace(" 32 24 ", " 320 240 ", 1).replace(" 32 24 ", " 3 2 "))
    with pytest.raises(ValueError, match=r"cameras\.txt, line \d+: camera \d+: K: the principal point"):
        read_colmap_cameras(cameras)


def test_sequence_refuses_intrinsics_of_another_image_size(tmp_path, scene, capsys):
    folder = write_tum(scene, tmp_path / "capture")
    code = main(["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "out"), "--dry-run",
                 "--intrinsics", "525,525,319.5,239.5"])
    err = capsys.readouterr().err
    assert code == 2 and "intrinsics" in err and "principal point (319.5, 239.5)" in err, err


# --------------------------------------------------------------------------- nothing left out without a word

def _uneven_tum(tmp_path, scene):
    folder = write_tum(scene, tmp_path / "capture")
    lines = (folder / "depth.txt").read_text().splitlines()
    (folder / "depth.txt").write_text("\n".join(lines[:-1]) + "\n")  # 3 colour frames, 2 depth frames
    return folder, sorted(p.name for p in (folder / "rgb").iterdir())[-1]


def test_tum_names_the_frame_it_leaves_out_and_strict_refuses(tmp_path, scene):
    folder, last = _uneven_tum(tmp_path, scene)
    with pytest.warns(SkippedWarning, match=rf"1 of 3 colour frame\(s\) .* left out: rgb/{last}"):
        assert len(read_tum(folder)) == 2
    with pytest.raises(ValueError, match=rf"1 of 3 colour frame\(s\).*rgb/{last}.*strict"):
        read_tum(folder, strict=True)


def test_tum_names_depth_frames_no_colour_frame_uses(tmp_path, scene):
    folder = write_tum(scene, tmp_path / "capture")
    lines = (folder / "rgb.txt").read_text().splitlines()
    (folder / "rgb.txt").write_text("\n".join(lines[:-1]) + "\n")  # 2 colour frames, 3 depth frames
    with pytest.warns(SkippedWarning, match=r"1 of 3 depth frame\(s\) have no colour frame.*depth/"):
        assert len(read_tum(folder)) == 2


def test_sequence_prints_what_it_left_out_and_strict_makes_it_an_error(tmp_path, scene, capsys):
    folder, last = _uneven_tum(tmp_path, scene)
    base = ["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "out"), "--views", "9"]
    assert main(base) == 2  # read (and warned), then refused for --views: nothing measured or fitted
    err = capsys.readouterr().err
    assert f"ddp-lite sequence: warning: {folder}: 1 of 3 colour frame(s)" in err and last in err, err
    assert main(base + ["--strict"]) == 2
    err = capsys.readouterr().err
    assert last in err and "strict" in err and "Traceback" not in err, err


def test_colmap_names_images_it_has_no_pose_for(tmp_path, scene):
    write_colmap(scene, tmp_path / "ws")
    cv2.imwrite(str(tmp_path / "ws" / "images" / "unregistered.png"), np.zeros((H, W, 3), np.uint8))
    with pytest.warns(SkippedWarning, match=r"1 of 4 image\(s\) are not listed in .*images\.txt.*unregistered\.png"):
        assert len(read_colmap(tmp_path / "ws")) == 3
    with pytest.raises(ValueError, match=r"unregistered\.png"):
        read_colmap(tmp_path / "ws", strict=True)


def test_sequence_views_refuses_a_negative_index(tmp_path, scene, capsys):
    folder = write_tum(scene, tmp_path / "capture")
    assert main(["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "out"), "--dry-run",
                 "--views", "-1"]) == 2
    assert "--views: -1 is out of range" in capsys.readouterr().err


# --------------------------------------------------------------------------- colour in [0, 1] where assumed

def test_colour_in_0_255_is_refused_where_0_1_is_assumed(scene):
    view = scene[0]
    bright = view.rgb * 255.0  # float 0–255: an image scaled twice, or never
    with pytest.raises(ValueError, match=r"rgb must lie in \[0, 1\]"):
        View(bright, view.depth, view.camera)
    as_bytes = View((view.rgb * 255).round().astype(np.uint8), view.depth, view.camera)  # uint8 is scaled
    assert as_bytes.rgb.dtype == np.float32 and as_bytes.rgb.max() <= 1.0
    holed = view.depth.copy()
    holed[5:10, 5:10] = np.nan
    for fill in (fill_colorization, fill_cross_bilateral):
        with pytest.raises(ValueError, match=r"rgb must lie in \[0, 1\]"):
            fill(holed, bright)
    with pytest.raises(ValueError, match=r"guide must lie in \[0, 1\]"):
        joint_bilateral_fill(holed, bright[..., 0], 3.0, 0.1)
    noisy = np.clip(view.rgb + 0.01, 0, 1)
    with pytest.raises(ValueError, match=r"target spans .*data_range=1.*255"):
        metrics.psnr(noisy * 255.0, view.rgb * 255.0)
    assert metrics.psnr(noisy * 255.0, view.rgb * 255.0, data_range=255.0) == pytest.approx(
        metrics.psnr(noisy, view.rgb), rel=1e-6)


def test_masks_of_the_wrong_shape_are_refused_naming_them(scene):
    depth = scene[0].depth
    transform = DisparityTransform(float(np.nanmin(depth)), float(np.nanmax(depth)))
    with pytest.raises(ValueError, match=r"mask must have shape \(24, 32\)"):
        metrics.disparity_rmse(depth, depth, np.ones((H, W + 1), bool), transform)
    with pytest.raises(ValueError, match=r"region must have shape \(24, 32\)"):
        metrics.texture_leakage(depth, depth, transform, region=np.ones((H + 1, W), bool))
    with pytest.raises(ValueError, match="mask selects no pixel"):
        metrics.rmse(depth, depth, np.zeros((H, W), bool))


# --------------------------------------------------------------------------- no traceback reaches a user

def test_an_unexpected_error_is_one_line_and_exit_1(monkeypatch, capsys):
    """Whatever a handler raises (here an OpenCV error injected into the scene listing) is one line on stderr."""
    import ddp_lite.interface.cli_demo as cli_demo

    def broken(args):
        raise cv2.error("OpenCV(4.x) resize.cpp: error: (-215) !ssize.empty()")
    monkeypatch.setattr(cli_demo, "scenes_command", broken)
    assert main(["scenes"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("ddp-lite scenes: failed: error: OpenCV") and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
