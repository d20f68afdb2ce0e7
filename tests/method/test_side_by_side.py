"""Independent fits side by side (``ddp_lite.method.runtime.side_by_side``): each gives the numbers of a fit
run alone on one thread, the last round's too (so the numbers do not depend on the machine's core
count), and results come back in the jobs' order."""
import threading

import numpy as np
import torch

from ddp_lite.evaluation.experiments import make_case, run_cases, run_jobs
from ddp_lite.method.runtime.side_by_side import run_side_by_side

TINY_FIT = dict(channels=(8, 16, 32), iterations=8, auto_stop=False, lr_milestones=())


def _with_threads(n, function):
    threads = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        return function()
    finally:
        torch.set_num_threads(threads)


def test_every_fit_runs_on_one_thread_in_order_and_one_worker_runs_them_in_turn():
    seen = {}

    def job(k):
        seen[k] = (torch.get_num_threads(), threading.current_thread() is threading.main_thread())
        return 10 * k

    assert _with_threads(2, lambda: run_side_by_side(job, 3, workers=2)) == [0, 10, 20]
    assert seen[0] == (1, False) and seen[1] == (1, False)  # a round of two, one thread each, in threads
    assert seen[2] == (1, False)  # the one left over too: a 4-core machine would run it beside others
    assert _with_threads(2, lambda: run_side_by_side(job, 2, workers=1)) == [0, 10]
    assert seen[1] == (2, True)


def test_cases_fitted_side_by_side_give_each_fit_alone_on_one_thread():
    cases = [make_case(scene, "ci", holes="random") for scene in ("house", "desk", "room")]  # the third: alone
    together = _with_threads(2, lambda: run_cases(cases, "rgbd", "ci", **TINY_FIT))
    assert torch.get_num_threads() >= 1
    for case, result in zip(cases, together):
        alone = _with_threads(1, lambda: run_jobs([(case, "rgbd", "unet", TINY_FIT)], "ci")[0])
        np.testing.assert_array_equal(result.disparity, alone.disparity)  # and in the cases' order
    assert not np.array_equal(together[0].disparity, together[1].disparity)
