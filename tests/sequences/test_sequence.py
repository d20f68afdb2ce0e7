"""``ddp-lite sequence``: serial and Dask runs agree, an interrupted run resumes with only the missing
views, a worker killed mid-run loses and duplicates nothing, and the dry run prints its estimate.

Tiny sizes (4 views of 24×32, ci profile, a few iterations): these test the bookkeeping, not the
quality; four views are more than each view's two neighbours and give each of two workers two views.
Every fit runs on one thread, so the same seed gives the same numbers on any process."""
import functools
import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import torch

from ddp_lite.interface.cli import main
from ddp_lite.method.config import FitConfig
from ddp_lite.data.tum import read_tum, write_tum
from ddp_lite.classical.holes import random_holes
from ddp_lite.sequences.runner import open_client, run_jobs
from ddp_lite.world.scenes import make_scene
from ddp_lite.sequences.sequence_jobs import VARIANT, plan_jobs
from ddp_lite.sequences.sequence_files import read_manifest
from ddp_lite.sequences import sequence_cost
from ddp_lite.sequences.sequence import run_sequence

N_VIEWS, ITERATIONS = 4, 6


@pytest.fixture(scope="module")
def tum(tmp_path_factory):
    """A 4-view TUM folder: the desk scene with random holes in every depth map."""
    scene = make_scene("desk", size=(24, 32), n_views=N_VIEWS, seed=0)
    folder = tmp_path_factory.mktemp("seq") / "tum"
    write_tum(scene, folder, depths=[random_holes(v.depth, fraction=0.2, seed=i)[0] for i, v in enumerate(scene)])
    return folder


def _cli(tum, out, *extra, iterations=ITERATIONS):
    return ["sequence", str(tum), "--format", "tum", "--out", str(out), "--profile", "ci",
            "--iterations", str(iterations), *extra]


def _depths(out):
    manifest = read_manifest(out)
    return {name: np.load(out / entry["files"]["npy"]) for name, entry in manifest["views"].items()}


@pytest.fixture(scope="module")
def serial(tum, tmp_path_factory):
    """The reference: the in-process run's per-view depths."""
    out = tmp_path_factory.mktemp("serial")
    assert main(_cli(tum, out)) == 0
    return out, _depths(out)


def test_serial_run_writes_every_output(serial, tum):
    out, depths = serial
    manifest = read_manifest(out)
    assert len(depths) == N_VIEWS and all(e["status"] == "done" for e in manifest["views"].values())
    scene = read_tum(tum)
    for view in scene:
        entry = manifest["views"][view.name]
        assert len(entry["neighbors"]) == 2 and view.name not in entry["neighbors"]
        depth = depths[view.name]
        valid = np.isfinite(view.depth)
        np.testing.assert_array_equal(depth[valid], view.depth[valid])  # SGM+DDP keeps the input where valid
        assert np.isfinite(depth).all()  # and fills every hole
        import cv2
        png = cv2.imread(str(out / entry["files"]["png"]), cv2.IMREAD_UNCHANGED)
        assert png.dtype == np.uint16
        np.testing.assert_array_equal(png, np.round(depth.astype(np.float64) * 1000).astype(np.uint16))
        assert (out / entry["files"]["preview"]).stat().st_size > 0
    assert manifest["fused"]["points"] > 0 and (out / "fused.ply").stat().st_size > 0
    assert not list(out.rglob(".tmp-*"))  # atomic writes leave no temporary files


@pytest.fixture(scope="module")
def cluster():
    """One local Dask cluster of two one-thread worker processes (``--workers 2``'s), for the module's Dask
    tests: starting and closing one takes about 2.5 s. Closed, it leaves this process's environment
    as it found it (distributed's nanny writes its workers' settings into it; a kernel or command started
    afterwards would inherit them)."""
    def environment():
        return {name: value for name, value in os.environ.items() if name != "PYTEST_CURRENT_TEST"}

    before = environment()
    with open_client(workers=2) as client:
        now = environment()
        set_by_dask = {name for name in set(before) | set(now) if now.get(name) != before.get(name)}
        assert set_by_dask  # what the nanny does, so that the last line tests the taking back
        yield client
    assert {name: os.environ.get(name) for name in set_by_dask} == {name: before.get(name) for name in set_by_dask}


