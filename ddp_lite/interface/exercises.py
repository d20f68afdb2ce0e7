"""Checks for the notebooks' exercises: a student's function against an independent reference.

Each ``check_*`` takes the student's function, runs it on a few seeded cases, compares with a
reference that does not come from the student's code (scikit-image, SciPy, a hand-computed
value or the kit's tested implementation) and prints ``PASS`` or ``FAIL: <what is wrong>``.
It returns True or False. A check also FAILs a function that calls the kit's or a library's
implementation of that very exercise (each check names those it forbids, in its ``@_own_work(...)``
line; the rule is :mod:`ddp_lite.interface.own_work`): a one-line answer that calls
``skimage.metrics.peak_signal_noise_ratio`` is not the student's PSNR. In the notebooks each check
sits in a read-only nbgrader test cell as ``assert check_x(student_function)``: a FAIL prints what is wrong and the assert marks the cell
failed, which is what nbgrader and ``ddp-lite grade`` (``ddp_lite.interface.grading``) score.

    >>> from ddp_lite.interface.exercises import check_psnr
    >>> check_psnr(lambda a, b: 10 * np.log10(1 / np.mean((a - b) ** 2)))
    PASS psnr: matches scikit-image on 4 cases
    True
"""
from __future__ import annotations

import contextlib
import functools
import io

import numpy as np

from ..core.camera import Camera, look_at
from ..evaluation.metrics import d1_error
from ..method.paper.warp import warp_to_reference
from .own_work import call_watched

__all__ = ["check_psnr", "check_masked_mse", "check_disparity_transform", "check_hole_rmse", "check_ssim",
           "check_masked_l1", "check_backproject", "check_warp", "check_fscore", "check_nearest_fill",
           "check_d1", "check_depth_from_disparity", "check_resize_calibration", "check_kinect_quantisation",
           "check_paired_change"]


class _Watched:
    """The student's function as a check calls it: each call watched for the forbidden callables, here or,
    for a function in a grading kernel (``call_watched`` method), there."""

    def __init__(self, fn, forbidden):
        self.fn, self.forbidden, self.seen = fn, forbidden, set()

    def __call__(self, *args, **kwargs):
        if hasattr(self.fn, "call_watched"):  # grading_kernel.RemoteFunction: the kernel watches
            return self.fn.call_watched(args, kwargs, self.forbidden, self.seen)
        return call_watched(self.fn, args, kwargs, self.forbidden, self.seen)


def _own_work(*forbidden):
    """Decorate a check: it FAILs the student's function if that calls one of ``forbidden`` (dotted names
    of the kit's and libraries' implementations of the same exercise), whatever the numbers say."""
    def decorate(check):
        @functools.wraps(check)
        def run(student_fn) -> bool:
            watched = _Watched(student_fn, forbidden)
            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                verdict = check(watched)
            text = printed.getvalue()
            if not watched.seen:
                print(text, end="")
                return verdict
            label = text.split(":", 1)[0].split(" ", 1)[-1] if text.startswith(("PASS ", "FAIL ")) else check.__name__
            who = getattr(student_fn, "name", None) or getattr(student_fn, "__name__", "the function")
            print(f"FAIL {label}: {who} calls {', '.join(sorted(watched.seen))}, an implementation of this very "
                  f"exercise: write it yourself (NumPy, SciPy's building blocks)")
            return False
        run.forbidden = forbidden
        return run
    return decorate


def _raised(error: BaseException) -> str:
    """What the student's function raised, as a phrase: its type, then its message when it has one (``raise
    NotImplementedError()`` has none). From a grading kernel (``StudentError``) the phrase came ready-made."""
    message = str(error).strip()
    if type(error).__name__ == "StudentError":
        return message or "an error"
    return f"{type(error).__name__}: {message}" if message else type(error).__name__


def _report(name: str, failures: list[str], cases: int, reference: str) -> bool:
    if failures:
        print(f"FAIL {name}: {failures[0]}" + (f" (and {len(failures) - 1} more)" if len(failures) > 1 else ""))
        return False
    print(f"PASS {name}: matches {reference} on {cases} cases")
    return True


