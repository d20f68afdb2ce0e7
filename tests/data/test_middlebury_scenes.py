"""Real Middlebury scenes as calibrated multi-view scenes: the shipped samples, the rail geometry checked
by warping real neighbours through the real ground truth, the truth's occlusions against a hand-made
case, the suite's cases, and a clear refusal for each malformed file."""
from __future__ import annotations

import hashlib
import shutil

import cv2
import numpy as np
import pytest

from ddp_lite.classical.holes import stroke_holes
from ddp_lite.core.camera import backproject_pixels, project_points
from ddp_lite.data.middlebury import load_middlebury, make_middlebury_fixture
from ddp_lite.data.middlebury_rail import (ground_truth_occlusion, load_middlebury_scene, load_rail_scene,
                                           scene_disparity, size_scale)
from ddp_lite.data.samples import SAMPLES, depthcomp_holes, sample_scene
from ddp_lite.studies.real_suite import find_scenes, make_suite_case, suite_case_names


def warped_grey_error(ref, nbr) -> float:
    """Median |colour difference| (grey levels) between ``ref`` and ``nbr`` warped onto it through ``ref``'s
    depth, with the kit's Camera maths and OpenCV's remap (independent of the kit's torch warp)."""
    H, W = ref.depth.shape
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    known = np.isfinite(ref.depth)
    pu, pv, _ = project_points(backproject_pixels(u[known], v[known], ref.depth[known], ref.camera), nbr.camera)
    map_x = np.full((H, W), -1.0, np.float32)
    map_y = np.full((H, W), -1.0, np.float32)
    map_x[known], map_y[known] = pu, pv
    warped = cv2.remap(nbr.rgb, map_x, map_y, cv2.INTER_LINEAR)
    inside = known & (map_x >= 0) & (map_x <= W - 1)
    return float(np.median(np.abs(warped[inside] - ref.rgb[inside])) * 255)


@pytest.mark.parametrize("name", ["Plastic", "Art"])
def test_the_ground_truth_warps_every_neighbour_onto_view1(name):
    scene = load_rail_scene(sample_scene(name), neighbors=(0, 2))
    assert [v.name for v in scene.views] == ["view1", "view0", "view2"] and scene.right[0].name == "view5"
    for neighbour in [*scene.views[1:], scene.right[0]]:
        assert warped_grey_error(scene[0], neighbour) <= 3.5, neighbour.name
    # the check can fail: view0 taken for view2 (its camera on the other side) is far off
    wrong = type(scene[1])(scene[1].rgb, scene[1].depth, scene[2].camera, "view0 as view2")
    assert warped_grey_error(scene[0], wrong) > 2 * warped_grey_error(scene[0], scene[1])


def test_depth_and_disparity_round_trip_against_the_png():
    folder = sample_scene("Plastic")
    scene = load_rail_scene(folder)
    intensity = cv2.imread(str(folder / "disp1.png"), cv2.IMREAD_UNCHANGED).astype(np.float64)  # 4 × quarter px
    dmin = float((folder / "dmin.txt").read_text().split()[0])
    known = intensity > 0
    # Z = 3740 · 0.160 / (intensity + dmin) metres at every size (hand-computed from the dataset's figures)
    np.testing.assert_allclose(scene[0].depth[known], 3740 * 0.160 / (intensity[known] + dmin), rtol=1e-6)
    assert np.isnan(scene[0].depth[~known]).all()
    np.testing.assert_allclose(scene_disparity(scene, scene[0].depth)[known], intensity[known] / 4, atol=1e-3)
    assert scene.meta["focal"] == 3740 / 4 and scene.meta["doffs"] == dmin / 4


def test_every_shipped_sample_loads_with_its_neighbours():
    for name in SAMPLES:
        scene = load_rail_scene(sample_scene(name))
        assert size_scale(scene[0].camera.width) == 4 and 260 <= scene.size[0] <= 290
        assert np.isfinite(scene[0].depth).mean() > 0.95 and np.isfinite(scene.right[0].depth).mean() > 0.9
    holes = depthcomp_holes()
    assert holes.shape == load_rail_scene(sample_scene("Plastic")).size and 0.07 < holes.mean() < 0.11


def _write_rail(folder, disp1, disp5, dmin=100, views=(0, 1, 2, 5)):
    folder.mkdir(parents=True, exist_ok=True)
    H, W = disp1.shape
    rng = np.random.default_rng(0)
    for k in views:
        cv2.imwrite(str(folder / f"view{k}.png"), rng.integers(0, 255, (H, W, 3), dtype=np.uint8))
    cv2.imwrite(str(folder / "disp1.png"), disp1.astype(np.uint8))
    cv2.imwrite(str(folder / "disp5.png"), disp5.astype(np.uint8))
    (folder / "dmin.txt").write_text(f"{dmin}\n")
    return folder


