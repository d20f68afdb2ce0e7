"""``ddp-lite complete --scene DIR|NAME``: a Middlebury scene (shipped, installed in the data root, or a folder)
completed from SGBM's depth, blobs or a hole file, scored against its truth, written at its size. ci fits at a
tiny working size."""
import hashlib
import re
import shutil

import cv2
import numpy as np
import pytest

from ddp_lite.data.middlebury import make_middlebury_fixture
from ddp_lite.data.samples import sample_scene
from ddp_lite.interface.cli import main

FAST = ["--profile", "ci", "--iterations", "12"]


def digest(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def test_a_shipped_scene_by_name_is_completed_at_its_size_and_scored_in_its_own_disparity(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("DDP_DATA", str(tmp_path / "empty"))  # nothing installed: the shipped Plastic
    before = digest(sample_scene("Plastic"))
    out = tmp_path / "plastic.npy"
    assert main(["complete", "--scene", "Plastic", "--out", str(out), "--variant", "rgbd", *FAST, "--max-side", "32"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith("data: the shipped quarter-size Plastic")
    assert printed[0].endswith("python -m data_fetch fetch middlebury2006 --only HalfSize/Plastic)")
    assert "plastic-disp-hole.png" in printed[1]  # DepthComp's own holes: the scene has them
    # the truth, read here from the files: intensity = 4 × the quarter-size disparity, Z = 3740·0.16 / (I + dmin)
    intensity = cv2.imread(str(sample_scene("Plastic") / "disp1.png"), cv2.IMREAD_UNCHANGED).astype(np.float64)
    dmin = float((sample_scene("Plastic") / "dmin.txt").read_text().split()[0])
    holes = cv2.imread(str(sample_scene("Plastic") / "plastic-disp-hole.png"), cv2.IMREAD_UNCHANGED) == 0
    known = intensity > 0
    truth = np.where(known, 3740 * 0.16 / (intensity + dmin), np.nan)
    filled = np.load(out)
    kept = known & ~holes
    assert filled.shape == intensity.shape and np.isfinite(filled).all()
    np.testing.assert_allclose(filled[kept], truth[kept], rtol=1e-6)  # the valid input is the truth, kept
    scored = holes & known
    line = next(l for l in printed if l.startswith("hole RMSE in disparity px"))
    px = dict(re.findall(r"(DDP|linear) ([0-9.]+)", line))
    fb = 3740 / 4 * 0.16  # f·B at quarter size: disparity px = fb / Z − dmin / 4
    ours = np.sqrt(np.mean((fb / filled[scored] - dmin / 4 - intensity[scored] / 4) ** 2))
    assert float(px["DDP"]) == pytest.approx(ours, abs=1e-3) and float(px["linear"]) > 0
    assert (tmp_path / "plastic.preview.png").is_file() and digest(sample_scene("Plastic")) == before


def test_an_installed_2014_scene_by_name_takes_sgbm_holes_and_warps_its_partner(tmp_path, capsys, monkeypatch):
    root = tmp_path / "root"
    folder = make_middlebury_fixture(root / "middlebury2014q" / "MiddEval3" / "trainingQ" / "Desk", size=(72, 96),
                                     hole_fraction=0.02)
    (folder / "disp0.pfm").rename(folder / "disp0GT.pfm")  # as MiddEval3 names it
    monkeypatch.setenv("DDP_DATA", str(root))
    out = tmp_path / "desk.pfm"
    assert main(["complete", "--scene", "Desk", "--out", str(out), *FAST, "--max-side", "32"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] == f"data: Desk (middlebury2014q, trainingQ) in {folder}"
    assert "OpenCV SGBM" in printed[1] and "variant rgbd+warp (neighbours: Desk-right)" in printed[1]
    from ddp_lite.data.fileio import read_pfm
    assert read_pfm(out).shape == (72, 96) and np.isfinite(read_pfm(out)).all()
    assert any(l.startswith("hole RMSE in disparity px") for l in printed)


def cropped_rail(source, folder, rows=slice(100, 200)):
    """A 2005/2006 scene folder cut to a band of rows (every view alike: a rail's views share their rows), so
    that a test's fills and fit are quick; the calibration along the rail is unchanged."""
    folder.mkdir(parents=True)
    for path in source.iterdir():
        if path.suffix == ".png":
            cv2.imwrite(str(folder / path.name), cv2.imread(str(path), cv2.IMREAD_UNCHANGED)[rows])
        else:
            shutil.copy(path, folder / path.name)
    return folder


def test_a_scene_folder_with_blobs_or_a_hole_file(tmp_path, capsys):
    art = cropped_rail(sample_scene("Art"), tmp_path / "HalfSize" / "Art")
    mask = np.full((art_shape := cv2.imread(str(art / "disp1.png"), 0).shape), 255, np.uint8)
    mask[40:70, 120:200] = 0
    cv2.imwrite(str(tmp_path / "holes.png"), mask)
    assert main(["complete", "--scene", str(art), "--holes", str(tmp_path / "holes.png"), "--variant", "rgbd",
                 "--out", str(tmp_path / "art.npy"), *FAST, "--max-side", "64"]) == 0
    filled = np.load(tmp_path / "art.npy")
    intensity = cv2.imread(str(art / "disp1.png"), cv2.IMREAD_UNCHANGED).astype(np.float64)
    truth = 3740 * 0.16 / (intensity + float((art / "dmin.txt").read_text()))
    kept = (mask > 0) & (intensity > 0)
    assert filled.shape == art_shape and np.allclose(filled[kept], truth[kept], rtol=1e-6)
    assert "holes.png" in capsys.readouterr().out
    from ddp_lite.data.scene_input import scene_input  # the other kinds' input, without a fit
    blobs = scene_input(art, "blobs")
    cut = np.isnan(blobs.depth) & (intensity > 0)
    assert 0.15 < cut.mean() < 0.25 and np.allclose(blobs.depth[~np.isnan(blobs.depth)], truth[~np.isnan(blobs.depth)])
    sgbm = scene_input(art, "sgbm")
    assert sgbm.depth_source == "stereo" and [v.name for v in sgbm.neighbors] == ["view0", "view2"]
    answered = np.isfinite(sgbm.depth) & (intensity > 0)  # SGBM's own depth: near the truth mostly, not equal to it
    assert 0.3 < answered.mean() and np.median(np.abs(sgbm.depth[answered] / truth[answered] - 1)) < 0.05
    assert not np.allclose(sgbm.depth[answered], truth[answered])


@pytest.mark.parametrize("argv, message", [
    (["--scene", "Plastic", "--rgb", "x.png"], "--scene takes the photo.*drop --rgb"),
    (["--scene", "Plastic", "--gt", "x.npy", "--depth-scale", "1"], "drop --gt, --depth-scale"),
    (["--rgb", "a.png", "--depth", "b.npy", "--holes", "sgbm"], "--holes needs --scene"),
    (["--rgb", "a.png", "--depth", "b.npy", "--variant", "rgbd+warp"], "rgbd\\+warp needs --scene"),
    (["--rgb", "a.png"], "give --rgb and --depth.*--depth missing.*or --scene"),
    (["--scene", "Plastic", "--holes", "strokes"], "--holes must be sgbm, blobs or a hole file"),
    (["--scene", "Nowhere"], "--scene: no scene 'Nowhere'"),
])
def test_bad_scene_arguments_are_refused_before_any_work(argv, message, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("DDP_DATA", str(tmp_path / "empty"))
    assert main(["complete", *argv, "--out", str(tmp_path / "o.npy")]) == 2
    assert re.search(message, capsys.readouterr().err), message
    assert not (tmp_path / "o.npy").exists()


def test_a_middlebury_disparity_png_as_depth_names_scene_and_outputs_never_overwrite_the_scene(tmp_path, capsys):
    plastic = sample_scene("Plastic")
    before = digest(plastic)
    assert main(["complete", "--rgb", str(plastic / "view1.png"), "--depth", str(plastic / "plastic-disp-hole.png"),
                 "--out", str(tmp_path / "o.npy")]) == 2
    assert "--scene" in capsys.readouterr().err
    copy = shutil.copytree(plastic, tmp_path / "Plastic")
    assert main(["complete", "--scene", str(copy), "--out", str(copy / "view1.png")]) == 2
    assert "refusing to overwrite an input" in capsys.readouterr().err
    assert digest(plastic) == before and digest(copy) == before
