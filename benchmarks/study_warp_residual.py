"""Where does the warp term point? Its photometric cost inside the real pair's holes, at the truth and at its own minimum.

    python benchmarks/study_warp_residual.py            # the five real hole kinds at 125×185, ~15 s
    python benchmarks/study_warp_residual.py --data DIR --holes sgbm occlusion   # every Middlebury scene under DIR,
                                                        # each rail neighbour (view0, view2) apart; a line per scene

For each real case (``ddp_lite.studies.real_cases``, the right view as the neighbour), a plane sweep of the
warp term's own per-pixel cost (``warp_confidence.photometric_cost``: λw (1 − SSIM) + (1 − λw) L1, through
the kit's ``Warper``) over the fit's depth range, 0.25 px of disparity apart. Inside the scored holes:
the cost at the ground truth (warped through the true depth map) and at the sweep's minimum, and how far
that minimum's disparity lies from the truth; split by visible / hidden in the neighbour (the kit's
``Visibility`` on the true depth) and by textured / flat colour (grey-level std over 5×5 above / below
0.03, as ``RealCase.regions``). Then the share of hole pixels ``warp_confidence`` keeps, and how often
the minimum is wrong (> 2 px) among the kept and the dropped ones. Ground truth is used only to score.
"""
from __future__ import annotations

import argparse
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402
from scipy import ndimage  # noqa: E402

from ddp_lite.method.paper.disparity import DisparityTransform  # noqa: E402
from ddp_lite.method.runtime.tensors import to_tensor  # noqa: E402
from ddp_lite.method.kit.visibility import Visibility  # noqa: E402
from ddp_lite.method.paper.warp import Warper  # noqa: E402
from ddp_lite.method.kit.warp_confidence import cost_volume, photometric_cost, sweep_planes, warp_confidence  # noqa: E402
from ddp_lite.studies.real_cases import REAL_HOLES, make_real_case  # noqa: E402
from _common import parse_args  # noqa: E402

WRONG_PX = 2.0  # a minimum this far from the truth pulls the fit wrong


def real_sweep(holes: str, case=None, neighbor: int = 0):
    """The real pair at 1/4 with ``holes`` (or ``case``), its neighbour ``neighbor``, both images as tensors
    (1, 3, H, W), the fit's disparity range and the sweep's depth planes over it:
    ``(case, nbr, ref, image, transform, planes)``."""
    case = make_real_case(holes, 4) if case is None else case
    nbr = case.neighbors[neighbor]
    ref, image = to_tensor(case.rgb, "cpu"), to_tensor(nbr.rgb, "cpu")
    transform = DisparityTransform.from_depth(case.depth)  # the fit's range (the default a user gets)
    planes = sweep_planes(case.camera, nbr.camera, transform.d_min, transform.d_max)
    return case, nbr, ref, image, transform, planes


def filled_truth(case) -> np.ndarray:
    """(H, W) float32 metres: the true depth, its unknown pixels at its median (so every pixel warps somewhere)."""
    return np.where(np.isfinite(case.gt), case.gt, np.nanmedian(case.gt)).astype(np.float32)


def textured_pixels(case) -> np.ndarray:
    """(H, W) bool: the grey level's standard deviation over 5×5 above 0.03 (else "flat")."""
    grey = case.rgb.mean(axis=2)
    std = np.sqrt(np.maximum(ndimage.uniform_filter(grey ** 2, 5) - ndimage.uniform_filter(grey, 5) ** 2, 0))
    return std > 0.03


def study(holes: str) -> None:
    case, nbr, ref, image, transform, planes = real_sweep(holes)
    cost = cost_volume(ref, image, Warper(case.camera, nbr.camera), planes).numpy()  # (D, H, W)
    at_min = cost.min(axis=0)
    seen = np.isfinite(at_min)  # some plane lands inside the neighbour (not so at the left border: no minimum)
    disparity_min = case.fb / planes[cost.argmin(axis=0)]
    truth = filled_truth(case)
    with torch.no_grad():
        warped, _ = Warper(case.camera, nbr.camera)(image, to_tensor(truth, "cpu"))
        at_truth = photometric_cost(ref, warped)[0, 0].numpy()
        hidden = Visibility(case.camera, nbr.camera)(to_tensor(truth, "cpu"))[0, 0].numpy()
        confident = warp_confidence(ref, image, case.camera, nbr.camera, transform.d_min, transform.d_max)[0, 0].numpy()
    wrong = np.abs(disparity_min - case.fb / truth) > WRONG_PX
    textured, scored = textured_pixels(case), case.scored_holes & seen
    valid = np.isfinite(case.depth) & np.isfinite(case.gt) & seen
    print(f"{holes}: {scored.sum()} hole px with a minimum (of {case.scored_holes.sum()}), {len(planes)} planes; hidden {hidden[scored].mean():.2f}, "
          f"textured {textured[scored].mean():.2f}")
    print(f"  {'pixels':22s} {'n':>5s} {'cost@truth':>10s} {'cost@min':>9s} {'|d_min-d|':>9s} {'>2px':>5s}")
    for name, mask in (("holes", scored), ("holes visible", scored & ~hidden), ("holes hidden", scored & hidden),
                       ("holes visible textured", scored & ~hidden & textured),
                       ("holes visible flat", scored & ~hidden & ~textured), ("valid input", valid)):
        if mask.any():
            error = np.abs(disparity_min - case.fb / truth)[mask]
            print(f"  {name:22s} {mask.sum():5d} {at_truth[mask].mean():10.3f} {at_min[mask].mean():9.3f} "
                  f"{np.median(error):9.2f} {wrong[mask].mean():5.2f}")
    kept = scored & confident
    print(f"  warp_confidence keeps {kept.sum() / scored.sum():.2f} of the holes (wrong among kept "
          f"{wrong[kept].mean() if kept.any() else float('nan'):.2f}, among dropped {wrong[scored & ~confident].mean():.2f}), "
          f"{confident[valid].mean():.2f} of the valid input")


