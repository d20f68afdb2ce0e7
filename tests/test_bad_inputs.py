"""The bad inputs a user can give, as tests: every one refused before any work, with a clear message.

Each case builds its inputs in a fresh folder, then acts; the test asserts the exception type,
that the message names the argument, that no file in the folder was created or changed, and
that no array the caller gave was modified. Nothing here starts a fit except the two tests at the
end (non-finite output, CLI writers), which run one or two iterations of a tiny net.

``python tests/test_bad_inputs.py`` prints every case's verdict against whatever ``ddp_lite`` is
on the path (clear / unclear / silent): how the list was counted before and after the fix.
"""
from __future__ import annotations

import contextlib
import gzip
import io
import os
import stat
import sys
import tarfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

if __name__ != "__main__":
    os.environ.setdefault("DDP_PROFILE", "ci")

import cv2  # noqa: E402
import torch  # noqa: E402

from data_fetch import Dataset, FetchError, RemoteFile, fetch, safe_extract  # noqa: E402
from data_fetch.__main__ import main as fetch_main  # noqa: E402
from ddp_lite.data import datasets as ds  # noqa: E402
from ddp_lite.data.file_writers import write_pfm  # noqa: E402
from ddp_lite.data.fileio import read_depth_image, read_pfm  # noqa: E402
from ddp_lite.data.middlebury import (load_middlebury, make_middlebury_fixture, parse_middlebury_calib,  # noqa: E402
                                      read_middlebury_calib)
from ddp_lite.data.resample import resize_scene  # noqa: E402
from ddp_lite.classical.stereo import disparity_to_depth  # noqa: E402
from ddp_lite.core.files import write_bytes_atomic  # noqa: E402
from ddp_lite.core.camera import Camera, look_at  # noqa: E402
from ddp_lite.interface.cli import main as cli_main  # noqa: E402
from ddp_lite.method.paper.disparity import DisparityTransform  # noqa: E402
from ddp_lite.method.coarse_to_fine import complete_depth_coarse_to_fine  # noqa: E402
from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.dip import fit_image  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.method.result import merge  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402
from ddp_lite.core.views import View  # noqa: E402

H, W = 24, 32
BAD = (TypeError, ValueError)


class Refused(Exception):
    """A command line that exited non-zero; the message is what it printed on stderr."""


@dataclass
class Case:
    id: str
    setup: Callable  # setup(tmp: Path) -> act(), a callable that must raise
    exc: type | tuple
    name: str  # what the message must contain (the argument's name)


CASES: list[Case] = []
_WATCHED: list = []


def case(id, exc, name):
    def register(setup):
        CASES.append(Case(id, setup, exc, name))
        return setup
    return register


def watch(array):
    """Remember ``array`` and a copy: the test checks that it was not modified."""
    _WATCHED.append((array, np.array(array, copy=True)))
    return array


