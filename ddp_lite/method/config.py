"""FitConfig: everything a fit needs besides the data, in seven sections.

    network       the net and what it is fed             (nets.py)
    optimisation  Adam's learning rate, its schedule, the iterations, DIP's per-iteration tricks (loop.py)
    loss          the paper's loss: L1/SSIM shares, γ1, γ2, the warp term, the disparity range
    holes         the kit's hole terms and their edge weights (hole_losses.py, hole_terms.py)
    combination   what is averaged or blended into the answer: an ensemble, the paper's fit, a classical fill
    stopping      auto-stop on held-out pixels (stopping.PlateauStopper)
    runtime       seed, device, precision, memory, progress: where and how it runs, not what it computes

Each section is a frozen dataclass; ``config.holes.smoothness`` names a field by its section. Every field
also goes by its own name, as users and recipes write it: ``FitConfig(lr=1e-2, smoothness=1.0)``,
``config.lr``, ``config.lr = 1e-2`` (a new section with that field changed), ``config.replace(lr=1e-2)``,
``FitConfig.for_profile("ci", iterations=50)``. Defaults are the paper's (supplement). A profile's sizes and
schedules come from :meth:`FitConfig.for_profile`, the one place a :class:`~ddp_lite.method.profiles.Profile`
becomes a config; what differs between the DDP variants comes from :mod:`ddp_lite.method.paper.variants`.
"""
from __future__ import annotations

import dataclasses
import difflib
from dataclasses import dataclass

import numpy as np

from ..core.checks import check_bool, check_choice, check_int, check_int_tuple, check_real
from .runtime.device import resolve_device
from .kit.hole_losses import EDGE_GUIDES
from .paper.nets import DOWNSAMPLINGS, NET_INPUTS, NETS, PADDINGS, UPSAMPLINGS
from .profiles import Profile, get_profile
from .kit.recipes import get_recipe
from .kit.warp_cost import WARP_COSTS
from .kit.warp_terms import WARP_COMBINATIONS
from .paper.variants import get_variant

__all__ = ["FitConfig", "HOLDOUTS", "NetworkConfig", "OptimisationConfig", "LossConfig", "HolesConfig",
           "CombinationConfig", "StoppingConfig", "RuntimeConfig"]

HOLDOUTS = ("pixels", "blobs")


MAX_ITERATIONS = 1_000_000  # 60× the paper's 16000; more would only allocate (a loss history row per iteration)
MAX_SEED = 2**63 - 1  # seeds are signed 64-bit wherever torch and NumPy take them


class _Section:
    """What every section does on construction: NumPy integers become Python ints (``np.int64(3)`` → 3:
    torch's seeding takes Python ints only)."""

    def __post_init__(self):
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.integer):
                object.__setattr__(self, f.name, int(value))


@dataclass(frozen=True)
class NetworkConfig(_Section):
    """The network and its input (:mod:`ddp_lite.method.paper.nets`)."""

    net: str = "unet"  # "unet" or "skip"
    channels: tuple | None = None  # encoder widths; None → the paper's
    down: str = "stride"  # UNet down-sampling: "stride" (DIP) or "pool" (Ronneberger)
    up: str = "bilinear"  # UNet up-sampling: "bilinear" or "nearest"
    pad: str = "reflect"  # UNet conv padding: "reflect" (DIP) or "zeros"
    noise_channels: int = 16  # channels of the fixed network input
    net_input: str = "noise"  # "noise" (the paper) or "meshgrid" (x, y in the first two channels; nets.make_input)
    image_input: float = 0.0  # > 0: the colour image × this joins the net input (variants with colour; kit.net_inputs.image_channels)
    image_blur: float = 1.0  # σ in px of the Gaussian blur on that image (0: none)
    fill_input: float = 0.0  # > 0: a classical fill of the input disparity × this joins the net input (kit.net_inputs.fill_channel)