def test_two_dask_workers_joined_by_address_give_the_serial_depths(serial, tum, cluster, tmp_path):
    _, reference = serial
    # as on a researcher's cluster: the CLI joins a running scheduler (`--workers` starts one: `cluster` above)
    assert main(_cli(tum, tmp_path, "--scheduler", cluster.scheduler.address)) == 0
    depths = _depths(tmp_path)
    assert depths.keys() == reference.keys()
    for name in reference:
        np.testing.assert_array_equal(depths[name], reference[name])


def test_views_side_by_side_in_process_give_the_serial_depths(serial, tum, tmp_path):
    _, reference = serial
    lines = []
    threads = torch.get_num_threads()
    torch.set_num_threads(2)  # as on a 2-core laptop: two views at once, one thread each
    try:
        config = FitConfig.for_profile("ci", variant=VARIANT, seed=0, iterations=ITERATIONS)
        summary = run_sequence(read_tum(tum), tmp_path, config, log=lines.append)
    finally:
        torch.set_num_threads(threads)
    assert "2 at a time in this process" in lines[0]
    assert sorted(summary["computed"]) == sorted(reference) and not summary["failed"]
    assert torch.get_num_threads() == threads
    depths = _depths(tmp_path)
    for name in reference:
        np.testing.assert_array_equal(depths[name], reference[name])


def test_an_interrupted_run_resumes_with_only_the_missing_views(serial, tum, tmp_path):
    _, reference = serial
    # a real interruption: the CLI in its own process, killed once the manifest shows a finished view
    env = dict(os.environ, OMP_NUM_THREADS="1", DDP_PROFILE="ci")
    process = subprocess.Popen([sys.executable, "-m", "ddp_lite.interface.cli", *_cli(tum, tmp_path)], env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        done = []
        while process.poll() is None and not done:
            time.sleep(0.05)
            try:
                done = [n for n, e in read_manifest(tmp_path).get("views", {}).items() if e["status"] == "done"]
            except ValueError:  # never happens with atomic writes; would fail the assertion below
                raise
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    manifest = read_manifest(tmp_path)
    done = {n for n, e in manifest["views"].items() if e["status"] == "done"}
    assert done and len(done) < N_VIEWS, "the run must be interrupted between its first and last view"
    assert {e["status"] for n, e in manifest["views"].items() if n not in done} <= {"running"}
    kept = {n: (tmp_path / manifest["views"][n]["files"]["npy"]).read_bytes() for n in done}

    scene = read_tum(tum)
    config = FitConfig.for_profile("ci", variant=VARIANT, seed=0, iterations=ITERATIONS)
    summary = run_sequence(scene, tmp_path, config, log=lambda *_: None)
    assert set(summary["skipped"]) == done
    assert sorted(summary["computed"]) == sorted(set(reference) - done)
    for name, data in kept.items():
        assert (tmp_path / manifest["views"][name]["files"]["npy"]).read_bytes() == data
    for name, depth in _depths(tmp_path).items():
        np.testing.assert_array_equal(depth, reference[name])
    # and a changed config redoes every view (the job key covers it)
    again = run_sequence(scene, tmp_path, config.replace(seed=1), views=[0], fuse=False, log=lambda *_: None)
    assert again["computed"] == [scene[0].name]


def test_a_worker_killed_mid_run_loses_and_duplicates_nothing(serial, tum, cluster, tmp_path):
    _, reference = serial
    scene = read_tum(tum)
    config = FitConfig.for_profile("ci", variant=VARIANT, seed=0, iterations=ITERATIONS)
    client = cluster  # its nanny starts a new worker in place of the killed one
    killed = []

    def kill_a_busy_worker():
        while not killed:
            busy = [w for w, keys in client.processing().items() if keys]
            if busy:
                pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)
            time.sleep(0.02)
    killer = threading.Thread(target=kill_a_busy_worker, daemon=True)
    killer.start()
    summary = run_sequence(scene, tmp_path, config, client=client, log=lambda *_: None)
    killer.join(timeout=60)
    assert killed, "a worker must have been killed while it was fitting"
    assert sorted(summary["computed"]) == sorted(reference) and not summary["failed"]
    assert len(summary["computed"]) == len(set(summary["computed"]))  # each view's result arrived once
    for name, depth in _depths(tmp_path).items():
        np.testing.assert_array_equal(depth, reference[name])