def depth(h=H, w=W):
    d = np.full((h, w), 2.0, np.float32)
    d[h // 4:h // 2, w // 4:w // 2] = np.nan
    return watch(d)


def rgb(h=H, w=W):
    return watch(np.random.default_rng(0).random((h, w, 3)).astype(np.float32))


def camera(pose=None, h=H, w=W):
    return Camera.from_fov(w, h, 60.0, pose)


def tiny(**fields):
    return FitConfig(**{"channels": (8, 16), "iterations": 2, **fields})


# --------------------------------------------------------------------------- FitConfig fields

CONFIG_BAD = {
    "lr": [float("inf"), float("nan"), -1.0, 0.0, "0.01", True, None],
    "lr_gamma": [float("inf"), float("nan"), 0.0, -0.1, True],
    "iterations": [0, -5, 2.7, True, "10", float("nan")],
    "lr_milestones": [(-1,), ("a",), (1.5,), 5, (True,)],
    "gammas": [(float("nan"), 0.1), (float("inf"), 0.0), (0.6, 0.6), (0.5,), (-0.1, 0.5), "ab", (0.5, None)],
    "channels": [(), (8,), (8, 0), (8, 16.5), (8, True), "816", (8, -16)],
    "noise_channels": [0, 2.5, True, -1],
    "lambda_z": [1.5, float("nan"), -0.1], "lambda_i": [1.5, float("nan"), -0.1],
    "lambda_w": [1.5, float("nan"), -0.1],
    "reg_noise_std": [-1.0, float("inf"), float("nan")],
    "average_outputs": [1.0, -0.1, float("nan")],
    "ensemble": [0, 1.5, True],
    "smoothness": [-1.0, float("inf"), float("nan")],
    "smoothness_edge": [-1.0, float("inf")],
    "flatness": [-0.5, float("inf"), float("nan")], "flatness_reach": [-1.0, float("inf"), "4"],
    "image_input": [-1.0, float("nan"), "1"], "image_blur": [-0.5, float("inf")],
    "disparity_margin": [0.5, float("inf"), float("nan")],
    "held_out_fraction": [0.0, 0.5, float("nan")],
    "patience": [0, 2.5], "plateau_decays": [-1, 1.5], "eval_every": [0, True],
    "seed": [-1, 1.5, "0"],
    "auto_stop": ["yes", 1], "bf16": ["no", 0],
    "net": ["resnet", 3, None], "down": ["avg"], "up": ["cubic"], "pad": ["circular"],
    "schedule": ["linear", None], "net_input": ["grid", None, 2], "edge_guide": ["colour", None, 3],
}
for _field, _values in CONFIG_BAD.items():
    for _i, _value in enumerate(_values):
        def _setup(tmp, field=_field, value=_value):
            r, d = rgb(), depth()
            return lambda: complete_depth(r, d, variant="d", config=tiny(**{field: value}))
        case(f"config.{_field}={_value!r}", BAD, _field)(_setup)

# the run's options: checked at the run, each message naming its field
OPTIONS_BAD = {
    "callback_every": [-1, 0.5], "channels_last": [1], "progress": ["false"],
    "device": ["tpu", "cuda", "cuda:7", 3, "gpu"],
    "max_memory_gb": [0.0, -1.0, float("nan"), "8"],
}
for _field, _values in OPTIONS_BAD.items():
    for _i, _value in enumerate(_values):
        def _setup(tmp, field=_field, value=_value):
            r, d = rgb(), depth()
            return lambda: complete_depth(r, d, variant="d", config=tiny(), options=RunOptions(**{field: value}))
        case(f"options.{_field}={_value!r}", BAD, f"options.{_field}")(_setup)
# a run option given to the method's config: refused, saying where it goes
for _field in OPTIONS_BAD:
    case(f"FitConfig({_field}=...)", TypeError, f"options=RunOptions({_field}=")(
        lambda tmp, field=_field: (lambda: tiny(**{field: OPTIONS_BAD[field][0]})))
case("for_profile(progress=False)", TypeError, "progress")(
    lambda tmp: (lambda: FitConfig.for_profile("ci", variant="d", progress=False)))
case("config.replace(device='cpu')", TypeError, "device")(lambda tmp: (lambda: tiny().replace(device="cpu")))
case("config.run", AttributeError, "RunOptions")(lambda tmp: (lambda: tiny().run))
case("config.progress", AttributeError, "run option")(lambda tmp: (lambda: tiny().progress))


# --------------------------------------------------------------------------- complete_depth's inputs

def _fit(**kw):
    def setup(tmp):
        args = dict(rgb=rgb(), depth=depth(), variant="rgbd", config=tiny())
        args.update({k: (v() if callable(v) and not isinstance(v, type) else v) for k, v in kw.items()})
        return lambda: complete_depth(**args)
    return setup


def _holes(fraction_valid):
    d = np.full((H, W), np.nan, np.float32)
    d.flat[:fraction_valid] = 2.0
    return d


FIT_BAD = {
    "depth int": (dict(depth=lambda: np.ones((H, W), np.int32)), "depth"),
    "depth 3-D": (dict(depth=lambda: np.ones((H, W, 1), np.float32)), "depth"),
    "depth inf": (dict(depth=lambda: np.where(depth() > 0, np.inf, np.nan).astype(np.float32)), "depth"),
    "depth negative": (dict(depth=lambda: -depth()), "depth"),
    "depth all NaN": (dict(depth=lambda: _holes(0)), "depth"),
    "depth 10 valid": (dict(depth=lambda: _holes(10)), "depth"),
    "depth torch": (dict(depth=lambda: torch.ones(H, W)), "depth"),
    "depth bool": (dict(depth=lambda: np.ones((H, W), bool)), "depth"),
    "rgb (H, W)": (dict(rgb=lambda: np.zeros((H, W), np.float32)), "rgb"),
    "rgb other size": (dict(rgb=lambda: rgb(H + 2, W)), "rgb"),
    "rgb > 1": (dict(rgb=lambda: rgb() * 255), "rgb"),
    "rgb NaN": (dict(rgb=lambda: np.full((H, W, 3), np.nan, np.float32)), "rgb"),
    "rgb int64": (dict(rgb=lambda: np.zeros((H, W, 3), np.int64)), "rgb"),
    "rgb torch": (dict(rgb=lambda: torch.zeros(H, W, 3)), "rgb"),
    "rgb None for rgbd": (dict(rgb=None), "rgb"),
    "variant x": (dict(variant="x"), "variant"),
    "variant None": (dict(variant=None), "variant"),
    "config dict": (dict(config={"lr": 1e-2}), "config"),
    "config str": (dict(config="ci"), "config"),
    "options dict": (dict(options={"progress": False}), "options"),
    "options a FitConfig": (dict(options=lambda: tiny()), "options"),
    "camera array": (dict(camera=lambda: np.eye(3)), "camera"),
    "camera other size": (dict(camera=lambda: camera(h=H * 2, w=W * 2)), "camera"),
    "warp without neighbours": (dict(variant="rgbd+warp", camera=lambda: camera()), "neighbor"),
    "warp without camera": (dict(variant="rgbd+warp", neighbors=lambda: [(rgb(), camera())]), "camera"),
    "neighbour bare array": (dict(variant="rgbd+warp", camera=lambda: camera(), neighbors=lambda: [rgb()]),
                             "neighbors[0]"),
    "neighbours one View": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                 neighbors=lambda: View(rgb(), depth(), camera(), "n")), "neighbors"),
    "neighbour 1-tuple": (dict(variant="rgbd+warp", camera=lambda: camera(), neighbors=lambda: [(rgb(),)]),
                          "neighbors[0]"),
    "neighbour K for camera": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                    neighbors=lambda: [(rgb(), np.eye(3))]), "neighbors[0]"),
    "neighbour rgb size": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                neighbors=lambda: [(rgb(H + 1, W), camera())]), "neighbors[0]"),
    "neighbour faces away": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                  neighbors=lambda: [(rgb(), camera(look_at((0, 0, 0), (0, 0, -1))))]), "neighbo"),
    "neighbour 1e6 m away": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                  neighbors=lambda: [(rgb(), camera(look_at((1e6, 0, 0), (1e6, 0, 1))))]), "neighbo"),
    "gt_depth shape": (dict(gt_depth=lambda: np.ones((H, W + 1), np.float32)), "gt_depth"),
    "transform str": (dict(transform="auto"), "transform"),
    "init str": (dict(init="last"), "init"),
    "3000×4000 at ci": (dict(rgb=None, variant="d", depth=lambda: np.full((3000, 4000), 2.0, np.float32),
                             config=lambda: FitConfig.for_profile("ci", variant="d")), "max_memory_gb"),
    "max_memory_gb too small": (dict(options=lambda: RunOptions(max_memory_gb=0.01)), "max_memory_gb"),
}
for _id, (_kw, _name) in FIT_BAD.items():
    case(f"complete_depth {_id}", BAD, _name)(_fit(**_kw))


