"""Implausible data is not read as truth: each reader checks what it can (the file's real format, its units
against the other inputs, the range a scene allows) and refuses or warns, naming the file or argument, before
any fit."""
from __future__ import annotations

import os
import shutil
import warnings

import cv2
import numpy as np
import pytest

os.environ.setdefault("DDP_PROFILE", "ci")

from ddp_lite.core.checks import check_depth  # noqa: E402
from ddp_lite.data.fileio import read_depth, read_pfm  # noqa: E402
from ddp_lite.data.middlebury import load_middlebury, make_middlebury_fixture  # noqa: E402
from ddp_lite.data.middlebury_rail import ground_truth_occlusion, load_rail_scene  # noqa: E402
from ddp_lite.data.samples import read_depthcomp_holes, sample_scene  # noqa: E402


def plastic(tmp_path):
    folder = tmp_path / "Plastic"
    shutil.copytree(sample_scene("Plastic"), folder)
    return folder


def as_jpeg(path, name=None):
    """Re-encode the image at ``path`` as a JPEG, written under ``name`` (default: its own name, e.g. disp1.png)."""
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95])
    assert ok
    (path.parent / (name or path.name)).write_bytes(data.tobytes())


# ------------------------------------------------------------------ the file's real format, not its name

def test_a_ground_truth_png_that_is_really_a_jpeg_is_refused(tmp_path):
    folder = plastic(tmp_path)
    as_jpeg(folder / "disp1.png")
    assert cv2.imread(str(folder / "disp1.png"), cv2.IMREAD_UNCHANGED) is not None  # OpenCV reads it regardless
    with pytest.raises(ValueError, match=r"folder: .*disp1.png is a JPEG.*named .png.*lossy"):
        load_rail_scene(folder)
    with pytest.raises(ValueError, match="disp1.png is a JPEG"):
        ground_truth_occlusion(folder)


def test_every_depth_and_truth_reader_refuses_a_jpeg_whatever_its_name(tmp_path):
    grey = (np.arange(48 * 64).reshape(48, 64) % 200 + 20).astype(np.uint8)
    cv2.imwrite(str(tmp_path / "holes.png"), grey)
    as_jpeg(tmp_path / "holes.png")
    with pytest.raises(ValueError, match="holes.png is a JPEG"):
        read_depthcomp_holes(tmp_path / "holes.png")
    cv2.imwrite(str(tmp_path / "depth.jpg"), grey)
    with pytest.raises(ValueError, match="depth.jpg is a JPEG"):
        read_depth(tmp_path / "depth.jpg", 0.001)


def test_a_colour_png_that_is_really_a_jpeg_is_read_with_a_warning(tmp_path):
    from ddp_lite.data.fileio import read_rgb
    folder = plastic(tmp_path)
    as_jpeg(folder / "view1.png")
    with pytest.warns(UserWarning, match="view1.png is a JPEG file, not the PNG its name says"):
        rgb = read_rgb(folder / "view1.png")
    assert rgb.shape[2] == 3


# ------------------------------------------------------------------ numbers a file must hold

@pytest.mark.parametrize("text", ["200 17\n", "200\n17\n", "", "two hundred"])
def test_a_dmin_that_is_not_one_number_is_refused(tmp_path, text):
    folder = plastic(tmp_path)
    (folder / "dmin.txt").write_text(text)
    with pytest.raises(ValueError, match="dmin.txt must hold one number"):
        load_rail_scene(folder)


def test_a_calib_baseline_in_metres_is_refused(tmp_path):
    folder = make_middlebury_fixture(tmp_path / "scene")
    reference = load_middlebury(folder)
    lines = (folder / "calib.txt").read_text().splitlines()
    millimetres = float(next(line for line in lines if line.startswith("baseline=")).split("=")[1])
    assert 50 < millimetres < 1000  # the fixture's rig, as Middlebury writes it
    (folder / "calib.txt").write_text("\n".join(f"baseline={millimetres / 1000}" if line.startswith("baseline=")
                                                else line for line in lines) + "\n")
    with pytest.raises(ValueError, match=r"baseline is .*metres.*baseline=" + f"{millimetres:g}"[:4]):
        load_middlebury(folder)
    assert 0.1 < np.nanmedian(reference[0].depth) < 100