@dataclass(frozen=True)
class OptimisationConfig(_Section):
    """Adam's learning rate and its schedule, how many iterations, and Deep Image Prior's two
    per-iteration tricks (off in the paper). ``iterations=None`` means 16000 (6000 for depth only);
    milestones are absolute iterations."""

    lr: float = 5e-5
    schedule: str = "step"  # "step" (lr × lr_gamma at each milestone) or "cosine" (to 0 at the last iteration)
    iterations: int | None = None
    lr_milestones: tuple = (12000, 15000)
    lr_gamma: float = 0.01
    reg_noise_std: float = 0.0  # DIP input jitter: n + σ·N(0, 1) every iteration
    average_outputs: float = 0.0  # DIP output averaging: EMA weight (0.99 in DIP), 0 = off


@dataclass(frozen=True)
class LossConfig(_Section):
    """The paper's loss (Eq. 2-5): L_total = γ1·L_disp + γ2·L_rgb + (1-γ1-γ2)·L_warp, on the disparity range."""

    lambda_z: float = 0.8  # L1 share of L_disp
    lambda_i: float = 0.5  # L1 share of L_rgb
    lambda_w: float = 0.5  # SSIM share of L_warp
    gammas: tuple | None = None  # (γ1, γ2); None → (0.96, 0.02) with warp, (0.98, 0.01) without
    warp_occlusion: bool = False  # L_warp skips pixels a nearer point hides from the neighbour (warp.Warper; not in the paper)
    warp_confidence: bool = False  # L_warp only where the images single out one depth (method.warp_confidence; not in the paper)
    warp_reach: float | None = None  # L_warp only on the unfitted pixels (holes, held-out) and within this many px of
    # them, off the valid input L_disp pins (kit.warp_terms.warp_region; None: every pixel, the paper)
    warp_cost: str = "intensity"  # what L_warp compares: "intensity" (L1 + SSIM on colour, the paper), "census" (a
    # soft census, no L1/SSIM), "gradient" (L1 on the images' differences + SSIM) or "census+intensity" (half each,
    # the census at L1 + SSIM's size) (method.kit.warp_cost; not in the paper)
    warp_texture: bool = False  # L_warp weighted per pixel by the reference's change along the epipolar line
    # (method.kit.warp_cost.texture_weights: flat colour little; not in the paper)
    warp_combine: str = "mean"  # over the N neighbours: "mean" (the paper's Eq. 5) or "min": per pixel the neighbour
    # that agrees best (kit.warp_terms.minimum_over_neighbours; not in the paper)
    disparity_margin: float = 1.25  # transform=None: d_min / margin … d_max × margin around the valid depth


@dataclass(frozen=True)
class HolesConfig(_Section):
    """The kit's terms on the disparity in the holes (:mod:`ddp_lite.method.kit.hole_losses`; 0: off, the paper)."""

    smoothness: float = 0.0  # weight of an edge-aware second-order smoothness of disparity in the holes (0: the paper)
    smoothness_edge: float = 10.0  # how strongly colour edges relax both hole terms: exp(-edge · |∇I|)
    edge_guide: str = "grey"  # |∇I| of the grey image, or "rgb": the largest over the three channels
    flatness: float = 0.0  # weight of an edge-aware first-order smoothness in the holes (0: off)
    affinity: float = 0.0  # weight of the colorization energy in the holes (hole_losses.affinity_loss; 0: off)
    flatness_reach: float | None = None  # enclosed holes: that term only within this many px of valid depth (None: everywhere)
    step_reach: float | None = None  # hole terms off within this many px of a depth step in the valid input (None: on)


@dataclass(frozen=True)
class CombinationConfig(_Section):
    """What goes into the answer besides one fit (:mod:`ddp_lite.method.complete`): more seeds, the
    paper's fit, a classical fill."""

    ensemble: int = 1  # fits with seeds seed, seed+1, ...; their disparities are averaged
    blend_paper: bool = False  # also fit the paper's recipe and blend the two fits (method.blend)
    blend_weight: float | None = 0.5  # this config's fit's weight in that blend; None: chosen on a held-out ring
    blend_fill: float | None = 0.0  # share of the input's colour-guided fill in the final disparity (method.blend;
    # 0: none; None: chosen on held-out blobs of the valid input)


@dataclass(frozen=True)
class StoppingConfig(_Section):
    """When a fit stops before its iterations: on plateaus of the error on held-out valid pixels."""

    auto_stop: bool = False
    holdout_fraction: float = 0.05  # share of valid pixels held out when auto_stop is on
    holdout: str = "pixels"  # their shape: "pixels" (scattered) or "blobs" (hole-like patches)
    patience: int = 200  # iterations without held-out improvement that make a plateau
    plateau_decays: int = 0  # auto-stop: cut lr by lr_gamma at the first this-many plateaus, stop at the next
    eval_every: int = 10