def _c2f(**kw):
    def setup(tmp):
        r, d = rgb(), depth()
        return lambda: complete_depth_coarse_to_fine(r, d, variant="rgbd", config=tiny(), **kw)
    return setup


for _kw, _name in ((dict(scale=1), "scale"), (dict(scale=2.0), "scale"), (dict(coarse_fraction=1.0), "coarse_fraction"),
                   (dict(coarse_fraction=float("nan")), "coarse_fraction")):
    case(f"coarse_to_fine {_kw}", BAD, _name)(_c2f(**_kw))


def _dip(**kw):
    def setup(tmp):
        args = dict(image=rgb(), config=tiny())
        args.update({k: (v() if callable(v) else v) for k, v in kw.items()})
        return lambda: fit_image(**args)
    return setup


for _id, _kw, _name in (("mask uint8", dict(mask=lambda: np.ones((H, W), np.uint8)), "mask"),
                        ("mask 3 known", dict(mask=lambda: np.arange(H * W).reshape(H, W) < 3), "mask"),
                        ("image (H, W)", dict(image=lambda: np.zeros((H, W), np.float32)), "image"),
                        ("clean size", dict(clean=lambda: rgb(H + 1, W)), "clean"),
                        ("config lr nan", dict(config=lambda: tiny(lr=float("nan"))), "lr")):
    case(f"fit_image {_id}", BAD, _name)(_dip(**_kw))

