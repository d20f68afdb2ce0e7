"""Masked arrays (``np.ma``): a mask means unknown everywhere, in the checks, ``merge``, every metric, the
disparity range and the warp, whatever lies under it; a masked colour image or integer depth is refused.
The refusals use ``bad_input_harness``.
"""
from __future__ import annotations

import numpy as np
import pytest

from bad_input_harness import H, W, CaseList, camera, depth, refusal_test, rgb, tiny
from ddp_lite.core.camera import look_at
from ddp_lite.core.checks import check_depth
from ddp_lite.method.complete import complete_depth
from ddp_lite.method.paper.disparity import DisparityTransform
from ddp_lite.method.result import merge

_SIDE = look_at((0.2, 0.0, 0.0), (0.0, 0.0, 2.0))

CASES = CaseList()
case = CASES.case

case("masked colour", TypeError, "rgb")(
    lambda tmp: (lambda: complete_depth(np.ma.masked_less(rgb(), 0.5), depth(), variant="rgbd", config=tiny())))
case("masked integer depth", TypeError, "depth")(
    lambda tmp: (lambda: check_depth(np.ma.masked_equal(np.full((H, W), 2, np.int32), 0))))


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)


def test_masked_depth_is_a_hole_everywhere():
    """np.ma: masked = hole (NaN), whatever lies under the mask; the same in merge()."""
    raw = np.full((H, W), 2.0, np.float32)
    raw[:5] = 123.0  # garbage under the mask
    masked = np.ma.masked_array(raw, mask=np.zeros((H, W), bool))
    masked[:5] = np.ma.masked
    checked = check_depth(masked)
    assert np.isnan(checked[:5]).all() and (checked[5:] == 2.0).all()
    filled = merge(masked, np.full((H, W), 3.0, np.float32))
    assert (filled[:5] == 3.0).all() and (filled[5:] == 2.0).all()
    half = np.ma.masked_array(np.full((H, W), 3.0), mask=np.zeros((H, W), bool))
    half[:2] = np.ma.masked  # a masked fill: no value there, a hole in the merge too
    merged = merge(masked, half)
    assert np.isnan(merged[:2]).all() and (merged[2:5] == 3.0).all()
    assert (raw[:5] == 123.0).all()  # the caller's data untouched


def test_masked_arrays_are_honoured_wherever_depth_is_scored_or_warped():
    """A masked array's mask means unknown everywhere, not only in the fit: every metric, the disparity
    range and the warp give exactly what they give for the same array with NaN under the mask."""
    from ddp_lite.evaluation import metrics
    from ddp_lite.method.paper.warp import warp_to_reference
    raw = np.full((H, W), 2.0)
    raw[:, W // 2:] = 3.0  # a depth edge, so edge_band and texture_leakage have something to see
    masked = np.ma.masked_array(raw.copy(), mask=np.zeros((H, W), bool))
    masked[:5] = np.ma.masked
    masked.data[:5] = 99.0  # garbage under the mask
    nan = raw.copy()
    nan[:5] = np.nan  # the reference: the kit's own hole marker
    pred = np.full((H, W), 2.5)
    transform = DisparityTransform(1.0, 4.0)
    assert DisparityTransform.from_depth(masked) == DisparityTransform.from_depth(nan)
    assert metrics.rmse(pred, masked) == metrics.rmse(pred, nan)
    assert metrics.mae(masked, nan, mask=np.isfinite(nan)) == 0.0
    assert metrics.psnr(pred, masked, data_range=1.0) == metrics.psnr(pred, nan, data_range=1.0)
    assert metrics.disparity_rmse(pred, masked, np.ones((H, W), bool), transform) == \
        metrics.disparity_rmse(pred, nan, np.ones((H, W), bool), transform)
    filled = np.where(np.isnan(nan), 2.0, nan)
    assert metrics.texture_leakage(filled, np.ma.masked_array(filled, mask=masked.mask), transform) == \
        metrics.texture_leakage(filled, filled, transform)
    ref, nbr = camera(), camera(_SIDE)
    image = rgb()
    for a, b in zip(warp_to_reference(image, masked, ref, nbr), warp_to_reference(image, nan, ref, nbr)):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(TypeError, match="nbr_image"):
        warp_to_reference(np.ma.masked_less(image, 0.5), nan, ref, nbr)
    assert (masked.data[:5] == 99.0).all()  # the caller's array untouched
