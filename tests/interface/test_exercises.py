"""The exercise checks pass a right answer and fail every known wrong one (with a message).

The wrong answers are the mistakes students make (and ones that once passed): D1 with
5 % of the prediction instead of the truth, ``>=`` instead of ``>``, SSIM with a sample covariance.
"""
import numpy as np
import pytest
from scipy import ndimage
from skimage.metrics import structural_similarity

from ddp_lite.interface import exercises
from ddp_lite.method.paper.losses import ssim
from ddp_lite.method.paper.warp import warp_to_reference


def _d1(compare=np.greater, of_truth=True):
    def d1(pred, gt):
        err, valid = np.abs(pred - gt), np.isfinite(gt)
        bad = compare(err, 3.0) & compare(err, 0.05 * (gt if of_truth else pred))
        return 100 * np.mean(bad[valid])
    return d1


def _ssim_skimage(**options):
    settings = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0)
    return lambda x, y: structural_similarity(x, y, **{**settings, **options})


def _ssim(sample=False, uniform=False, data_range=1.0):
    """SSIM written out (a student's own): Gaussian 11×11 window, σ = 1.5, valid windows only."""
    from scipy.ndimage import correlate
    g = np.ones(11) if uniform else np.exp(-(np.arange(11) - 5) ** 2 / (2 * 1.5 ** 2))
    window = np.outer(g, g) / g.sum() ** 2
    scale = 121 / 120 if sample else 1.0

    def ssim_(x, y):
        mean = lambda image: correlate(image, window)[5:-5, 5:-5]
        mx, my = mean(x), mean(y)
        vx, vy, cxy = [scale * (mean(a * b) - ma * mb) for a, b, ma, mb in ((x, x, mx, mx), (y, y, my, my), (x, y, mx, my))]
        c1, c2 = (0.01 * data_range) ** 2, (0.03 * data_range) ** 2
        return float(((2 * mx * my + c1) * (2 * cxy + c2) / ((mx ** 2 + my ** 2 + c1) * (vx + vy + c2))).mean())
    return ssim_


def _warp(depth_scale=1.0):
    """The warp written out in NumPy (a student's own): back-project, move, project, bilinear sampling."""
    from ddp_lite.core.camera import relative_pose

    def warp(image, depth, ref, nbr):
        H, W = depth.shape
        v, u = np.mgrid[0:H, 0:W]
        rays = np.stack([u, v, np.ones_like(u)], -1).reshape(-1, 3) @ np.linalg.inv(ref.K).T
        points = rays * (depth_scale * depth.reshape(-1, 1))
        pose = relative_pose(ref, nbr)
        uvw = (points @ pose[:3, :3].T + pose[:3, 3]) @ nbr.K.T
        x, y = uvw[:, 0] / uvw[:, 2], uvw[:, 1] / uvw[:, 2]
        x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
        dx, dy = x - x0, y - y0
        out = np.zeros((H * W, image.shape[2]))
        for i, j, weight in ((0, 0, (1 - dx) * (1 - dy)), (1, 0, dx * (1 - dy)), (0, 1, (1 - dx) * dy), (1, 1, dx * dy)):
            out += weight[:, None] * image[np.clip(y0 + j, 0, image.shape[0] - 1), np.clip(x0 + i, 0, image.shape[1] - 1)]
        return out.reshape(H, W, -1)
    return warp


def _nearest(depth):
    _, (rows, cols) = ndimage.distance_transform_edt(np.isnan(depth), return_indices=True)
    return depth[rows, cols]


def _backproject(depth, K, swap=False):
    v, u = np.mgrid[0:depth.shape[0], 0:depth.shape[1]].astype(np.float64)
    if swap:
        u, v = v, u
    return np.stack([(u - K[0, 2]) / K[0, 0] * depth, (v - K[1, 2]) / K[1, 1] * depth, depth], axis=-1)


def _disparity(d, a, b, c):
    return (1 / (np.clip(d, a, b) + c) - 1 / (b + c)) / (1 / (a + c) - 1 / (b + c))


