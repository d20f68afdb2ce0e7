"""FitConfig: what a fit computes, besides the data, in eight sections, each defined beside the code
that reads it and validated there.

    paper         the paper's settings: net, schedule, loss shares, γ, disparity range, seed  (paper/config.py)
    net_inputs    the kit's net inputs: the coordinates, the colour image, a classical fill   (kit/net_inputs.py)
    holes         the kit's hole terms and their edge weights                                (kit/hole_terms.py)
    warp          the kit's changes to the warp term                                         (kit/warp_terms.py)
    combination   what is averaged or blended into the answer: an ensemble, the paper's fit,
                  a classical fill                                                           (kit/blend.py)
    stopping      auto-stop on held-out pixels                                               (stopping.py)
    tricks        Deep Image Prior's per-iteration tricks                                    (dip_tricks.py)
    precision     the arithmetic the net runs in: bfloat16 or float32                        (runtime/device.py)

How a fit runs and not what it computes (the device, the memory format and limit, the progress bar, the
callback's rate) is no part of it: that is a :class:`~ddp_lite.method.runtime.options.RunOptions`, passed
to the run (``complete_depth(..., config=config, options=RunOptions(progress=False))``). ``FitConfig`` refuses
those names with a ``TypeError`` that says so.

Each section is a frozen dataclass; ``config.holes.smoothness`` reads a field by its section. Users and
recipes pass fields by their flat names: ``FitConfig(lr=1e-2, smoothness=1.0)``, ``config.replace(lr=1e-2)``,
``FitConfig.for_profile("ci", iterations=50)``; :meth:`FitConfig.flat` gives them back by those names, which
are also the fit cache's key. A flat name is the field's own name, except where that would repeat its
section's name inside the section: there the field drops the repeat and its flat name is qualified by the
section (:data:`QUALIFIED_NAMES`: ``warp_cost`` is ``config.warp.cost``, ``net_input`` is
``config.net_inputs.base``).
Defaults are the paper's (supplement). A profile's sizes and schedules come from
:meth:`FitConfig.for_profile`, the one place a :class:`~ddp_lite.method.profiles.Profile` becomes a config;
what differs between the DDP variants comes from :mod:`ddp_lite.method.paper.variants`. The rules that
tie two sections together are :meth:`FitConfig.validate`'s. The environment (``DDP_PROFILE``, ``DDP_RECIPE``)
is read only where a profile or recipe is None (:meth:`FitConfig.for_profile`), never by a check.
"""
from __future__ import annotations

import dataclasses
import difflib
import warnings
from dataclasses import dataclass

from ..core.checks import check_int
from .dip_tricks import DipTricks
from .kit.blend import CombinationConfig
from .kit.hole_terms import HoleConfig
from .kit.net_inputs import NetInputConfig
from .kit.recipes import get_recipe
from .kit.warp_terms import WarpConfig
from .paper.config import MAX_SEED, PaperConfig
from .paper.variants import get_variant
from .profiles import get_profile
from .runtime.device import Precision
from .runtime.options import RUN_OPTIONS
from .stopping import StoppingConfig

__all__ = ["FitConfig", "SECTIONS", "FIELDS", "QUALIFIED_NAMES", "RENAMED_FIELDS"]

SECTIONS = {"paper": PaperConfig, "net_inputs": NetInputConfig, "holes": HoleConfig, "warp": WarpConfig,
            "combination": CombinationConfig, "stopping": StoppingConfig, "tricks": DipTricks, "precision": Precision}
# every field by its flat name → (its section, its name there); each section spells out the flat names that are
# not its fields' own (its flat_names: the section refuses them, naming the field, where it stands alone)
FIELD_OF = {cls.flat_name(f.name): (section, f.name)
            for section, cls in SECTIONS.items() for f in dataclasses.fields(cls)}
FIELDS = tuple(FIELD_OF)  # every field by its flat name, section by section: the order of every flat view
# the flat names that are not the field's own: flat name → where the field is read
QUALIFIED_NAMES = {name: f"config.{section}.{field}" for name, (section, field) in FIELD_OF.items() if name != field}
# old spellings of fields, refused with the new name wherever a field is given or read by name
RENAMED_FIELDS = {"holdout": "held_out_shape", "holdout_fraction": "held_out_fraction"}


