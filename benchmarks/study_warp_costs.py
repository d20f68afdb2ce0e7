"""Where does each warp cost point? The per-pixel minimum of the intensity, census and gradient costs on the real pair.

    python benchmarks/study_warp_costs.py            # the five real hole kinds at 125×185, ~15 s
    python benchmarks/study_warp_costs.py --scale    # each cost's mean at the true depth, on the valid input

As ``study_warp_residual.py`` does for the paper's cost: for each real case (the right view as the
neighbour), a plane sweep over the fit's depth range, 0.25 px of disparity apart, of each cost of
``ddp_lite.method.kit.warp_cost`` per pixel (the intensity cost: ``warp_confidence.photometric_cost``; the
census: the soft Hamming distance of the two soft censuses, with the kit's constants and with UnFlow's
(ε = 0.81 on 0-255, 5×5); the gradient cost: ½ L1 of the forward differences + ½ (1 − SSIM), SSIM's map
padded as ``photometric_cost`` pads it). Printed: the share of pixels whose sweep minimum lies more than
2 px of disparity from the truth, in the scored holes (all, visible textured, visible flat, hidden; as
``study_warp_residual.py`` splits them) and on the valid input. Ground truth is used only to score.
"""
from __future__ import annotations

import argparse
import math
import os
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from ddp_lite.method.runtime.tensors import to_tensor  # noqa: E402
from ddp_lite.method.kit.visibility import Visibility  # noqa: E402
from ddp_lite.method.paper.warp import Warper  # noqa: E402
from ddp_lite.method.kit.warp_confidence import CHUNK, photometric_cost, structure_per_pixel  # noqa: E402
from ddp_lite.method.kit.warp_cost import forward_differences, census_distance, grey, soft_census  # noqa: E402
from ddp_lite.studies.real_cases import REAL_HOLES  # noqa: E402

sys.path.insert(0, os.path.dirname(__file__))
from _common import parse_args  # noqa: E402
from study_warp_residual import filled_truth, real_sweep, textured_pixels  # noqa: E402  (the same pair, planes, truth)

WRONG_PX = 2.0  # a minimum this far from the truth pulls the fit wrong
UNFLOW = dict(radius=2, epsilon=0.81 / 255.0 ** 2)  # UnFlow's soft sign (its patch is 7×7; 5×5 here)


def costs(reference: torch.Tensor, warped: torch.Tensor) -> dict:
    """Each cost per pixel, (D, 1, H, W), of ``warped`` (D, 3, H, W) against ``reference`` (1, 3, H, W)."""
    structure = structure_per_pixel(reference, warped)
    gradient = (forward_differences(warped) - forward_differences(reference)).abs().mean(dim=1, keepdim=True)
    return {"intensity": photometric_cost(reference, warped),
            "census": census_distance(soft_census(grey(warped)), soft_census(grey(reference))),
            "census, UnFlow's ε, 5×5": census_distance(soft_census(grey(warped), **UNFLOW),
                                                       soft_census(grey(reference), **UNFLOW)),
            "gradient": 0.5 * gradient + 0.5 * (1.0 - structure)}


@torch.no_grad()
def study(holes: str) -> None:
    case, nbr, ref, image, _, planes = real_sweep(holes)
    warper, (H, W) = Warper(case.camera, nbr.camera), ref.shape[-2:]
    volumes: dict = {}
    for start in range(0, len(planes), CHUNK):
        depths = torch.tensor(planes[start:start + CHUNK], dtype=ref.dtype).reshape(-1, 1, 1, 1).expand(-1, 1, H, W)
        warped, valid = warper(image.expand(len(depths), -1, -1, -1), depths)
        for name, cost in costs(ref, warped).items():
            volumes.setdefault(name, []).append(torch.where(valid, cost, torch.full_like(cost, math.inf))[:, 0])
    truth = filled_truth(case)
    hidden = Visibility(case.camera, nbr.camera)(to_tensor(truth, "cpu"))[0, 0].numpy()
    textured = textured_pixels(case)
    print(f"{holes}: share of pixels whose minimum is > {WRONG_PX:g} px from the truth")
    print(f"  {'cost':26s} {'holes':>6s} {'vis tex':>8s} {'vis flat':>9s} {'hidden':>7s} {'valid':>6s}")
    for name, slices in volumes.items():
        volume = torch.cat(slices).numpy()
        seen = np.isfinite(volume.min(axis=0))
        wrong = np.abs(case.fb / planes[volume.argmin(axis=0)] - case.fb / truth) > WRONG_PX
        scored = case.scored_holes & seen
        valid = np.isfinite(case.depth) & np.isfinite(case.gt) & seen
        shares = [wrong[mask].mean() for mask in (scored, scored & ~hidden & textured, scored & ~hidden & ~textured,
                                                  scored & hidden, valid)]
        print(f"  {name:26s} " + " ".join(f"{s:{w}.2f}" for s, w in zip(shares, (6, 8, 9, 7, 6))))


@torch.no_grad()
def scale_at_truth(holes: str) -> dict:
    """Each cost's mean per pixel at the true depth over the valid input (known truth, landing inside the
    neighbour): the size of the warp term each cost gives where the depth is right, to weight one like another."""
    case, nbr, ref, image, _, _ = real_sweep(holes)
    truth = filled_truth(case)
    warped, seen = Warper(case.camera, nbr.camera)(image, to_tensor(truth, "cpu"))
    valid = np.isfinite(case.depth) & np.isfinite(case.gt) & seen[0, 0].numpy()
    return {name: float(cost[0, 0].numpy()[valid].mean()) for name, cost in costs(ref, warped).items()}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scale", action="store_true", help="each cost's mean at the true depth, on the valid input")
    args = parse_args(parser, argv)
    torch.set_num_threads(1)
    if args.scale:
        print(f"mean cost per pixel at the true depth, valid input: {'holes':10s} intensity  census  ratio")
        for kind in REAL_HOLES:
            means = scale_at_truth(kind)
            print(f"{'':52s}{kind:10s} {means['intensity']:9.4f} {means['census']:7.4f} "
                  f"{means['intensity'] / means['census']:6.3f}")
    else:
        for kind in REAL_HOLES:
            study(kind)


if __name__ == "__main__":
    main()
