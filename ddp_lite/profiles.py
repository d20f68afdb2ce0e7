"""One switch for sizes and schedules: the ``DDP_PROFILE`` environment variable.

- ``ci``: seconds per notebook on a 2-core CPU (what nbval runs): tiny images, a narrow net;
- ``class`` (default): minutes per notebook on a laptop CPU, sizes where the effects show;
- ``paper``: the paper's sizes and schedules (lr 5e-5, ×0.01 at 12000 and 15000 of 16000
  iterations; depth-only 6000), meant for a GPU.

The paper's learning rate was tuned for 960×512 images and 16000 iterations; at our small
sizes it fills nothing in 1000 iterations, so ``ci`` and ``class`` use a larger rate. ``ci``
cuts it ×0.3 at iterations 90 and 128 of a short fixed run of 150; ``class`` lets a held-out
5 % of the valid pixels decide: the rate is cut ×0.3 at the first plateau of their error (50
iterations without a new best) and the run stops at the second, keeping the best output (``fit.PlateauStopper``).

``ci`` and ``class`` add one term the paper does not have: an edge-aware curvature penalty on
the disparity in the holes (``FitConfig.smoothness``, ``losses.smoothness_loss``). At these
sizes nothing else keeps a hole far from valid pixels, above all one touching the image border,
from bending wherever the net's features happen to take it; the term is zero on any plane and
weaker across colour edges. On the quality suite (``benchmarks/bench_quality.py``) it cut DDP's
mean hole error relative to the best classical fill from 5.4× to 2.4× at ``ci`` (19 cases,
2 seeds) and from 1.34× to 1.22× at ``class`` (8 cases, 2 seeds; worse on large holes over thin
structures).

``class`` adds a second term in the holes: an edge-aware *first-order* smoothness
(``FitConfig.flatness``, ``losses.flatness_loss``), weight 0.6. Between valid pixels it leaves a
plane a plane; where a hole reaches the image border it makes the fill level off instead of
carrying the last slope outward, which the curvature term alone allows and which put some fits
far off (logs/sgm-sparse: 3.9× the best classical fill). Over the suite's 22 ``class`` cases
(seeds 0 and 1, issue 12), one fit with it scores 1.15× the best classical fill of each case
(geometric mean 1.09), against 1.26× (1.16) for one fit without it and 1.28× (1.18) for the
previous ``class`` recipe, the mean of three fits without it; on the 10 curved-scene and fixture
cases 1.06× against 1.35× (linear interpolation: 1.30×). Weight 0.3 lost logs/sgm-sparse again
(2.5×), weight 1 lost more on ground planes seen at a slant whose holes touch the border
(street/blobs 2.9×), where the slope should go on. Confining it to holes that touch the border and a
4 px rim of the enclosed ones (``FitConfig(flatness_reach=4)``, ninth pass), so that curvature alone
fills the middle of a large enclosed hole as biharmonic interpolation does, scored 0.825× against
0.840× over three seeds (blobs gain, two SGM and street cases lose), inside the spread. With the
term the seeds agree (weight 1: one fit 1.18-1.22× by seed, the mean of three 1.19×), so ``class``
fits once. Its UNet has half the
paper's widths (16–256, a quarter of its convolution work): at 96×128 one such fit scored 1.33×
against 1.57× for the paper's 32–512 (both without the term), at a third of the time. ``ci``
kept the curvature term only until the eighth pass (below): at 48×64, before the colour image
was in the net's input, a first-order weight of 1 helped the suite's mean (2.27× → 2.01×) and
hurt its curved-scene cases (1.33× → 1.40×).
``class`` feeds the net the pixel coordinates instead of noise (``FitConfig(net_input="meshgrid",
noise_channels=2)``: channel 0 is x, channel 1 is y, both in [0, 1]), the input Deep Image Prior
uses for large holes. From noise, a hole pixel's output depends on the noise under it, through
the UNet's full-resolution skips, and only the loss terms keep it in line; from the coordinates
the net starts as a smooth function of position, so holes at the border and far from valid
pixels are continued smoothly. Over the 22 cases (seeds 0 and 1, issue 12, fifth pass) one fit
scores 0.99× the best classical fill of each case (geometric mean 0.94; 15 of 22 cases better)
against 1.15× (1.09) from noise; on the 10 curved-scene and fixture cases 1.00× against 1.06×.
Coordinates plus 14 noise channels scored 1.03× (0.97), and DIP's hourglass (its skip net without
skip branches) from noise 1.04× at twice the time. ``ci`` keeps the noise: at 48×64 the
coordinates helped the geometric mean (1.57× → 1.46×) and the curved cases (1.53× → 1.44×) but
doubled two blob cases on planes (house/blobs 2.3× → 4.7×).
Both hole terms are relaxed at colour edges by ``exp(-edge · |∇I|)`` of the grey image
(``FitConfig.smoothness_edge``). Each term is divided by the sum of its weights, so only their
ratio matters: ``class`` used edge 100 (300 since the seventh pass, below), where the terms act
almost only where the colour is flat and leave textured regions to the net; ``ci`` kept 10 until
the eighth pass (100 since, below).
Over the 22 cases (seeds 0 and 1, issue 12, sixth pass) one ``class`` fit scored 0.90× the best
classical fill (geometric mean 0.88; 16 of 22 better; worst 1.46×) against 0.99× (0.94; worst 2.26×) at 10; with seed 0 only, 30 gave 0.97×,
300 0.92× and 1000 0.95×. The largest gain is a blob hole over a textured ground plane at the
border (house/blobs: 2.3× → 0.7×): at 10 the flatness term levelled the grass off, at 100 the
net carries the ground's slope on. At ``ci`` (48×64, noise input, no flatness term) edge 100
was worse (2.28× vs 2.24×; curved cases 1.71× vs 1.53×). Measuring the colour change on R, G
and B (``edge_guide="rgb"``) instead of grey scored 0.88× against 0.90× on the suite, within its
paired spread (±0.025), and was worse on the notebooks' own cases (notebook 06: 0.416 px against
0.287), so ``class`` stays on grey.
``class`` also gives the net the view's colour image, blurred with σ = 1 px, as three more input
channels (``FitConfig(image_input=1, image_blur=1)``, ``nets.image_channels``; only variants that
see the colour image, so depth-only stays depth-only); ``ci`` too, blurred with σ = 0.5 px (the
same blur relative to its 48×64 image). From the coordinates alone the net draws a
depth edge inside a hole as a blurred ramp; with the colours in its input it can put the edge where
the colour edge is. Over the 22 cases (seeds 0 and 1, issue 12, seventh pass), at colour-edge
strength 100, one fit scored 0.875× the best classical fill (geometric mean 0.851; 18 of 22
better; worst 1.32×) against 0.904× (0.878; 16; 1.46×) without it, better in 30 of 44 (case, seed) fits, and 0.910× against 0.968× on the
curved-scene and fixture cases. The mean's gain (0.029) is about one standard error of the paired
fits: two cases lose (a blob over textured grass, where the colour says "far" and the slope says
"near"; a large hole on an untextured wall), most gain a little. Unblurred colours scored 0.880×
(seed 0, where σ = 1 px scored 0.869×; the grass case 1.47× against 1.15×), σ = 2 px 0.873×, the grey
image alone 0.918×. At ``ci`` (22 cases, two seeds) it cut the mean from 2.24× to 1.53× (geometric
mean 1.57× → 1.32×; worst 16.5× → 5.6×), with σ = 1 px 1.73×, unblurred 1.93×.
With the colours in the net's input, ``class`` relaxes the hole terms at colour edges more
strongly, ``smoothness_edge=300`` (without the image 300 was worse than 100): 0.825× the best
classical fill (geometric mean 0.804; 19 of 22 better; worst 1.30×) against 0.875× at 100,
better in 34 of 44 fits (paired −0.049 ± 0.014), 0.863× on the curved-scene and fixture cases.
The image now draws the depth edges, so the terms need only act where the colour is flat; the
grass case recovers (house/blobs 1.08× → 0.82×).
``ci`` followed in the eighth pass: with the colour image in its input, colour-edge strength 100
and the flatness term at 0.6 (``smoothness_edge=100, flatness=0.6``; it had 10 and none). Over
the 22 cases at 48×64 (seeds 0 and 1) one fit scored 1.38× the best classical fill (geometric
mean 1.15×; 10 of 22 better) against 1.53× (1.32×; 7), better in 32 of 44 fits (log ratio
−0.14 ± 0.05), 1.08× against 1.34× on the curved-scene and fixture cases; its worst case, a blob
on a plane that biharmonic fills almost exactly, rose from 5.6× to 6.4×. Strength 100 alone
scored 1.41× (30: 1.41×, 300: 1.67×); with flatness 0.3 1.43×, with curvature weight 2 1.52×,
from the coordinates 1.71×.
``paper`` keeps the paper's net, input and losses. ``class`` runs the net in bfloat16 where the
CPU computes it natively (``FitConfig(bf16=None)``): over the 22 cases (seeds 0 and 1, eighth
pass) float32 scored 0.857× the best classical fill against bfloat16's 0.825× (paired +0.032 ±
0.016; 16 of 44 fits better in float32), at 23.0 against 20.4 s per fit.
"""
from __future__ import annotations

