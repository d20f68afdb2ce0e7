"""The real Middlebury pair and its completion cases: calibration against the docstring's formula, the
right view warped through the truth onto the left, pooling against hand-computed blocks, and holes
where SGBM really fails."""
import numpy as np
import pytest
from skimage import data

from ddp_lite.core.camera import Camera
from ddp_lite.data.middlebury import load_motorcycle
from ddp_lite.studies.real_cases import REAL_HOLES, make_real_case, pool_scene
from ddp_lite.core.views import Scene, View
from ddp_lite.method.paper.warp import warp_to_reference


@pytest.fixture(scope="module")
def motorcycle():
    return load_motorcycle()


def test_motorcycle_depth_follows_the_calibration_of_the_docstring(motorcycle):
    _, _, disparity = data.stereo_motorcycle()
    disparity = np.where(np.isfinite(disparity), disparity, np.nan)  # its unknown marker is inf
    v, u = 300, 300
    assert np.isfinite(disparity[v, u])
    expected = 994.978 * 0.193001 / (disparity[v, u] + 31.086)  # Z = f·B / (d + doffs), metres
    assert motorcycle[0].depth[v, u] == pytest.approx(expected, rel=1e-6)
    assert np.isnan(motorcycle[0].depth[~np.isfinite(disparity)]).all()
    K1 = motorcycle.right[0].camera.K
    assert K1[0, 2] == pytest.approx(311.193 + 31.086) and motorcycle.meta["doffs"] == pytest.approx(31.086)


def test_the_right_view_warped_through_the_true_depth_lands_on_the_left_view(motorcycle):
    left, right = motorcycle[0], motorcycle.right[0]
    warped, valid = warp_to_reference(right.rgb, left.depth, left.camera, right.camera)
    error = np.abs(warped - left.rgb).mean(axis=2)[valid]
    # the same warp with the principal points equal (doffs ignored) lands 31 px off
    wrong = Camera(left.camera.K, right.camera.cam_from_world, right.camera.width, right.camera.height)
    warped_wrong, valid_wrong = warp_to_reference(right.rgb, left.depth, left.camera, wrong)
    error_wrong = np.abs(warped_wrong - left.rgb).mean(axis=2)[valid_wrong]
    assert np.median(error) < 0.03 and np.median(error_wrong) > 2 * np.median(error)


def test_pooling_takes_block_means_of_colour_and_of_inverse_depth():
    K = np.array([[100.0, 0.0, 3.5], [0.0, 100.0, 3.5], [0.0, 0.0, 1.0]])
    rng = np.random.default_rng(0)
    depth = rng.uniform(1.0, 3.0, (8, 8)).astype(np.float32)
    depth[0, 0] = np.nan  # 1 of 16 unknown: still pooled (≥ 3/4 known)
    depth[4:6, 4:8] = np.nan  # 8 of 16 unknown: a hole
    rgb = rng.random((8, 8, 3)).astype(np.float32)
    view = View(rgb, depth, Camera(K, np.eye(4), 8, 8))
    pooled = pool_scene(Scene("t", [view], [view], {"baseline": 0.1, "doffs": 8.0}), 4)
    block = depth[:4, :4]
    assert pooled[0].depth[0, 0] == pytest.approx(1.0 / np.nanmean(1.0 / block), rel=1e-6)
    assert np.isnan(pooled[0].depth[1, 1])
    np.testing.assert_allclose(pooled[0].rgb[0, 1], rgb[:4, 4:].mean(axis=(0, 1)), rtol=1e-6)
    # the pooled pixel (0, 0) sees what the full-size image sees at the centre of its block, (1.5, 1.5)
    K2 = pooled[0].camera.K
    assert K2[0, 0] == pytest.approx(25.0) and (1.5 - K[0, 2]) / K[0, 0] == pytest.approx((0 - K2[0, 2]) / K2[0, 0])
    assert pooled.meta["doffs"] == pytest.approx(2.0) and pooled.meta["baseline"] == 0.1


