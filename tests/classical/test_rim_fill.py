"""The linear fill `ddp-lite complete` compares against: triangulating the holes' rim only."""
import numpy as np

from ddp_lite.classical.depth_fills import fill_linear_from_rim


def _holes(depth):
    out = depth.copy()
    out[5:15, 4:12] = np.nan  # an enclosed hole
    out[20:, 25:] = np.nan  # one at the corner: outside the rim's hull, nearest there
    return out


def test_exact_on_a_plane_and_above_a_convex_surface():
    v, u = np.mgrid[0:30, 0:40].astype(np.float32)
    plane = 2.0 + 0.03 * u - 0.02 * v  # affine: any linear interpolation is exact inside the hull
    filled = fill_linear_from_rim(_holes(plane))
    np.testing.assert_allclose(filled[5:15, 4:12], plane[5:15, 4:12], atol=1e-5)
    bowl = 2.0 + 0.002 * ((u - 8) ** 2 + (v - 10) ** 2)  # convex: a chord lies above the surface
    depth = _holes(bowl)
    filled = fill_linear_from_rim(depth)
    inside = np.zeros_like(bowl, bool)
    inside[5:15, 4:12] = True
    assert np.all(filled[inside] >= bowl[inside] - 1e-5) and np.any(filled[inside] > bowl[inside] + 1e-3)
    assert np.array_equal(filled[np.isfinite(depth)], depth[np.isfinite(depth)])  # valid pixels kept
    assert np.all(np.isfinite(filled))


def test_the_input_is_not_modified():
    depth = _holes(np.full((30, 40), 3.0, np.float32))
    before = depth.copy()
    fill_linear_from_rim(depth)
    np.testing.assert_array_equal(depth, before)
