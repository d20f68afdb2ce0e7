"""Profiles: how big and how long, the ``DDP_PROFILE`` switch (``ci``, ``class`` or ``paper``).

- ``ci``: seconds per notebook on a 2-core CPU (what nbval runs): tiny images, a narrow net; ``make test``
  runs every notebook at ``ci`` as a smoke test of its cells, so a notebook's fits there run
  ``notebook_iterations`` (50 of 150). The notebooks' checks that read a fit hold there over fit seeds
  0-2, the two thinnest (04, 12) over 0-5 (``benchmarks/notebook_margins.py``,
  ``docs/studies/benchmark_history.md``);
- ``class`` (default): minutes per notebook on a laptop CPU, sizes where the effects show;
- ``paper``: the paper's sizes and schedules (lr 5e-5, ×0.01 at 12000 and 15000 of 16000
  iterations; depth-only 6000), meant for a GPU.

A profile sets size and budget only: image size, net widths, iterations, learning-rate schedule,
auto-stop, views per scene, seeds. What a fit optimises is the recipe (:mod:`ddp_lite.method.kit.recipes`).
The paper's rate fills nothing in 1000 iterations at our small sizes, so ``ci`` and ``class`` use
1e-2: ``ci`` cuts it ×0.3 at iterations 90 and 128 of a fixed 150; ``class`` cuts it at the first
plateau of a held-out error and stops at the second (:class:`~ddp_lite.method.stopping.PlateauStopper`).
How these settings were chosen: ``docs/studies/tuning_history.md``.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..core.checks import check_int, env_choice, named_choice
from .kit.recipes import get_recipe
from .paper.variants import get_variant

__all__ = ["Profile", "PROFILES", "get_profile", "current_profile_name", "profile_table", "update_profile_table"]

ENV_VAR = "DDP_PROFILE"
DEFAULT = "class"


@dataclass(frozen=True)
class Profile:
    """How big and how long: the sizes and the budget one profile uses everywhere.

    The learning-rate schedule and auto-stop are budget, not method: they decide how many iterations a
    fit spends and are tuned to that count (the paper's 5e-5 schedule is for 16000; 1e-2 fills in a few
    hundred), while what a fit optimises is the recipe's. :meth:`fit_settings` names the ``FitConfig``
    fields it sets (the configs :meth:`FitConfig.for_profile` builds); the others size scenes, tables and DIP."""

    name: str
    # how big
    size: tuple[int, int]  # (H, W) of scenes and images
    channels: tuple[int, ...]  # UNet encoder widths
    skip_channels: tuple[int, ...]  # SkipNet widths
    n_views: int  # views per synthetic multi-view scene
    seeds: tuple[int, ...]  # seeds for "mean and spread" tables
    # how long
    iterations: int  # RGBD variants
    iterations_depth_only: int
    image_iterations: int  # Deep Image Prior on a natural image
    notebook_iterations: int | None  # a notebook's depth fits (notebook_settings); None: iterations
    lr: float
    lr_milestones: tuple[int, ...]  # iterations (as in FitConfig) where lr × lr_gamma; a shorter run skips them
    lr_gamma: float
    auto_stop: bool
    patience: int
    plateau_decays: int  # auto-stop: lr cuts on held-out plateaus before the stop
    eval_every: int

    def iterations_for(self, variant) -> int:
        """The iteration count of ``variant`` (a name or :class:`~ddp_lite.method.paper.variants.Variant`) here."""
        return self.iterations_depth_only if get_variant(variant).depth_only else self.iterations

    def milestones(self, iterations: int) -> tuple[int, ...]:
        """The learning-rate decay iterations a run of ``iterations`` reaches (paper depth-only: none)."""
        return tuple(m for m in self.lr_milestones if m < iterations)

    def cut_short(self, iterations: int | None) -> dict:
        """The ``FitConfig`` fields that end this profile's schedule at ``iterations``: the count and the
        learning-rate decays it still reaches ({} for None: the profile's own run)."""
        if iterations is None:
            return {}
        iterations = check_int(iterations, "iterations", minimum=1)
        return {"iterations": iterations, "lr_milestones": self.milestones(iterations)}

    def notebook_settings(self) -> dict:
        """The ``FitConfig`` fields a notebook's depth fits take on top of :meth:`fit_settings`: the run cut to
        ``notebook_iterations`` (:meth:`cut_short`; {} where it is None, as at ``class`` and ``paper``).
        The notebooks' studies apply it (``evaluation.experiments``, ``studies``); a notebook that builds its
        own config passes it: ``FitConfig.for_profile(profile, ..., **profile.notebook_settings())``."""
        return self.cut_short(self.notebook_iterations)

    def fit_settings(self, variant, net: str = "unet") -> dict:
        """The ``FitConfig`` fields this profile sets for ``variant`` (a name or
        :class:`~ddp_lite.method.paper.variants.Variant`) and ``net``, each named here, field by field: a
        field renamed on either side fails loudly (here, or as ``FitConfig``'s unexpected field), never by a
        copy that stops in silence. ``channels``, ``iterations`` and ``lr_milestones`` are derived: the
        net's widths, the variant's count, the milestones that count reaches."""
        iterations = self.iterations_for(variant)
        return {"lr": self.lr, "lr_gamma": self.lr_gamma, "auto_stop": self.auto_stop, "patience": self.patience,
                "plateau_decays": self.plateau_decays, "eval_every": self.eval_every,
                "net": net, "channels": self.channels if net == "unet" else self.skip_channels,
                "iterations": iterations, "lr_milestones": self.milestones(iterations)}

    def describe(self, recipe=None) -> str:
        """One line for a notebook's first cell: the size and budget. With ``recipe`` (a name or
        :class:`Recipe`) a second line says what that recipe runs here (:meth:`Recipe.describe`)."""
        H, W = self.size
        return (f"profile '{self.name}': {H}×{W} images, UNet {'-'.join(map(str, self.channels))}, "
                f"{'≤ ' if self.auto_stop else ''}{self.iterations} iterations (depth-only {self.iterations_depth_only}), "
                f"lr {self.lr:g}, auto-stop {'on' if self.auto_stop else 'off'}"
                + (f"\n{get_recipe(recipe).describe(self)}" if recipe is not None else ""))


PROFILES = {
    "ci": Profile("ci", size=(48, 64), channels=(8, 16, 32, 64), skip_channels=(32, 32, 32, 32),
                  iterations=150, iterations_depth_only=150, lr=1e-2, lr_milestones=(90, 128),
                  lr_gamma=0.3, auto_stop=False, patience=60, plateau_decays=0, eval_every=10, n_views=4, seeds=(0,),
                  image_iterations=50, notebook_iterations=50),
    "class": Profile("class", size=(96, 128), channels=(16, 32, 64, 128, 256), skip_channels=(128,) * 5,
                     iterations=600, iterations_depth_only=600, lr=1e-2, lr_milestones=(),
                     lr_gamma=0.3, auto_stop=True, patience=50, plateau_decays=1, eval_every=10, n_views=6, seeds=(0, 1),
                     image_iterations=300, notebook_iterations=None),
    "paper": Profile("paper", size=(512, 960), channels=(32, 64, 128, 256, 512), skip_channels=(128,) * 5,
                     iterations=16000, iterations_depth_only=6000, lr=5e-5, lr_milestones=(12000, 15000),
                     lr_gamma=0.01, auto_stop=False, patience=2000, plateau_decays=0, eval_every=100, n_views=8,
                     seeds=(0, 1, 2), image_iterations=3000, notebook_iterations=None),
}


def current_profile_name() -> str:
    """The profile named by ``DDP_PROFILE`` (default ``class``)."""
    return env_choice(ENV_VAR, DEFAULT, PROFILES)


def get_profile(name: str | Profile | None = None) -> Profile:
    """The named profile, or the one ``DDP_PROFILE`` selects; a :class:`Profile` is returned as is
    (so every function taking ``profile`` accepts a name, a Profile or None the same way)."""
    if isinstance(name, Profile):
        return name
    return named_choice(name, PROFILES, "profile", current_profile_name)


MEANT_FOR = {"ci": "nbval in CI: seconds per notebook", "class": "a laptop CPU: minutes per notebook",
             "paper": "a GPU"}
TABLE_START = ("<!-- profile table: written by ddp_lite.method.profiles.profile_table; "
               "refresh: python -m ddp_lite.method.profiles README.md -->")
TABLE_END = "<!-- end of the profile table -->"


def profile_table() -> str:
    """The README's Markdown table of the profiles, written from :data:`PROFILES` so that it cannot drift
    from what a fit runs: size, net, a depth fit's iterations (and a notebook's, ``notebook_iterations``, where
    they differ) and learning rate, and an image fit's (notebook 01's Deep Image Prior fits, ``image_iterations``,
    always a fixed count)."""
    rows = ["| profile | size | net | iterations of a depth fit | learning rate | image fits (notebook 01) | meant for |",
            "|---|---|---|---|---|---|---|"]
    for name, p in PROFILES.items():
        iterations = (f"{'≤ ' if p.auto_stop else ''}{p.iterations}"
                      + (f" (depth-only {p.iterations_depth_only})" if p.iterations_depth_only != p.iterations else "")
                      + (", stops by itself" if p.auto_stop else ", fixed")
                      + (f"; a notebook's {p.notebook_iterations}" if p.notebook_iterations is not None else ""))
        if p.lr_milestones:
            schedule = f"{p.lr:g}, ×{p.lr_gamma:g} at {' and '.join(map(str, p.lr_milestones))}"
        elif p.plateau_decays:
            schedule = f"{p.lr:g}, ×{p.lr_gamma:g} at the held-out error's first plateau"
        else:
            schedule = f"{p.lr:g}"
        label = f"`{name}`" + (" (default)" if name == DEFAULT else "")
        rows.append(f"| {label} | {p.size[0]}×{p.size[1]} | UNet {p.channels[0]}–{p.channels[-1]} | {iterations} "
                    f"| {schedule} | {p.image_iterations}, fixed | {MEANT_FOR[name]} |")
    return "\n".join(rows)


def update_profile_table(readme) -> bool:
    """Rewrite the profile table between ``TABLE_START`` and ``TABLE_END`` in ``readme`` (atomically);
    True if it changed."""
    from ..core.files import replace_between_markers
    return replace_between_markers(readme, TABLE_START, TABLE_END, profile_table(), "profile table")


if __name__ == "__main__":  # python -m ddp_lite.method.profiles README.md: refresh the profile table
    import sys
    if len(sys.argv) != 2:
        sys.exit("usage: python -m ddp_lite.method.profiles README.md")
    print(f"{sys.argv[1]}: profile table {'updated' if update_profile_table(sys.argv[1]) else 'already up to date'}")
