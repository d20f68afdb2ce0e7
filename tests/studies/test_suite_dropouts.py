"""The real suite's sensor dropouts (``real_suite.dropout_holes``): many small blobs over 2–5 % of the pixels,
seeded, the same holes at every size; and the half A / half B split the studies choose and confirm on."""
import shutil

import numpy as np
import pytest
from scipy import ndimage

from ddp_lite.data.samples import sample_scene
from ddp_lite.studies.real_suite import (SUITE_HALF_A, dropout_holes, make_suite_case, suite_case_names,
                                         suite_half)


@pytest.mark.parametrize("name", ["Art", "Plastic", "Motorcycle", "Adirondack"])
def test_dropouts_are_many_small_blobs_over_two_to_five_percent(name):
    holes = dropout_holes((555, 695), name)
    assert 0.02 <= holes.mean() <= 0.05
    labels, count = ndimage.label(holes)
    areas = np.bincount(labels.ravel())[1:]
    assert count >= 50  # many blobs ...
    assert np.median(areas) < 0.001 * holes.size  # ... each small: a median blob under 0.1 % of the image
    assert np.array_equal(dropout_holes((555, 695), name), holes)  # seeded by the name
    assert not np.array_equal(dropout_holes((555, 695), name + "x"), holes)


def test_a_dropout_blob_is_the_same_share_of_the_image_at_twice_the_size():
    small, large = dropout_holes((300, 400), "Art"), dropout_holes((600, 800), "Art")
    assert large.mean() == pytest.approx(small.mean(), rel=0.02)
    (_, n_small), (_, n_large) = ndimage.label(small), ndimage.label(large)
    assert n_large == pytest.approx(n_small, rel=0.25)  # as many blobs, each 4× the pixels


def test_the_suite_has_dropouts_on_every_scene_the_same_holes_at_the_eighth_and_quarter_size(tmp_path):
    shutil.copytree(sample_scene("Art"), tmp_path / "2005-Art")
    names = suite_case_names(tmp_path)
    assert {"Art/dropouts", "Motorcycle/dropouts"} <= set(names)
    assert names.index("Art/blobs") < names.index("Art/dropouts") < names.index("Art/sgbm")  # kind by kind
    eighth, quarter = (make_suite_case(tmp_path, "Art/dropouts", size) for size in ("eighth", "quarter"))
    assert eighth.name == "Art/dropouts" and eighth.depth_source == "clean" and len(eighth.neighbors) == 2
    cut = [~np.isfinite(c.depth) & np.isfinite(c.gt) for c in (eighth, quarter)]  # the cut holes, where truth is known
    assert 0.015 < cut[0].mean() < 0.06 and 0.015 < cut[1].mean() < 0.06
    # the sample is a quarter of full size: the eighth pools 2×2 of the quarter's pixels, a hole where half are one
    H, W = eighth.depth.shape
    pooled = quarter.depth[:2 * H, :2 * W].reshape(H, 2, W, 2)
    pooled_holes = np.isnan(pooled).mean(axis=(1, 3)) >= 0.5
    assert (pooled_holes == ~np.isfinite(eighth.depth)).mean() > 0.97


def test_the_halves_split_the_scenes_of_every_family():
    assert suite_half("Art/dropouts") == "A" and suite_half("Books") == "B" and suite_half("Motorcycle/sgbm") == "B"
    assert len(SUITE_HALF_A) == 10
    assert {"Art", "Baby1", "Adirondack"} <= set(SUITE_HALF_A)  # a 2005, a 2006 and a 2014 scene
