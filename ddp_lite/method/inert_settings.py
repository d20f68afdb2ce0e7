"""Settings that act on nothing: a :class:`~ddp_lite.method.config.FitConfig` field set to something other
than its default in a combination where nothing reads it, said before the fit (a warning naming the field and
why), so that a result is never read as what a setting did when it did nothing.

Only fields the stock recipes never set for that combination are judged: a recipe's settings at every
profile and variant warn about nothing (the kit's image input is off for a depth-only fit by design and
says so in its description). Each rule names the component that would have read the field:

- the warp term's fields (``warp_*``) without the warp term (variants ``d`` and ``rgbd``);
- ``warp_combine="min"`` with one neighbour: the minimum over one cost is that cost, as the mean is;
- ``gammas`` for the depth-only variant, whose loss is L_disp alone;
- ``blend_weight`` without ``blend_paper`` (there is no blend to weigh);
- ``depth_source`` other than ``"clean"`` with no step after the fit that reads the input depth (no fill's
  share, no ``refine``): the fit itself reads every valid pixel the same way;
- ``edge_guide`` other than ``"grey"`` without hole terms (``smoothness``, ``flatness``), the only ones it guides;
- ``flatness_reach`` without ``flatness``.

A recipe whose own refinement a variant drops (``photo`` for ``d``: the solve is guided by the colour image)
is said by :meth:`FitConfig.for_profile <ddp_lite.method.config.FitConfig.for_profile>`, which drops it; a
run's ``callback_every`` without a callback by :func:`~ddp_lite.method.fit.check_run`; ``ddp-lite complete``'s
flags by ``interface.cli_complete``.
"""
from __future__ import annotations

import dataclasses
import warnings

__all__ = ["InertSettingWarning", "inert_settings", "warn_inert_settings"]


class InertSettingWarning(UserWarning):
    """A setting that changes nothing in the fit it was given to (:func:`inert_settings`)."""


def _changed(section, name: str) -> bool:
    """Whether ``section``'s field ``name`` differs from its class default."""
    default = next(f.default for f in dataclasses.fields(section) if f.name == name)
    return getattr(section, name) != default


def inert_settings(config, variant, neighbors: int) -> list[str]:
    """What each setting of ``config`` that acts on nothing for ``variant`` (a name or
    :class:`~ddp_lite.method.paper.variants.Variant`) with ``neighbors`` views would not do; [] where each acts."""
    from .paper.variants import get_variant

    spec = get_variant(variant) if isinstance(variant, str) else variant
    warp, holes, combination = config.warp, config.holes, config.combination
    said = []
    if not spec.needs_neighbors:
        for name in (f.name for f in dataclasses.fields(warp)):
            if _changed(warp, name):
                said.append(f"config.{warp.flat_name(name)}={getattr(warp, name)!r} acts on nothing: variant "
                            f"{spec.name!r} has no warp term (it is the 'rgbd+warp' variant's, with a camera and "
                            f"neighbours)")
    elif warp.combine == "min" and neighbors == 1:
        said.append("config.warp_combine='min' acts on nothing with one neighbour: the minimum over one neighbour's "
                    "cost is that cost, as the mean is (it picks between two or more)")
    if not spec.uses_rgb and config.paper.gammas is not None:
        said.append(f"config.gammas={config.paper.gammas!r} acts on nothing: variant {spec.name!r} fits depth alone "
                    f"(L_disp, weight 1), with no colour or warp term to weigh against it")
    if not combination.blend_paper and _changed(combination, "blend_weight"):
        said.append(f"config.blend_weight={combination.blend_weight!r} acts on nothing without blend_paper=True "
                    f"(there is no blend with the paper recipe's fit to weigh)")
    if combination.depth_source != "clean" and combination.blend_fill == 0 and not combination.refine:
        said.append(f"config.depth_source={combination.depth_source!r} acts on nothing here: only the steps after "
                    f"the fit read it (a share of the colour-guided fill, blend_fill, and refine), and both are off")
    if _changed(holes, "edge_guide") and holes.smoothness == 0 and holes.flatness == 0:
        said.append(f"config.edge_guide={holes.edge_guide!r} acts on nothing: it guides the hole terms, and "
                    f"smoothness and flatness are both 0")
    if holes.flatness_reach is not None and holes.flatness == 0:
        said.append(f"config.flatness_reach={holes.flatness_reach!r} acts on nothing: config.flatness is 0")
    return said


def warn_inert_settings(config, variant, neighbors: int, stacklevel: int = 3) -> None:
    """One :class:`InertSettingWarning` per line of :func:`inert_settings`, before the fit."""
    for line in inert_settings(config, variant, neighbors):
        warnings.warn(line, InertSettingWarning, stacklevel=stacklevel)