case("merge shapes", BAD, "input_depth")(lambda tmp: (lambda: merge(depth(), depth(H + 1, W))))


# --------------------------------------------------------------------------- Camera

def _cam(K=None, pose=None, width=W, height=H):
    K = np.array([[30.0, 0, 15.5], [0, 30.0, 11.5], [0, 0, 1]]) if K is None else K
    return lambda tmp: (lambda: Camera(K, np.eye(4) if pose is None else pose, width, height))


_rot = np.eye(4)
_rot[:3, :3] = [[1, 0, 0], [0, 1, 0], [0, 0, 2]]
_nanpose = np.eye(4)
_nanpose[0, 3] = np.nan
for _id, _setup, _name in (
        ("focal 1e12", _cam(K=np.array([[1e12, 0, 15.5], [0, 1e12, 11.5], [0, 0, 1]])), "focal"),
        ("focal 1e-5", _cam(K=np.array([[1e-5, 0, 15.5], [0, 1e-5, 11.5], [0, 0, 1]])), "focal"),
        ("width True", _cam(width=True), "width"),
        ("height 0", _cam(height=0), "height"),
        ("width 2.5", _cam(width=2.5), "width"),
        ("width inf", _cam(width=float("inf")), "width"),
        ("K nan", _cam(K=np.full((3, 3), np.nan)), "K"),
        ("K last row", _cam(K=np.array([[30.0, 0, 15.5], [0, 30.0, 11.5], [0, 1, 1]])), "K"),
        ("K 2×2", _cam(K=np.eye(2)), "K"),
        ("pose not a rotation", _cam(pose=_rot), "cam_from_world"),
        ("pose nan", _cam(pose=_nanpose), "cam_from_world"),
        ("fov 180", lambda tmp: (lambda: Camera.from_fov(W, H, 180.0)), "fov_x_deg"),
        ("fov str", lambda tmp: (lambda: Camera.from_fov(W, H, "60")), "fov_x_deg")):
    case(f"Camera {_id}", BAD, _name)(_setup)


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


def run_cli(main, argv):
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            rc = main(argv)
        except SystemExit as exit_:
            rc = exit_.code
            if isinstance(rc, str):
                err.write(rc)
    if rc != 0:
        raise Refused(err.getvalue())


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


# --------------------------------------------------------------------------- loaders

PFM_HEAD = b"Pf\n2 2\n-1.0\n"
PFM_BODY = np.ones(4, "<f4").tobytes()


def _pfm(data):
    def setup(tmp):
        (tmp / "x.pfm").write_bytes(data)
        return lambda: read_pfm(tmp / "x.pfm")
    return setup


for _id, _data in (("not a PFM", b"P6\n2 2\n255\n" + PFM_BODY), ("truncated", PFM_HEAD + PFM_BODY[:7]),
                   ("zero scale", b"Pf\n2 2\n0.0\n" + PFM_BODY), ("nan scale", b"Pf\n2 2\nnan\n" + PFM_BODY)):
    case(f"read_pfm {_id}", ValueError, "path")(_pfm(_data))

CALIB = {"cam0": "[30 0 15.5; 0 30 11.5; 0 0 1]", "cam1": "[30 0 15.5; 0 30 11.5; 0 0 1]", "doffs": "0",
         "baseline": "100", "width": "32", "height": "24", "ndisp": "16"}


def _calib(**changes):
    entries = {**CALIB, **changes}
    text = "\n".join(f"{k}={v}" for k, v in entries.items() if v is not None)
    return lambda tmp: (lambda: parse_middlebury_calib(text))