@dataclass(init=False, slots=True)
class FitConfig:
    """What a fit computes besides the data: eight sections (this module's docstring). Defaults are the
    paper's (supplement).

    Use :meth:`for_profile` for the sizes and schedules of ``DDP_PROFILE``. Fields are given by their flat
    names (``FitConfig(lr=1e-2)``, ``config.replace(lr=1e-2)``, ``FitConfig(warp_cost="census")``) and read
    by their sections (``config.paper.lr``, ``config.warp.cost``); ``config.lr``, ``config.lr = 1e-2`` and a
    misspelt name raise ``AttributeError`` saying what to write instead, as does a run option
    (``FitConfig(progress=False)``: ``TypeError``, it goes to the run as ``options=RunOptions(progress=False)``).
    NumPy integers given for integer fields become Python ints.

    Example:
        >>> config = FitConfig(lr=1e-2, smoothness=1.0)
        >>> config.paper.lr, config.holes.smoothness, config.paper.lr_gamma
        (0.01, 1.0, 0.01)
    """

    paper: PaperConfig
    net_inputs: NetInputConfig
    holes: HoleConfig
    warp: WarpConfig
    combination: CombinationConfig
    stopping: StoppingConfig
    tricks: DipTricks
    precision: Precision

    def __init__(self, **settings):
        """Fields by their flat names (``lr=1e-2``, ``warp_cost="census"``) or whole sections
        (``holes=HoleConfig(...)``); a field given by name wins over its section. What is not given is the
        paper's default."""
        changes = {section: {} for section in SECTIONS}
        for name, value in settings.items():
            if name in FIELD_OF:
                section, field = FIELD_OF[name]
                changes[section][field] = value
            elif name not in SECTIONS:
                raise TypeError(_not_a_field(name, f"FitConfig got an unexpected field {name!r}"))
        for section, cls in SECTIONS.items():
            given = settings.get(section) or cls()
            object.__setattr__(self, section, dataclasses.replace(given, **changes[section]))

    def __getattr__(self, name):  # only names that are no attribute come here: say where the field is
        if name in FIELD_OF:
            section, field = FIELD_OF[name]
            raise AttributeError(f"FitConfig reads {name!r} by its section: config.{section}.{field}")
        raise AttributeError(_not_a_field(name, f"FitConfig has no field {name!r}"))

    def __setattr__(self, name, value):  # a whole section may be set; a field, or a typo, must not pass in silence
        if name in FIELD_OF:
            raise AttributeError(f"FitConfig changes {name!r} by a copy: config = config.replace({name}=...)")
        if name not in SECTIONS:
            raise AttributeError(_not_a_field(name, f"FitConfig has no field {name!r}"))
        object.__setattr__(self, name, value)

    def flat(self) -> dict:
        """Every field by its flat name, ``{"net": "unet", ..., "bf16": False}``, in :data:`FIELDS` order
        (the fit cache's key, a sequence's manifest); ``FitConfig(**config.flat())`` is ``config`` again."""
        return {name: getattr(getattr(self, section), field) for name, (section, field) in FIELD_OF.items()}

    @classmethod
    def for_profile(cls, profile=None, variant: str = "rgbd+warp", recipe=None, **overrides) -> "FitConfig":
        """The config of a profile (name, :class:`~ddp_lite.method.profiles.Profile` or None for
        ``DDP_PROFILE``) for ``variant``, running ``recipe`` (name, :class:`~ddp_lite.method.kit.recipes.Recipe`
        or None for ``DDP_RECIPE``; ``"kit"``, the default, is the paper's losses plus the kit's additions at
        that profile, ``"paper"`` the paper's method), then ``overrides``.

        The profile gives size and budget, the fields its :meth:`~ddp_lite.method.profiles.Profile.fit_settings`
        names: its schedule and auto-stop as they are, and three derived: ``channels`` (the UNet's or the
        SkipNet's widths, by ``net``), ``iterations`` (the variant's count) and ``lr_milestones`` (those the
        variant's run reaches).
        The recipe gives the method: its :meth:`~ddp_lite.method.kit.recipes.Recipe.settings` at the profile's name.

        Example:
            >>> config = FitConfig.for_profile("ci", variant="rgbd", recipe="paper")
            >>> config.holes.smoothness, config.net_inputs.base, config.net_inputs.image_input
            (0.0, 'noise', 0.0)
        """
        profile = get_profile(profile)
        values = profile.fit_settings(get_variant(variant), overrides.get("net", "unet"))
        values.update(get_recipe(recipe).settings(profile.name))
        if not get_variant(variant).uses_rgb:  # a colour-guided fill or solve would bring colour into a depth-only result
            if values.get("refine") and "refine" not in overrides:  # the recipe's own solve: say that it is dropped
                from .inert_settings import InertSettingWarning
                fill = " and its share of a colour-guided fill" if values.get("blend_fill", 0.0) != 0 else ""
                warnings.warn(f"recipe {get_recipe(recipe).name!r}: its refine (an image-guided solve toward the fit)"
                              f"{fill} dropped for variant {get_variant(variant).name!r} (depth only, no colour to "
                              f"guide it): the result is its fit alone", InertSettingWarning, stacklevel=2)
            values["blend_fill"] = 0.0
            values["refine"] = False
        values.update(overrides)
        return cls(**values)

    def replace(self, **changes) -> "FitConfig":
        """A copy with some fields (by their flat names) or sections changed."""
        return dataclasses.replace(self, **changes)

    def resolved_iterations(self, variant: str) -> int:
        """The iteration count this config runs for ``variant``: ``iterations``, or the paper's."""
        if self.paper.iterations is not None:
            return int(self.paper.iterations)
        return get_variant(variant).paper_iterations

    def fit_count(self) -> int:
        """How many fits one call of ``complete_depth`` runs: the ensemble's members, or the blend's two."""
        return int(self.combination.ensemble) * (2 if self.combination.blend_paper else 1)

    def validate(self) -> None:
        """Raise ``TypeError``/``ValueError`` naming the first bad field: each section's own checks (every
        number finite and of its type, every choice one of its values), then the rules across sections."""
        for section in SECTIONS:
            getattr(self, section).validate()
        # seeds seed, seed+1, ... of the ensemble's members must all be seeds
        check_int(self.paper.seed, "config.seed", minimum=0, maximum=MAX_SEED - (self.combination.ensemble - 1))
        if self.net_inputs.base == "meshgrid" and self.paper.noise_channels < 2:
            raise ValueError(f"config.noise_channels must be at least 2 with net_input='meshgrid' (x and y), "
                             f"got {self.paper.noise_channels}")


