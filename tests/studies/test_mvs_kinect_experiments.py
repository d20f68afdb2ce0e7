"""Notebook 12's plumbing (ddp_lite.studies.mvs_kinect_experiments) against hand computations: the paper's
reprojection PSNR (Sec. 4.4) on a fronto-parallel plane whose warp is an integer shift, the fill
table's two PSNRs, and the NYU v2 branch on a labelled-.mat fixture."""
import numpy as np
import pytest

from ddp_lite.core.camera import Camera
from ddp_lite.method.config import FitConfig
from ddp_lite.studies.mvs_kinect_experiments import fill_table, nyu_fill_table, reprojection_psnr
from ddp_lite.core.views import View

H, W, F = 32, 48, 40.0
BASELINE, Z = 0.2, 2.0  # the neighbour 0.2 m to the right of the reference: a plane at 2 m shifts by F·b/Z = 4 px


def _g(u, v):
    """A smooth colour pattern of continuous pixel coordinates, in [0, 1]."""
    return np.stack([0.5 + 0.4 * np.sin(u / 3.0 + 0.3 * v), 0.5 + 0.3 * np.cos(u / 5.0 - v / 4.0),
                     0.5 + 0.2 * np.sin((u + v) / 7.0)], -1).astype(np.float32)


def _pair():
    K = np.array([[F, 0.0, (W - 1) / 2], [0.0, F, (H - 1) / 2], [0.0, 0.0, 1.0]])
    pose = np.eye(4)
    pose[0, 3] = -BASELINE  # cam_from_world of a camera centred at (b, 0, 0)
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    shift = F * BASELINE / Z  # a point seen at u in the reference is at u − shift in the neighbour
    ref = View(_g(u, v), np.full((H, W), Z, np.float32), Camera(K, np.eye(4), W, H), "ref")
    nbr = View(_g(u + shift, v), np.full((H, W), Z, np.float32), Camera(K, pose, W, H), "nbr")
    return ref, nbr, u, v


def _hand_psnr(a, b, mask):
    mse = np.mean((a[mask] - b[mask]) ** 2)
    return 10 * np.log10(1.0 / mse)  # the paper's 20·log10(MAX_I / √MSE), MAX_I = 1


def test_reprojection_psnr_is_the_papers_on_an_integer_shift():
    ref, nbr, u, v = _pair()
    assert reprojection_psnr(ref.depth, ref, nbr) > 60  # through the true depth the warp is the reference itself
    wrong = np.full((H, W), F * BASELINE / 5.0, np.float32)  # a 5 px shift: the reference's pattern 1 px off
    seen = u >= 5 + 1  # the pixels whose neighbour sample lies inside the neighbour image (one column of margin)
    expected = _hand_psnr(_g(u - 1, v), ref.rgb, np.broadcast_to(seen[..., None], ref.rgb.shape))
    assert reprojection_psnr(wrong, ref, nbr, mask=seen) == pytest.approx(expected, abs=0.01)
    holes = seen & (v < H // 2)
    expected_holes = _hand_psnr(_g(u - 1, v), ref.rgb, np.broadcast_to(holes[..., None], ref.rgb.shape))
    assert reprojection_psnr(wrong, ref, nbr, mask=holes) == pytest.approx(expected_holes, abs=0.01)


def test_fill_table_scores_each_fill_on_one_pixel_set():
    ref, nbr, u, v = _pair()
    truth = np.full((H, W), Z, np.float32) + 0.05 * np.sin(u / 9.0).astype(np.float32)  # a gentle wave
    reading = truth.copy()
    reading[8:20, 20:30] = np.nan
    holes = np.isnan(reading)
    ddp = np.where(holes, Z + 0.1, truth).astype(np.float32)  # a "DDP" 10 cm off in the holes
    table = fill_table(ref, reading, truth, nbr, ddp, methods=("linear",))
    peak = float(truth.max() - truth.min())
    rmse = np.sqrt(np.mean((ddp[holes] - truth[holes]) ** 2))
    assert table["DDP"]["depth PSNR"] == pytest.approx(20 * np.log10(peak / rmse), abs=1e-4)
    assert set(table) == {"DDP", "linear"}
    assert table["DDP"]["reproj. PSNR"] == pytest.approx(reprojection_psnr(ddp, ref, nbr, mask=holes), abs=1e-6)
    assert np.isnan(reading[8:20, 20:30]).all() and np.isfinite(truth).all()  # inputs untouched


def test_nyu_branch_on_a_labelled_mat_fixture(tmp_path):
    """The notebook's NYU cell: raw Kinect depth with holes (0), the toolbox's fill, held-out blobs."""
    h5py = pytest.importorskip("h5py")
    rng = np.random.default_rng(0)
    v, u = np.mgrid[0:480, 0:640].astype(np.float64)
    truth = (1.0 / (0.3 + 0.0004 * u + 0.0002 * v)).astype(np.float32)  # a tilted plane, 1.7–3.3 m
    raw = truth.copy()
    raw[200:260, 300:380] = 0.0  # a Kinect hole
    toolbox = truth + np.float32(0.01)  # the dataset's fill: 1 cm off everywhere
    rgb = (rng.random((480, 640, 3)) * 255).astype(np.uint8)
    with h5py.File(tmp_path / "nyu.mat", "w") as f:  # MATLAB v7.3: axes reversed
        f["images"] = rgb[None].transpose(0, 3, 2, 1)
        f["rawDepths"] = raw[None].transpose(0, 2, 1)
        f["depths"] = toolbox[None].transpose(0, 2, 1)
    config = FitConfig.for_profile("ci", variant="rgbd", iterations=5)
    table = nyu_fill_table(tmp_path / "nyu.mat", "ci", config=config, methods=("linear",))
    assert set(table) == {"DDP (rgbd)", "dataset's fill", "linear"}
    from ddp_lite.data.datasets import load_nyu
    from ddp_lite.data.resample import resize_scene
    small = resize_scene(load_nyu(tmp_path / "nyu.mat", raw=True), (48, 64))[0].depth
    peak = float(np.nanmax(small) - np.nanmin(small))
    assert table["dataset's fill"]["depth PSNR"] == pytest.approx(20 * np.log10(peak / 0.01), abs=0.01)
    assert table["linear"]["depth PSNR"] > 55  # disparity affine in the pixels: a linear fill is near exact
    assert np.isfinite(table["DDP (rgbd)"]["depth PSNR"])


def test_printed_tables_keep_long_column_names_apart():
    """Notebook 12's tables have column names longer than the 12-character default ("off >2 % (%)",
    "reproj. PSNR"): each name must stand apart and right above its numbers."""
    from ddp_lite.evaluation.experiments import format_table
    text = format_table({"p ≥ 0.1": {"kept %": 67.3, "off >2 % (%)": 59.6, "reproj. PSNR": 21.04}}, digits=1)
    header, row = text.splitlines()
    assert "  off >2 % (%)  reproj. PSNR" in header
    for name, value in (("kept %", "67.3"), ("off >2 % (%)", "59.6"), ("reproj. PSNR", "21.0")):
        assert header.index(name) + len(name) == row.index(value) + len(value)  # right-aligned together