for _id, _kw, _name in (("baseline nan", dict(baseline="nan"), "baseline"), ("baseline inf", dict(baseline="inf"), "baseline"),
                        ("baseline -1", dict(baseline="-1"), "baseline"), ("doffs nan", dict(doffs="nan"), "doffs"),
                        ("width 0", dict(width="0"), "width"), ("width 2.5", dict(width="2.5"), "width"),
                        ("ndisp missing", dict(ndisp=None), "ndisp"), ("cam0 2×2", dict(cam0="[1 0; 0 1]"), "cam0"),
                        ("height inf", dict(height="inf"), "height")):
    case(f"calib {_id}", ValueError, _name)(_calib(**_kw))
case("calib not text", ValueError, "text")(lambda tmp: (lambda: parse_middlebury_calib(b"cam0=[1]")))


def _latin1_calib(tmp):
    (tmp / "calib.txt").write_bytes("cam0=[30 0 15.5; 0 30 11.5; 0 0 1] # f\xe9\n".encode("latin-1"))
    return lambda: read_middlebury_calib(tmp / "calib.txt")


case("calib.txt not UTF-8", ValueError, "calib.txt")(_latin1_calib)

P2 = "P_rect_02: 700 0 600 45 0 700 180 0 0 0 1 0"
P3 = "P_rect_03: 700 0 600 -340 0 700 180 0 0 0 1 0"


def _kitti_calib(text):
    def setup(tmp):
        (tmp / "c.txt").write_bytes(text if isinstance(text, bytes) else text.encode())
        return lambda: ds.read_kitti_calib(tmp / "c.txt")
    return setup


for _id, _text in (("focal 0", P2.replace("700 0 600 45", "0 0 600 45") + "\n" + P3),
                   ("P2 = P3", P2 + "\n" + P2.replace("02", "03")), ("no P_rect_03", P2),
                   ("not UTF-8", (P2 + "\n" + P3 + "\n# caf\xe9").encode("latin-1"))):
    case(f"kitti calib {_id}", ValueError, "c.txt")(_kitti_calib(_text))


def _kitti_disp8(tmp):
    cv2.imwrite(str(tmp / "d.png"), np.ones((4, 4), np.uint8))
    return lambda: ds.read_kitti_disparity(tmp / "d.png")


case("kitti disparity 8-bit", ValueError, "path")(_kitti_disp8)


def _mb_all_inf(tmp):
    folder = make_middlebury_fixture(tmp / "mb", size=(24, 32))
    write_pfm(folder / "disp0.pfm", np.full((24, 32), np.inf, np.float32))
    return lambda: load_middlebury(folder)


case("middlebury all-invalid disparity", ValueError, "disp0.pfm")(_mb_all_inf)


def _kitti_tree(tmp, disparity=None):
    base = tmp / "kitti" / "training"
    for sub in ("image_2", "image_3", "calib_cam_to_cam", "disp_occ_0"):
        (base / sub).mkdir(parents=True)
    for sub in ("image_2", "image_3"):
        cv2.imwrite(str(base / sub / "000000_10.png"), np.zeros((H, W, 3), np.uint8))
    small = {"700 0 600": "30 0 15.5", "0 700 180": "0 30 11.5"}  # K of a 32×24 image
    (base / "calib_cam_to_cam" / "000000.txt").write_text("\n".join(
        text.replace("700 0 600", small["700 0 600"]).replace("0 700 180", small["0 700 180"]) for text in (P2, P3)))
    cv2.imwrite(str(base / "disp_occ_0" / "000000_10.png"),
                np.zeros((H, W), np.uint16) if disparity is None else disparity)
    return tmp / "kitti"


case("kitti all-zero disparity", ValueError, "disp_occ_0")(lambda tmp: (lambda root=_kitti_tree(tmp): ds.load_kitti(root)))
case("kitti index -1", ValueError, "index")(lambda tmp: (lambda: ds.load_kitti(tmp, index=-1)))
case("kitti split val", ValueError, "split")(lambda tmp: (lambda: ds.load_kitti(tmp, split="val")))

for _id, _kw, _name in (("focal 0", dict(focal=0.0, baseline=0.1), "focal"),
                        ("baseline nan", dict(focal=30.0, baseline=float("nan")), "baseline"),
                        ("doffs inf", dict(focal=30.0, baseline=0.1, doffs=float("inf")), "doffs")):
    case(f"disparity_to_depth {_id}", ValueError, _name)(
        lambda tmp, kw=_kw: (lambda: disparity_to_depth(np.ones((4, 4)), **kw)))
