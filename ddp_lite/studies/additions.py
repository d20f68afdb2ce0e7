"""Beyond the paper: the kit's additions put on the paper's recipe one at a time, and what each buys.

The ``kit`` recipe is the paper's method plus a few pieces (``ddp_lite.method.kit.recipes.KIT_AT``).
:func:`addition_steps` orders them into a cumulative path from the ``paper`` recipe to the ``kit``
recipe at a profile; :func:`run_additions` fits every step on real and synthetic cases over several
seeds and scores each fit against the best classical fill of its case, so a step's gain is read
against the seeds' spread, on the real photograph and the rendered scenes apart.
"""
from __future__ import annotations

import numpy as np
import torch

from ..classical.baselines import BASELINES
from ..classical.stereo import pixel_disparity
from ..method.config import FitConfig
from ..method.complete import complete_depth
from ..method.kit.combine import mixed_with_fill
from ..method.runtime.options import RunOptions
from ..method.runtime.side_by_side import run_side_by_side
from ..method.profiles import get_profile
from ..method.kit.recipes import get_recipe
from ..evaluation.experiments import Case, make_case
from .real_cases import RealCase, factor_for_profile, make_real_case

__all__ = ["ADDITIONS", "addition_steps", "additions_cases", "run_additions", "hole_error_px", "paired_change",
           "format_additions"]

# The kit's additions in the order they are put on: (what, the FitConfig fields that carry it).
ADDITIONS = (
    ("the pixel coordinates as input", ("net_input", "noise_channels")),
    ("curvature in the holes", ("smoothness", "smoothness_edge", "edge_guide")),
    ("flatness in the holes", ("flatness", "flatness_reach")),
    ("the blurred colour image as input", ("image_input", "image_blur")),
    ("a share of a colour-guided fill in the result", ("blend_fill",)),
)


def addition_steps(profile=None) -> dict[str, dict]:
    """{step name: FitConfig overrides}, cumulative: ``"paper"`` (the paper's recipe), then ``"+ <what>"``
    for each of :data:`ADDITIONS` the ``kit`` recipe sets at ``profile``, the last being the kit's
    recipe. A step's overrides go with ``recipe="paper"`` to :meth:`FitConfig.for_profile`.

    Example:
        >>> list(addition_steps("ci"))  # ci's kit keeps the noise input
        ['paper', '+ curvature in the holes', '+ flatness in the holes', '+ the blurred colour image as input', '+ a share of a colour-guided fill in the result']
    """
    name = get_profile(profile).name
    paper, kit = get_recipe("paper").settings(name), get_recipe("kit").settings(name)
    steps, current = {"paper": {}}, {}
    for what, fields in ADDITIONS:
        change = {field: kit[field] for field in fields if field in kit and kit[field] != paper.get(field)}
        if change:
            current = {**current, **change}
            steps[f"+ {what}"] = dict(current)
    return steps


def additions_cases(profile=None, scenes=("house",), real_holes=("blobs-1", "occlusion")) -> dict[str, Case]:
    """The cases of the study: each synthetic scene with Depthcomp-style blob holes at the profile's size,
    then the real Motorcycle pair at the profile's pooling with each kind of ``real_holes``."""
    cases = {f"{scene}/blobs": make_case(scene, profile, holes="random") for scene in scenes}
    for holes in real_holes:
        case = make_real_case(holes, factor=factor_for_profile(profile))
        cases[case.name] = case
    return cases


def hole_error_px(case: Case, depth) -> float:
    """Hole RMSE of ``depth`` (H, W metres) in disparity pixels (d = f·B/Z) over the case's scored holes."""
    if isinstance(case, RealCase):
        return case.rmse_px(depth)
    f, baseline = case.camera.focal, case.scene.meta["baseline"]
    error = pixel_disparity(depth, f, baseline) - pixel_disparity(case.gt, f, baseline)
    return float(np.sqrt(np.mean(error[case.holes] ** 2)))


def _best_fill_px(case: Case) -> tuple[str, float]:
    """The classical fill with the lowest hole error on ``case`` and that error (px); fills work on disparity."""
    f_b = case.fb if isinstance(case, RealCase) else case.camera.focal * case.scene.meta["baseline"]
    disparity_in = f_b / case.depth  # (H, W) px, NaN holes
    errors = {name: hole_error_px(case, f_b / np.maximum(fill(disparity_in, case.rgb), 1e-6))
              for name, fill in BASELINES.items()}
    best = min(errors, key=errors.get)
    return best, errors[best]