@dataclass(frozen=True)
class RuntimeConfig(_Section):
    """Where and how a fit runs; the seed decides its numbers, the rest only its speed, memory and output."""

    seed: int = 0
    device: str | None = None  # None → cuda or mps when available, else cpu
    bf16: bool | None = False  # the network (not the losses) under bfloat16 autocast; None: where the hardware has it
    channels_last: bool = False  # memory format of the network's activations
    progress: bool = True
    callback_every: int = 0
    max_memory_gb: float | None = None  # refuse a fit whose estimated peak exceeds this; None → 75 % of RAM


SECTIONS = {"network": NetworkConfig, "optimisation": OptimisationConfig, "loss": LossConfig, "holes": HolesConfig,
            "combination": CombinationConfig, "stopping": StoppingConfig, "runtime": RuntimeConfig}
SECTION_OF = {f.name: section for section, cls in SECTIONS.items() for f in dataclasses.fields(cls)}  # field → section
# Every field by its own name, in one order for every flat view of a config (the fit cache's key, a
# sequence's manifest): the order of the fields when FitConfig had no sections, so a config hashes as it did.
FIELDS = ("net", "channels", "down", "up", "pad", "noise_channels", "net_input", "image_input", "image_blur",
          "fill_input", "lr", "schedule", "iterations", "lr_milestones", "lr_gamma", "lambda_z", "lambda_i",
          "lambda_w", "gammas", "warp_occlusion", "warp_confidence", "warp_reach",
          "warp_cost", "warp_texture", "warp_combine", "reg_noise_std", "average_outputs", "ensemble", "blend_paper",
          "blend_weight", "blend_fill", "smoothness", "smoothness_edge", "edge_guide", "flatness", "affinity",
          "flatness_reach", "step_reach", "disparity_margin", "auto_stop", "holdout_fraction", "holdout", "patience",
          "plateau_decays", "eval_every", "seed", "device", "bf16", "channels_last", "progress", "callback_every",
          "max_memory_gb")
assert sorted(FIELDS) == sorted(SECTION_OF), "FIELDS must name every section field once"