case("disparity_to_depth 3-D", ValueError, "disparity")(
    lambda tmp: (lambda: disparity_to_depth(np.ones((4, 4, 1)), 30.0, 0.1)))
case("read_depth_image scale 0", ValueError, "scale")(lambda tmp: (lambda: read_depth_image(tmp / "x.png", 0.0)))


def _depth8(tmp):
    cv2.imwrite(str(tmp / "d8.png"), np.ones((4, 4), np.uint8))
    return lambda: read_depth_image(tmp / "d8.png")


case("read_depth_image 8-bit", ValueError, "path")(_depth8)
case("resize_scene not a Scene", TypeError, "scene")(lambda tmp: (lambda: resize_scene("scene", (8, 8))))
case("write_pfm bool", ValueError, "array")(lambda tmp: (lambda: write_pfm(tmp / "b.pfm", np.ones((2, 2), bool))))
case("write_pfm 4-D", ValueError, "array")(lambda tmp: (lambda: write_pfm(tmp / "b.pfm", np.ones((2, 2, 2, 2)))))


# --------------------------------------------------------------------------- files and data_fetch

def _readonly(tmp):
    (tmp / "ro.bin").write_bytes(b"old")
    os.chmod(tmp / "ro.bin", 0o444)
    return lambda: write_bytes_atomic(tmp / "ro.bin", b"new")


case("atomic write over a read-only file", PermissionError, "read-only")(_readonly)
case("atomic write onto a folder", IsADirectoryError, "folder")(lambda tmp: (lambda: write_bytes_atomic(tmp, b"x")))


def _manual(tmp, name, data):
    (tmp / "d" / "m").mkdir(parents=True)
    (tmp / "d" / "m" / name).write_bytes(data)
    dataset = Dataset("m", "manual", (RemoteFile(name, None, None, None, True),), "CC0", "tests", "-", "-",
                      manual="put it in {dest}")
    return lambda: fetch(dataset, dest=tmp / "d", trust_first_download=True, say=lambda *a: None)


def _zip(members, method=zipfile.ZIP_STORED):
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", method) as zf:
        for name, data in members:
            zf.writestr(name, data)
    return buffer.getvalue()


def _bad_crc():
    data = bytearray(_zip([("S/calib.txt", b"ndisp=1\n" * 50)]))
    data[bytes(data).index(b"ndisp") + 3] ^= 0xFF
    return bytes(data)


def _tar(members, gz=True):
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w") as tf:
        for name, data in members:
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tf.addfile(info, io.BytesIO(data))
    return gzip.compress(buffer.getvalue()) if gz else buffer.getvalue()


_big = bytes(range(256)) * 400
for _id, _name, _data, _msg in (
        ("corrupt zip", "S.zip", _bad_crc(), "S.zip"),
        ("truncated tar.gz", "S.tar.gz", _tar([("a", _big)])[:600], "S.tar.gz"),
        ("truncated tar", "S.tar", _tar([("a", _big)], gz=False)[:3000], "S.tar"),
        ("zip bomb", "B.zip", _zip([("zeros", b"\0" * (4 << 20))], zipfile.ZIP_DEFLATED), "B.zip"),
        ("not an archive", "N.zip", b"just text", "N.zip")):
    case(f"fetch {_id}", FetchError, _msg)(lambda tmp, n=_name, d=_data: _manual(tmp, n, d))


def _toy():
    return Dataset("toy", "toy", (RemoteFile("a.bin", "http://127.0.0.1:9/a.bin"),), "CC0", "tests", "-", "-")


def _registry(text):
    def setup(tmp):
        (tmp / "toy").mkdir()
        (tmp / "toy" / "registry.json").write_text(text)
        return lambda: fetch(_toy(), dest=tmp, trust_first_download=True, say=lambda *a: None, retries=0)
    return setup


for _id, _text in (("entry a string", '{"a.bin": "abc"}'), ("a list", '["a.bin"]'), ("bad JSON", "{"),
                   ("sha256 a number", '{"a.bin": {"sha256": 5}}')):
    case(f"fetch registry.json {_id}", FetchError, "registry.json")(_registry(_text))


def _dest_file(tmp):
    (tmp / "f").write_text("x")
    return lambda: fetch(_toy(), dest=tmp / "f", trust_first_download=True, say=lambda *a: None, retries=0)


