"""Classical completion baselines: exact where the method is exact (planes), close where it is
not, colour-guided where it should be, and the same contract (finite, float32, input untouched)."""
import cv2
import numpy as np
import pytest

from ddp_lite.classical.baselines import BASELINES, fill
from ddp_lite.classical.depth_fills import fill_linear, fill_nearest, fill_telea
from ddp_lite.classical.guided_fills import fill_colorization
from ddp_lite.evaluation.metrics import hole_rmse

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


def _brute_force_guided_filter(guide, target, weight, r, eps):
    """He et al.'s guided filter with per-pixel weights, one window at a time: a weighted ridge regression
    per window (numpy lstsq), then each pixel averages the windows over it, weighted by their mean weight.
    The border reflects as scipy's 'reflect' (numpy's 'symmetric')."""
    Hs, Ws, C = guide.shape
    pad = lambda x: np.pad(x, [(r, r), (r, r)] + [(0, 0)] * (x.ndim - 2), mode="symmetric")
    G, P, M = pad(guide), pad(target), pad(weight)
    a, b, w = np.zeros((Hs, Ws, C)), np.zeros((Hs, Ws)), np.zeros((Hs, Ws))
    for y in range(Hs):
        for x in range(Ws):
            g = G[y:y + 2 * r + 1, x:x + 2 * r + 1].reshape(-1, C)
            p = P[y:y + 2 * r + 1, x:x + 2 * r + 1].ravel()
            m = M[y:y + 2 * r + 1, x:x + 2 * r + 1].ravel()
            w[y, x] = m.mean()
            if w[y, x] == 0:
                continue
            # minimise Σ m (a·g + b − p)² / Σ m + eps |a|²: rows scaled by sqrt(m / Σ m), plus the ridge rows
            s = np.sqrt(m / m.sum())[:, None]
            A = np.vstack([np.hstack([g, np.ones((len(p), 1))]) * s, np.hstack([np.sqrt(eps) * np.eye(C), np.zeros((C, 1))])])
            coef = np.linalg.lstsq(A, np.concatenate([p * s[:, 0], np.zeros(C)]), rcond=None)[0]
            a[y, x], b[y, x] = coef[:C], coef[C]
    A_, B_, W_ = pad(a * w[..., None]), pad(b * w), pad(w)
    out = np.zeros((Hs, Ws))
    for y in range(Hs):
        for x in range(Ws):
            total = W_[y:y + 2 * r + 1, x:x + 2 * r + 1].sum()
            out[y, x] = (A_[y:y + 2 * r + 1, x:x + 2 * r + 1].sum(axis=(0, 1)) @ guide[y, x]
                         + B_[y:y + 2 * r + 1, x:x + 2 * r + 1].sum()) / total
    return out


def test_guided_filter_fill_matches_a_window_by_window_regression():
    from ddp_lite.classical.guided_fills import fill_guided_filter
    rng = np.random.default_rng(3)
    rgb = rng.random((9, 11, 3))
    depth = 2.0 + rgb @ np.array([0.5, -0.3, 0.2]) + 0.05 * rng.standard_normal((9, 11))
    holes = np.zeros((9, 11), bool)
    holes[::3, 1::4] = True  # isolated holes: every one is reached at the first radius
    depth[holes] = np.nan
    out = fill_guided_filter(depth, rgb, radius=1, eps=1e-2)
    unclamped = _brute_force_guided_filter(rgb, np.where(holes, 0.0, depth), (~holes).astype(float), 1, 1e-2)
    expected = unclamped.copy()
    # each pixel within the valid depth its windows saw: the 5×5 square around it, cut at the image's border
    for y, x in zip(*np.nonzero(holes)):
        seen = depth[max(0, y - 2):y + 3, max(0, x - 2):x + 3]
        expected[y, x] = np.clip(expected[y, x], np.nanmin(seen), np.nanmax(seen))
    assert np.abs(out - unclamped)[holes].max() > 0.05  # the clamp matters here
    np.testing.assert_allclose(out[holes], expected[holes], rtol=0, atol=1e-5)