@pytest.mark.parametrize("holes", REAL_HOLES)
def test_real_cases_score_only_known_truth_and_keep_their_size(holes):
    case = make_real_case(holes, factor=4)
    assert case.depth.shape == case.gt.shape == (125, 185) and case.rgb.shape == (125, 185, 3)
    assert not np.isfinite(case.gt[case.scored_holes]).sum() < case.scored_holes.sum()  # all scored truth known
    assert 0.05 < case.scored_holes.mean() < 0.35
    assert case.rmse_px(case.gt) == 0.0
    assert case.depth_source == ("stereo" if holes == "sgbm" else "clean")  # SGBM's depth, or the truth with holes


def test_sgbm_input_is_stereo_depth_close_to_the_truth_where_it_answered():
    case = make_real_case("sgbm", factor=4)
    both = np.isfinite(case.depth) & np.isfinite(case.gt)
    error = np.abs(case.fb / case.depth[both] - case.fb / case.gt[both])  # disparity px at 125×185
    assert np.median(error) < 0.25 and both.mean() > 0.7
    assert case.rmse_px(np.where(np.isfinite(case.depth), case.depth, case.gt)) == 0.0


def test_occlusion_holes_lie_beside_a_nearer_surface_on_their_right():
    """A left-view pixel the right view cannot see is hidden by something nearer on its right: the
    holes have such a surface within 5 px five times as often as the pixels kept (SGBM's left-right
    check also drops some mismatches, so not every hole is an occlusion)."""
    case = make_real_case("occlusion", factor=4)
    disparity = case.fb / case.gt  # larger = nearer

    def share_beside_a_nearer_surface(mask):
        return np.mean([np.nanmax(np.r_[disparity[v, u + 1:u + 6], -1.0]) > disparity[v, u] + 1.0
                        for v, u in np.argwhere(mask) if u + 6 < disparity.shape[1]])
    kept = np.isfinite(case.gt) & np.isfinite(case.depth)
    assert share_beside_a_nearer_surface(case.scored_holes) > 3 * share_beside_a_nearer_surface(kept)


def test_the_pair_written_in_middlebury_format_reads_back_as_loaded(tmp_path, motorcycle):
    from ddp_lite.data.middlebury import load_middlebury, write_motorcycle_folder
    folder = write_motorcycle_folder(tmp_path / "Motorcycle")
    assert "doffs=31.086" in (folder / "calib.txt").read_text() and "baseline=193.001" in (folder / "calib.txt").read_text()
    read = load_middlebury(folder)
    np.testing.assert_array_equal(read[0].rgb, motorcycle[0].rgb)
    np.testing.assert_allclose(read[0].depth, motorcycle[0].depth, rtol=1e-6)  # NaN where unknown, in both
    np.testing.assert_allclose(read.right[0].camera.K, motorcycle.right[0].camera.K)


def test_another_middlebury_folder_gives_the_same_cases_as_the_pair_it_holds(tmp_path):
    from ddp_lite.data.middlebury import write_motorcycle_folder

    folder = write_motorcycle_folder(tmp_path / "Motorcycle")  # the pair, read back from Middlebury's file format
    for holes in ("blobs-2", "occlusion"):
        shipped, read = make_real_case(holes, factor=8), make_real_case(holes, factor=8, scene=folder)
        assert read.name == f"Motorcycle/{holes}" and shipped.name == f"motorcycle/{holes}"
        np.testing.assert_allclose(read.gt, shipped.gt, rtol=1e-5)
        assert np.array_equal(np.isfinite(read.depth), np.isfinite(shipped.depth))
        assert read.fb == pytest.approx(shipped.fb, rel=1e-6)