case("fetch --dest a file", FetchError, "dest")(_dest_file)
case("fetch unknown name", ValueError, "name")(lambda tmp: (lambda: fetch("nope", dest=tmp)))
case("fetch dataset an int", TypeError, "dataset")(lambda tmp: (lambda: fetch(3, dest=tmp)))
case("fetch only matches nothing", ValueError, "only")(lambda tmp: (lambda: fetch("nyu", dest=tmp, only="x*")))
case("fetch retries -1", ValueError, "retries")(lambda tmp: (lambda: fetch(_toy(), dest=tmp, retries=-1,
                                                                           trust_first_download=True)))
case("fetch retries 1.5", ValueError, "retries")(lambda tmp: (lambda: fetch(_toy(), dest=tmp, retries=1.5,
                                                                            trust_first_download=True)))


def _fetch_cli_dest_file(tmp):
    (tmp / "f").write_text("x")
    return lambda: run_cli(fetch_main, ["fetch", "nyu", "--dest", str(tmp / "f"), "--no-progress"])


case("fetch cli --dest a file", Refused, "dest")(_fetch_cli_dest_file)
case("fetch cli unknown name", Refused, "name")(lambda tmp: (lambda: run_cli(fetch_main, ["fetch", "nope"])))
case("safe_extract a text file", FetchError, "x.txt")(
    lambda tmp: ((tmp / "x.txt").write_text("x"), lambda: safe_extract(tmp / "x.txt", tmp / "out"))[1])


# --------------------------------------------------------------------------- found while hardening

case("complete_depth callback=5", TypeError, "callback")(_fit(callback=5))
case("Camera.resized(0, 0)", BAD, "width")(lambda tmp: (lambda: camera().resized(0, 0)))
case("DisparityTransform.from_depth margin 0", BAD, "margin")(
    lambda tmp: (lambda: DisparityTransform.from_depth(depth(), margin=0.0)))
case("calib a key twice", ValueError, "baseline")(
    lambda tmp: (lambda: parse_middlebury_calib("\n".join(f"{k}={v}" for k, v in CALIB.items()) + "\nbaseline=5")))
case("fetch dest ''", ValueError, "dest")(lambda tmp: (lambda: fetch(_toy(), dest="", trust_first_download=True)))
case("safe_extract duplicate members", FetchError, "more than once")(
    lambda tmp: ((tmp / "dup.zip").write_bytes(_zip([("a", b"1"), ("a", b"22")])),
                 lambda: safe_extract(tmp / "dup.zip", tmp / "out"))[1])


# --------------------------------------------------------------------------- the test

def snapshot(folder: Path) -> dict:
    """Every path under ``folder`` with its size, mtime and mode (a folder's mtime, which a temporary
    file made and removed inside it changes, is left out)."""
    return {str(p.relative_to(folder)): (p.is_dir(), p.stat().st_size if p.is_file() else 0,
                                         0 if p.is_dir() else p.stat().st_mtime_ns, stat.S_IMODE(p.stat().st_mode))
            for p in folder.rglob("*")}