def _not_finite(got, expected=None) -> str | None:
    """The one rule every check applies to a student's result before comparing it: a NaN or an infinity
    is a failure (``nan > tol`` is False, so a comparison alone would pass a function that returns NaN),
    except a NaN where the reference itself is NaN (an unknown pixel that must stay unknown) or an
    infinity equal to the reference's. None if the result is finite where it must be, else why not."""
    try:
        got = np.asarray(got, dtype=np.float64)
    except (TypeError, ValueError):
        return None  # not numbers: the comparison says what is wrong
    allowed = np.zeros(got.shape, bool)
    if expected is not None:
        try:
            expected = np.asarray(expected, dtype=np.float64)
        except (TypeError, ValueError):
            expected = None
        if expected is not None and expected.shape == got.shape:
            allowed = (np.isnan(got) & np.isnan(expected)) | (np.isinf(got) & (got == expected))
    bad = ~np.isfinite(got) & ~allowed
    if not bad.any():
        return None
    index = tuple(int(k) for k in np.argwhere(bad)[0]) if got.ndim else ()
    return (f"got {got[index]} at index {index}{f' ({int(bad.sum())} of {bad.size} values)' if got.ndim else ''}, "
            f"expected a finite number: a NaN or an infinity never passes a check")


def _run(name, fn, cases, reference_name, compare):
    failures = []
    for i, (args, expected) in enumerate(cases):
        try:
            got = fn(*args)
        except Exception as error:  # a student's bug should be reported, not raised
            failures.append(f"case {i} raised {_raised(error)}")
            continue
        problem = _not_finite(got, expected) or compare(got, expected)
        if problem:
            failures.append(f"case {i}: {problem}")
    return _report(name, failures, len(cases), reference_name)


def _close(atol):
    def compare(got, expected):
        got = np.asarray(got, dtype=np.float64)
        expected = np.asarray(expected, dtype=np.float64)
        if got.shape != expected.shape:
            return f"shape {got.shape}, expected {expected.shape}"
        bad = ~np.isclose(got, expected, atol=atol, rtol=0, equal_nan=True)
        if bad.any():
            index = np.argwhere(bad)[0] if got.ndim else ()
            return f"got {got[tuple(index)]:.6g}, expected {expected[tuple(index)]:.6g} at index {tuple(index)}"
        return None
    return compare


@_own_work("skimage.metrics.peak_signal_noise_ratio",
           "cv2.PSNR",
           "cv2.quality.QualityPSNR_compute",
           "ddp_lite.evaluation.metrics.psnr")
def check_psnr(student_psnr) -> bool:
    """``student_psnr(a, b)`` for images in [0, 1] vs ``skimage.metrics.peak_signal_noise_ratio``."""
    from skimage.metrics import peak_signal_noise_ratio  # here, not above: it imports scipy.stats (~1 s)

    rng = np.random.default_rng(0)
    cases = []
    for shape, sigma in (((16, 20, 3), 0.01), ((16, 20, 3), 0.05), ((16, 20, 3), 0.2), ((12, 9), 0.1)):
        a = rng.random(shape)  # colour, then a grey image
        b = np.clip(a + sigma * rng.standard_normal(a.shape), 0, 1)
        cases.append(((a, b), peak_signal_noise_ratio(a, b, data_range=1.0)))
    return _run("psnr", student_psnr, cases, "scikit-image", _close(1e-6))


@_own_work("skimage.metrics.mean_squared_error",
           "ddp_lite.evaluation.metrics.rmse")