def test_another_pair_is_pooled_and_holed_where_sgbm_fails_and_cropped_to_a_multiple_of_four(tmp_path):
    from skimage.measure import block_reduce

    from ddp_lite.classical.stereo import sgm_left_right_failures
    from ddp_lite.data.middlebury import load_middlebury, make_middlebury_fixture

    folder = make_middlebury_fixture(tmp_path / "Desk", size=(96, 128), seed=1)
    case = make_real_case("occlusion", factor=2, scene=folder)
    assert case.name == "Desk/occlusion" and case.depth.shape == case.gt.shape == (48, 64)
    # a pooled pixel is a hole if SGBM's left-right check failed anywhere in its 2×2 block
    expected = block_reduce(sgm_left_right_failures(load_middlebury(folder), 0), (2, 2), np.max)
    known_truth = np.isfinite(case.gt)
    assert expected.any() and np.array_equal(np.isnan(case.depth) & known_truth, expected & known_truth)
    known = np.isfinite(case.depth)
    np.testing.assert_array_equal(case.depth[known], case.gt[known])  # elsewhere the input is the truth
    odd = load_middlebury(make_middlebury_fixture(tmp_path / "Odd", size=(99, 130), seed=1))
    blobs = make_real_case("blobs-1", factor=2, scene=odd)  # a loaded Scene works as a folder does
    assert blobs.depth.shape == (48, 64) and blobs.name == "Odd/blobs-1"  # 99×130 cropped to 96×128
    assert 0.2 <= np.isnan(blobs.depth).mean() < 0.35


def test_a_scene_without_a_right_view_or_a_bad_factor_is_refused():
    view = View(np.zeros((8, 8, 3), np.float32), np.ones((8, 8), np.float32), Camera(np.eye(3), np.eye(4), 8, 8))
    with pytest.raises(ValueError, match="scene must be a Middlebury stereo pair"):
        make_real_case("blobs-1", factor=2, scene=Scene("x", [view], [], {"baseline": 0.1, "doffs": 0.0}))
    for bad in (0, 2.5, True):
        with pytest.raises(ValueError, match="factor must be a positive integer"):
            make_real_case("blobs-1", factor=bad)


def test_compare_fills_fits_each_distinct_method_once_and_matches_each_recipe_run_alone(monkeypatch):
    import dataclasses

    import torch

    from ddp_lite.studies import real_cases
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.profiles import get_profile

    case = make_real_case("blobs-1", factor=16)  # 31×46: what is counted and compared does not depend on the size
    profile = dataclasses.replace(get_profile("ci"), iterations=8)
    fits, real = [], real_cases.complete_depth
    monkeypatch.setattr(real_cases, "complete_depth", lambda *a, **k: fits.append(k["config"]) or real(*a, **k))
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # the fits then run one after the other, as compare_fills runs them
    try:
        out = real_cases.compare_fills(case, profile, recipes=("paper", "kit", "photo", "kit"))
        alone = {recipe: case.fb / real(case.rgb, case.depth, case.camera, (), variant="rgbd",
                                          config=FitConfig.for_profile(profile, variant="rgbd",
                                                                       recipe=recipe)).merged(case.depth)
                 for recipe in ("kit", "photo")}
    finally:
        torch.set_num_threads(threads)
    # paper's, kit's and photo's (which fits without the kit's hole terms); kit listed twice is fitted once
    assert len(fits) == 3 and all(config.combination.blend_fill == 0 for config in fits)
    assert [config.holes.smoothness > 0 for config in fits] == [False, True, False]
    for recipe, px in alone.items():  # each recipe as complete_depth computes it on its own
        assert np.allclose(out[f"DDP {recipe}"], px, rtol=1e-5, atol=1e-5), recipe
    assert not np.allclose(out["DDP photo"], out["DDP kit"], atol=1e-3)


def test_compare_fills_tells_the_fit_a_stereo_matchers_depth():
    # the SGBM case's kit DDP is what complete_depth gives when told the depth is a matcher's (its fill read
    # without the rim of the holes), not what it gives for clean depth
    import dataclasses

    from ddp_lite.studies import real_cases
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.profiles import get_profile

    case = make_real_case("sgbm", factor=16)
    profile = dataclasses.replace(get_profile("ci"), iterations=6)
    out = real_cases.compare_fills(case, profile, recipes=("kit",))

    def alone(source):
        config = FitConfig.for_profile(profile, variant="rgbd", recipe="kit", depth_source=source)
        return case.fb / real_cases.complete_depth(case.rgb, case.depth, case.camera, (), variant="rgbd",
                                                   config=config).merged(case.depth)
    assert np.allclose(out["DDP kit"], alone("stereo"), rtol=1e-5, atol=1e-5)
    assert not np.allclose(out["DDP kit"], alone("clean"), atol=1e-3)


