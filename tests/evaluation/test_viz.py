"""Figure helpers: one error scale across a comparison, outlines of unscored regions."""
import matplotlib.pyplot as plt
import numpy as np
import pytest

from ddp_lite.evaluation.viz import (HOLE_RGB, error_vmax, outline, overlay_holes, shared_colorbar, show_depth, show_error,
                                     show_errors)
from ddp_lite.method.paper.disparity import DisparityTransform


def test_error_vmax_is_the_percentile_of_all_maps_together():
    truth = np.zeros((4, 5))
    small, large = np.full((4, 5), 0.1), np.arange(20.0).reshape(4, 5)
    mask = np.ones((4, 5), bool)
    mask[0, 0] = False  # outside the mask: not counted
    errors = np.concatenate([np.full(19, 0.1), np.arange(1.0, 20.0)])
    assert error_vmax([small, large], truth, mask) == pytest.approx(np.percentile(errors, 99))
    assert error_vmax({"a": small, "b": large}, truth, mask, percentile=50) == pytest.approx(np.median(errors))
    with pytest.raises(ValueError, match="estimates"):
        error_vmax([], truth)


def test_a_shared_vmax_gives_both_maps_the_same_colour_scale():
    truth = np.zeros((3, 3))
    fig, axes = plt.subplots(1, 2)
    top = error_vmax([np.ones((3, 3)), 3 * np.ones((3, 3))], truth)
    images = [show_error(ax, estimate, truth, vmax=top) for ax, estimate in zip(axes, (np.ones((3, 3)), 3 * np.ones((3, 3))))]
    assert images[0].get_clim() == images[1].get_clim() == (0, pytest.approx(3.0))
    plt.close(fig)


def test_outline_draws_a_contour_and_a_legend_entry():
    fig, ax = plt.subplots()
    region = np.zeros((6, 6), bool)
    region[:2] = True
    outline(ax, region, label="sky: not scored")
    assert ax.get_legend().get_texts()[0].get_text() == "sky: not scored"
    assert ax.collections  # the contour
    outline(ax, np.zeros((6, 6), bool))  # nothing to outline: no error
    plt.close(fig)


def test_overlay_holes_paints_only_the_holes_in_the_hole_colour():
    image = np.full((2, 3, 3), 0.25, np.float32)
    holes = np.array([[True, False, False], [False, False, True]])
    out = overlay_holes(image, holes)
    assert HOLE_RGB == (1.0, 0.0, 1.0)  # magenta
    np.testing.assert_array_equal(out[holes], [HOLE_RGB] * 2)
    np.testing.assert_array_equal(out[~holes], image[~holes])
    assert image[0, 0, 0] == 0.25  # the input is not modified


def test_show_errors_draws_a_row_in_the_tables_unit_on_one_clipped_scale_with_one_bar():
    truth = np.full((4, 5), 2.0)  # metres
    near, far = np.full((4, 5), 1.5), np.full((4, 5), 4.0)
    transform = DisparityTransform(d_min=1.0, d_max=5.0, constant=0.0)
    fig, axes = plt.subplots(1, 2)
    top = show_errors(axes, {"near": near, "far": far}, truth, transform=transform)
    # normalised disparity ×100 by hand: (1/z − 1/5) / (1 − 1/5) × 100
    to_z = lambda z: (1.0 / z - 0.2) / 0.8 * 100.0  # noqa: E731
    errors = np.array([abs(to_z(1.5) - to_z(2.0)), abs(to_z(4.0) - to_z(2.0))])
    assert top == pytest.approx(np.percentile(np.repeat(errors, 20), 99))
    assert axes[0].images[0].get_clim() == axes[1].images[0].get_clim() == (0, pytest.approx(top))
    bars = _colorbar_axes(fig)
    assert len(bars) == 1 and "×100" in bars[0].get_ylabel()  # the two maps share one colour bar
    with pytest.raises(ValueError, match="estimates"):
        show_errors(axes, {"only one": near}, truth)
    plt.close(fig)


def _colorbar_axes(fig) -> list:
    """Every colour bar's axis in ``fig``, an inset one (a child of a panel) included."""
    every = list(fig.axes) + [child for ax in fig.axes for child in ax.child_axes]
    bars = [ax for ax in every if hasattr(ax, "_colorbar")]
    assert all(ax.get_label() == "<colorbar>" for ax in bars)  # as matplotlib labels the bars it places
    return bars


def test_a_row_on_one_scale_gets_one_colour_bar_and_keeps_its_panels_equal():
    fig, axes = plt.subplots(2, 3, figsize=(9, 5))
    depth = np.linspace(1.0, 5.0, 12).reshape(3, 4)
    images = [show_depth(ax, depth, f"panel {i}", vmin=1.0, vmax=5.0, colorbar=False) for i, ax in enumerate(axes[0])]
    shared_colorbar(images[-1], axes[0], label="depth (m)")
    show_errors(axes[1], {f"map {i}": depth + i for i in range(3)}, depth)
    fig.tight_layout()
    bars = _colorbar_axes(fig)
    assert len(bars) == 2  # one per shared scale: the depths' and the errors'
    widths = [ax.get_position().width for ax in axes.ravel()]
    assert max(widths) - min(widths) < 1e-9 * max(widths)  # no panel gave width to a bar
    for bar, row in zip(sorted(bars, key=lambda b: -b.get_position().y0), axes):
        assert bar.get_position().x0 > row[-1].get_position().x1  # beside the row, right of its last panel
    with pytest.raises(ValueError, match="axes"):
        shared_colorbar(images[0], [])
    plt.close(fig)