from dataclasses import dataclass

from .checks import env_choice, named_choice
from .variants import get_variant

__all__ = ["Profile", "PROFILES", "get_profile", "current_profile_name"]

ENV_VAR = "DDP_PROFILE"
DEFAULT = "class"


@dataclass(frozen=True)
class Profile:
    """Sizes and schedules one profile uses everywhere. A field named like a ``FitConfig`` field is
    copied into the configs :meth:`FitConfig.for_profile` builds (``channels``, ``iterations`` and
    ``lr_milestones`` are derived per variant and net); the others size scenes, tables and DIP."""

    name: str
    size: tuple[int, int]  # (H, W) of scenes and images
    channels: tuple[int, ...]  # UNet encoder widths
    skip_channels: tuple[int, ...]  # SkipNet widths
    iterations: int  # RGBD variants
    iterations_depth_only: int
    lr: float
    lr_milestones: tuple[int, ...]  # iterations (as in FitConfig) where lr × lr_gamma; a shorter run skips them
    lr_gamma: float
    auto_stop: bool
    patience: int
    plateau_decays: int  # auto-stop: lr cuts on held-out plateaus before the stop
    eval_every: int
    n_views: int  # views per synthetic multi-view scene
    seeds: tuple[int, ...]  # seeds for "mean and spread" tables
    image_iterations: int  # Deep Image Prior on a natural image
    smoothness: float = 0.0  # FitConfig.smoothness: curvature penalty in the holes (0 = the paper's losses only)
    smoothness_edge: float = 10.0  # FitConfig.smoothness_edge
    edge_guide: str = "grey"  # FitConfig.edge_guide: the colour change those edges are measured on
    flatness: float = 0.0  # FitConfig.flatness: first-order smoothness in the holes (0 = off)
    flatness_reach: float | None = None  # FitConfig.flatness_reach: its reach into enclosed holes (None: all of them)
    net_input: str = "noise"  # FitConfig.net_input: the fixed network input ("noise" or "meshgrid")
    noise_channels: int = 16  # FitConfig.noise_channels: its channel count
    image_input: float = 0.0  # FitConfig.image_input: the colour image's scale as extra input channels (0: off)
    image_blur: float = 1.0  # FitConfig.image_blur: σ (px) of the blur on that image
    bf16: bool | None = False  # FitConfig.bf16 (None: bfloat16 where the hardware computes it natively)
    ensemble: int = 1  # FitConfig.ensemble: the mean disparity of this many seeds' fits

    def iterations_for(self, variant) -> int:
        """The iteration count of ``variant`` (a name or :class:`~ddp_lite.variants.Variant`) here."""
        return self.iterations_depth_only if get_variant(variant).depth_only else self.iterations

    def milestones(self, iterations: int) -> tuple[int, ...]:
        """The learning-rate decay iterations a run of ``iterations`` reaches (paper depth-only: none)."""
        return tuple(m for m in self.lr_milestones if m < iterations)

    def describe(self) -> str:
        """One line for a notebook's first cell."""
        H, W = self.size
        return (f"profile '{self.name}': {H}×{W} images, UNet {'-'.join(map(str, self.channels))}, "
                f"{'≤ ' if self.auto_stop else ''}{self.iterations} iterations (depth-only {self.iterations_depth_only}), "
                f"lr {self.lr:g}, auto-stop {'on' if self.auto_stop else 'off'}"
                + (f", hole curvature weight {self.smoothness:g}" if self.smoothness else "")
                + (f", hole flatness weight {self.flatness:g}" if self.flatness else "")
                + (f" (in enclosed holes only within {self.flatness_reach:g} px of valid depth)"
                   if self.flatness and self.flatness_reach is not None else "")
                + (f" (relaxed at colour edges by exp(-{self.smoothness_edge:g}·"
                   + ("|∇grey|" if self.edge_guide == "grey" else "max over R, G, B of |∇I|") + "))"
                   if self.smoothness or self.flatness else "")
                + (", input: the pixel coordinates" + (" + noise" if self.noise_channels > 2 else "")
                   if self.net_input == "meshgrid" else "")
                + (f" + the colour image (blurred, σ {self.image_blur:g} px; not for depth-only)" if self.image_input else "")
                + (f", mean of {self.ensemble} fits" if self.ensemble > 1 else ""))


