"""What do the real cases where DDP trails the fills have in common? Features of each suite case against DDP's ratio.

    python benchmarks/study_where_ddp_loses.py --data DIR [--method "DDP kit"] [--variant rgbd]

For every case of the real suite (``ddp_lite.studies.real_suite``) with rows in
``benchmarks/results/real_suite_<size>.jsonl``: DDP's hole RMSE over the best fill's, beside what the case's
holes are like: their share of the image, the share of the scored hole pixels near a depth edge of the truth,
on textured colour, far (> 6 px) from any valid input pixel (``RealCase.regions``), and the disparity range of
the truth in the holes. Prints each feature's Spearman rank correlation with the ratio over the cases, the
feature's mean over the quarter of cases where DDP does worst and the quarter where it does best, and the
worst cases. Asserts nothing; reads the ground truth only to describe the cases.
"""
from __future__ import annotations

import argparse
import os
from collections import defaultdict
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from ddp_lite.studies.real_suite import make_suite_case  # noqa: E402
from _common import parse_args, data_root, read_rows  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"


def ratios(path: Path, method: str, variant: str) -> dict:
    """{case: DDP px / best fill px} from the rows in ``path`` (mean over seeds)."""
    fills, fits = defaultdict(dict), defaultdict(list)
    for row in read_rows(path):
        if row["variant"] is None:
            fills[row["case"]][row["method"]] = row["px"]
        elif row["method"] == method and row["variant"] == variant:
            fits[row["case"]].append(row["px"])
    return {case: float(np.mean(px)) / min(fills[case].values()) for case, px in fits.items() if fills.get(case)}


def features(case) -> dict:
    """What the case's scored holes are like (shares of the scored hole pixels, disparity px)."""
    regions, scored = case.regions(), case.scored_holes
    count = max(int(scored.sum()), 1)
    disparity = case.fb / case.gt[scored]
    return {"hole share": float((~np.isfinite(case.depth)).mean()),
            "near an edge": regions["edges"].sum() / count,
            "textured": regions["textured"].sum() / count,
            "far from valid": regions["far"].sum() / count,
            "disparity spread": float(np.percentile(disparity, 95) - np.percentile(disparity, 5))}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, type=data_root, help="the folder of Middlebury scenes the suite ran on")
    parser.add_argument("--size", default="eighth", choices=("eighth", "quarter"))
    parser.add_argument("--method", default="DDP kit")
    parser.add_argument("--variant", default="rgbd", choices=("d", "rgbd", "rgbd+warp"))
    args = parse_args(parser, argv)
    table = ratios(RESULTS / f"real_suite_{args.size}.jsonl", args.method, args.variant)
    names = sorted(table)
    described = {name: features(make_suite_case(args.data, name, args.size)) for name in names}
    ratio = np.array([table[n] for n in names])
    order = np.argsort(ratio)
    quarter = max(1, len(names) // 4)
    print(f"{args.method}, {args.variant}: {len(names)} cases, ratio to the best fill {ratio.mean():.2f} on the mean")
    print(f"{'feature':<18} {'Spearman ρ':>10} {'p':>7} {'worst quarter':>14} {'best quarter':>13}")
    for key in described[names[0]]:
        values = np.array([described[n][key] for n in names])
        rho, p = stats.spearmanr(values, ratio)
        print(f"{key:<18} {rho:>10.2f} {p:>7.3f} {values[order[-quarter:]].mean():>14.3f} {values[order[:quarter]].mean():>13.3f}")
    print("worst cases: " + ", ".join(f"{names[i]} {ratio[i]:.2f}" for i in order[::-1][:8]))


if __name__ == "__main__":
    main()
