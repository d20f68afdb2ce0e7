"""Figures: depth with holes in a distinct colour, images, error maps.

Every depth panel has a colour bar (metres or disparity) and draws holes (NaN) in magenta, so a
hole is never mistaken for a far or near value. Panels that share one scale share one colour bar
(:func:`shared_colorbar`), drawn beside the row so that every panel keeps its width.
"""
from __future__ import annotations

import os

import matplotlib
import numpy as np

from ..core.files import atomic_path

__all__ = ["show_depth", "show_image", "show_error", "show_errors", "shared_colorbar", "error_vmax", "outline",
           "overlay_holes", "save_figure", "HOLE_COLOUR", "HOLE_RGB"]

HOLE_COLOUR = "magenta"
HOLE_RGB = matplotlib.colors.to_rgb(HOLE_COLOUR)  # (1.0, 0.0, 1.0)


def shared_colorbar(image, axes, label: str = "", **options):
    """One colour bar for a row of panels drawn on one scale (``image``: any of their images), in its
    own thin axis just right of the right-most of ``axes``: unlike ``fig.colorbar(image, ax=ax)`` it
    takes no width from any panel, so the panels stay equal (and ``tight_layout`` makes room for it).
    ``options`` go to ``Figure.colorbar`` (e.g. ``extend="max"``). Returns the colour bar."""
    axes = list(np.ravel(axes))
    if not axes:
        raise ValueError("axes must hold at least one axis")
    rightmost = max(axes, key=lambda ax: ax.get_position().x1)
    bar_axis = rightmost.inset_axes([1.04, 0.0, 0.05, 1.0])  # axes fraction: a bar 5 % as wide as a panel
    bar_axis.set_label("<colorbar>")  # the label matplotlib gives the bars it places itself
    return rightmost.figure.colorbar(image, cax=bar_axis, label=label, **options)


def show_depth(ax, depth, title: str = "", vmin=None, vmax=None, cmap: str = "viridis_r", label: str = "depth (m)",
               colorbar: bool = True):
    """Draw (H, W) depth on ``ax`` with a colour bar; NaN holes in magenta. Returns the image.

    ``colorbar=False`` for a row of panels on one ``vmin``/``vmax``: give the row one
    :func:`shared_colorbar` instead of a copy beside every panel."""
    depth = np.asarray(depth, dtype=np.float32)
    colours = matplotlib.colormaps[cmap].copy()
    colours.set_bad(HOLE_COLOUR)
    finite = depth[np.isfinite(depth)]
    vmin = float(finite.min()) if vmin is None and finite.size else vmin
    vmax = float(finite.max()) if vmax is None and finite.size else vmax
    image = ax.imshow(np.ma.masked_invalid(depth), cmap=colours, vmin=vmin, vmax=vmax, interpolation="nearest")
    if colorbar:
        ax.figure.colorbar(image, ax=ax, fraction=0.046, pad=0.04, label=label)
    ax.set_title(title)
    ax.axis("off")
    return image


def show_image(ax, image, title: str = ""):
    """Draw an (H, W, 3) image in [0, 1] on ``ax``."""
    ax.imshow(np.clip(np.asarray(image), 0, 1), interpolation="nearest")
    ax.set_title(title)
    ax.axis("off")


def show_error(ax, estimate, truth, title: str = "", vmax=None, mask=None, label: str = "|error| (m)"):
    """Absolute error |estimate - truth| (H, W) on ``ax``; pixels outside ``mask`` greyed out."""
    error = np.abs(np.asarray(estimate, np.float32) - np.asarray(truth, np.float32))
    if mask is not None:
        error = np.where(mask, error, np.nan)
    colours = matplotlib.colormaps["magma"].copy()
    colours.set_bad("lightgrey")
    vmax = float(np.nanpercentile(error, 99)) if vmax is None else vmax
    image = ax.imshow(np.ma.masked_invalid(error), cmap=colours, vmin=0, vmax=max(vmax, 1e-6), interpolation="nearest")
    ax.figure.colorbar(image, ax=ax, fraction=0.046, pad=0.04, label=label)
    ax.set_title(title)
    ax.axis("off")
    return image