@pytest.mark.parametrize("c", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_refused_clearly_and_changes_nothing(c, tmp_path):
    _WATCHED.clear()
    act = c.setup(tmp_path)
    before = snapshot(tmp_path)
    with pytest.raises(c.exc) as info:
        act()
    assert c.name in str(info.value), f"the message does not name {c.name!r}: {info.value}"
    assert snapshot(tmp_path) == before, "a file was created or changed"
    for array, copy in _WATCHED:
        np.testing.assert_array_equal(np.asarray(array), copy)  # the caller's arrays are untouched


def test_the_list_is_long_enough():
    assert len(CASES) >= 200 and len({c.id for c in CASES}) == len(CASES)


# --------------------------------------------------------------------------- accepted on purpose

def test_accepted_on_purpose(tmp_path):
    """Inputs that look odd but are right, and must keep working."""
    # PFM with CRLF line ends and a comment line (both occur in the wild)
    (tmp_path / "crlf.pfm").write_bytes(b"Pf\r\n2 2\r\n-1.0\r\n" + PFM_BODY)
    (tmp_path / "comment.pfm").write_bytes(b"Pf\n# made by hand\n2 2\n-1.0\n" + PFM_BODY)
    for name in ("crlf.pfm", "comment.pfm"):
        np.testing.assert_array_equal(read_pfm(tmp_path / name), np.ones((2, 2), np.float32))
    # an integral float size (from arithmetic) is a size
    assert Camera(np.array([[30.0, 0, 15.5], [0, 30.0, 11.5], [0, 0, 1]]), np.eye(4), 32.0, 24.0).width == 32
    # learning-rate growth (lr_gamma > 1) is a lever, not a mistake; NumPy integers are integers
    tiny(lr_gamma=2.0, iterations=np.int64(2), lr_milestones=(np.int32(1),)).validate()
    # KITTI's testing split has no ground truth: all-NaN depth is the truth there
    # one blind neighbour among seeing ones: a warning, the fit goes on
    from ddp_lite.method.input_checks import check_fit_inputs
    away = camera(look_at((0, 0, 0), (0, 0, -1)))
    with pytest.warns(UserWarning, match=r"neighbors\[1\]"):
        check_fit_inputs(rgb(), depth(), camera(), [(rgb(), camera(look_at((0.1, 0, 0), (0.1, 0, 1)))), (rgb(), away)],
                          "rgbd+warp", tiny(), None, None)


def test_umask_is_respected(tmp_path):
    old = os.umask(0o027)
    try:
        write_bytes_atomic(tmp_path / "a.bin", b"x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.bin").stat().st_mode) == 0o640
    os.chmod(tmp_path / "a.bin", 0o600)
    write_bytes_atomic(tmp_path / "a.bin", b"y")  # a replaced file keeps its mode
    assert stat.S_IMODE((tmp_path / "a.bin").stat().st_mode) == 0o600


# --------------------------------------------------------------------------- after a fit has run

def test_non_finite_output_raises(monkeypatch):
    """A diverged fit raises; it never returns NaN that merged() would hide among the valid pixels."""
    import ddp_lite.method.loop as loop

    real_run = loop.run

    def diverging(*args, **kwargs):
        output, *rest = real_run(*args, **kwargs)
        return (torch.full_like(output, float("nan")), *rest)
    monkeypatch.setattr(loop, "run", diverging)
    with pytest.raises(FloatingPointError, match="lr"):
        complete_depth(rgb(), depth(), variant="d", config=tiny(iterations=1))
    with pytest.raises(FloatingPointError, match="lr"):
        fit_image(rgb(), config=tiny(iterations=1))


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


# --------------------------------------------------------------------------- counting verdicts

def judge(c) -> tuple[str, str]:
    """One case against the ddp_lite on the path → (verdict, note): 'clear' (the expected exception,
    naming the argument, no file changed), 'unclear' (another exception, or a message not naming the
    argument, or files changed) or 'silent' (accepted)."""
    import tempfile
    import warnings
    _WATCHED.clear()
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            act = c.setup(Path(tmp))
            before = snapshot(Path(tmp))
            act()
            return "silent", "accepted"
        except c.exc as error:
            changed = snapshot(Path(tmp)) != before
            verdict = "clear" if c.name in str(error) and not changed else "unclear"
            return verdict, ("changed files; " if changed else "") + (str(error).splitlines()[0][:100] if str(error) else "")
        except BaseException as error:  # noqa: BLE001 - a count, not a test
            return "unclear", f"{type(error).__name__}: {str(error).splitlines()[0][:100] if str(error) else ''}"


def verdicts(cases=None, skip=()) -> tuple[dict, list]:
    """Every case's verdict (``judge``): the counts and one (verdict, id, note) row per case. A case in
    ``skip`` (too heavy to run unguarded) counts as silent, as the measurement that listed it found."""
    counts, rows = {"clear": 0, "unclear": 0, "silent": 0}, []
    for c in CASES if cases is None else cases:
        if c.id in skip:
            verdict, note = "silent", "not run here (SKIP_CASES): accepted, as measured"
        else:
            verdict, note = judge(c)
        counts[verdict] += 1
        rows.append((verdict, c.id, note))
    return counts, rows


if __name__ == "__main__":
    os.environ.setdefault("DDP_PROFILE", "ci")
    counts, rows = verdicts(skip=set(os.environ.get("SKIP_CASES", "").split("|")) - {""})
    for verdict, id_, note in rows:
        print(f"{verdict:8} {id_:55} {note}")
    print(counts, "of", len(CASES))
