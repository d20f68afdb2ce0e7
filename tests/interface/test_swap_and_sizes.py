"""`ddp-lite complete` refuses a swapped --rgb/--depth before any work, and size messages print H×W."""
import cv2
import numpy as np
import pytest

from ddp_lite.core.camera import Camera
from ddp_lite.core.views import View
from ddp_lite.data.fileio import check_same_size
from ddp_lite.interface.cli import main
from ddp_lite.method.paper.nets import check_input_size

H, W = 30, 45  # landscape: a W×H message would read 45×30


def _files(tmp_path):
    rng = np.random.default_rng(0)
    depth = 1.0 + rng.random((H, W))
    depth[5:12, 8:20] = np.nan
    cv2.imwrite(str(tmp_path / "rgb.png"), (rng.random((H, W, 3)) * 255).astype(np.uint8))
    cv2.imwrite(str(tmp_path / "grey.png"), (rng.random((H, W)) * 255).astype(np.uint8))
    cv2.imwrite(str(tmp_path / "depth.png"), np.nan_to_num(depth * 1000).astype(np.uint16))
    np.save(tmp_path / "depth.npy", depth.astype(np.float32))


def _complete(tmp_path, monkeypatch, capsys, rgb, depth):
    import ddp_lite.method.complete as combine

    def no_fit(*args, **kwargs):
        raise AssertionError("the fit started: the refusal must come first")
    monkeypatch.setattr(combine, "complete_depth", no_fit)
    code = main(["complete", "--rgb", str(tmp_path / rgb), "--depth", str(tmp_path / depth), "--depth-scale", "0.001",
                 "--out", str(tmp_path / "filled.npy"), "--profile", "ci"])
    err = capsys.readouterr().err
    assert not (tmp_path / "filled.npy").exists()
    return code, err


@pytest.mark.parametrize("rgb", ["depth.png", "grey.png"])
def test_complete_refuses_a_one_channel_or_16_bit_rgb_and_asks_about_a_swap(tmp_path, monkeypatch, capsys, rgb):
    _files(tmp_path)
    code, err = _complete(tmp_path, monkeypatch, capsys, rgb, "rgb.png" if rgb == "depth.png" else "depth.png")
    assert code == 2 and "--rgb" in err and "did you swap --rgb and --depth?" in err, err
    assert "one channel" in err and (("uint16" in err) == (rgb == "depth.png")), err
    assert f"{H}×{W} (H×W)" in err, err


def test_complete_refuses_a_colour_picture_as_depth_and_asks_about_a_swap(tmp_path, monkeypatch, capsys):
    _files(tmp_path)
    cv2.imwrite(str(tmp_path / "rgb2.png"), cv2.imread(str(tmp_path / "rgb.png")))
    code, err = _complete(tmp_path, monkeypatch, capsys, "rgb2.png", "rgb.png")
    assert code == 2 and "8-bit" in err and "did you swap --rgb and --depth?" in err, err


def test_a_grey_8_bit_depth_picture_is_refused_without_the_swap_hint(tmp_path, monkeypatch, capsys):
    _files(tmp_path)
    code, err = _complete(tmp_path, monkeypatch, capsys, "rgb.png", "grey.png")
    assert code == 2 and "8-bit" in err and "swap" not in err, err


def test_complete_size_error_says_h_by_w(tmp_path, monkeypatch, capsys):
    _files(tmp_path)
    np.save(tmp_path / "short.npy", 1000 * np.load(tmp_path / "depth.npy")[:20])  # millimetres, as --depth-scale says
    code, err = _complete(tmp_path, monkeypatch, capsys, "rgb.png", "short.npy")
    assert code == 2 and f"--rgb is {H}×{W} (H×W) but --depth is 20×{W}" in err, err


def test_size_messages_print_height_first():
    with pytest.raises(ValueError, match=r"rgb is 30×45 \(H×W\) but depth is 30×44;"):
        check_same_size((30, 45, 3), (30, 44), None, "rgb", "depth")
    camera = Camera.from_fov(W, H, 60.0)
    assert f"Camera({H}×{W} (H×W)" in repr(camera)
    with pytest.raises(ValueError, match=rf"camera is {H}×{W} but the images are 20×{W} \(H×W\)"):
        View(np.zeros((20, W, 3), np.float32), np.ones((20, W), np.float32), camera)
    with pytest.raises(ValueError, match=r"depth is 8×40 px \(H×W\)"):
        check_input_size("unet", (16, 32, 64, 128), 8, 40)