def check_masked_mse(student_mse) -> bool:
    """``student_mse(output, target, mask)`` (H, W, C), (H, W, C), (H, W) bool: mean over masked pixels
    and channels."""
    rng = np.random.default_rng(1)
    cases = []
    masks = [rng.random((8, 9)) > 0.4, rng.random((8, 9)) > 0.8, np.ones((8, 9), bool), np.zeros((8, 9), bool)]
    masks[3][2, 5] = True  # a single known pixel
    for mask in masks:
        out, target = rng.random((8, 9, 3)), rng.random((8, 9, 3))
        by_hand = sum(((out[r, c] - target[r, c]) ** 2).sum() for r, c in zip(*np.nonzero(mask))) / (mask.sum() * 3)
        cases.append(((out, target, mask), by_hand))
    return _run("masked mse", student_mse, cases, "a per-pixel loop", _close(1e-9))


@_own_work("ddp_lite.method.paper.disparity.DisparityTransform.to_disparity")
def check_disparity_transform(student_to_disparity) -> bool:
    """``student_to_disparity(depth, d_min, d_max, constant)`` → [0, 1], 1 = nearest (paper Sec. 3.2)."""
    cases = []
    for d_min, d_max, c in ((1.0, 9.0, 1.0), (2.0, 7.5, 0.0), (0.2, 25.0, 4.0)):
        depth = np.array([d_min / 2, d_min, (d_min + d_max) / 2, d_max, 2 * d_max])
        inverse = 1 / (np.clip(depth, d_min, d_max) + c)
        cases.append(((depth, d_min, d_max, c), (inverse - 1 / (d_max + c)) / (1 / (d_min + c) - 1 / (d_max + c))))
    cases.append(((np.array([4.0]), 1.0, 9.0, 1.0), np.array([0.25])))  # by hand: (1/5 - 1/10) / (1/2 - 1/10)
    return _run("disparity transform", student_to_disparity, cases, "the paper's formula", _close(1e-9))


@_own_work("ddp_lite.evaluation.metrics.hole_rmse",
           "ddp_lite.evaluation.metrics.rmse",
           "skimage.metrics.mean_squared_error",
           "skimage.metrics.normalized_root_mse")
def check_hole_rmse(student_hole_rmse) -> bool:
    """``student_hole_rmse(pred, gt, input_depth)``: RMSE over pixels that are holes (NaN) in the input."""
    gt = np.array([[1.0, 2.0], [3.0, 4.0]])
    pred = np.array([[9.0, 2.5], [3.0, 2.0]])
    inp = np.array([[1.0, np.nan], [3.0, np.nan]])
    cases = [((pred, gt, inp), np.sqrt((0.5 ** 2 + 2.0 ** 2) / 2))]
    inp2 = np.array([[np.nan, np.nan], [3.0, 4.0]])
    cases.append(((pred, gt, inp2), np.sqrt((8.0 ** 2 + 0.5 ** 2) / 2)))
    inp3 = np.array([[np.nan, 2.0], [3.0, 4.0]])  # one hole: the RMSE is its absolute error
    cases.append(((pred, gt, inp3), 8.0))
    rng = np.random.default_rng(7)
    gt4, pred4 = rng.random((9, 11)) + 1, rng.random((9, 11)) + 1
    inp4 = np.where(rng.random((9, 11)) < 0.3, np.nan, gt4)
    by_hand = np.sqrt(sum((pred4[r, c] - gt4[r, c]) ** 2 for r, c in zip(*np.nonzero(np.isnan(inp4))))
                      / np.isnan(inp4).sum())
    cases.append(((pred4, gt4, inp4), by_hand))
    return _run("hole rmse", student_hole_rmse, cases, "hand-computed values and a per-pixel loop", _close(1e-9))


@_own_work("skimage.metrics.structural_similarity",
           "cv2.quality.QualitySSIM_compute",
           "ddp_lite.method.paper.losses.ssim")