def test_the_truths_occlusions_match_a_hand_made_case(tmp_path):
    # 300 px wide: quarter size, intensity = 4 × disparity. Background at d = 10 px, a foreground band at
    # d = 20 px over columns 150–199. In view5 a view1 pixel x lands at x − d: the background columns
    # 140–149 land where the foreground (now at 130–179) hides them, and columns 0–9 fall off the image.
    H, W = 40, 300
    disp1 = np.full((H, W), 40)
    disp1[:, 150:200] = 80
    disp5 = np.full((H, W), 40)
    disp5[:, 130:180] = 80
    occluded = ground_truth_occlusion(_write_rail(tmp_path / "Band", disp1, disp5))
    expected = np.zeros(W, bool)
    expected[0:10] = expected[140:150] = True
    np.testing.assert_array_equal(occluded, np.broadcast_to(expected, (H, W)))


def test_a_2014_folder_reads_the_evaluation_sets_truth_name(tmp_path):
    folder = make_middlebury_fixture(tmp_path / "Desk", size=(48, 64))
    expected = load_middlebury(folder)[0].depth
    (folder / "disp0.pfm").rename(folder / "disp0GT.pfm")
    np.testing.assert_array_equal(load_middlebury_scene(folder)[0].depth, expected)


@pytest.mark.parametrize("breakage, message", [
    (lambda f: (f / "dmin.txt").unlink(), "dmin.txt"),
    (lambda f: (f / "dmin.txt").write_text("minus\n"), "one number"),
    (lambda f: cv2.imwrite(str(f / "disp1.png"), np.zeros((40, 300, 3), np.uint8) + 40), "1-channel"),
    (lambda f: cv2.imwrite(str(f / "disp1.png"), np.full((30, 300), 40, np.uint8)), "view1.png is"),
    (lambda f: cv2.imwrite(str(f / "disp1.png"), np.zeros((40, 300), np.uint8)), "no valid disparity"),
    (lambda f: (f / "view0.png").unlink(), "view0.png"),
    (lambda f: cv2.imwrite(str(f / "view2.png"), np.zeros((20, 300, 3), np.uint8)), "view2.png is"),
])
def test_a_malformed_file_is_refused_by_name(tmp_path, breakage, message):
    folder = _write_rail(tmp_path / "Scene", np.full((40, 300), 40), np.full((40, 300), 40))
    breakage(folder)
    before = {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir()}
    with pytest.raises(ValueError, match=message):
        load_rail_scene(folder)
    assert {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir()} == before


@pytest.mark.parametrize("kwargs, message", [
    (dict(neighbors=(1, 2)), "neighbors"), (dict(neighbors=(0, 7)), "neighbors"), (dict(neighbors=(0, 0)), "neighbors"),
    (dict(scale=5), "scale"),
])
def test_bad_arguments_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        load_rail_scene(sample_scene("Plastic"), **kwargs)


def test_an_unknown_width_asks_for_the_scale(tmp_path):
    folder = _write_rail(tmp_path / "Wide", np.full((20, 900), 40), np.full((20, 900), 40))
    with pytest.raises(ValueError, match="scale="):
        load_rail_scene(folder)
    assert load_rail_scene(folder, scale=2).meta["focal"] == 3740 / 2


def test_stroke_holes_cover_their_fraction_and_leave_the_input_alone():
    depth = np.full((138, 158), 2.0, np.float32)
    fractions = []
    for seed in range(4):
        out, mask = stroke_holes(depth, seed=seed)
        fractions.append(1 - mask.mean())
        np.testing.assert_array_equal(np.isnan(out), ~mask)
    assert all(0.08 <= f <= 0.13 for f in fractions) and len(set(fractions)) > 1
    assert np.isfinite(depth).all()
    np.testing.assert_array_equal(stroke_holes(depth, seed=2)[1], stroke_holes(depth, seed=2)[1])


def test_the_suite_finds_scenes_and_builds_each_hole_kind(tmp_path):
    for name in ("Plastic", "Art"):
        shutil.copytree(sample_scene(name), tmp_path / f"2006-{name}")
    assert sorted(find_scenes(tmp_path)) == ["Art", "Plastic"]
    names = suite_case_names(tmp_path)
    assert names[0] == "Plastic/depthcomp" and "Motorcycle/sgbm" in names and "Art/depthcomp" not in names
    depthcomp = make_suite_case(tmp_path, "Plastic/depthcomp")
    assert len(depthcomp.neighbors) == 2 and 0.06 < depthcomp.scored_holes.mean() < 0.11
    occlusion = make_suite_case(tmp_path, "Art/occlusion")
    assert occlusion.scored_holes.any() and np.isfinite(occlusion.gt[occlusion.scored_holes]).all()
    with pytest.raises(ValueError, match="Plastic only"):
        make_suite_case(tmp_path, "Art/depthcomp")
