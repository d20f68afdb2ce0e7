"""How good is a fit's time left? The auto-stop's expected stop replayed on recorded `class` fits.

    python benchmarks/study_time_left.py                       # replay the stored fits (seconds)
    python benchmarks/study_time_left.py --record 0/2 rows.jsonl   # fit lane 0 of 2 and append its rows (~15 min a lane, one thread)

Records the held-out error at every evaluation, the learning-rate cut and the stop of `class` fits on the
22 rendered and 5 real cases of ``bench_quality.py`` (rgbd seed 0, rgbd+warp seed 1), then replays
:class:`ddp_lite.method.stopping.PlateauStopper` on each curve (a fit is deterministic, so the replay is the
fit's own stopper) and compares, at each progress line (every 10 % of the cap) from 20 % on, the expected
stop with the real one: the iterations left as estimated against those actually left. "old" is the rule
before the run after the cut was counted (after the cut: the next plateau). Prints figures; asserts nothing.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from ddp_lite.method.stopping import PlateauStopper
from ddp_lite.method.time_left import EXPECTED_STOP_SHARE, earliest_stop, expected_stop
from _common import RowsFile, check_rows_out, existing_file, lane, parse_args, read_rows

ROWS = Path(__file__).parent / "results" / "time_left_class.jsonl"


def record(lane: int, lanes: int, out: str) -> None:
    import torch
    from ddp_lite.method.complete import complete_depth
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.runtime.options import RunOptions
    from bench_quality import build_case, suite  # benchmarks/ is on the path: the scripts run from there
    from ddp_lite.method.profiles import get_profile
    torch.set_num_threads(1)
    profile = get_profile("class")
    jobs = [(name, variant, seed) for name in suite(False, "synthetic") + suite(False, "real")
            for variant, seed in (("rgbd", 0), ("rgbd+warp", 1))]
    rows = RowsFile(out, ("case", "variant", "seed", "profile"))  # a stopped lane resumes
    try:
        for name, variant, seed in jobs[lane::lanes]:
            if rows.done(dict(case=name, variant=variant, seed=seed, profile=profile.name)):
                continue
            case, _ = build_case(name, profile)
            if variant == "rgbd+warp" and not case.neighbors:
                continue
            config = FitConfig.for_profile(profile, variant=variant, seed=seed)
            start = time.perf_counter()
            result = complete_depth(case.rgb, case.depth, case.camera,
                                    case.neighbors if variant == "rgbd+warp" else (), variant=variant, config=config,
                                    options=RunOptions(progress=False))
            history = result.history
            rows.record(dict(case=name, variant=variant, seed=seed, profile=profile.name, cap=config.paper.iterations,
                             ran=int(result.iterations), cuts=[int(i) for i in history["lr_decay_iteration"]],
                             eval_iteration=[int(i) for i in history["eval_iteration"]],
                             held_out=[float(e) for e in history["held_out"]],
                             patience=config.stopping.patience, eval_every=config.stopping.eval_every,
                             decays=config.stopping.plateau_decays, seconds=time.perf_counter() - start))
    finally:
        rows.close()


def old_rule(stopper: PlateauStopper, done: int, cap: int) -> int:
    """The expected stop before the run after the cut was counted: after the cut, the next plateau."""
    if stopper.since_cut is not None:
        return earliest_stop(stopper, done, cap)
    return min(cap, max(earliest_stop(stopper, done, cap), round(EXPECTED_STOP_SHARE * cap)))


def replay(row: dict, rule) -> list:
    """(estimated − actual) / actual iterations left at each progress line from 20 % of the cap on."""
    stopper, errors = PlateauStopper(row["patience"], row["eval_every"], row["decays"]), []
    held_out = row["held_out"] if "held_out" in row else row["heldout"]  # the committed rows spell it "heldout"
    for done, error in zip(row["eval_iteration"], held_out):
        if stopper.update(error) == "stop":
            break
        if done % (row["cap"] // 10) == 0 and done >= 0.2 * row["cap"] and done < row["ran"]:
            errors.append((rule(stopper, done, row["cap"]) - done) / (row["ran"] - done) - 1)
    return errors


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", nargs=2, metavar=("LANE/LANES", "OUT"), help="fit and append rows instead")
    parser.add_argument("--rows", default=str(ROWS), type=existing_file, help="the recorded rows to replay")

    def check(args):
        if args.record:
            try:
                lane(args.record[0])
            except argparse.ArgumentTypeError as error:
                raise ValueError(f"--record LANE/LANES: {error}") from None
            check_rows_out(args.record[1], "--record OUT")
    args = parse_args(parser, argv, check)
    if args.record:
        record(*lane(args.record[0]), args.record[1])
        return
    rows = read_rows(args.rows)
    after = sorted(r["ran"] - r["cuts"][0] for r in rows if r["cuts"])
    print(f"{len(rows)} fits; stopped at {statistics.median(r['ran'] for r in rows):.0f} of 600 (median), "
          f"{sum(r['ran'] == r['cap'] for r in rows)} at the cap; after the cut ({len(after)} fits) they ran "
          f"{after[0]}–{after[-1]} more (median {statistics.median(after):.0f})")
    for name, rule in (("old", old_rule), ("now", lambda s, done, cap: expected_stop(s, done, cap))):
        errors = [e for row in rows for e in replay(row, rule)]
        print(f"{name}: {sum(abs(e) <= 0.3 for e in errors)}/{len(errors)} progress lines within 30 % of the iterations "
              f"left, mean error {statistics.mean(errors):+.2f}, median |error| {statistics.median(abs(e) for e in errors):.2f}")


if __name__ == "__main__":
    main()