def check_ssim(student_ssim) -> bool:
    """``student_ssim(x, y)`` for grey images in [0, 1] vs scikit-image (Gaussian 11×11, σ = 1.5,
    population covariance, data range 1, mean over the windows that fit inside the image)."""
    from skimage.metrics import structural_similarity  # as in check_psnr: only where a check needs it

    rng = np.random.default_rng(2)
    cases = []
    # Low-contrast pairs come first: there the constants C1, C2 are as large as the variances, so a
    # sample covariance (÷ (N-1)) or a uniform window moves SSIM by ~1e-3, ten times the tolerance.
    for shape, contrast, noise in (((32, 40), 0.05, 0.3), ((32, 40), 0.1, 0.2), ((32, 40), 1.0, 0.3),
                                   ((24, 50), 1.0, 0.05)):
        x = 0.5 + contrast * (rng.random(shape) - 0.5)
        y = np.clip(x + contrast * noise * rng.standard_normal(shape), 0, 1)
        cases.append(((x, y), structural_similarity(x, y, gaussian_weights=True, sigma=1.5,
                                                     use_sample_covariance=False, data_range=1.0)))
    same = rng.random((20, 20))
    cases.append(((same, same.copy()), 1.0))  # identical images: exactly 1
    return _run("ssim", student_ssim, cases, "scikit-image", _close(1e-4))


@_own_work("ddp_lite.method.paper.losses.masked_l1",
           "ddp_lite.evaluation.metrics.mae")
def check_masked_l1(student_l1) -> bool:
    """``student_l1(x, y, mask)`` (H, W) arrays: mean |x - y| over mask only."""
    rng = np.random.default_rng(3)
    cases = []
    for threshold in (0.5, 0.5, 0.9, -1.0):  # the last mask is all True
        x, y, mask = rng.random((6, 7)), rng.random((6, 7)), rng.random((6, 7)) > threshold
        cases.append(((x, y, mask), sum(abs(x[r, c] - y[r, c]) for r, c in zip(*np.nonzero(mask))) / mask.sum()))
    return _run("masked L1", student_l1, cases, "a per-pixel loop", _close(1e-9))


@_own_work("ddp_lite.core.camera.backproject",
           "ddp_lite.core.camera.backproject_pixels",
           "ddp_lite.core.camera.pixel_rays",
           "ddp_lite.evaluation.fusion.points_from_depth")
def check_backproject(student_backproject) -> bool:
    """``student_backproject(depth (H, W), K)`` → camera-frame points (H, W, 3), OpenCV convention:
    u = column, v = row, pixel (0, 0) = centre of the top-left pixel."""
    cases = []
    # a square-pixel camera, then one with fx ≠ fy and cx, cy off-centre: a swapped u/v or fx/fy shows
    for K, shape in ((np.array([[50.0, 0, 15.5], [0, 50.0, 11.5], [0, 0, 1]]), (24, 32)),
                     (np.array([[40.0, 0, 9.0], [0, 65.0, 3.0], [0, 0, 1]]), (7, 20))):
        depth = np.full(shape, 2.0)
        depth[5, 7] = 4.0
        depth[1, 3] = 0.5
        expected = np.zeros((*shape, 3))
        for v in range(shape[0]):
            for u in range(shape[1]):
                z = depth[v, u]
                expected[v, u] = ((u - K[0, 2]) / K[0, 0] * z, (v - K[1, 2]) / K[1, 1] * z, z)
        cases.append(((depth, K), expected))
    return _run("backproject", student_backproject, cases, "the pinhole model, pixel by pixel", _close(1e-9))


@_own_work("ddp_lite.method.paper.warp.warp_to_reference",
           "ddp_lite.method.paper.warp.Warper.forward")