# check name → (right answer, {mistake: wrong answer})
CASES = {
    "check_psnr": (lambda a, b: 10 * np.log10(1 / np.mean((a - b) ** 2)), {
        "the MSE itself": lambda a, b: np.mean((a - b) ** 2),
        "a 255 data range": lambda a, b: 10 * np.log10(255 ** 2 / np.mean((a - b) ** 2)),
        "20 log10 of the MSE": lambda a, b: 20 * np.log10(1 / np.mean((a - b) ** 2)),
    }),
    "check_masked_mse": (lambda o, t, m: ((o - t) ** 2)[m].mean(), {
        "mean over every pixel": lambda o, t, m: ((o - t) ** 2).mean(),
        "divided by pixels, not pixels × channels": lambda o, t, m: ((o - t) ** 2)[m].sum() / m.sum(),
    }),
    "check_disparity_transform": (_disparity, {
        "plain inverse depth": lambda d, a, b, c: 1 / np.clip(d, a, b),
        "no clipping": lambda d, a, b, c: (1 / (d + c) - 1 / (b + c)) / (1 / (a + c) - 1 / (b + c)),
        "no constant": lambda d, a, b, c: _disparity(d, a, b, 0.0),
        "1 = farthest": lambda d, a, b, c: 1 - _disparity(d, a, b, c),
    }),
    "check_hole_rmse": (lambda p, g, i: np.sqrt(np.mean((p - g)[np.isnan(i)] ** 2)), {
        "RMSE over every pixel": lambda p, g, i: np.sqrt(np.mean((p - g) ** 2)),
        "MSE, no root": lambda p, g, i: np.mean((p - g)[np.isnan(i)] ** 2),
        "RMSE over the valid pixels": lambda p, g, i: np.sqrt(np.mean((p - g)[np.isfinite(i)] ** 2)),
    }),
    "check_ssim": (_ssim(), {
        "sample covariance": _ssim(sample=True),
        "uniform 11×11 window": _ssim(uniform=True),
        "data range 2": _ssim(data_range=2.0),
        "1 - mean |x - y|": lambda x, y: 1 - np.abs(x - y).mean(),
    }),
    "check_masked_l1": (lambda x, y, m: np.abs(x - y)[m].mean(), {
        "mean over every pixel": lambda x, y, m: np.abs(x - y).mean(),
        "sum, not mean": lambda x, y, m: np.abs(x - y)[m].sum(),
        "squared error": lambda x, y, m: ((x - y) ** 2)[m].mean(),
    }),
    "check_backproject": (_backproject, {
        "depth copied to x, y, z": lambda d, K: np.stack([d, d, d], axis=-1),
        "u and v swapped": lambda d, K: _backproject(d, K, swap=True),
        "fx used for both axes": lambda d, K: _backproject(d, np.array([[K[0, 0], 0, K[0, 2]], [0, K[0, 0], K[1, 2]],
                                                                      [0, 0, 1]])),
    }),
    "check_warp": (_warp(), {
        "the neighbour image unwarped": lambda img, d, r, n: img,
        "warped with the wrong depth": _warp(depth_scale=1.3),
    }),
    "check_fscore": (lambda p, r: 0.0 if p + r == 0 else 2 * p * r / (p + r), {
        "arithmetic mean": lambda p, r: (p + r) / 2,
        "geometric mean": lambda p, r: np.sqrt(p * r),
        "the smaller of the two": lambda p, r: min(p, r),
    }),
    "check_nearest_fill": (_nearest, {
        "zeros in the holes": lambda d: np.nan_to_num(d, nan=0.0),
        "mean of the valid pixels": lambda d: np.where(np.isnan(d), np.nanmean(d), d),
        "city-block nearest": lambda d: d[tuple(ndimage.distance_transform_cdt(np.isnan(d), metric="taxicab",
                                                                               return_indices=True)[1])],
    }),
    "check_d1": (_d1(), {
        "5 % of the prediction": _d1(of_truth=False),
        ">= instead of >": _d1(compare=np.greater_equal),
        "3 px only": lambda p, g: 100 * np.mean((np.abs(p - g) > 3)[np.isfinite(g)]),
        "a fraction, not a percentage": lambda p, g: _d1()(p, g) / 100,
        "NaN truths counted as good": lambda p, g: 100 * np.mean(np.nan_to_num(
            (np.abs(p - g) > 3) & (np.abs(p - g) > 0.05 * g), nan=0.0)),
    }),
}


def test_every_check_is_tested():
    assert set(CASES) == set(exercises.__all__)


@pytest.mark.parametrize("name", sorted(CASES))
def test_check_passes_the_right_answer(name, capsys):
    right, _ = CASES[name]
    assert getattr(exercises, name)(right) is True
    assert capsys.readouterr().out.startswith("PASS")