def test_run_jobs_keys_results_and_returns_failures():
    def fails(x):
        raise ValueError(f"bad {x}")
    assert dict(run_jobs(abs, {"a": (-1,), "b": (2,)})) == {"a": 1, "b": 2}
    outcome = dict(run_jobs(fails, {"a": (1,)}))["a"]
    assert isinstance(outcome, ValueError) and str(outcome) == "bad 1"
    # in threads: every key once, the first to finish first; each job ran in a thread other than the caller's
    release = threading.Event()

    def job(x):
        if x == 0:
            release.wait(10)  # finishes only after job 1 has been yielded
        return x, threading.get_ident()
    order = []
    for key, (x, ident) in run_jobs(job, {"slow": (0,), "fast": (1,)}, workers=2):
        order.append(key)
        assert ident != threading.get_ident()
        release.set()
    assert order == ["fast", "slow"]
    assert dict(run_jobs(fails, {"a": (1,), "b": (2,)}, workers=2))["b"].args == ("bad 2",)
    with pytest.raises(ValueError, match="workers must be a positive integer"):
        next(run_jobs(abs, {"a": (1,)}, workers=0))


def test_plan_refuses_bad_input_before_any_fit(tum):
    scene = read_tum(tum)
    config = FitConfig.for_profile("ci", variant=VARIANT, iterations=1)
    with pytest.raises(ValueError, match=rf"views must be view indices in \[0, {N_VIEWS}\)"):
        plan_jobs(scene, config, views=[7])
    scene.views[2].depth = np.full(scene.size, np.nan, np.float32)
    with pytest.raises(ValueError, match=r"view 2 \("):
        plan_jobs(scene, config)
    with pytest.raises(ValueError, match="at least 2 views"):
        plan_jobs(type(scene)("one", scene.views[:1]), config)


def test_cli_refusals_and_dry_run(tum, tmp_path, capsys, monkeypatch):
    assert main(["sequence", str(tum), "--format", "colmap", "--out", str(tmp_path), "--every", "2"]) == 2
    assert "--every does not apply to --format colmap" in capsys.readouterr().err
    assert main(["sequence", str(tum), "--format", "tum", "--out", str(tmp_path), "--views", "nope"]) == 2
    assert "--views: 'nope' is neither" in capsys.readouterr().err
    # the paper net's cost measured at 48×64 instead of 96×128 (half the time), timed over 1 and 2 iterations: what
    # the measurement counts is tested in test_sequence_cost.py, what the dry run makes of it here
    monkeypatch.setattr(sequence_cost, "measure_fit_cost", functools.partial(sequence_cost.measure_fit_cost,
                                                                             size=(48, 64), iterations=(1, 2)))
    assert main(["sequence", str(tum), "--format", "tum", "--out", str(tmp_path), "--profile", "paper",
                 "--dry-run"]) == 0
    printed = capsys.readouterr().out
    assert f"{N_VIEWS} jobs" in printed and "16000 iterations" in printed and "GPU-hours" in printed
    assert "counted at 48×64" in printed and "per pixel-iteration, measured now" in printed
    assert "--scheduler tcp://" in printed
    assert not (tmp_path / "manifest.json").exists()  # a dry run writes nothing