@dataclass(init=False, slots=True)
class FitConfig:
    """Everything a fit needs besides the data: seven sections (this module's docstring), each field also
    by its own name. Defaults are the paper's (supplement).

    Use :meth:`for_profile` for the sizes and schedules of ``DDP_PROFILE``. A field may be changed
    (``config.lr = 1e-2``); a misspelt one (``config.lerning_rate``) raises ``AttributeError`` instead of
    being ignored. NumPy integers given for integer fields become Python ints. A field by its own name
    goes through ``__getattr__`` (a type checker sees ``Any``); by its section it is typed.

    Example:
        >>> config = FitConfig(lr=1e-2, smoothness=1.0)
        >>> config.lr, config.holes.smoothness, config.optimisation.lr_gamma
        (0.01, 1.0, 0.01)
    """

    network: NetworkConfig
    optimisation: OptimisationConfig
    loss: LossConfig
    holes: HolesConfig
    combination: CombinationConfig
    stopping: StoppingConfig
    runtime: RuntimeConfig

    def __init__(self, **settings):
        """Fields by their own names (``lr=1e-2``) or whole sections (``holes=HolesConfig(...)``); a field
        given by name wins over its section. What is not given is the paper's default."""
        changes = {section: {} for section in SECTIONS}
        for name, value in settings.items():
            if name in SECTION_OF:
                changes[SECTION_OF[name]][name] = value
            elif name not in SECTIONS:
                raise TypeError(f"FitConfig got an unexpected field {name!r}" + _did_you_mean(name))
        for section, cls in SECTIONS.items():
            given = settings.get(section) or cls()
            object.__setattr__(self, section, dataclasses.replace(given, **changes[section]))

    def __getattr__(self, name):
        """A field by its own name (``config.lr``): only names that are no attribute come here."""
        section = SECTION_OF.get(name)
        if section is None:
            raise AttributeError(f"FitConfig has no field {name!r}" + _did_you_mean(name))
        return getattr(object.__getattribute__(self, section), name)

    def __setattr__(self, name, value):
        section = SECTION_OF.get(name)
        if section is not None:  # config.lr = 1e-2: the section is frozen, so a new one with that field changed
            name, value = section, dataclasses.replace(getattr(self, section), **{name: value})
        elif name not in SECTIONS:  # a typo must not pass in silence
            raise AttributeError(f"FitConfig has no field {name!r}" + _did_you_mean(name))
        object.__setattr__(self, name, value)

    def flat(self) -> dict:
        """Every field by its own name, ``{"net": "unet", ..., "max_memory_gb": None}``, in :data:`FIELDS` order."""
        return {name: getattr(self, name) for name in FIELDS}

    @classmethod
    def for_profile(cls, profile=None, variant: str = "rgbd+warp", recipe=None, **overrides) -> "FitConfig":
        """The config of a profile (name, :class:`Profile` or None for ``DDP_PROFILE``) for ``variant``,
        running ``recipe`` (name, :class:`~ddp_lite.method.kit.recipes.Recipe` or None for ``DDP_RECIPE``; ``"kit"``,
        the default, is the paper's losses plus the kit's additions at that profile, ``"paper"`` the
        paper's method), then ``overrides``.

        The profile gives size and budget: every :class:`Profile` field that is also a FitConfig field
        is copied, and three are derived: ``channels`` (the UNet's or the SkipNet's widths, by ``net``),
        ``iterations`` (the variant's count) and ``lr_milestones`` (those the variant's run reaches).
        The recipe gives the method: its :meth:`~ddp_lite.method.kit.recipes.Recipe.settings` at the profile's name.

        Example:
            >>> config = FitConfig.for_profile("ci", variant="rgbd", recipe="paper")
            >>> config.smoothness, config.net_input, config.image_input
            (0.0, 'noise', 0.0)
        """
        profile = get_profile(profile)
        iterations = profile.iterations_for(get_variant(variant))
        net = overrides.get("net", "unet")
        values = {name: getattr(profile, name) for name in _COPIED_FROM_PROFILE}
        values.update(net=net, channels=profile.channels if net == "unet" else profile.skip_channels,
                      iterations=iterations, lr_milestones=profile.milestones(iterations))
        values.update(get_recipe(recipe).settings(profile.name))
        if not get_variant(variant).uses_rgb:  # a colour-guided fill would bring colour into a depth-only result
            values["blend_fill"] = 0.0
        values.update(overrides)
        return cls(**values)

    def replace(self, **changes) -> "FitConfig":
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    def resolved_iterations(self, variant: str) -> int:
        """The iteration count this config runs for ``variant``: ``iterations``, or the paper's."""
        if self.iterations is not None:
            return int(self.iterations)
        return get_variant(variant).paper_iterations

    def fit_count(self) -> int:
        """How many fits one call of ``complete_depth`` runs: the ensemble's members, or the blend's two."""
        return int(self.ensemble) * (2 if self.blend_paper else 1)

    def validate(self) -> None:
        """Raise ``TypeError``/``ValueError`` naming the first bad field: every number must be finite and
        of its type (no bool for an int, no 2.7 for an iteration count), every choice one of its values."""
        check_choice(self.net, "config.net", NETS)
        if self.channels is not None:
            check_int_tuple(self.channels, "config.channels", minimum=1, min_length=2 if self.net == "unet" else 1)
        for name, choices in (("down", DOWNSAMPLINGS), ("up", UPSAMPLINGS), ("pad", PADDINGS),
                              ("schedule", ("step", "cosine")), ("holdout", HOLDOUTS), ("net_input", NET_INPUTS),
                              ("edge_guide", EDGE_GUIDES), ("warp_cost", WARP_COSTS),
                              ("warp_combine", WARP_COMBINATIONS)):
            check_choice(getattr(self, name), f"config.{name}", choices)
        for name, minimum in (("noise_channels", 1), ("ensemble", 1), ("patience", 1), ("plateau_decays", 0),
                              ("eval_every", 1), ("callback_every", 0)):
            check_int(getattr(self, name), f"config.{name}", minimum=minimum)
        check_int(self.seed, "config.seed", minimum=0, maximum=MAX_SEED - (self.ensemble - 1))
        if self.net_input == "meshgrid" and self.noise_channels < 2:
            raise ValueError(f"config.noise_channels must be at least 2 with net_input='meshgrid' (x and y), "
                             f"got {self.noise_channels}")
        if self.iterations is not None:
            check_int(self.iterations, "config.iterations", minimum=1, maximum=MAX_ITERATIONS)
        check_int_tuple(self.lr_milestones, "config.lr_milestones", minimum=1)
        for name, low, high, low_open, high_open in (
                ("lr", 0.0, None, True, False), ("lr_gamma", 0.0, None, True, False),
                ("lambda_z", 0.0, 1.0, False, False), ("lambda_i", 0.0, 1.0, False, False),
                ("lambda_w", 0.0, 1.0, False, False), ("reg_noise_std", 0.0, None, False, False),
                ("average_outputs", 0.0, 1.0, False, True), ("smoothness", 0.0, None, False, False),
                ("flatness", 0.0, None, False, False), ("affinity", 0.0, None, False, False), ("image_input", 0.0, None, False, False),
                ("image_blur", 0.0, None, False, False), ("fill_input", 0.0, None, False, False),
                ("smoothness_edge", 0.0, None, False, False), ("disparity_margin", 1.0, None, False, False),
                ("holdout_fraction", 0.0, 0.5, True, True)):
            check_real(getattr(self, name), f"config.{name}", low, high, low_open, high_open)
        for name in ("auto_stop", "blend_paper", "channels_last", "progress", "warp_occlusion", "warp_confidence",
                     "warp_texture"):
            check_bool(getattr(self, name), f"config.{name}")
        if self.bf16 is not None:  # None: decided by the hardware (use_bf16)
            check_bool(self.bf16, "config.bf16")
        if self.gammas is not None:
            if isinstance(self.gammas, (str, bytes)) or not isinstance(self.gammas, (tuple, list)) or len(self.gammas) != 2:
                raise TypeError(f"config.gammas must be a pair (γ1, γ2), got {self.gammas!r}")
            g1, g2 = (check_real(g, f"config.gammas[{i}]", 0.0, 1.0) for i, g in enumerate(self.gammas))
            if g1 + g2 > 1.0:
                raise ValueError(f"config.gammas must have γ1 + γ2 ≤ 1, got {self.gammas}")
        if self.blend_paper and self.ensemble > 1:
            raise ValueError(f"config.blend_paper and config.ensemble > 1 cannot be combined (a blend of two fits "
                             f"is not averaged with more), got ensemble={self.ensemble}")
        if self.blend_weight is not None:
            check_real(self.blend_weight, "config.blend_weight", 0.0, 1.0)
        if self.blend_fill is not None:
            check_real(self.blend_fill, "config.blend_fill", 0.0, 1.0, high_open=True)  # 1 would be the fill alone
        if self.flatness_reach is not None:
            check_real(self.flatness_reach, "config.flatness_reach", 0.0, None)
        if self.step_reach is not None:
            check_real(self.step_reach, "config.step_reach", 0.0, None)
        if self.warp_combine == "min" and self.warp_texture:
            raise ValueError("config.warp_texture weights each neighbour's cost over the image; with "
                             "config.warp_combine='min' use one or the other")
        if self.warp_reach is not None:
            check_real(self.warp_reach, "config.warp_reach", 0.0, None)
        if self.max_memory_gb is not None:
            check_real(self.max_memory_gb, "config.max_memory_gb", 0.0, None, low_open=True)
        if self.device is not None:
            resolve_device(self)  # a name torch knows and a device this machine has


def _did_you_mean(name: str) -> str:
    close = difflib.get_close_matches(name, FIELDS, n=1)
    return f"; did you mean {close[0]!r}?" if close else "; see ddp_lite.method.config.FIELDS"


# the Profile fields for_profile copies as they are (channels, iterations, lr_milestones are derived)
_COPIED_FROM_PROFILE = tuple(sorted({f.name for f in dataclasses.fields(Profile)} & set(FIELDS)
                                    - {"channels", "iterations", "lr_milestones"}))
