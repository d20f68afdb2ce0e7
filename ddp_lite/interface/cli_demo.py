"""``ddp-lite demo`` and ``ddp-lite scenes``: DDP on a built-in synthetic scene, beside classical fills.

``demo`` renders a scene at the profile's size (``--profile``, else ``DDP_PROFILE``, else class),
cuts holes, fills them with DDP (rgbd+warp, two neighbours), prints the hole RMSE of DDP, linear
and colorization fills (normalised disparity ×100, near depth edges, metres) and writes a 2×3
figure. ``--out`` (a format Matplotlib writes, in a writable folder) and the fit's memory estimate
at ``--size`` are checked before the scene is rendered. Handlers take the parsed ``argparse``
namespace and return the exit code; the parser is in ``cli``.
"""
from __future__ import annotations

import dataclasses
import os
import time

import numpy as np
from matplotlib.figure import Figure  # no pyplot: no backend to choose, no global figure state

from ..classical.depth_fills import fill_linear
from ..classical.guided_fills import fill_colorization
from ..method.runtime.device import resolve_device
from ..evaluation.experiments import error_table, format_table, make_case
from ..method.config import FitConfig
from ..method.complete import complete_depth
from ..method.runtime.memory import check_memory
from ..method.runtime.options import RunOptions, run_options
from ..method.time_left import earliest_share, expected_share
from ..method.paper.nets import check_input_size
from ..evaluation.metrics import hole_rmse
from ..core.outpaths import check_output_file
from ..method.profiles import get_profile
from ..method.kit.recipes import get_recipe
from ..core.progress import command_progress
from ..world.scenes import SCENES, list_scenes
from ..method.paper.variants import get_variant
from ..evaluation.viz import save_figure, show_depth, show_error, show_image

VARIANT = "rgbd+warp"
N_NEIGHBORS = 2  # make_case's neighbours of the reference view


def figure_suffixes() -> tuple[str, ...]:
    """The file endings Matplotlib can write (".png", ".pdf", ".svg", ...)."""
    return tuple(f".{kind}" for kind in Figure().canvas.get_supported_filetypes())


def demo_command(args) -> int:
    """``ddp-lite demo``: complete one synthetic scene's depth and save the figure."""
    start = time.perf_counter()
    check_output_file(args.out, "--out", suffixes=figure_suffixes(), example="ddp_demo.png")
    if args.scene not in SCENES:
        raise ValueError(f"--scene must be one of {', '.join(SCENES)} (ddp-lite scenes), got {args.scene!r}")
    profile = get_profile(args.profile)  # --profile, else DDP_PROFILE, else class
    profile = dataclasses.replace(profile, size=tuple(args.size)) if args.size else profile
    config = FitConfig.for_profile(profile, variant=VARIANT, recipe=args.recipe, iterations=args.iterations,
                                   seed=args.seed)
    config.validate()
    options = run_options(RunOptions(device=args.device, max_memory_gb=args.max_memory_gb))
    check_input_size(config.paper.net, config.paper.channels, *profile.size, name="--size")  # the net's smallest input
    # before the scene is rendered (minutes at a large --size): a fit that cannot fit in memory
    check_memory(config, options, get_variant(VARIANT).out_channels, *profile.size, N_NEIGHBORS,
                 resolve_device(options))
    case = make_case(args.scene, profile, holes=args.holes, seed=args.seed)
    print(f"{case.scene}\n{args.holes} holes: {np.isnan(case.depth).mean():.0%} of the reference view; "
          f"warp loss uses views {[n.name for n in case.neighbors]}")
    planned = config.resolved_iterations(VARIANT) * config.fit_count()  # every fit of the command
    with command_progress(planned, expected_share(config), earliest_share(config)):
        result = complete_depth(case.rgb, case.depth, case.camera, case.neighbors, variant=VARIANT, config=config,
                                gt_depth=case.scored_gt, transform=case.transform, options=options)
    estimates = {"linear": fill_linear(case.depth), "colorization": fill_colorization(case.depth, case.rgb),
                 "DDP rgbd+warp": result.depth}
    table = error_table(case, estimates)
    for name, depth in estimates.items():
        table[name]["holes (m)"] = hole_rmse(depth, case.gt, case.holes)
    print(format_table(table, 3, f"RMSE in the holes (sky not scored), DDP ({get_recipe(args.recipe).name} recipe) "
                                 f"after {result.iterations} iterations"
                                 + (f" (the mean of {result.fits} fits)" if result.fits > 1 else "") + ": "
                                 "normalised disparity ×100, its part near depth edges, metres"))

    ddp_error, linear_error = table["DDP rgbd+warp"]["holes (m)"], table["linear"]["holes (m)"]
    vmin, vmax = float(np.nanmin(case.gt)), float(np.nanmax(case.scored_gt))
    fig = Figure(figsize=(13, 6.5))
    axes = fig.subplots(2, 3)
    show_image(axes[0, 0], case.rgb, f"'{case.name}' reference view")
    show_depth(axes[0, 1], case.depth, f"input ({np.isnan(case.depth).mean():.0%} holes)", vmin, vmax)
    show_depth(axes[0, 2], case.gt, "ground truth", vmin, vmax)
    show_depth(axes[1, 0], result.depth, f"DDP (hole RMSE {ddp_error:.3f} m)", vmin, vmax)
    error_vmax = float(np.nanpercentile(np.abs(result.depth - case.gt)[case.holes], 99))
    show_error(axes[1, 1], result.depth, case.gt, "DDP |error| in holes", mask=case.holes, vmax=error_vmax)
    show_error(axes[1, 2], estimates["linear"], case.gt, f"linear fill |error| (RMSE {linear_error:.3f} m)",
               mask=case.holes, vmax=error_vmax)
    fig.tight_layout()
    save_figure(fig, args.out)
    print(f"figure written to {os.path.abspath(args.out)}; took {time.perf_counter() - start:.1f} s")
    return 0


def scenes_command(args) -> int:
    """``ddp-lite scenes``: list the built-in synthetic scenes."""
    scenes = list_scenes()
    width = max(len(name) for name in scenes)
    for name, description in scenes.items():
        print(f"{name:<{width}}  {description}")
    return 0
