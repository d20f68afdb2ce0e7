"""Classical completion baselines: exact where the method is exact (planes), close where it is
not, colour-guided where it should be, and the same contract (finite, float32, input untouched)."""
import cv2
import numpy as np
import pytest

from ddp_lite.baselines import BASELINES, fill, fill_colorization, fill_linear, fill_nearest, fill_telea
from ddp_lite.metrics import hole_rmse

H, W = 48, 64


def _ramp():
    """z = 2 + 0.01·u + 0.005·v metres (a tilted plane) with interior holes: a disc and a rectangle."""
    v, u = np.mgrid[0:H, 0:W]
    gt = (2.0 + 0.01 * u + 0.005 * v).astype(np.float32)
    holes = ((u - 20) ** 2 + (v - 20) ** 2 < 8 ** 2) | ((u >= 40) & (u < 52) & (v >= 10) & (v < 38))
    depth = gt.copy()
    depth[holes] = np.nan
    return depth, gt, holes


def _grey(value=0.5):
    return np.full((H, W, 3), value, np.float32)


@pytest.mark.parametrize("method", sorted(BASELINES))
def test_every_baseline_keeps_the_contract(method):
    depth, gt, holes = _ramp()
    rgb = _grey()
    before = depth.copy(), rgb.copy()
    out = fill(depth, rgb, method=method)
    assert out.dtype == np.float32 and out.shape == depth.shape
    assert np.all(np.isfinite(out))
    np.testing.assert_array_equal(out[~holes], depth[~holes])  # valid input pixels are kept exactly
    np.testing.assert_array_equal(depth, before[0])  # inputs untouched
    np.testing.assert_array_equal(rgb, before[1])
    assert BASELINES[method](depth, rgb).tobytes() == out.tobytes()  # fill() is just a lookup


@pytest.mark.parametrize("method", ["linear", "cubic", "biharmonic"])
def test_exact_methods_reproduce_a_plane(method):
    depth, gt, holes = _ramp()
    out = fill(depth, method=method)
    assert np.abs(out - gt)[holes].max() < 1e-4  # measured: ~2e-7 m (float32 rounding)


def test_inpainting_is_within_a_few_centimetres_on_the_ramp():
    depth, gt, holes = _ramp()
    # measured on this ramp (slope 1 cm/px, holes up to 16 px across): Telea RMSE 2.4 cm
    # (max 4.9 cm), Navier-Stokes 2.2 cm (max 4.9 cm), nearest 3.1 cm (max 8 cm). Telea's fast
    # marching copies a weighted mean of its neighbours with no linear extrapolation, so a ramp
    # bends inside the hole.
    assert hole_rmse(fill(depth, method="telea"), gt, holes) < 0.035
    assert hole_rmse(fill(depth, method="navier-stokes"), gt, holes) < 0.035
    # why we quantise to uint16: OpenCV's Telea on float32 metres adds a gradient term worth
    # up to ~1.4 *units*, i.e. metres (measured RMSE here: 0.96 m)
    naive = cv2.inpaint(np.nan_to_num(depth, nan=0.0), holes.astype(np.uint8), 5, cv2.INPAINT_TELEA)
    assert hole_rmse(naive, gt, holes) > 10 * hole_rmse(fill_telea(depth), gt, holes)


def test_linear_falls_back_to_nearest_outside_the_convex_hull():
    depth, gt, _ = _ramp()
    depth[:6, :6] = np.nan  # the corner is outside the hull of the valid pixels
    out = fill_linear(depth)
    assert np.all(np.isfinite(out))
    np.testing.assert_array_equal(out[0, 0], fill_nearest(depth)[0, 0])


def test_colorization_fills_a_ramp_under_a_constant_colour():
    depth, gt, holes = _ramp()
    out = fill_colorization(depth, _grey())
    # flat colour: equal weights, a discrete harmonic fill, exact on a plane away from the border
    assert np.abs(out - gt)[holes].max() < 1e-3  # measured ~2e-7 m


def test_colorization_respects_a_colour_edge_where_nearest_does_not():
    rgb = np.zeros((H, W, 3), np.float32)
    rgb[:, :32] = (0.8, 0.2, 0.2)  # red near object on the left,
    rgb[:, 32:] = (0.2, 0.2, 0.8)  # blue far wall on the right
    gt = np.where(np.arange(W)[None, :] < 32, 1.0, 2.0).repeat(H, 0).astype(np.float32)
    depth = gt.copy()
    holes = np.zeros((H, W), bool)
    holes[12:36, 32:46] = True  # a hole in the far half that touches the colour (and depth) edge
    depth[holes] = np.nan
    colour_fill, nearest_fill = fill_colorization(depth, rgb), fill_nearest(depth)
    assert np.abs(colour_fill - 2.0)[holes].max() < 0.05  # stays on the far wall
    # measured hole RMSE (m): colorization 0.002; nearest 0.61, linear 0.48, biharmonic 0.47,
    # Telea 0.54: every colour-blind method bleeds the near depth into the hole
    assert hole_rmse(nearest_fill, gt, holes) > 0.4
    assert hole_rmse(colour_fill, gt, holes) < 0.1 * hole_rmse(nearest_fill, gt, holes)


def test_nearest_on_a_row():
    np.testing.assert_array_equal(fill_nearest(np.array([[1.0, np.nan, np.nan, 4.0]])), [[1.0, 1.0, 4.0, 4.0]])


def test_bad_inputs_raise_clear_errors():
    depth, _, _ = _ramp()
    with pytest.raises(ValueError, match=r"depth must be \(H, W\)"):
        fill(depth[None])
    with pytest.raises(TypeError, match="float"):
        fill(np.ones((4, 4), np.int32))
    with pytest.raises(ValueError, match="at least 1 valid"):
        fill_nearest(np.full((4, 4), np.nan))
    two = np.full((4, 4), np.nan)
    two[0, 0], two[3, 3] = 1.0, 2.0
    with pytest.raises(ValueError, match="at least 3 valid"):
        fill(two, method="linear")
    line = np.full((4, 4), np.nan)
    line[1] = 2.0  # valid pixels on one line: no triangle to interpolate over
    with pytest.raises(ValueError, match="one line"):
        fill(line, method="linear")
    with pytest.raises(ValueError, match="inf"):
        fill(np.where(np.isnan(depth), np.inf, depth))
    with pytest.raises(ValueError, match=r"rgb must be \(H, W, 3\)"):
        fill(depth, np.zeros((H, W + 1, 3)), method="telea")
    with pytest.raises(ValueError, match="rgb is required"):
        fill(depth, method="colorization")
    with pytest.raises(ValueError, match="method must be one of"):
        fill(depth, method="bilateral")