def test_a_calib_whose_depths_no_scene_holds_is_refused(tmp_path):
    folder = make_middlebury_fixture(tmp_path / "scene")
    text = (folder / "calib.txt").read_text()
    line = next(line for line in text.splitlines() if line.startswith("baseline="))
    (folder / "calib.txt").write_text(text.replace(line, f"baseline={float(line.split('=')[1]) * 1e6}"))
    with pytest.raises(ValueError, match=r"disp0.pfm gives depths .* which no scene holds.*baseline"):
        load_middlebury(folder)


# ------------------------------------------------------------------ PFM byte order

def test_a_big_endian_pfm_reads_as_its_little_endian_twin(tmp_path):
    values = np.random.default_rng(0).uniform(0.5, 8.0, (5, 7)).astype(np.float32)
    values[1, 2] = np.inf
    (tmp_path / "le.pfm").write_bytes(b"Pf\n7 5\n-1.0\n" + np.flipud(values).astype("<f4").tobytes())
    (tmp_path / "be.pfm").write_bytes(b"Pf\n7 5\n1.0\n" + np.flipud(values).astype(">f4").tobytes())
    np.testing.assert_array_equal(read_pfm(tmp_path / "be.pfm"), values)
    np.testing.assert_array_equal(read_depth(tmp_path / "be.pfm"), read_depth(tmp_path / "le.pfm"))
    folder = make_middlebury_fixture(tmp_path / "scene")
    little = load_middlebury(folder)[0].depth
    disparity = read_pfm(folder / "disp0.pfm")
    H, W = disparity.shape
    (folder / "disp0.pfm").write_bytes(f"Pf\n{W} {H}\n1.0\n".encode() + np.flipud(disparity).astype(">f4").tobytes())
    np.testing.assert_array_equal(load_middlebury(folder)[0].depth, little)


def test_a_pfm_whose_scale_sign_names_the_wrong_byte_order_is_refused(tmp_path):
    values = np.random.default_rng(1).uniform(0.5, 8.0, (5, 7)).astype(np.float32)
    (tmp_path / "wrong.pfm").write_bytes(b"Pf\n7 5\n1.0\n" + np.flipud(values).astype("<f4").tobytes())
    with pytest.raises(ValueError, match="wrong.pfm.*scale 1 says big-endian.*sign is wrong"):
        read_depth(tmp_path / "wrong.pfm")


# ------------------------------------------------------------------ depth values no camera gives

def test_varied_negative_depths_are_refused_and_one_marker_is_warned(tmp_path):
    depth = np.random.default_rng(2).uniform(1.0, 3.0, (20, 30)).astype(np.float32)
    left_negative = depth.copy()
    left_negative[:, :15] *= -1
    np.save(tmp_path / "negative.npy", left_negative)
    with pytest.raises(ValueError, match=r"depth: .*negative.npy holds 300 negative value\(s\) \(50.0% of its pixels"):
        read_depth(tmp_path / "negative.npy", name="depth")
    marked = depth.copy()
    marked[:2] = -1.0
    np.save(tmp_path / "marked.npy", marked)
    with pytest.warns(UserWarning, match=r"60 pixel\(s\) \(10.0%\) hold -1"):
        read = read_depth(tmp_path / "marked.npy")
    assert np.isnan(read[:2]).all() and np.isfinite(read[2:]).all()