def scene_line(case, neighbor: int) -> str:
    """One line for a suite case and one neighbour: inside the scored holes the neighbour sees, the median
    distance (px) of the photometric minimum from the truth and the share farther than ``WRONG_PX``."""
    case, nbr, ref, image, transform, planes = real_sweep("", case, neighbor)
    cost = cost_volume(ref, image, Warper(case.camera, nbr.camera), planes).numpy()  # (D, H, W)
    seen = np.isfinite(cost.min(axis=0))
    truth = filled_truth(case)
    with torch.no_grad():
        hidden = Visibility(case.camera, nbr.camera)(to_tensor(truth, "cpu"))[0, 0].numpy()
    error = np.abs(case.fb / planes[np.nanargmin(np.where(np.isfinite(cost), cost, np.inf), axis=0)] - case.fb / truth)
    scored = case.scored_holes & seen & ~hidden
    if not scored.any():
        return f"{case.name:<22} {nbr.name:<7} no scored hole pixel the neighbour sees"
    return (f"{case.name:<22} {nbr.name:<7} {scored.sum():6d} px seen (hidden {(case.scored_holes & hidden).sum():5d}): "
            f"|d_min − d| median {np.median(error[scored]):5.2f} px, > {WRONG_PX:g} px {np.mean(error[scored] > WRONG_PX):.2f}")


def combined_lines(case) -> list[str]:
    """Two lines for a suite case with two or more neighbours: inside the scored holes, how far from the truth
    the minimum of the neighbours' *mean* cost lies (what the warp loss optimises) and that of their per-pixel
    *minimum* (the occlusion-robust reading: a pixel hidden from one neighbour is judged by the other)."""
    volumes, planes = [], None
    for k in range(len(case.neighbors)):
        _, nbr, ref, image, transform, planes_k = real_sweep("", case, k)
        planes = planes_k if planes is None else planes
        if len(planes_k) != len(planes) or not np.allclose(planes_k, planes):
            return [f"{case.name:<22} neighbours sweep different planes: no combined line"]
        volumes.append(cost_volume(ref, image, Warper(case.camera, nbr.camera), planes).numpy())  # (D, H, W) each
    stacked = np.stack(volumes)  # (N, D, H, W), NaN where a plane falls outside that neighbour
    truth_disparity = case.fb / filled_truth(case)
    lines = []
    for name, cost in (("mean", np.nanmean(stacked, axis=0)), ("min", np.nanmin(stacked, axis=0))):
        seen = np.isfinite(cost).any(axis=0)
        error = np.abs(case.fb / planes[np.argmin(np.where(np.isfinite(cost), cost, np.inf), axis=0)] - truth_disparity)
        scored = case.scored_holes & seen
        lines.append(f"{case.name:<22} {name + ' of ' + str(len(volumes)):<7} {scored.sum():6d} px: |d_min − d| median "
                     f"{np.median(error[scored]):5.2f} px, > {WRONG_PX:g} px {np.mean(error[scored] > WRONG_PX):.2f}")
    return lines


def main(argv=None) -> None:
    from ddp_lite.studies.real_suite import SUITE_HOLES, make_suite_case, suite_case_names
    from _common import data_root

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", metavar="DIR", type=data_root,
                        help="a folder of Middlebury scenes: the real suite's cases instead")
    parser.add_argument("--holes", nargs="+", default=None, choices=sorted(set(REAL_HOLES) | set(SUITE_HOLES)),
                        help="hole kinds (default: all of the chosen suite's)")
    parser.add_argument("--size", default="eighth", choices=("eighth", "quarter"))

    def check(args):
        kinds = SUITE_HOLES if args.data else REAL_HOLES
        wrong = [h for h in args.holes or () if h not in kinds]
        if wrong:
            raise ValueError(f"--holes: {', '.join(wrong)} not among the chosen suite's ({', '.join(kinds)})")
    args = parse_args(parser, argv, check)
    torch.set_num_threads(1)
    if args.data:
        for name in suite_case_names(args.data):
            if args.holes is None or name.split("/")[1] in args.holes:
                case = make_suite_case(args.data, name, args.size)
                for k in range(len(case.neighbors)):
                    print(scene_line(case, k), flush=True)
                if len(case.neighbors) > 1:
                    print("\n".join(combined_lines(case)), flush=True)
    else:
        for kind in args.holes or REAL_HOLES:
            study(kind)


if __name__ == "__main__":
    main()
