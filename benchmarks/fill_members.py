"""Which classical fill, and how much of it, to mix into a fit's result: offline, from saved fits.

    python benchmarks/bench_quality.py --profile class --suite all --recipes 'alone:blend_fill=0' \\
        --variants rgbd --seeds 0 1 2 --out alone.jsonl --save-fits fits/       # the fits alone, once
    python benchmarks/fill_members.py --profile class --fits fits/ alone.jsonl --out members.jsonl

For every saved fit Z of the recipe ``alone`` (a fit with no fill mixed in) and every member M (one
classical fill of ``ddp_lite.classical.baselines``, or the mean of several) and share f, the hole
RMSE of (1 − f)·Z + f·M, all in disparity px (every fill is linear in its input, so mixing in
disparity px is mixing in the kit's normalised disparity), divided by the best classical fill of the
case. Printed per suite (real photographs, rendered scenes) and variant: the mean ratio, the paired
change against ``--reference`` with its standard error and how many fits gain, and the geometric
mean, which one case with a near-exact fill cannot carry. No fit runs here. Asserts nothing.
"""
from __future__ import annotations

import argparse
import collections
import json
from pathlib import Path

import numpy as np

import bench_quality as bq
from ddp_lite.core.files import atomic_path
from ddp_lite.classical.baselines import BASELINES
from ddp_lite.method.kit.blend import FILL_MEMBERS
from _common import add_profile_args, profile_from_args, parse_args, existing_file, existing_folder, check_rows_out, read_rows

MEMBERS = {
    "col": ("colorization",),
    "bs": ("bilateral-solver",),
    "col+bs": FILL_MEMBERS,  # the kit's
    "col+bs+gf": ("colorization", "bilateral-solver", "guided-filter"),
}
SHARES = (0.0, 0.2, 0.25, 0.3)


def ratios(rows: list[dict], fits: Path, profile) -> dict:
    """{(case, seed, variant): {"real": bool, (member, share): ratio to the case's best fill}}."""
    cases, out = {}, {}
    for row in rows:
        path = bq.fit_path(fits, row["case"], row["method"], row["variant"], row["seed"], row["size"])
        if not path.exists():
            continue
        name = row["case"]
        if name not in cases:
            case, fb = bq.build_case(name, profile)
            disparity_in = fb / case.depth  # (H, W) px, NaN holes
            filled = {fill: method(disparity_in, case.rgb) for fill, method in BASELINES.items()}
            best = min(bq.rmse_px(fb / d, case, fb) for d in filled.values())
            cases[name] = case, fb, filled, best
        case, fb, filled, best = cases[name]
        fit_px = fb * np.load(path)  # saved as 1/m
        entry = {"real": bq.is_real(name)}
        for member, names in MEMBERS.items():
            fill = np.mean([filled[n] for n in names], axis=0)
            for share in SHARES:
                entry[(member, share)] = bq.rmse_px(fb / ((1 - share) * fit_px + share * fill), case, fb) / best
        out[(name, row["seed"], row["variant"])] = entry
    return out


def report(out: dict, reference: tuple[str, float]) -> None:
    groups = collections.defaultdict(list)
    for key, entry in out.items():
        groups[("real" if entry["real"] else "rendered", key[2])].append(key)
    for (suite, variant), keys in sorted(groups.items()):
        ref = np.array([out[k][reference] for k in keys])
        print(f"{suite}, {variant}: {len(keys)} fits; the fit alone {np.mean([out[k][('col', 0.0)] for k in keys]):.3f}, "
              f"{reference[0]} at {reference[1]}: {ref.mean():.3f} (geometric {np.exp(np.log(ref).mean()):.3f})")
        for member in MEMBERS:
            for share in SHARES[1:]:
                value = np.array([out[k][(member, share)] for k in keys])
                change = bq.paired_difference(value, ref)
                print(f"  {member:<10} {share:<5} {value.mean():.3f}  {change['mean']:+.3f} ± {change['se']:.3f} "
                      f"({change['better']}/{change['n']} gain)  geometric {np.exp(np.log(value).mean()):.3f}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_profile_args(parser)
    parser.add_argument("rows", nargs="+", type=existing_file, help="bench_quality.py --out files of the fits")
    parser.add_argument("--fits", type=existing_folder, required=True, help="their --save-fits folder")
    parser.add_argument("--recipe", default="alone", help="the recipe whose saved fits are the fits alone")
    parser.add_argument("--reference", default="col:0.2", help="member:share the changes are paired against")
    parser.add_argument("--out", type=Path, help="one JSON line per fit: its ratio at every member and share")
    args = parse_args(parser, argv, lambda a: check_rows_out(a.out) if a.out else None)
    member, share = args.reference.split(":")
    rows = [row for path in args.rows for row in read_rows(path)]
    rows = list({(r["case"], r["seed"], r["variant"]): r for r in rows
                 if r.get("method") == args.recipe and r.get("seed") is not None}.values())
    out = ratios(rows, args.fits, profile_from_args(args))
    report(out, (member, float(share)))
    if args.out:
        lines = [json.dumps({"case": case, "seed": seed, "variant": variant, "ratio_to_best_fill":
                             {f"{k[0]}@{k[1]}": round(v, 5) for k, v in entry.items() if k != "real"}})
                 for (case, seed, variant), entry in out.items()]
        with atomic_path(args.out) as tmp:
            Path(tmp).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