def test_compare_fills_on_pools_the_fits_of_several_cases_and_gives_each_case_its_own():
    # two cases of different sizes and depth sources in one pool: each case's recipes fitted once, on its own
    # input (the fit's input shapes say which), and each case's answer what complete_depth gives it alone
    import dataclasses

    import torch

    from ddp_lite.studies import real_cases
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.profiles import get_profile

    cases = [make_real_case("blobs-1", factor=16), make_real_case("sgbm", factor=32)]
    profile = dataclasses.replace(get_profile("ci"), iterations=6)
    shapes, real = [], real_cases.complete_depth
    monkeypatch = pytest.MonkeyPatch()
    monkeypatch.setattr(real_cases, "complete_depth", lambda *a, **k: shapes.append(a[1].shape) or real(*a, **k))
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        outs = real_cases.compare_fills_on(cases, profile, recipes=("kit", "photo"))
        monkeypatch.undo()
        alone = [case.fb / real(case.rgb, case.depth, case.camera, (), variant="rgbd", config=FitConfig.for_profile(
            profile, variant="rgbd", recipe="kit", depth_source=case.depth_source)).merged(case.depth) for case in cases]
    finally:
        torch.set_num_threads(threads)  # the fits above ran on one thread each, as the pool runs them
        monkeypatch.undo()
    assert sorted(shapes) == sorted([cases[0].depth.shape] * 2 + [cases[1].depth.shape] * 2)
    assert len(outs) == 2
    for case, out, px in zip(cases, outs, alone):
        assert set(out) >= {"DDP kit", "DDP photo", "linear"} and out["linear"].shape == case.depth.shape
        assert np.allclose(out["DDP kit"], px, rtol=1e-5, atol=1e-5), case.depth_source
    assert cases[0].depth.shape != cases[1].depth.shape


def test_table6_fits_the_papers_recipe_and_the_one_recommended_for_photographs_at_class(monkeypatch):
    # class: two fits per scene, the paper's and the photographs' recipe, read from the one place that names it;
    # paper adds the kit recipe between them; ci (make test's smoke run) the paper's alone; a recipe is never
    # fitted twice
    from ddp_lite.method.kit import recipes
    from ddp_lite.studies import table6

    assert recipes.FOR_PHOTOGRAPHS in recipes.RECIPES
    assert table6.table6_recipes("class") == ("paper", recipes.FOR_PHOTOGRAPHS)
    assert table6.table6_recipes("ci") == ("paper",)
    assert table6.table6_recipes("paper") == ("paper", "kit", recipes.FOR_PHOTOGRAPHS)
    monkeypatch.setattr(table6, "FOR_PHOTOGRAPHS", "kit")  # another study may recommend kit one day
    assert table6.table6_recipes("paper") == ("paper", "kit") and table6.table6_recipes("class") == ("paper", "kit")


def test_table6_pools_each_scene_to_at_most_the_profiles_pixels_by_the_smallest_integer_factor():
    from ddp_lite.studies.real_cases import factor_for_pixels
    from ddp_lite.studies.table6 import table6_case, table6_factor
    assert factor_for_pixels((100, 100), 2500) == 2  # 50×50 = 2500 exactly
    assert factor_for_pixels((100, 100), 2499) == 3  # 33×33 = 1089; 2 would leave 2500
    assert factor_for_pixels((103, 103), 2500) == 2  # cropped to 100×100 first, as make_real_case crops
    # a quarter-size Plastic (276×316 after the crop): 2 → 138×158 = 21804 > 96·128 = 12288; 3 → 92×105 = 9660
    assert table6_factor("class", (277, 318)) == 3
    assert table6_factor("paper", (1110, 1270)) == 2  # 555×635 = 352425 ≤ 512·960
    case = table6_case("Plastic", "class")
    assert case.depth.shape == (92, 105) and case.depth.size <= 96 * 128