def _not_a_field(name: str, message: str) -> str:
    """What to say of ``name``, no field of a FitConfig: its new name, where a run option goes, or the nearest name."""
    if name in RENAMED_FIELDS:
        return f"FitConfig has no {name!r}: the field is now {RENAMED_FIELDS[name]!r}"
    qualified = next((flat for flat, (_, field) in FIELD_OF.items() if field == name and flat != name), None)
    if qualified is not None:  # a field's name in its section, given where its flat name goes
        return f"FitConfig has no {name!r}: {QUALIFIED_NAMES[qualified]} is given by its flat name {qualified!r}"
    if name in RUN_OPTIONS:
        return (f"FitConfig has no {name!r}: it is a run option (how a fit runs, not what it computes); pass it to "
                f"the run: complete_depth(..., options=RunOptions({name}=...)) (ddp_lite.RunOptions)")
    if name == "run":
        return ("FitConfig has no section 'run': the run options (how a fit runs, not what it computes) are passed "
                "to the run: complete_depth(..., options=RunOptions(...)) (ddp_lite.RunOptions)")
    close = difflib.get_close_matches(name, FIELDS + RUN_OPTIONS, n=1)
    if not close:
        return message + "; see ddp_lite.method.config.FIELDS"
    if close[0] in RUN_OPTIONS:
        return message + f"; did you mean the run option {close[0]!r}? (options=RunOptions({close[0]}=...))"
    return message + f"; did you mean {close[0]!r}?"