def run_additions(cases: dict[str, Case], profile=None, seeds=(0, 1, 2), variant: str = "rgbd", log=print,
                  options: RunOptions = RunOptions(progress=False), net_of=None) -> dict:
    """Fit every step of :func:`addition_steps` on every case and seed: all the fits side by side, one
    torch thread each, as many at once as torch has threads (``side_by_side.run_side_by_side``), each run
    as ``options`` say (no progress bars by default). ``net_of``: the profile whose UNet widths the fits take
    (the one whose image size the cases have; None: ``profile``'s); ``profile`` sets the recipe and the budget.

    Returns ``{"steps": [names], "best_fill": {case: (name, px)}, "px": {case: {step: [px per seed]}},
    "ratio": {case: {step: [DDP px / best fill px, per seed]}}, "example": {case: {step: depth}}}``
    (the example: seed ``seeds[0]``'s completed depth, for figures). The fits run as a notebook's
    (``Profile.notebook_settings``: at ``ci`` a shorter run).
    """
    profile = get_profile(profile)
    steps = addition_steps(profile)
    short = profile.notebook_settings()
    widths = {} if net_of is None else {"channels": get_profile(net_of).channels}
    if short:
        log(f"each fit {short['iterations']} iterations (the profile's notebook_iterations)")
    names = list(steps)
    # a step that only adds the fill's share mixes it into the previous step's fits: the same net fit
    mixes_fill = {name: i > 0 and not steps[names[i - 1]].get("blend_fill")
                  and steps[name] == {**steps[names[i - 1]], "blend_fill": steps[name].get("blend_fill")}
                  for i, name in enumerate(names)}
    jobs = [(case_name, step, seed) for case_name in cases for step in names if not mixes_fill[step] for seed in seeds]

    def fit(k: int):
        case_name, step, seed = jobs[k]
        case = cases[case_name]
        config = FitConfig.for_profile(profile, variant=variant, recipe="paper", seed=seed, **steps[step], **short,
                                       **widths)
        neighbors = case.neighbors if variant == "rgbd+warp" else ()
        return complete_depth(case.rgb, case.depth, case.camera, neighbors, variant=variant, config=config,
                              options=options)
    workers = max(1, min(len(jobs), torch.get_num_threads()))  # independent fits side by side, a thread each
    fitted = dict(zip(jobs, run_side_by_side(fit, len(jobs), workers)))  # one pool: no core idles between cases
    out = {"steps": names, "best_fill": {}, "px": {}, "ratio": {}, "example": {}}
    for case_name, case in cases.items():
        out["best_fill"][case_name] = best = _best_fill_px(case)
        out["px"][case_name], out["ratio"][case_name], out["example"][case_name] = {}, {}, {}
        fits = {(step, seed): fitted[name, step, seed] for name, step, seed in fitted if name == case_name}
        for i, step in enumerate(names):
            if mixes_fill[step]:
                share = FitConfig.for_profile(profile, variant=variant, recipe="paper", **steps[step]).combination.blend_fill
                for seed in seeds:
                    fits[step, seed] = mixed_with_fill(fits[names[i - 1], seed], np.asarray(case.depth, np.float32),
                                                       np.asarray(case.rgb, np.float32), share)
            merged = [fits[step, seed].merged(case.depth) for seed in seeds]
            errors = [hole_error_px(case, depth) for depth in merged]
            out["example"][case_name][step] = merged[0]
            out["px"][case_name][step] = errors
            out["ratio"][case_name][step] = [e / best[1] for e in errors]
            log(f"{case_name:<22} {step:<38} " + " ".join(f"{e:.3f}" for e in errors) + " px")
    return out


def paired_change(before, after) -> tuple[float, float, int]:
    """How ``after`` changed the errors ``before`` of the same fits (same case, same seed): the mean of
    after − before, its standard error (sample standard deviation / √n; 0 for one pair) and how
    many pairs got lower. Pairing removes what the case and the seed do to both.

    Example:
        >>> mean, stderr, better = paired_change([1.0, 1.2, 0.9], [0.9, 0.9, 1.0])
        >>> round(mean, 3), round(stderr, 3), better
        (-0.1, 0.115, 2)
    """
    difference = np.asarray(after, np.float64) - np.asarray(before, np.float64)
    stderr = float(difference.std(ddof=1) / np.sqrt(difference.size)) if difference.size > 1 else 0.0
    return float(difference.mean()), stderr, int((difference < 0).sum())


def format_additions(results: dict, cases=None) -> str:
    """The table of :func:`run_additions`' results: per step, the mean ± std over seeds of DDP / the best
    classical fill on each case (below 1: DDP wins), and the paired change against the step before."""
    cases = list(results["ratio"]) if cases is None else list(cases)
    steps = results["steps"]
    width = max(len(s) for s in steps) + 2
    column = max(24, *(len(c) + 2 for c in cases), *(len(results["best_fill"][c][0]) + 10 for c in cases))
    lines = [" " * width + "".join(f"{name:>{column}}" for name in cases) + f"{'paired vs the step before':>34}"]
    lines.append(" " * width + "".join(f"{'(best: ' + results['best_fill'][c][0] + ')':>{column}}" for c in cases))
    for i, step in enumerate(steps):
        cells = "".join(f"{np.mean(results['ratio'][c][step]):>{column - 9}.3f} ± {np.std(results['ratio'][c][step]):.3f}"
                        for c in cases)
        change = ""
        if i > 0:
            before = np.concatenate([results["ratio"][c][steps[i - 1]] for c in cases])
            after = np.concatenate([results["ratio"][c][step] for c in cases])
            mean, stderr, better = paired_change(before, after)
            change = f"{mean:+.3f} ± {stderr:.3f}, {better}/{after.size} better"
        lines.append(f"{step:<{width}}{cells}{change:>34}")
    return "\n".join(lines)