def check_warp(student_warp) -> bool:
    """``student_warp(nbr_image, ref_depth, ref_cam, nbr_cam)`` → (H, W, 3) vs the kit's tested warp
    (compared where the kit's warp is valid)."""
    rng = np.random.default_rng(4)
    ref = Camera.from_fov(32, 24, 60.0)
    failures = []
    for i, eye in enumerate(([0.1, 0.0, 0.0], [0.05, -0.05, 0.1])):
        nbr = Camera(ref.K, look_at(eye, [0.0, 0.0, 3.0]), 32, 24)
        image = rng.random((24, 32, 3)).astype(np.float32)
        depth = (2.0 + rng.random((24, 32))).astype(np.float32)
        expected, valid = warp_to_reference(image, depth, ref, nbr)
        try:
            got = np.asarray(student_warp(image, depth, ref, nbr), dtype=np.float64)
        except Exception as error:
            failures.append(f"case {i} raised {_raised(error)}")
            continue
        if got.shape != expected.shape:
            failures.append(f"case {i}: shape {got.shape}, expected {expected.shape}")
        elif _not_finite(got[valid], expected[valid]):
            failures.append(f"case {i}: on valid pixels, {_not_finite(got[valid], expected[valid])}")
        elif not np.abs(got - expected)[valid].max() <= 1e-3:
            failures.append(f"case {i}: max error {np.abs(got - expected)[valid].max():.4f} on valid pixels "
                            "(pixel centres? u is the column, v the row)")
    return _report("warp", failures, 2, "the kit's warp_to_reference")


@_own_work("scipy.stats.hmean",
           "statistics.harmonic_mean",
           "ddp_lite.evaluation.metrics.point_cloud_prf")
def check_fscore(student_fscore) -> bool:
    """``student_fscore(precision, recall)`` → the harmonic mean (0 when both are 0); works for
    fractions and for percentages alike."""
    cases = [((0.5, 0.5), 0.5), ((1.0, 0.0), 0.0), ((0.0, 0.0), 0.0), ((0.3, 0.6), 2 * 0.18 / 0.9),
             ((1.0, 1.0), 1.0), ((40.0, 50.6), 2 * 40.0 * 50.6 / 90.6)]  # the last: Table 2's UNet+RGBD+warp, %
    return _run("f-score", student_fscore, cases, "hand-computed values", _close(1e-9))


@_own_work("ddp_lite.classical.depth_fills.fill_nearest",
           "ddp_lite.classical.depth_fills.nearest_values",
           "scipy.interpolate.NearestNDInterpolator.__call__",
           "scipy.interpolate.griddata")
def check_nearest_fill(student_fill) -> bool:
    """``student_fill(depth_with_nans)`` → every hole takes the depth of a nearest valid pixel
    (Euclidean distance in pixels; any of several equally near ones is accepted); valid pixels kept."""
    rng = np.random.default_rng(5)
    failures = []
    for case in range(2):
        depth = rng.random((12, 15)) + 1.0
        depth[rng.random(depth.shape) < 0.3] = np.nan
        valid = np.isfinite(depth)
        try:
            got = np.asarray(student_fill(depth.copy()), dtype=np.float64)
        except Exception as error:
            failures.append(f"case {case} raised {_raised(error)}")
            continue
        if got.shape != depth.shape:
            failures.append(f"case {case}: shape {got.shape}, expected {depth.shape}")
            continue
        if _not_finite(got):
            failures.append(f"case {case}: {_not_finite(got)} (every hole gets a depth)")
            continue
        known, holes = np.argwhere(valid), np.argwhere(~valid)  # (N, 2), (M, 2) rows, cols
        distance = ((holes[:, None, :] - known[None, :, :]) ** 2).sum(-1)  # (M, N)
        nearest = distance == distance.min(axis=1, keepdims=True)
        candidates = np.where(nearest, depth[valid][None, :], np.nan)  # (M, N)
        ok = np.any(np.isclose(candidates, got[~valid][:, None], atol=1e-9), axis=1)
        if not np.allclose(got[valid], depth[valid]):
            failures.append(f"case {case}: valid pixels were changed")
        elif not ok.all():
            r, c = holes[np.argmin(ok)]
            failures.append(f"case {case}: hole ({r}, {c}) got {got[r, c]:.4g}, not the depth of a nearest valid pixel")
    return _report("nearest fill", failures, 2, "a brute-force nearest search")


