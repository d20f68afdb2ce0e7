"""How long a fit will still run: where auto-stopped fits stop, as a share of their cap, and where a
running fit is expected to stop from its stopper's state. Only the time-left estimates use these
(a command's clock, :class:`ddp_lite.core.progress.CommandClock`); no fit's numbers depend on them.

Where ``class``'s auto-stopped fits stop: of 3,771 fits in ``benchmarks/results/quality_class*.jsonl``
the median stopped at 490 of 600, one in twenty before 320, a quarter ran to the cap. After the
learning-rate cut a fit goes on improving for a while at the lower rate: of 54 ``class`` fits (the 22
rendered and 5 real cases of ``bench_quality.py``, rgbd seed 0 and rgbd+warp seed 1, held to AVX2) the
53 that cut stopped 80-360 iterations after the cut (median 220), where the next plateau could have
ended them 50 after (``benchmarks/study_time_left.py``).
"""
from __future__ import annotations

from .stopping import PlateauStopper

__all__ = ["EXPECTED_STOP_SHARE", "EARLIEST_STOP_SHARE", "RUN_AFTER_CUT_SHARE", "expected_share", "earliest_share",
           "earliest_stop", "expected_stop"]

EXPECTED_STOP_SHARE = 0.8
EARLIEST_STOP_SHARE = 0.55
RUN_AFTER_CUT_SHARE = 0.4  # 240 of 600: the cut's iteration plus this share of the cap, where such fits stopped


def expected_share(config) -> float:
    """The share of its iterations a fit of ``config`` (a FitConfig) is expected to run (1 without auto-stop)."""
    return EXPECTED_STOP_SHARE if config.stopping.auto_stop else 1.0


def earliest_share(config) -> float:
    """The share of its iterations a fit of ``config`` runs at least, bar one in twenty (1 without auto-stop)."""
    return EARLIEST_STOP_SHARE if config.stopping.auto_stop else 1.0


def earliest_stop(stopper: PlateauStopper, done: int, cap: int) -> int:
    """The earliest iteration a run can stop at, ``done`` of ``cap`` run: the plateaus ``stopper`` still has
    to come, none of them broken by a new best."""
    return min(cap, done + max(0, stopper.patience - stopper.since_best) + stopper.decays_left * stopper.patience)


def expected_stop(stopper: PlateauStopper, done: int, cap: int) -> int:
    """The iteration a run is expected to stop at, ``done`` of ``cap`` run: a cut's iteration plus the run
    fits usually go on for after it (:data:`RUN_AFTER_CUT_SHARE` of the cap), the last cut's once it has
    come, else the earliest the first can come; before the first cut, at least the share auto-stopped fits
    usually run (:data:`EXPECTED_STOP_SHARE`); never before the plateaus still to come
    (:func:`earliest_stop`), never past ``cap``. Without cuts (``decays=0``): at least that share."""
    at_least = earliest_stop(stopper, done, cap)
    run_on = round(RUN_AFTER_CUT_SHARE * cap)
    if stopper.since_cut is not None:
        return min(cap, max(at_least, done - stopper.since_cut + run_on))
    expected = max(at_least, round(EXPECTED_STOP_SHARE * cap))
    if stopper.decays_left > 0:  # a cut to come (with none, the next plateau is the stop)
        expected = max(expected, done + max(0, stopper.patience - stopper.since_best) + run_on)
    return min(cap, expected)