@pytest.mark.parametrize("name, mistake", [(name, mistake) for name, (_, wrongs) in sorted(CASES.items())
                                           for mistake in wrongs])
def test_check_fails_a_known_wrong_answer(name, mistake, capsys):
    wrong = CASES[name][1][mistake]
    with np.errstate(all="ignore"):
        assert getattr(exercises, name)(wrong) is False, mistake
    out = capsys.readouterr().out
    assert out.startswith("FAIL") and "case" in out, out


def test_the_written_out_ssim_and_warp_agree_with_scikit_image_and_the_kit():
    rng = np.random.default_rng(0)
    x = rng.random((20, 24))
    y = np.clip(x + 0.1 * rng.standard_normal(x.shape), 0, 1)
    for options in ({}, {"use_sample_covariance": True}, {"data_range": 2.0}):
        mine = _ssim(sample=bool(options.get("use_sample_covariance")), data_range=options.get("data_range", 1.0))
        assert np.isclose(mine(x, y), _ssim_skimage(**options)(x, y), atol=1e-6), options
    assert np.isclose(_ssim(uniform=True)(x, y), structural_similarity(x, y, win_size=11, data_range=1.0), atol=1e-6)
    from ddp_lite.core.camera import Camera, look_at
    ref = Camera.from_fov(32, 24, 60.0)
    nbr = Camera(ref.K, look_at([0.1, 0.0, 0.0], [0.0, 0.0, 3.0]), 32, 24)
    image, depth = rng.random((24, 32, 3)).astype(np.float32), np.full((24, 32), 2.5, np.float32)
    expected, valid = warp_to_reference(image, depth, ref, nbr)
    assert np.abs(_warp()(image, depth, ref, nbr) - expected)[valid].max() < 1e-4


def test_the_kit_ssim_is_not_the_students_own(capsys):
    assert exercises.check_ssim(lambda x, y: ssim(x, y)) is False
    assert "ddp_lite.method.paper.losses.ssim" in capsys.readouterr().out


def test_d1_cases_agree_with_the_hand_computed_definition():
    """The D1 check's reference for the random case is the kit's metric; both agree with _d1 here."""
    from ddp_lite.evaluation.metrics import d1_error
    rng = np.random.default_rng(0)
    gt = rng.uniform(5, 80, (10, 10))
    pred = gt + rng.normal(0, 4, gt.shape)
    assert np.isclose(100 * d1_error(pred, gt)["d1_all"], _d1()(pred, gt))


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_crashing_or_stub_answer_is_reported_not_raised(name, capsys):
    def stub(*args):
        raise NotImplementedError()

    assert getattr(exercises, name)(stub) is False
    out = capsys.readouterr().out
    assert out.startswith("FAIL") and "NotImplementedError" in out