def test_guided_filter_fill_reproduces_depth_affine_in_colour():
    from ddp_lite.classical.guided_fills import fill_guided_filter
    v, u = np.mgrid[0:H, 0:W]
    rgb = np.stack([u / W, v / H, 0.5 + 0.3 * np.sin(u / 1.5)], axis=2)
    gt = 1.5 + 0.8 * rgb[..., 0] - 0.4 * rgb[..., 1] + 0.2 * rgb[..., 2]  # not planar in (u, v): sin(u / 1.5)
    depth = gt.copy()
    holes = (v % 8 >= 3) & (v % 8 < 6) & (u % 8 >= 3) & (u % 8 < 6)  # 3×3 holes off the border: every 5×5 window fits exactly
    depth[holes] = np.nan
    out = fill_guided_filter(depth, rgb, radius=2, eps=1e-9)
    np.testing.assert_allclose(out, gt, atol=1e-4)
    assert np.abs(fill_linear(depth) - gt)[holes].max() > 1e-2  # where a colour-blind fill is not exact


def _two_regions():
    """A dark left half and a bright right half, depth 1 m and 3 m, holes on both sides of the edge."""
    rgb = np.zeros((H, W, 3), np.float32)
    rgb[:, W // 2:] = 0.9
    gt = np.where(np.arange(W)[None, :] < W // 2, 1.0, 3.0) * np.ones((H, 1))
    depth = gt.copy()
    depth[12:36, W // 2 - 12:W // 2 + 12] = np.nan  # a hole straddling the colour (and depth) edge
    return rgb, depth, gt


def test_bilateral_solver_does_not_cross_a_colour_edge():
    from ddp_lite.classical.guided_fills import fill_bilateral_solver
    rgb, depth, gt = _two_regions()
    out = fill_bilateral_solver(depth, rgb)
    np.testing.assert_allclose(out, gt, atol=1e-3)  # each side of the hole takes its own region's depth
    assert np.abs(fill_linear(depth) - gt).max() > 0.5  # where a colour-blind fill blends the two


def test_bilateral_solver_keeps_a_constant_and_goes_smoothly_between_two_values():
    from ddp_lite.classical.guided_fills import fill_bilateral_solver
    depth = np.full((H, W), 2.5)
    depth[10:30, 10:40] = np.nan
    np.testing.assert_allclose(fill_bilateral_solver(depth, _grey()), 2.5, atol=1e-5)
    # one colour everywhere: the fill between a 1 m left column and a 2 m right column is monotone in u,
    # between the two (a smoothness prior, not a copy of either side)
    ramp = np.full((H, W), np.nan)
    ramp[:, 0], ramp[:, -1] = 1.0, 2.0
    out = fill_bilateral_solver(ramp, _grey())
    row = out[H // 2]
    assert np.all(np.diff(row) >= -1e-6) and 1.3 < row[W // 2] < 1.7


def test_guided_fills_refuse_bad_parameters_and_need_the_image():
    from ddp_lite.classical.guided_fills import fill_bilateral_solver, fill_guided_filter
    depth, _, _ = _ramp()
    for call, match in ((lambda: fill_guided_filter(depth, _grey(), radius=0), "radius must be a positive integer"),
                        (lambda: fill_guided_filter(depth, _grey(), radius=1.5), "radius"),
                        (lambda: fill_guided_filter(depth, _grey(), eps=0.0), "eps must be a positive number"),
                        (lambda: fill_bilateral_solver(depth, _grey(), lam=-1.0), "lam must be a positive"),
                        (lambda: fill_bilateral_solver(depth, _grey(), sigma_xy=np.nan), "sigma_xy"),
                        (lambda: fill_bilateral_solver(depth), "rgb is required"),
                        (lambda: fill_guided_filter(depth), "rgb is required")):
        with pytest.raises(ValueError, match=match):
            call()


def test_the_colorization_fill_zeroes_the_affinity_hole_term():
    """The kit's affinity term (hole_losses.affinity_loss) is the colorization system's residual in the holes:
    the fill scipy solves for makes it vanish there, a colour-blind fill does not."""
    import torch
    from ddp_lite.classical.guided_fills import NEIGHBOUR_OFFSETS, colorization_affinities
    from ddp_lite.method.kit.hole_losses import affinity_loss
    rgb, depth, gt = _two_regions()
    rgb = rgb + 0.05 * np.random.default_rng(0).random(rgb.shape).astype(np.float32)  # texture on both sides
    holes = np.isnan(depth)
    weights = torch.from_numpy(colorization_affinities(rgb))[None]  # (1, 8, H, W)
    region = torch.from_numpy(holes.astype(np.float32))[None, None]

    def energy(filled):
        return affinity_loss(torch.from_numpy(filled.astype(np.float32))[None, None], weights, NEIGHBOUR_OFFSETS,
                             region, region.sum()).item()
    zero = energy(fill_colorization(depth, rgb))
    assert zero < 1e-4  # float32 rounding of metre-sized values
    assert energy(fill_linear(depth)) > 100 * zero