def show_errors(axes, estimates: dict, truth, mask=None, transform=None, percentile: float = 99.0,
                label: str | None = None) -> float:
    """A row of error maps on one scale with one colour bar: |estimate - truth| of each (H, W) depth
    in ``estimates`` ({title: depth}) on the matching axis of ``axes``, outside ``mask`` grey. The bar
    is a :func:`shared_colorbar`: every map keeps the same width.

    With ``transform`` (a :class:`~ddp_lite.method.paper.disparity.DisparityTransform`) the error is in
    the unit of the kit's tables, normalised disparity ×100; without it, in the arrays' own unit
    (metres, or px for disparity maps). The scale stops at the ``percentile`` of all the maps' errors
    (the bar says so), so that a few large errors at the border do not turn every other error
    black. ``label`` names the colour bar's quantity instead. Returns that top.

    Example:
        >>> import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
        >>> fig, axes = plt.subplots(1, 2)
        >>> show_errors(axes, {"a": np.zeros((4, 4)), "b": np.full((4, 4), 2.0)}, np.ones((4, 4)))
        1.0
    """
    axes = list(np.ravel(axes))
    if len(estimates) != len(axes):
        raise ValueError(f"estimates must hold one map per axis: {len(estimates)} maps for {len(axes)} axes "
                         "(two maps with the same title count once)")
    if transform is not None:
        maps = {name: 100.0 * np.abs(transform.to_disparity(np.asarray(d, np.float64))
                                     - transform.to_disparity(np.asarray(truth, np.float64)))
                for name, d in estimates.items()}
        default_label = "|error| (norm. disparity ×100)"
    else:
        maps = {name: np.abs(np.asarray(d, np.float64) - np.asarray(truth, np.float64)) for name, d in estimates.items()}
        default_label = "|error|"
    if mask is not None:
        maps = {name: np.where(mask, e, np.nan) for name, e in maps.items()}
    label = label or default_label
    values = np.concatenate([e[np.isfinite(e)] for e in maps.values()])
    top = max(float(np.percentile(values, percentile)) if values.size else 1.0, 1e-6)
    colours = matplotlib.colormaps["magma"].copy()
    colours.set_bad("lightgrey")
    for ax, (name, error) in zip(axes, maps.items()):
        image = ax.imshow(np.ma.masked_invalid(error), cmap=colours, vmin=0, vmax=top, interpolation="nearest")
        ax.set_title(name)
        ax.axis("off")
    # two lines: on one, a long label outgrows a short panel
    shared_colorbar(image, axes, label=f"{label}\ntop: {percentile:g}th pct.", extend="max")
    return top


def error_vmax(estimates, truth, mask=None, percentile: float = 99.0) -> float:
    """One colour-scale top for several error maps: the ``percentile`` of |estimate - truth| over all
    of ``estimates`` (a list or dict of (H, W) arrays), inside ``mask``. Maps drawn with their own
    scales invite a wrong comparison (a darker map is not a better one)."""
    maps = list(estimates.values()) if isinstance(estimates, dict) else list(estimates)
    if not maps:
        raise ValueError("estimates must hold at least one (H, W) array")
    truth = np.asarray(truth, np.float64)
    errors = []
    for estimate in maps:
        error = np.abs(np.asarray(estimate, np.float64) - truth)
        errors.append(error[mask] if mask is not None else error.ravel())
    errors = np.concatenate(errors)
    errors = errors[np.isfinite(errors)]
    return float(np.percentile(errors, percentile)) if errors.size else 1.0


def outline(ax, region, colour: str = "white", label: str | None = None):
    """Draw the border of a (H, W) bool ``region`` on ``ax`` (e.g. where nothing is scored); with
    ``label``, add it to the axes' legend."""
    region = np.asarray(region, dtype=float)
    if region.any() and not region.all():
        ax.contour(region, levels=[0.5], colors=[colour], linewidths=1.0)
    if label:
        ax.plot([], [], color=colour, lw=1.0, label=label)
        ax.legend(loc="lower right", fontsize=7, framealpha=0.8)


def overlay_holes(image, holes) -> np.ndarray:
    """An (H, W, 3) image in [0, 1] with the pixels of the (H, W) bool ``holes`` painted in
    ``HOLE_COLOUR`` (float64, a new array), to show where something is missing or scored."""
    return np.where(np.asarray(holes, bool)[..., None], HOLE_RGB, image)


def save_figure(fig, path, dpi: int = 120) -> None:
    """Save a figure atomically (temporary file in the same folder, then rename)."""
    path = os.fspath(path)
    suffix = os.path.splitext(path)[1] or ".png"
    with atomic_path(path, suffix=suffix) as tmp:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format=suffix.lstrip("."))
