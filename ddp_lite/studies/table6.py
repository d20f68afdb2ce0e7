"""The paper's Table 6 on its own scenes: Plastic under DepthComp's own holes, Baby1 and Bowling1 under
holes of the same kind, every fill and DDP, our figures beside the paper's.

The paper took DepthComp's inputs (Middlebury 2006 disparities with holes cut by hand, full size) and
reported RMSE in full-size disparity px. Only Plastic's holes are public; Baby1 and Bowling1 get
DepthComp-style brush strokes (``holes.stroke_holes``: about 8.5 % of the image, strokes H/18 wide, as on
Plastic). The kit's shipped copies are a quarter of full size (``data.samples``), pooled further to at most
the profile's pixels (:func:`table6_factor`), so our px are px of that working size: compare *ratios*
(DDP / linear, / FMM, / GIF, / EBI), which do not depend on the unit.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..classical.baselines import BASELINES, PAPER_TABLE6
from ..classical.baselines import PAPER_TABLE6_RMSE as BASELINE_PAPER_RMSE
from ..classical.holes import stroke_holes
from ..data.installed import DEPTHCOMP_FILE, SceneCopy, data_line, depthcomp_hole_file, find_scene, shipped_scene
from ..data.middlebury_rail import load_rail_scene
from ..data.samples import read_depthcomp_holes
from ..method.kit.recipes import FOR_PHOTOGRAPHS
from ..method.profiles import get_profile
from .real_cases import RealCase, compare_fills_on, factor_for_pixels, make_real_case

__all__ = ["TABLE6_SCENES", "PAPER_TABLE6_RMSE", "PAPER_ROWS", "table6_recipes", "table6_factor", "table6_sources", "table6_data_line",
           "table6_case", "table6", "paper_ratios", "our_ratios"]

TABLE6_SCENES = ("Plastic", "Baby1", "Bowling1")
# The paper's Table 6 (RMSE, full-size disparity px: Plastic, Baby, Bowling) and the kit's fill for each row
PAPER_TABLE6_RMSE = {row: values[:3] for row, values in BASELINE_PAPER_RMSE.items()}
PAPER_ROWS = dict(PAPER_TABLE6)  # the paper's rows the kit has (SSI and Depthcomp: no open implementation)


def table6_recipes(profile=None) -> tuple[str, ...]:
    """The recipes DDP runs under in Table 6 at ``profile`` (a name, a Profile or None: ``DDP_PROFILE``):
    the paper's and the one the kit recommends for real photographs (``recipes.FOR_PHOTOGRAPHS``), and at
    ``paper`` the ``kit`` recipe between them. ``class`` leaves ``kit`` out to keep a laptop's run of
    notebook 06 to minutes (one fit per recipe and scene); ``ci`` runs the paper's recipe alone, to keep
    ``make test`` short (the cells need only the paper's recipe); notebook 10 puts the kit's additions on the
    paper's recipe one at a time."""
    name = get_profile(profile).name
    wanted = {"ci": ("paper",), "class": ("paper", FOR_PHOTOGRAPHS), "paper": ("paper", "kit", FOR_PHOTOGRAPHS)}[name]
    return tuple(dict.fromkeys(wanted))  # in order, once each (the recommendation may be one of the others)


def table6_factor(profile, shape) -> int:
    """The pooling factor of a Table 6 scene of size ``shape`` (H, W) at ``profile`` (a name, a Profile or None:
    ``DDP_PROFILE``): the smallest integer that brings it to at most the profile's pixels (``class``: a
    quarter-size copy → about 92×105; ``paper``: a full-size one → half size). A single real case elsewhere
    takes up to twice the profile's pixels (``real_cases.factor_for_profile``); Table 6 fits every recipe on
    three scenes side by side, so it takes the profile's own, which keeps notebook 06 to a lesson's minutes.

    Example:
        >>> table6_factor("class", (277, 325)), table6_factor("paper", (1110, 1300))
        (3, 2)
    """
    H, W = get_profile(profile).size
    return factor_for_pixels(shape, H * W)


def table6_sources(profile=None, dest=None) -> dict[str, SceneCopy]:
    """{scene: the copy Table 6 reads}: the copy of each of ``TABLE6_SCENES`` that ``data_fetch`` installed
    (``middlebury2006``, any size: ``data.installed.find_scene``), else the shipped quarter-size sample. The
    ``ci`` profile always takes the shipped ones (seconds, the same numbers on every machine)."""
    use_installed = get_profile(profile).name != "ci"
    return {scene: (use_installed and find_scene(scene, dest, ("middlebury2006",))) or shipped_scene(scene)
            for scene in TABLE6_SCENES}


def table6_data_line(profile=None, dest=None) -> str:
    """The line that says which data Table 6 runs on (``data.installed.data_line``: for a shipped copy, the
    command that installs the real one)."""
    sources = table6_sources(profile, dest)
    shipped = [scene for scene, copy in sources.items() if copy.dataset == "shipped"]
    installed = [copy for copy in sources.values() if copy.dataset != "shipped"]
    if installed and sources["Plastic"].dataset != "shipped":
        installed.append(f"DepthComp's holes from {depthcomp_hole_file(sources['Plastic'], dest)}")
    why = "the ci profile always runs on them" if get_profile(profile).name == "ci" else "not installed"
    return data_line(installed, f"the shipped quarter-size {', '.join(shipped)}" if shipped else "", "middlebury2006",
                     shipped, why)


def table6_case(scene: str, profile=None, seed: int = 0, data=None) -> RealCase:
    """A Table 6 scene (``TABLE6_SCENES``) with its holes, pooled to the profile's pixels (:func:`table6_factor`)
    → :class:`RealCase`
    (the rail's view0 and view2 as neighbours). Plastic: DepthComp's own holes; the others: strokes
    (``seed``). ``data``: a folder of Middlebury scenes (``real_suite.find_scenes``) to take the scene from
    at its own size, DepthComp's full-size hole file with it when it is there; None: the copy
    ``table6_sources`` names (installed, else shipped). Deterministic."""
    if scene not in TABLE6_SCENES:
        raise ValueError(f"scene must be one of {TABLE6_SCENES}, got {scene!r}")
    if data is None:
        copy = table6_sources(profile)[scene]
        full = load_rail_scene(copy.folder, name=scene)
        hole_file = depthcomp_hole_file(copy)
    else:
        from .real_suite import find_scenes  # the suite reads folders; only this path needs it

        full = load_rail_scene(find_scenes(data)[scene], name=scene)
        hole_file = next(iter(sorted(Path(data).rglob(DEPTHCOMP_FILE))), None) or depthcomp_hole_file(shipped_scene(scene))
    if scene == "Plastic":
        holes = read_depthcomp_holes(hole_file, full.size)
    else:
        holes = ~stroke_holes(full[0].depth, seed=seed)[1] & np.isfinite(full[0].depth)
    factor = table6_factor(profile, full.size)
    return make_real_case("depthcomp" if scene == "Plastic" else "strokes", factor, full, hole_mask=holes)


def table6(profile=None, recipes=None, seed: int = 0) -> tuple[dict, dict]:
    """Every fill and DDP under ``recipes`` (rgbd, as the paper runs Middlebury; None: ``table6_recipes``) on
    the three scenes → ``(rmse, outputs)``: {scene: {method: hole RMSE in working-size disparity px}} and
    {scene: (case, truth (H, W) px, {method: (H, W) px})}. The fits run as a notebook's
    (``Profile.notebook_settings``: at ``ci`` a shorter run)."""
    profile = get_profile(profile)
    recipes = table6_recipes(profile) if recipes is None else recipes
    rmse, outputs = {}, {}
    cases = [table6_case(scene, profile, seed) for scene in TABLE6_SCENES]
    every = compare_fills_on(cases, profile, recipes=recipes, seed=seed,  # every scene's fits in one side-by-side pool
                             **profile.notebook_settings())
    for scene, case, estimates in zip(TABLE6_SCENES, cases, every):
        truth = case.fb / case.gt
        rmse[scene] = {name: case.rmse_px(case.fb / d) for name, d in estimates.items()}
        outputs[scene] = (case, truth, estimates)
    return rmse, outputs


def paper_ratios() -> dict[str, float]:
    """The paper's DDP / row, on the mean over its three scenes, for the rows the kit has."""
    ddp = np.mean(PAPER_TABLE6_RMSE["DDP"])
    return {row: float(ddp / np.mean(PAPER_TABLE6_RMSE[row])) for row in PAPER_ROWS}


def our_ratios(rmse: dict, method: str = "DDP kit") -> dict[str, float]:
    """Our ``method`` / each of the paper's rows the kit has, on the mean over the scenes of ``rmse``."""
    ours = np.mean([table[method] for table in rmse.values()])
    return {row: float(ours / np.mean([table[fill] for table in rmse.values()]))
            for row, fill in PAPER_ROWS.items() if fill in BASELINES}
