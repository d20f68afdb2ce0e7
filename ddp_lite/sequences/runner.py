"""Run independent jobs (one DDP fit each) in this process or on a Dask cluster: no scheduler of our own.

DDP fits one network per image, so a sequence's views are independent jobs. Where they run is
one choice:

* **in-process** (``client=None``): here, nothing to install or start; ``workers`` jobs at once in
  threads (each fit sets its own torch threads: one, so two fill a 2-core CPU), else one after another;
* **a Dask ``LocalCluster``** (:func:`open_client` with ``workers=N``): N worker *processes* with
  one thread each. On a 2-core CPU, two single-thread fits finish sooner than one two-thread fit,
  because a small CNN does not keep two threads busy;
* **an existing Dask cluster** (``scheduler="tcp://host:8786"``): e.g. one that dask-jobqueue
  started on Slurm/PBS (README, "Your own data"); every worker needs ddp-lite installed.

Dask's ``Client.submit`` is the ``concurrent.futures``-style executor. Each job is submitted
under its own **key** (the caller's job id), so a job submitted twice is one task, and its result
arrives once. Dask does the rest: a job that raises is retried ``retries`` times; a job whose
worker dies is rescheduled on another worker (up to ``distributed.scheduler.allowed-failures``
times, 3 by default); the nanny restarts the dead worker.
"""
from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

__all__ = ["open_client", "run_jobs"]


@contextlib.contextmanager
def open_client(workers: int = 0, scheduler: str | None = None, threads_per_worker: int = 1):
    """Yield a ``distributed.Client`` (or None for in-process runs); closes what it started.

    ``workers`` > 0 starts a ``LocalCluster`` of that many processes × ``threads_per_worker``
    threads (no dashboard); ``scheduler`` ("tcp://host:port") joins a running cluster instead.

    Example:
        >>> with open_client() as client:
        ...     print(client)
        None
    """
    if isinstance(workers, bool) or int(workers) != workers or workers < 0:
        raise ValueError(f"workers must be a non-negative integer, got {workers!r}")
    if workers and scheduler:
        raise ValueError("give either workers (start a local cluster) or scheduler (join one), not both")
    if scheduler is not None and (not isinstance(scheduler, str) or "://" not in scheduler):
        raise ValueError(f"scheduler must be an address like tcp://host:8786, got {scheduler!r}")
    if not workers and scheduler is None:
        yield None
        return
    from distributed import Client, LocalCluster

    if scheduler is not None:
        client = Client(scheduler)
        try:
            yield client
        finally:
            client.close()
        return
    # processes: each fit gets its own interpreter and torch thread pool (the nanny also sets
    # OMP_NUM_THREADS=1 in the worker's environment before it starts)
    before = dict(os.environ)
    set_by_dask = None
    try:
        with LocalCluster(n_workers=int(workers), threads_per_worker=int(threads_per_worker), processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            set_by_dask = _changed_since(before)
            yield client
    finally:
        _take_back(before, _changed_since(before) if set_by_dask is None else set_by_dask)


def _changed_since(before: dict) -> dict:
    return {name: os.environ.get(name) for name in set(before) | set(os.environ)
            if os.environ.get(name) != before.get(name)}


def _take_back(before: dict, set_by_dask: dict):
    """Undo what starting the cluster wrote into this process's environment: distributed's nanny sets its
    workers' variables (MALLOC_TRIM_THRESHOLD_, OPENBLAS_NUM_THREADS, PYTHONHASHSEED, ...) in the caller's own
    ``os.environ`` before it spawns them, where every process the caller starts later would inherit them. A
    variable the caller changed meanwhile is left as the caller set it."""
    for name, value in set_by_dask.items():
        if os.environ.get(name) == value:
            if name in before:
                os.environ[name] = before[name]
            else:
                os.environ.pop(name, None)


def run_jobs(fn: Callable, jobs: Mapping[str, tuple], client=None, retries: int = 2,
             workers: int = 1) -> Iterator[tuple[str, object]]:
    """Run ``fn(*args)`` for every ``key: args`` of ``jobs``; yield ``(key, outcome)`` as each finishes.

    ``outcome`` is the return value, or the exception the job raised (after Dask's ``retries``), so a
    caller can record a failure and go on. In-process (``client=None``) ``workers`` jobs run at once
    in threads of this process (1: in order, in this thread); with a client, on Dask. Either way in
    whatever order they finish, each key exactly once, and only the caller's thread sees the results
    (it does the writing). On Dask ``fn`` must be importable by the workers (a module-level
    function), and ``args`` picklable. An interrupted caller starts no further job; in-process the
    jobs already running finish first (a thread cannot be stopped), on Dask they are cancelled.

    Example:
        >>> sorted(run_jobs(pow, {"a": (2, 3), "b": (3, 2)}))
        [('a', 8), ('b', 9)]
    """
    if not callable(fn):
        raise TypeError(f"fn must be callable, got {type(fn).__name__}")
    if isinstance(workers, bool) or int(workers) != workers or workers < 1:
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    if client is None and workers == 1:
        for key, args in jobs.items():
            yield key, _outcome(fn, args)
        return
    if client is None:
        yield from _in_threads(fn, jobs, int(workers))
        return
    from distributed import as_completed

    futures = [client.submit(fn, *args, key=key, pure=False, retries=int(retries)) for key, args in jobs.items()]
    try:
        for future in as_completed(futures):
            if future.status == "error":
                outcome = future.exception()
            elif future.status == "cancelled":  # e.g. someone cancelled it on a shared cluster
                outcome = RuntimeError(f"job {future.key} was cancelled on the cluster")
            else:
                outcome = future.result()
            yield future.key, outcome
            future.release()  # the result is with the caller now; free the worker's copy
    finally:
        client.cancel([f for f in futures if not f.done()])  # an interrupted caller leaves nothing running


def _outcome(fn: Callable, args: tuple):
    """``fn(*args)``, or the exception it raised: recorded by the caller; KeyboardInterrupt still stops the run."""
    try:
        return fn(*args)
    except Exception as error:
        return error


def _in_threads(fn: Callable, jobs: Mapping[str, tuple], workers: int) -> Iterator[tuple[str, object]]:
    """The in-process jobs, ``workers`` at a time in threads, yielded as each finishes."""
    pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="ddp-job")
    running = {pool.submit(_outcome, fn, args): key for key, args in jobs.items()}
    try:
        while running:
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                yield running.pop(future), future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)  # an interrupted caller starts nothing more