def _depth_from_disparity(with_doffs=True, unknown_nan=True, copy=True):
    def depth(disp, f, baseline, doffs):
        d = np.array(disp, dtype=np.float64) if copy else disp
        total = d + (doffs if with_doffs else 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = f * baseline / total
        if unknown_nan:
            z[~np.isfinite(total) | (total <= 0)] = np.nan
        else:
            z[~np.isfinite(z)] = 0.0
        if not copy:
            d[...] = 0
        return z
    return depth


def test_depth_from_disparity_check(capsys):
    assert exercises.check_depth_from_disparity(_depth_from_disparity())
    assert not exercises.check_depth_from_disparity(_depth_from_disparity(with_doffs=False))
    assert "doffs" in capsys.readouterr().out
    assert not exercises.check_depth_from_disparity(_depth_from_disparity(unknown_nan=False))
    assert "NaN (unknown)" in capsys.readouterr().out
    assert not exercises.check_depth_from_disparity(_depth_from_disparity(copy=False))
    assert not exercises.check_depth_from_disparity(lambda d, f, b, o: 1 / 0)


def _resize(centre=True, scale_doffs=True, fx_by=0):
    def resize(K, doffs, sx, sy):
        K = np.array(K, dtype=np.float64)
        K[0, 0] *= (sx, sy)[fx_by]
        K[1, 1] *= sy
        K[0, 2] = (K[0, 2] + 0.5) * sx - 0.5 if centre else K[0, 2] * sx
        K[1, 2] = (K[1, 2] + 0.5) * sy - 0.5 if centre else K[1, 2] * sy
        return K, doffs * sx if scale_doffs else doffs
    return resize


def test_resize_calibration_check(capsys):
    assert exercises.check_resize_calibration(_resize())
    assert not exercises.check_resize_calibration(_resize(centre=False))
    assert "pixel centres" in capsys.readouterr().out
    assert not exercises.check_resize_calibration(_resize(scale_doffs=False))
    assert "doffs" in capsys.readouterr().out
    assert not exercises.check_resize_calibration(_resize(fx_by=1))  # fx scaled by the height factor


def test_resize_calibration_agrees_with_the_kits_camera():
    from ddp_lite.core.camera import Camera
    K = np.array([[994.978, 0, 369.0], [0, 994.978, 247.0], [0, 0, 1.0]])
    small = Camera(K, np.eye(4), 741, 500).resized(64, 48)  # the kit's own resize, independently written
    got, _ = _resize()(K, 31.086, 64 / 741, 48 / 500)
    assert np.allclose(small.K, got)


CASES["check_depth_from_disparity"] = (_depth_from_disparity(), {
    "doffs left out": _depth_from_disparity(with_doffs=False),
    "unknown as 0 m": _depth_from_disparity(unknown_nan=False),
    "the input overwritten": _depth_from_disparity(copy=False),
})
CASES["check_resize_calibration"] = (_resize(), {
    "cx·sx (pixel corners)": _resize(centre=False),
    "doffs not scaled": _resize(scale_doffs=False),
    "fx by the height factor": _resize(fx_by=1),
})


def _quantise(round_depth=False, zero_is_reading=False, copy=True):
    def quantise(depth, focal, baseline, subpixel):
        depth = np.array(depth, dtype=np.float64) if copy else depth
        if round_depth:  # the common mistake: the depth rounded instead of the disparity
            return np.round(depth * subpixel) / subpixel
        levels = np.round(focal * baseline / depth * subpixel) / subpixel
        with np.errstate(divide="ignore"):
            out = focal * baseline / levels
        out = out if zero_is_reading else np.where(levels > 0, out, np.nan)
        depth[...] = out  # a copy unless copy=False: then the caller's array is overwritten
        return depth
    return quantise


def test_kinect_quantisation_check_agrees_with_the_kits_sensor_model():
    from ddp_lite.classical.kinect import quantise_depth
    depth = np.linspace(0.5, 4.5, 40).reshape(5, 8)
    assert np.allclose(_quantise()(depth, 580.0, 0.075, 8), quantise_depth(depth), rtol=1e-6)


def _paired(stderr_ddof=1, better=np.less):
    def paired(before, after):
        difference = np.asarray(after, float) - np.asarray(before, float)
        n = difference.size
        stderr = difference.std(ddof=stderr_ddof) / np.sqrt(n) if n > 1 else 0.0
        return difference.mean(), stderr, int(better(difference, 0).sum())
    return paired


CASES["check_paired_change"] = (_paired(), {
    "the population standard deviation": _paired(stderr_ddof=0),
    "an unchanged pair counted as better": _paired(better=np.less_equal),
    "before − after": lambda before, after: _paired()(after, before),
})

CASES["check_kinect_quantisation"] = (_quantise(), {
    "the depth rounded": _quantise(round_depth=True),
    "a zero disparity kept as a reading": _quantise(zero_is_reading=True),
    "the input overwritten": _quantise(copy=False),
})


@pytest.mark.parametrize("error", [NotImplementedError(), ValueError(""), KeyError("k")], ids=repr)
def test_a_failure_message_has_no_empty_part(error, tmp_path, capsys):
    """"raised NotImplementedError:  (and 3 more)": an error without a message is named alone, in the notebook
    and in the grader, where the student's function runs in a kernel (here a namespace of this process)."""
    import re

    from ddp_lite.interface.grading_kernel import RemoteFunction

    def stub(*args):
        raise error

    namespace = {"stub": stub}

    def run(code):
        exec(code, namespace)
    remote = RemoteFunction("stub", run, tmp_path)
    for fn in (stub, remote):
        assert exercises.check_psnr(fn) is False
        out = capsys.readouterr().out
        assert type(error).__name__ in out and "StudentError" not in out, out
        assert not re.search(r":\s*(\(|$)", out), out  # no "Name: " followed by nothing
