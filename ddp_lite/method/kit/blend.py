"""Blends of the kit's fit, the paper's and a classical fill (``CombinationConfig.blend_paper``, ``blend_fill``),
and the settings of every combination (``refine`` too). Not in the paper.

The two recipes err in different places. On rendered scenes the kit's hole terms and inputs fill
large holes far better; on the real photograph's occlusions the paper's plain loss is ahead, and
on its blob holes the two fits' mean beats both (``docs/studies/real_data.md``). ``blend_weight`` w gives

    Z = w·Z_kit + (1 − w)·Z_paper            (w = 0.5 when blended)

``blend_weight=None`` lets the image choose w, as self-validation does for deep priors: a ring of
valid input around the holes is held out of both fits, and the weight that best predicts it wins:

    V  = valid pixels within r px of a hole, in patches (half the ring)      validation_ring
    w* = argmin_{w ∈ {0, ¼, ½, ¾, 1}}  RMSE_V( w·Z_kit + (1 − w)·Z_paper − Z_in )   best_weight

Measured on the real pair, the ring costs more than it tells: both fits lose the valid pixels that
matter most (beside an occlusion, the far surface), and its choice is no better than the fixed mean.
It stays a study lever. The two fits run side by side on a CPU with two threads
(:func:`ddp_lite.method.runtime.side_by_side.run_side_by_side`).

``blend_fill`` f mixes in a third estimate that errs in yet other places: a colour-guided fill of the
input (:func:`fill_disparity`), the mean of Levin et al.'s colorization fill and Barron & Poole's fast
bilateral solver, which between them are the best classical fill on every real case (colorization on
the occlusions and the textured blob, the solver on the rest):

    Z = (1 − f)·(w·Z_kit + (1 − w)·Z_paper) + f·Z_fill          (kit at class: no paper fit, f = ¼)

``blend_fill=None`` lets the image choose f, on valid depth the fit never saw: 5 % of the valid
pixels, in smooth blobs like holes, are held out of the fit (and of a fill computed for the choice),
and the share that best predicts them wins:

    B  = blobs of valid pixels (5 %), held out of the fit and of the fill        fill_held_out_mask
    f* = argmin_{f ∈ {0, 0.1, …, 0.5}}  RMSE_B( (1 − f)·Z_fit + f·Z_fill − Z_in )    best_fill_share

The result mixes f* of the fill of the *whole* input into that fit. f stays at most ½, so the result
is mostly the network's. The blobs, unlike a ring around the holes, cost the fit almost nothing, but
measured, the choice does not tell the photograph from the rendered scenes: the held-out valid depth
prefers the fill on both, so it only buys a larger share with its cost (``docs/studies/real_data.md``). It
stays a study lever (recipe ``fill-chosen``); the ``kit`` recipe takes a fixed share where the variant
sees colour (:data:`~ddp_lite.method.kit.recipes.KIT_AT`). On the real suite a larger fixed share helps the
fit alone more, but the fit made sharp first (``refine``, the ``photo`` recipe) does better at ¼
(``docs/studies/real_suite.md``, "The fit made sharp, and how much fill to mix in").

``depth_source`` says where the input depth came from. A stereo matcher's holes have a rim it often
got wrong: on the real suite's SGBM depth the valid pixels within 2 px of a hole are many times more often
more than 1 px off than those further in (``docs/studies/real_suite.md``, "A stereo matcher's depth"), and
the fit, which reproduces the valid pixels, cannot tell. With ``"stereo"`` the steps after the fit (the fill mixed in, the ``refine`` solve) do not
read the valid pixels within :data:`RIM_DISTRUST` px of a hole (:func:`trusted_depth`); the answer keeps
them as given.

Lengths scale with the image: every pixel setting here was tuned on images whose short side was at most
:data:`TUNED_SHORT_SIDE` px (the eighth-size real suite, the ``class`` profile), holds there and grows with the
short side above it (:class:`~ddp_lite.core.pixel_lengths.PixelLength`): the rim's width (:func:`rim_width`) and
the bilateral solver's reach in the fill mixed in (:func:`fill_member_settings`). The held-out ring and blobs
are fractions of the image already (width min(H, W)/48, blobs blurred over min(H, W)/24, 5 % of the pixels).

Their settings, with the size of an ensemble (:mod:`ddp_lite.method.kit.ensemble`), the other way to
combine fits, are :class:`CombinationConfig`; :mod:`ddp_lite.method.complete` applies them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ...core.checks import check_bool, check_choice, check_int, check_real
from ...core.pixel_lengths import PixelLength
from ...core.settings import Settings

__all__ = ["CombinationConfig", "DEPTH_SOURCES", "RIM_DISTRUST", "TUNED_SHORT_SIDE", "FILL_MEMBER_LENGTHS",
           "fill_member_settings", "rim_width", "trusted_depth", "BLEND_WEIGHTS", "FILL_SHARES",
           "validation_ring", "best_weight", "ring_width", "fill_disparity", "FILL_MEMBERS",
           "fill_held_out_mask", "best_fill_share"]

BLEND_WEIGHTS = (0.0, 0.25, 0.5, 0.75, 1.0)  # the kit fit's weight; 0 is the paper's fit alone
RING_SHARE = 0.5  # the share of the ring held out: the rest keeps the holes' edges where they are
FILL_SHARES = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5)  # the fill's shares blend_fill=None chooses among: the fit keeps half
FILL_HELD_OUT = 0.05  # the share of the valid pixels held out to choose it
# the classical fills averaged into the one mixed in: on the real pair each is the best fill on some of the
# hole kinds, and their mean lets the share grow without costing the rendered scenes (docs/studies/real_data.md)
FILL_MEMBERS = ("colorization", "bilateral-solver")
# the largest short side (px) of the images the steps after the fit were tuned on (the eighth-size real suite,
# 115-138 rows; the class profile's 96×128): their pixel settings below hold there and scale with the short side
# above it (core.pixel_lengths)
TUNED_SHORT_SIDE = 138
# where the input depth came from → the px of valid rim around each hole the steps after the fit do not read
RIM_DISTRUST = {"clean": 0, "stereo": 1}
DEPTH_SOURCES = tuple(RIM_DISTRUST)
# the px settings of the fills in FILL_MEMBERS when the kit mixes them in (their own defaults as classical fills)
FILL_MEMBER_LENGTHS = {"bilateral-solver": {"sigma_xy": 8.0}}


@dataclass(frozen=True)
class CombinationConfig(Settings):
    """What goes into the answer besides one fit (6 fields; the defaults: one fit, as the paper)."""

    ensemble: int = 1  # fits with seeds seed, seed+1, ...; their disparities are averaged
    blend_paper: bool = False  # also fit the paper's recipe and blend the two fits
    blend_weight: float | None = 0.5  # this config's fit's weight in that blend; None: chosen on a held-out ring
    blend_fill: float | None = 0.0  # share of the input's colour-guided fill in the final disparity (0: none;
    # None: chosen on held-out blobs of the valid input)
    refine: bool = False  # the fit made sharp by an image-guided edge-aware solve toward it, before the fill's
    # share is mixed in (classical.full_resolution.refine_over_smoothness at the fit's own size; variants with colour)
    depth_source: str = "clean"  # "stereo": a matcher's depth, the rim of its holes not read after the fit

    def validate(self) -> None:
        check_int(self.ensemble, "config.ensemble", minimum=1)
        check_bool(self.blend_paper, "config.blend_paper")
        check_bool(self.refine, "config.refine")
        check_choice(self.depth_source, "config.depth_source", DEPTH_SOURCES)
        if self.blend_paper and self.ensemble > 1:
            raise ValueError(f"config.blend_paper and config.ensemble > 1 cannot be combined (a blend of two fits "
                             f"is not averaged with more), got ensemble={self.ensemble}")
        if self.blend_weight is not None:
            check_real(self.blend_weight, "config.blend_weight", 0.0, 1.0)
        if self.blend_fill is not None:
            check_real(self.blend_fill, "config.blend_fill", 0.0, 1.0, high_open=True)  # 1 would be the fill alone

    def describe(self) -> str:
        """What goes into the answer, as part of a recipe's one-line description (``kit.recipes.describe_method``);
        "" for one fit."""
        weight, fill = self.blend_weight, self.blend_fill
        return ((f", mean of {self.ensemble} fits" if self.ensemble > 1 else "")
                + (", made sharp by an image-guided bilateral solve toward the fit" if self.refine else "")
                + ((", blended with the paper recipe's fit, " + ("weight from a held-out ring" if weight is None
                   else f"weight {weight:g}")) if self.blend_paper else "")
                + (", and with the input's colour-guided fill (colorization and bilateral solver, averaged), " + (
                    "its share (0–0.5) chosen on held-out blobs of the valid depth" if fill is None
                    else f"share {fill:.3g}") + " (not for depth-only)"
                   if fill != 0 else ""))

    def equation(self) -> str:
        """The answer Ẑ from the fit Z in the equation a config optimises (``method.equation``), LaTeX: fits
        and a fill blended, the fit made sharp first (:math:`\\mathcal{R}_I`, ``refine``); "" where Ẑ is Z."""
        paper_fit, fill, refine = self.blend_paper, self.blend_fill, self.refine
        if not (paper_fit or fill != 0 or refine):
            return ""
        w = self.blend_weight if paper_fit else 1.0
        z, z_paper = "Z", "Z_{\\mathrm{paper}}"
        if fill is None:  # the share chosen on held-out depth
            fits = z if w == 1.0 else (f"(w^* {z} + (1 - w^*)\\,{z_paper})" if w is None else
                                       f"({w:.3g}\\,{z} + {1 - w:.3g}\\,{z_paper})")
            fits = f"\\mathcal{{R}}_I({fits})" if refine else fits
            mix = f"(1 - f^*)\\,{fits} + f^*\\,\\mathrm{{fill}}(Z_{{\\mathrm{{in}}}})"
        elif w is None:
            mix = f"w^* {z} + (1 - w^*)\\,{z_paper}"
            mix = f"\\mathcal{{R}}_I({mix})" if refine else mix
            if fill > 0:
                mix = f"{1 - fill:.3g}\\,({mix}) + {fill:.3g}\\,\\mathrm{{fill}}(Z_{{\\mathrm{{in}}}})"
        elif refine:  # the solve acts on the fits' blend, then the fill is mixed in
            fits = z if w == 1.0 else f"{w:.3g}\\,{z} + {1 - w:.3g}\\,{z_paper}"
            mix = f"\\mathcal{{R}}_I({fits})"
            if fill > 0:
                mix = f"{1 - fill:.3g}\\,{mix} + {fill:.3g}\\,\\mathrm{{fill}}(Z_{{\\mathrm{{in}}}})"
        else:
            mix = " + ".join(f"{share:.3g}\\,{term}" for share, term in
                             (((1 - fill) * w, z), ((1 - fill) * (1 - w), z_paper),
                              (fill, "\\mathrm{fill}(Z_{\\mathrm{in}})")) if share > 0)
        return mix


def rim_width(source: str = "clean", scale: float = 1.0, shape=None) -> int:
    """The px of valid rim around each hole that the steps after the fit do not read of a ``source``'s depth
    on an image of ``shape`` (H, W, ...): ``RIM_DISTRUST[source]`` up to ``TUNED_SHORT_SIDE``, in proportion to
    the short side above it (None: the tuned px), × ``scale`` for an image ``scale`` times that size, rounded.

    Example:
        >>> rim_width("stereo", shape=(138, 173)), rim_width("stereo", shape=(276, 346))
        (1, 2)
    """
    pixels = RIM_DISTRUST[check_choice(source, "source", DEPTH_SOURCES)]
    at = PixelLength(float(pixels), TUNED_SHORT_SIDE).at(shape) if shape is not None else pixels
    return int(round(at * check_real(scale, "scale", 1.0)))


def trusted_depth(depth: np.ndarray, source: str = "clean", scale: float = 1.0) -> np.ndarray:
    """``depth`` (H, W) metres, NaN holes, with the valid pixels within :func:`rim_width` px of a hole
    (4-connected steps; ``classical.holes.hole_rim``) made holes too: what the steps after the fit read of a
    ``source``'s depth (the rim's width for ``depth``'s own size, × ``scale``). A copy; ``depth`` itself where
    nothing is distrusted, or where too little valid depth would be left.

    Example:
        >>> depth = np.ones((5, 5), np.float32); depth[2, 2] = np.nan
        >>> int(np.isnan(trusted_depth(depth, "stereo")).sum()), int(np.isnan(trusted_depth(depth)).sum())
        (5, 1)
    """
    from ...classical.holes import hole_rim
    rim = hole_rim(np.isfinite(depth), rim_width(source, scale, np.shape(depth)))
    return np.where(rim, np.nan, depth).astype(depth.dtype) if rim.any() else depth


def ring_width(shape) -> int:
    """The ring's width in px for an (H, W) image: 2 px at 96–143 rows, 1 px below, ~min(H, W)/48 above."""
    return max(1, int(min(shape)) // 48)


def validation_ring(valid: np.ndarray, seed: int = 0, width: int | None = None,
                    share: float = RING_SHARE) -> np.ndarray:
    """(H, W) bool: the valid pixels within ``width`` px (Euclidean; None → :func:`ring_width`) of a
    hole, in patches: those where a smooth random field (blur min(H, W)/24 px, seeded) is below its
    ``share`` quantile over the ring. Patches, not scattered pixels: a scattered pixel is predicted
    from its neighbours by any smooth fit, a patch is not. Empty if ``valid`` has no hole.

    Example:
        >>> valid = np.ones((48, 64), bool); valid[20:28, 20:40] = False
        >>> ring = validation_ring(valid, seed=0)
        >>> bool((ring & ~valid).any()), int(ring.sum()) > 0
        (False, True)
    """
    valid = np.asarray(valid, bool)
    if valid.ndim != 2:
        raise ValueError(f"valid must be an (H, W) bool array, got shape {valid.shape}")
    width = ring_width(valid.shape) if width is None else width
    if valid.all():  # no hole: (scipy's distance transform measures to pixel (0, 0) then)
        return np.zeros_like(valid)
    ring = valid & (ndimage.distance_transform_edt(valid) <= width)
    if not ring.any() or share >= 1.0:
        return ring
    H, W = valid.shape
    field = ndimage.gaussian_filter(np.random.default_rng(seed + 777).standard_normal((H, W)),
                                    max(1.0, min(H, W) / 24.0), mode="wrap")
    return ring & (field <= np.quantile(field[ring], share))


def best_weight(kit: np.ndarray, paper: np.ndarray, target: np.ndarray, ring: np.ndarray,
                weights=BLEND_WEIGHTS) -> tuple[float, list[float]]:
    """The weight w of ``kit`` in w·kit + (1 − w)·paper whose RMSE against ``target`` on ``ring`` is
    least (ties: the larger w, the kit's), and the RMSE of every weight. All (H, W), one unit.

    Example:
        >>> target = np.zeros((2, 2)); ring = np.ones((2, 2), bool)
        >>> best_weight(target + 1.0, target - 1.0, target, ring)
        (0.5, [1.0, 0.5, 0.0, 0.5, 1.0])
    """
    errors = [float(np.sqrt(np.mean((w * kit[ring] + (1.0 - w) * paper[ring] - target[ring]) ** 2)))
              for w in weights]
    best = min(range(len(weights)), key=lambda k: (errors[k], -weights[k]))
    return float(weights[best]), errors


def fill_disparity(depth: np.ndarray, rgb: np.ndarray, transform) -> np.ndarray:
    """(H, W) float32: the fill of ``depth`` (H, W) metres with NaN holes that the kit mixes into its
    result, guided by ``rgb`` (H, W, 3) in [0, 1], in ``transform``'s normalised disparity: the mean of
    the classical fills :data:`FILL_MEMBERS` (Levin et al.'s colorization and Barron & Poole's fast
    bilateral solver), which err in different places on a real photograph. The fills work on inverse
    depth 1/z, where the kit's classical fills work (linear is exact on planes there); valid pixels keep
    their value.

    Example:
        >>> from ddp_lite.method.paper.disparity import DisparityTransform
        >>> depth = np.array([[1.0, np.nan, 0.5]] * 3, np.float32)
        >>> transform = DisparityTransform.from_depth(depth)
        >>> z = fill_disparity(depth, np.zeros((3, 3, 3), np.float32), transform)
        >>> bool(np.allclose(transform.to_depth(z[:, 1]), 1 / 1.5, rtol=1e-3))  # the mean of 1/1 and 1/0.5, inverted
        True
    """
    from ...classical.baselines import BASELINES

    inverse = 1.0 / np.asarray(depth, np.float64)  # (H, W) 1/m, NaN in the holes
    filled = np.mean([BASELINES[name](inverse, rgb, **fill_member_settings(name, inverse.shape))
                      for name in FILL_MEMBERS], axis=0, dtype=np.float64)
    return np.asarray(transform.to_disparity(1.0 / filled), np.float32)


def fill_member_settings(name: str, shape) -> dict:
    """The px settings of the fill ``name`` (one of ``FILL_MEMBERS``) mixed in on an image of ``shape`` (H, W, ...):
    ``FILL_MEMBER_LENGTHS`` up to ``TUNED_SHORT_SIDE``, in proportion to the short side above it.

    Example:
        >>> fill_member_settings("bilateral-solver", (276, 346)), fill_member_settings("colorization", (276, 346))
        ({'sigma_xy': 16.0}, {})
    """
    return {key: PixelLength(pixels, TUNED_SHORT_SIDE).at(shape)
            for key, pixels in FILL_MEMBER_LENGTHS.get(name, {}).items()}


def fill_held_out_mask(valid: np.ndarray, seed: int = 0) -> np.ndarray:
    """(H, W) bool: the valid pixels held out to choose the fill's share, ``FILL_HELD_OUT`` of them in
    smooth random blobs (seeded; :func:`ddp_lite.method.stopping.held_out_mask` with ``shape="blobs"``).
    Blobs, not scattered pixels: a scattered pixel is predicted from its neighbours by any smooth fit.

    Example:
        >>> valid = np.ones((48, 64), bool); valid[20:28, 20:40] = False
        >>> held = fill_held_out_mask(valid, seed=0)
        >>> bool((held & ~valid).any()), round(float(held.sum() / valid.sum()), 2)
        (False, 0.05)
    """
    from ..stopping import held_out_mask

    return held_out_mask(np.asarray(valid, bool), FILL_HELD_OUT, seed + 777, "blobs")


def best_fill_share(fit: np.ndarray, fill: np.ndarray, target: np.ndarray, held_out: np.ndarray,
                    shares=FILL_SHARES) -> tuple[float, list[float]]:
    """The share f in (1 − f)·fit + f·fill whose RMSE against ``target`` on ``held_out`` is least (ties:
    the smaller f, the fit's), and the RMSE of every share. All (H, W), one unit.

    Example:
        >>> target = np.zeros((2, 2)); held_out = np.ones((2, 2), bool)
        >>> best_fill_share(target + 1.0, target - 1.0, target, held_out, shares=(0.0, 0.25, 0.5))
        (0.5, [1.0, 0.5, 0.0])
    """
    _, errors = best_weight(fit, fill, target, held_out, [1.0 - f for f in shares])
    best = min(range(len(shares)), key=lambda k: (errors[k], shares[k]))
    return float(shares[best]), errors