def test_cli_refuses_a_depth_with_a_negative_half_naming_it(tmp_path, capsys, monkeypatch):
    from conftest import rgbd_files as _pair
    from ddp_lite.interface import cli_complete
    from ddp_lite.interface.cli import main
    depth, _ = _pair(tmp_path)
    depth[:, :45] *= -1
    np.save(tmp_path / "depth.npy", depth)
    monkeypatch.setattr(cli_complete, "_classical_fills", lambda *a: pytest.fail("the work started"))
    assert main(["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
                 "--out", str(tmp_path / "o.npy"), "--profile", "ci", "--iterations", "5"]) == 2
    assert "--depth" in capsys.readouterr().err


def test_denormal_depths_are_refused(tmp_path):
    depth = np.full((32, 32), 2e-40, np.float32)  # float32 denormals: > 0, and nothing after 1/Z
    depth[10:20, 10:20] = np.nan
    assert np.all(depth[np.isfinite(depth)] > 0)
    with pytest.raises(ValueError, match="depth has valid depths down to 2e-40 m"):
        check_depth(depth)
    from ddp_lite.method.complete import complete_depth
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.runtime.options import RunOptions
    with pytest.raises(ValueError, match="depth has valid depths down to"):
        complete_depth(np.zeros((32, 32, 3), np.float32), depth, variant="d",
                       config=FitConfig(channels=(8, 16), lr=1e-2, iterations=2), options=RunOptions(progress=False))


# ------------------------------------------------------------------ ground truth that cannot be scored against

def _small_fit(depth, gt):
    from ddp_lite.method.complete import complete_depth
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.runtime.options import RunOptions
    return complete_depth(np.zeros(depth.shape + (3,), np.float32), depth, variant="d", gt_depth=gt,
                          config=FitConfig(channels=(8, 16), lr=1e-2, iterations=2, blend_fill=0.0),
                          options=RunOptions(progress=False))


def test_an_all_nan_ground_truth_is_refused_and_one_with_nothing_in_the_holes_scores_nan():
    v, u = np.mgrid[0:32, 0:32]
    gt = (2.0 + 0.02 * u + 0.01 * v).astype(np.float32)
    depth = gt.copy()
    depth[10:20, 10:20] = np.nan
    with pytest.raises(ValueError, match="gt_depth has 0 valid pixels"):
        _small_fit(depth, np.full_like(gt, np.nan))
    outside = np.where(np.isfinite(depth), gt, np.nan)
    with pytest.warns(UserWarning, match="gt_depth has no valid value in the holes"):
        result = _small_fit(depth, outside)
    assert result.history["hole_rmse_m"] and np.isnan(result.history["hole_rmse_m"]).all()  # not 0.0: no score


@pytest.mark.parametrize("factor, unit", [(100.0, "centimetres"), (1 / 0.3048, "feet"), (1000.0, "millimetres")])
def test_ground_truth_in_another_unit_is_refused_naming_it(factor, unit):
    v, u = np.mgrid[0:32, 0:32]
    gt = (2.0 + 0.02 * u + 0.01 * v).astype(np.float32)
    depth = gt.copy()
    depth[10:20, 10:20] = np.nan
    with pytest.raises(ValueError, match=f"gt_depth is .* depth .*looks like {unit}"):
        _small_fit(depth, gt * np.float32(factor))


def test_cli_refuses_a_ground_truth_in_centimetres_before_any_work(tmp_path, capsys, monkeypatch):
    from conftest import rgbd_files as _pair
    from ddp_lite.interface import cli_complete
    from ddp_lite.interface.cli import main
    _, gt = _pair(tmp_path)
    np.save(tmp_path / "gt_cm.npy", gt * 100)
    monkeypatch.setattr(cli_complete, "_classical_fills", lambda *a: pytest.fail("the work started"))
    assert main(["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
                 "--gt", str(tmp_path / "gt_cm.npy"), "--out", str(tmp_path / "o.npy"), "--profile", "ci",
                 "--iterations", "5"]) == 2
    err = capsys.readouterr().err
    assert "--gt is 100 × --depth" in err and "centimetres" in err
    assert not (tmp_path / "o.npy").exists()
