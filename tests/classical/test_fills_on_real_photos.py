"""The classical fills on the real Middlebury pair scikit-image ships (Motorcycle, pooled to 62×92): none
worse than copying the nearest valid pixel, and none overshooting the depth around a hole."""
import numpy as np
import pytest

from ddp_lite.classical.baselines import BASELINES
from ddp_lite.classical.depth_fills import fill_biharmonic, fill_cubic, fill_nearest
from ddp_lite.classical.guided_fills import fill_guided_filter
from ddp_lite.studies.real_cases import REAL_HOLES, make_real_case


@pytest.fixture(scope="module")
def real_cases():
    """{holes: (disparity input (H, W) px with NaN holes, true disparity (H, W) px, rgb, scored (H, W) bool)}."""
    out = {}
    for holes in REAL_HOLES:
        case = make_real_case(holes, factor=8)
        out[holes] = (case.fb / case.depth, case.fb / case.gt, case.rgb, case.scored_holes)
    return out


def _rmse(filled, truth, scored):
    return float(np.sqrt(np.mean((filled[scored] - truth[scored]) ** 2)))


def test_the_guided_filter_does_not_extrapolate_its_colour_model_across_a_blob(real_cases):
    # an affine colour model fitted to the few valid pixels at a blob's rim, carried into the blob and
    # beyond by windows of doubled radius, was worse than nearest here (1.41 px against 1.21)
    disparity, truth, rgb, scored = real_cases["blobs-1"]
    nearest = _rmse(fill_nearest(disparity), truth, scored)
    assert _rmse(fill_guided_filter(disparity, rgb), truth, scored) < 0.95 * nearest  # measured 1.08 px: 0.90×


KNOWN_WORSE = {"cross-bilateral": "a mean over a 5 px disc blends the two sides of a depth edge "
                                  "(blobs-3 1.14×, occlusion 1.01× nearest); it does not extrapolate",
               "ebi": "shift-map pastes whole patches of valid depth, often from the wrong surface "
                      "(1.03× to 2.2× nearest on all five hole kinds)",
               "fbf": "a Fourier model fitted around holes as large as FSR's blocks, on 64 levels "
                      "(blobs-1 1.16×, blobs-2 1.15×, sgbm 1.05× nearest)",
               "fast-global-smoother": "its λ and σ were chosen at 250×370; at 62×92 a blob's fill spreads across "
                                       "surfaces (blobs-1 1.15×, blobs-3 1.01× nearest)"}


@pytest.mark.parametrize("method", [pytest.param(m, marks=pytest.mark.xfail(reason=KNOWN_WORSE[m], strict=True))
                                    if m in KNOWN_WORSE else m for m in sorted(BASELINES)])
def test_no_fill_is_worse_than_nearest_on_any_real_hole_kind(real_cases, method):
    worse = {}
    for holes, (disparity, truth, rgb, scored) in real_cases.items():
        error, nearest = (_rmse(f(disparity, rgb), truth, scored) for f in (BASELINES[method], fill_nearest))
        if error > nearest:
            worse[holes] = round(error / nearest, 3)
            break  # one hole kind worse fails the test: the known-worse fills (KNOWN_WORSE) stop here
    assert not worse, f"{method} is worse than nearest (ratio) on {worse}"


def test_the_cubic_fill_stays_between_the_depths_around_a_hole_across_a_step():
    # a 1 m / 3 m step with a hole across it: Clough-Tocher's gradients, estimated across the step,
    # overshoot it (to 0.50 m here unclamped), depth no pixel around the hole has
    v, u = np.mgrid[0:40, 0:40]
    depth = np.where(u < 20, 1.0, 3.0) + 0.002 * v
    hole = (u - 20) ** 2 + (v - 20) ** 2 < 12 ** 2
    depth[hole] = np.nan
    rim = ~hole & ((u - 20) ** 2 + (v - 20) ** 2 < 14 ** 2)
    out = fill_cubic(depth)[hole]
    assert depth[rim].min() <= out.min() and out.max() <= depth[rim].max()


def test_the_biharmonic_fill_stays_within_the_rim_of_a_real_blob():
    # the biharmonic surface has no maximum principle: on this 125×185 blob pattern it overshot a depth
    # edge (1.73 px, 1.28× nearest); clamped to each hole's rim it is 1.27 px
    case = make_real_case("blobs-2", factor=4)
    disparity, truth = case.fb / case.depth, case.fb / case.gt
    nearest = _rmse(fill_nearest(disparity), truth, case.scored_holes)
    assert _rmse(fill_biharmonic(disparity), truth, case.scored_holes) < nearest