PROFILES = {
    "ci": Profile("ci", size=(48, 64), channels=(16, 32, 64, 128), skip_channels=(32, 32, 32, 32),
                  iterations=150, iterations_depth_only=150, lr=1e-2, lr_milestones=(90, 128),
                  lr_gamma=0.3, auto_stop=False, patience=60, plateau_decays=0, eval_every=10, n_views=4, seeds=(0,),
                  image_iterations=120, smoothness=1.0, smoothness_edge=100.0, flatness=0.6, image_input=1.0,
                  image_blur=0.5),
    "class": Profile("class", size=(96, 128), channels=(16, 32, 64, 128, 256), skip_channels=(128,) * 5,
                     iterations=600, iterations_depth_only=600, lr=1e-2, lr_milestones=(),
                     lr_gamma=0.3, auto_stop=True, patience=50, plateau_decays=1, eval_every=10, n_views=6, seeds=(0, 1),
                     image_iterations=300, smoothness=1.0, smoothness_edge=300.0, flatness=0.6, net_input="meshgrid",
                     noise_channels=2, image_input=1.0, image_blur=1.0, bf16=None),
    "paper": Profile("paper", size=(512, 960), channels=(32, 64, 128, 256, 512), skip_channels=(128,) * 5,
                     iterations=16000, iterations_depth_only=6000, lr=5e-5, lr_milestones=(12000, 15000),
                     lr_gamma=0.01, auto_stop=False, patience=2000, plateau_decays=0, eval_every=100, n_views=8,
                     seeds=(0, 1, 2), image_iterations=3000),
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