@_own_work("ddp_lite.evaluation.metrics.d1_error")
def check_d1(student_d1) -> bool:
    """``student_d1(pred_disp, gt_disp)`` → percentage of bad pixels among those with a finite truth;
    bad = error > 3 px **and** error > 5 % of the *true* disparity (KITTI 2015)."""
    nan = np.nan
    cases = [
        # bad: 3.5 > 3 and > 0.5 ✓; 2.9 ✗; 4 > 3 but < 5 ✗; 6 > 3 and > 5 ✓; NaN truth not counted → 2 of 4
        ((np.array([13.5, 12.9, 104.0, 106.0, 1.0]), np.array([10.0, 10.0, 100.0, 100.0, nan])), 50.0),
        # strict inequalities: an error of exactly 3 px, or exactly 5 % of the truth, is not bad → 1 of 4
        ((np.array([23.0, 105.0, 64.0, 40.0]), np.array([20.0, 100.0, 60.0, 40.0])), 25.0),
        # 5 % of the truth, not of the prediction: 5.1 px on a truth of 100 is bad (5 % of 105.1 is 5.26) → 2 of 3
        ((np.array([105.1, 94.9, 50.0]), np.array([100.0, 100.0, 50.0])), 200 / 3),
        # a map (H, W) with unknown truth and no bad pixel → 0 %
        ((np.array([[10.0, 20.0], [30.0, 7.0]]), np.array([[10.5, nan], [31.0, 5.0]])), 0.0),
    ]
    rng = np.random.default_rng(6)
    gt = rng.uniform(5.0, 80.0, (12, 16))
    gt[rng.random(gt.shape) < 0.2] = nan
    pred = gt + rng.normal(0.0, 4.0, gt.shape)
    pred[np.isnan(pred)] = 1.0
    cases.append(((pred, gt), 100 * d1_error(pred, gt)["d1_all"]))  # a random map vs the kit's tested metric
    return _run("D1", student_d1, cases, "hand-computed cases and ddp_lite.evaluation.metrics.d1_error", _close(1e-9))


# The calibration of scikit-image's Middlebury 2014 pair (skimage.data.stereo_motorcycle's docstring):
# focal length px, baseline m, doffs = cx1 - cx0 px. Expected depths below were computed by hand
# (Z = f·B/(d + doffs)) and are written out as numbers, so the check does not run the formula it checks.
MOTORCYCLE_CALIBRATION = (994.978, 0.193001, 31.086)


@_own_work("ddp_lite.classical.stereo.disparity_to_depth",
           "ddp_lite.data.middlebury.MiddleburyCalib.depth")
def check_depth_from_disparity(student_depth) -> bool:
    """``student_depth(disp, f, baseline, doffs)`` → (H, W) metres: Z = f·B/(d + doffs), NaN where the
    disparity is unknown (inf or NaN, Middlebury's marker) or d + doffs ≤ 0; ``disp`` unchanged."""
    f, B, doffs = MOTORCYCLE_CALIBRATION
    disp = np.array([[100.0, 250.5, 0.0], [np.inf, np.nan, 3.0], [-20.0, -31.086, -40.0]])
    expected = np.array([[1.4649295041270614, 0.6819648312700205, 6.177435146947179],
                         [np.nan, np.nan, 5.6337425622836355], [17.32200513963558, np.nan, np.nan]])
    failures = []
    for i, (args, want) in enumerate((((disp, f, B, doffs), expected),
                                      ((disp[:1, :2] * 2, 2 * f, B, 2 * doffs), expected[:1, :2]))):
        before = args[0].copy()
        try:
            got = np.asarray(student_depth(*args), dtype=np.float64)
        except Exception as error:
            failures.append(f"case {i} raised {_raised(error)}")
            continue
        if not np.array_equal(args[0], before, equal_nan=True):
            failures.append(f"case {i}: the disparity passed in was modified")
        elif got.shape != want.shape:
            failures.append(f"case {i}: shape {got.shape}, expected {want.shape}")
        elif np.isinf(got).any():
            failures.append(f"case {i}: {_not_finite(got, want)}")
        elif not np.array_equal(np.isnan(got), np.isnan(want)):
            where = tuple(int(k) for k in np.argwhere(np.isnan(got) != np.isnan(want))[0])
            failures.append(f"case {i}: at {where} (disparity {args[0][where]}) expected "
                            f"{'NaN (unknown)' if np.isnan(want[where]) else f'{want[where]:.6g} m'}, got "
                            f"{got[where]:.6g} (NaN only where d is unknown or d + doffs ≤ 0)")
        elif not np.allclose(got[~np.isnan(want)], want[~np.isnan(want)], rtol=1e-9, atol=0):
            where = tuple(int(k) for k in np.argwhere(~np.isclose(got, want, rtol=1e-9, atol=0, equal_nan=True))[0])
            failures.append(f"case {i}: at {where} (disparity {args[0][where]}) got {got[where]:.6g} m, expected "
                            f"{want[where]:.6g} m (is doffs added to the disparity?)")
    return _report("depth_from_disparity", failures, 2, "hand-computed depths of the motorcycle calibration")


