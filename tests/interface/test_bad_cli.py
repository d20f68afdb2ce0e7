"""Bad command lines of ``ddp-lite``: every bad option a usage error naming it before any work, an output that
would overwrite an input refused, the format an output's suffix names written, and a finished fit never
thrown away by a late error. The refusals use ``bad_input_harness``.
"""
from __future__ import annotations

import contextlib
import io
import os

import cv2
import numpy as np
import pytest

from bad_input_harness import H, W, CaseList, Refused, refusal_test, run_cli
from ddp_lite.data.fileio import read_pfm
from ddp_lite.interface.cli import main as cli_main

CASES = CaseList()
case = CASES.case

# --------------------------------------------------------------------------- the CLI

def _files(tmp):
    cv2.imwrite(str(tmp / "rgb.png"), (np.random.default_rng(0).random((H, W, 3)) * 255).astype(np.uint8))
    d = np.full((H, W), 2.0, np.float32)
    d[5:10, 5:10] = np.nan
    np.save(tmp / "d.npy", d)
    cv2.imwrite(str(tmp / "d16.png"), np.where(np.isnan(d), 0, d * 1000).astype(np.uint16))
    np.save(tmp / "d3.npy", np.ones((H, W, 3), np.float32))
    (tmp / "text.npy").write_text("not an array")
    (tmp / "ro.npy").write_bytes(b"old")
    os.chmod(tmp / "ro.npy", 0o444)
    (tmp / "a_file").write_text("x")
    (tmp / "outdir").mkdir()


def _cli(*args, depth_file="d.npy", out="o.npy", rgb_file="rgb.png"):
    def setup(tmp):
        _files(tmp)
        argv = ["complete", "--rgb", str(tmp / rgb_file), "--depth", str(tmp / depth_file), "--out", str(tmp / out),
                "--profile", "ci", "--iterations", "2", *args]
        return lambda: run_cli(cli_main, argv)
    return setup


for _id, _setup, _name in (
        ("--out o.txt", _cli(out="o.txt"), "--out"),
        ("--out a folder", _cli(out="outdir"), "--out"),
        ("--out = --depth", _cli(out="d.npy"), "--depth"),
        ("--out = --rgb", _cli(out="rgb.png"), "--rgb"),
        ("--out read-only", _cli(out="ro.npy"), "--force"),
        ("--out under a file", _cli(out="a_file/o.npy"), "--out"),
        ("--out .exr without the codec", _cli(out="o.exr"), "--out"),
        ("--out .png beyond 65 m", _cli("--depth-scale", "50", out="o.png"), "--out"),
        ("--iterations 0", _cli("--iterations", "0"), "--iterations"),
        ("--iterations -3", _cli("--iterations", "-3"), "--iterations"),
        ("--iterations 2.5", _cli("--iterations", "2.5"), "--iterations"),
        ("--depth-scale 0", _cli("--depth-scale", "0"), "--depth-scale"),
        ("--depth-scale -1", _cli("--depth-scale", "-1"), "--depth-scale"),
        ("--depth-scale nan", _cli("--depth-scale", "nan"), "--depth-scale"),
        ("--depth-scale inf", _cli("--depth-scale", "inf"), "--depth-scale"),
        ("--depth-scale 1e-45", _cli("--depth-scale", "1e-45"), "--depth-scale"),
        ("--depth-scale 1e6", _cli("--depth-scale", "1e6"), "--depth-scale"),
        ("16-bit PNG without --depth-scale", _cli(depth_file="d16.png"), "--depth-scale"),
        ("--device cuda", _cli("--device", "cuda"), "device"),
        ("--device tpu", _cli("--device", "tpu"), "device"),
        ("--depth missing", _cli(depth_file="missing.npy"), "--depth"),
        ("--rgb missing", _cli(rgb_file="missing.png"), "--rgb"),
        ("--rgb not an image", _cli(rgb_file="a_file"), "--rgb"),
        ("--depth 3 channels", _cli(depth_file="d3.npy"), "--depth"),
        ("--depth not a .npy", _cli(depth_file="text.npy"), "--depth"),
        ("--max-memory-gb 0", _cli("--max-memory-gb", "0"), "--max-memory-gb"),
        ("--max-memory-gb -1", _cli("--max-memory-gb", "-1"), "--max-memory-gb"),
        ("--max-memory-gb 1e-6", _cli("--max-memory-gb", "1e-6"), "max_memory_gb"),
        ("--profile nope", _cli("--profile", "nope"), "profile"),
        ("--variant rgbd+warp", _cli("--variant", "rgbd+warp"), "--variant"),
        ("demo --iterations 0", lambda tmp: (lambda: run_cli(cli_main, ["demo", "--iterations", "0",
                                                                          "--out", str(tmp / "f.png")])), "--iterations"),
        ("demo --size 4 4", lambda tmp: (lambda: run_cli(cli_main, ["demo", "--size", "4", "4", "--iterations", "1",
                                                                      "--out", str(tmp / "f.png")])), "size")):
    case(f"cli {_id}", Refused, _name)(_setup)


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)


def test_cli_writes_the_format_its_suffix_names(tmp_path):
    _files(tmp_path)
    for out in ("o.png", "o.pfm", "o.npy"):
        run = ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "d16.png"),
               "--depth-scale", "0.001", "--out", str(tmp_path / out), "--profile", "ci", "--iterations", "1"]
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            assert cli_main(run) == 0
    png = cv2.imread(str(tmp_path / "o.png"), cv2.IMREAD_UNCHANGED)
    assert png.dtype == np.uint16 and png.shape == (H, W) and 1000 < np.median(png) < 3000  # millimetres
    pfm, npy = read_pfm(tmp_path / "o.pfm"), np.load(tmp_path / "o.npy")
    np.testing.assert_allclose(pfm, npy)
    np.testing.assert_allclose(png / 1000.0, npy, atol=6e-4)


def _complete_argv(tmp_path, out="filled.npy"):
    return ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
            "--out", f"{tmp_path}/{out}", "--profile", "ci", "--iterations", "5", "--max-side", "16"]


def test_a_terminal_that_cannot_print_an_arrow_still_gets_its_files(tmp_path, monkeypatch):
    import io
    import sys
    from conftest import rgbd_files as _pair
    from ddp_lite.interface.cli import main
    _pair(tmp_path)
    terminal = io.TextIOWrapper(io.BytesIO(), encoding="ascii")
    monkeypatch.setattr(sys, "stdout", terminal)
    assert main(_complete_argv(tmp_path)) == 0
    assert np.load(tmp_path / "filled.npy").shape == (60, 90) and (tmp_path / "filled.preview.png").exists()
    terminal.flush()
    assert b"? " in terminal.buffer.getvalue() or b"?" in terminal.buffer.getvalue()  # the arrow, replaced
    assert terminal.errors == "strict"  # the caller's stream as it was


def test_an_out_that_names_a_folder_or_is_given_twice_is_refused_before_the_fit(tmp_path, capsys, monkeypatch):
    from conftest import rgbd_files as _pair
    from ddp_lite.interface import cli_complete
    from ddp_lite.interface.cli import main
    _pair(tmp_path)
    monkeypatch.setattr(cli_complete, "_complete", lambda *a: pytest.fail("the fit started"))
    assert main(_complete_argv(tmp_path, "o.npy/")) == 2
    assert "folder" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(_complete_argv(tmp_path) + ["--out", str(tmp_path / "second.npy")])
    assert "--out was given twice" in capsys.readouterr().err
    assert not (tmp_path / "o.npy").exists() and not (tmp_path / "second.npy").exists()