@_own_work("ddp_lite.core.camera.Camera.resized",
           "ddp_lite.data.resample.resize_view",
           "ddp_lite.data.resample.resize_scene")
def check_resize_calibration(student_resize) -> bool:
    """``student_resize(K, doffs, sx, sy)`` → (K', doffs') of the image resized by (sx, sy), pixel (0, 0)
    the centre of the top-left pixel. Reference: a point seen at full-size pixel (u, v) is seen at
    ((u + 0.5)·sx − 0.5, (v + 0.5)·sy − 0.5) after the resize; each disparity scales by sx."""
    f, B, doffs = MOTORCYCLE_CALIBRATION
    K = np.array([[f, 0.0, 369.0], [0.0, f, 247.0], [0.0, 0.0, 1.0]])  # cx, cy: near the centre of 500×741 (H×W)
    rng = np.random.default_rng(0)
    points = np.stack([rng.uniform(-1, 1, 20), rng.uniform(-1, 1, 20), rng.uniform(2, 5, 20)], axis=1)
    failures = []
    cases = ((64 / 741, 48 / 500), (128 / 741, 128 / 741), (0.5, 0.25))
    for i, (sx, sy) in enumerate(cases):
        K_before = K.copy()
        try:
            K_small, doffs_small = student_resize(K, doffs, sx, sy)
            K_small = np.asarray(K_small, dtype=np.float64)
        except Exception as error:
            failures.append(f"case {i} raised {_raised(error)}")
            continue
        if not np.array_equal(K, K_before):
            failures.append(f"case {i}: K passed in was modified")
            continue
        if K_small.shape != (3, 3):
            failures.append(f"case {i}: K' has shape {K_small.shape}, expected (3, 3)")
            continue
        if _not_finite(K_small) or _not_finite(doffs_small):
            failures.append(f"case {i}: K' or doffs': {_not_finite(K_small) or _not_finite(doffs_small)}")
            continue
        u, v = points[:, 0] / points[:, 2] * K[0, 0] + K[0, 2], points[:, 1] / points[:, 2] * K[1, 1] + K[1, 2]
        want_u, want_v = (u + 0.5) * sx - 0.5, (v + 0.5) * sy - 0.5
        projected = points @ K_small.T
        got_u, got_v = projected[:, 0] / projected[:, 2], projected[:, 1] / projected[:, 2]
        error = max(np.abs(got_u - want_u).max(), np.abs(got_v - want_v).max())
        if not error < 1e-6:
            failures.append(f"case {i} (sx {sx:.4g}, sy {sy:.4g}): K' puts points up to {error:.3g} px off where the "
                            f"resized image shows them (pixel centres: u' = (u + 0.5)·sx − 0.5)")
            continue
        d = 60.0  # a disparity at full size; its depth must not change with the image size
        depth_full = f * B / (d + doffs)
        depth_small = K_small[0, 0] * B / (d * sx + float(doffs_small))
        if not abs(depth_small - depth_full) < 1e-9 * depth_full:
            failures.append(f"case {i}: doffs' {float(doffs_small):.6g} px turns a disparity of {d * sx:.4g} px into "
                            f"{depth_small:.6g} m, but the full-size pixel says {depth_full:.6g} m (doffs is a "
                            f"difference of u coordinates)")
    return _report("resize_calibration", failures, len(cases), "pixel-centre resizing of projected points")


@_own_work("ddp_lite.classical.kinect.quantise_depth")
def check_kinect_quantisation(student_quantise) -> bool:
    """``student_quantise(depth, focal, baseline, subpixel)`` → (H, W) metres as a structured-light
    sensor reads them: disparity f·b/z rounded to 1/subpixel px, back to depth; NaN stays NaN, and so
    does a disparity rounded to 0; ``depth`` unchanged. Reference: hand-computed values."""
    # f·b = 10 px·m. z = 2 → d = 5 → 2; z = 3 → d = 3.33 → 3 (subpixel 1) → 3.333 m; → 3.375 (subpixel 8)
    # → 2.962963 m; z = 40 → d = 0.25 → 0 at subpixel 1 (no reading); z = 30 → 0.333 → 0.375 → 26.667 m.
    depth = np.array([[2.0, 3.0], [np.nan, 40.0], [30.0, 0.5]])
    cases = ((depth, 100.0, 0.1, 1, np.array([[2.0, 10 / 3], [np.nan, np.nan], [np.nan, 0.5]])),
             (depth, 100.0, 0.1, 8, np.array([[2.0, 10 / 3.375], [np.nan, 40.0], [10 / 0.375, 0.5]])),
             (depth, 580.0, 0.075, 8, 43.5 / (np.round(43.5 / depth * 8) / 8)))
    failures = []
    for i, (z, f, b, subpixel, want) in enumerate(cases):
        before = z.copy()
        try:
            got = np.asarray(student_quantise(z, f, b, subpixel), dtype=np.float64)
        except Exception as error:
            failures.append(f"case {i} raised {_raised(error)}")
            continue
        if not np.array_equal(z, before, equal_nan=True):
            failures.append(f"case {i}: the depth passed in was modified")
        elif got.shape != want.shape:
            failures.append(f"case {i}: shape {got.shape}, expected {want.shape}")
        elif _not_finite(got, want):
            failures.append(f"case {i}: {_not_finite(got, want)}")
        elif not np.allclose(got, want, rtol=1e-5, atol=0, equal_nan=True):
            where = tuple(int(k) for k in np.argwhere(~np.isclose(got, want, rtol=1e-5, atol=0, equal_nan=True))[0])
            failures.append(f"case {i} (f {f:g} px, b {b:g} m, 1/{subpixel} px): at {where} (depth {z[where]:g} m) "
                            f"got {got[where]:.6g}, expected {want[where]:.6g} (round the disparity, not the depth; "
                            f"a disparity rounded to 0 is no reading)")
    return _report("kinect quantisation", failures, len(cases), "hand-computed readings")


@_own_work("ddp_lite.studies.additions.paired_change")
def check_paired_change(student_paired) -> bool:
    """``student_paired(before, after)`` → (mean of after − before, its standard error (sample standard
    deviation / √n; 0 for one pair), how many pairs got better, i.e. lower) for two equal-length
    sequences of errors of the same fits (same case and seed). Reference: hand-computed values."""
    # differences −0.1, −0.3, +0.1: mean −0.1; sample std 0.2 → stderr 0.2/√3; two of three lower
    cases = [(([1.0, 1.2, 0.9], [0.9, 0.9, 1.0]), (-0.1, 0.2 / np.sqrt(3), 2)),
             (([2.0, 2.0], [2.0, 2.0]), (0.0, 0.0, 0)),  # equal is not better
             (([1.5], [1.2]), (-0.3, 0.0, 1)),
             ((np.array([1.0, 1.0, 1.0, 1.0]), np.array([1.5, 0.5, 1.5, 0.5])), (0.0, 0.5 / np.sqrt(4) * np.sqrt(4 / 3), 2))]
    return _run("paired change", student_paired, cases, "hand-computed values", _close(1e-9))
