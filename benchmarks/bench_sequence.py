"""Sequences: views per minute in-process (one view at a time, and side by side) vs on a 2-worker Dask
LocalCluster, the dry run's estimate for a 150-view Tanks and Temples scene at paper size, and the fused
cloud's P/R/F (SGM vs SGM+DDP).

    python benchmarks/bench_sequence.py [--profile ci] [--views 6] [--threads 2]

The sequence: the 'desk' scene at the profile's size, every view's depth from OpenCV SGM (as
notebooks 07 and 11), written as a TUM folder and read back. Each fit runs on one thread: in-process
with torch at one thread the views run one after another, at ``--threads`` that many side by side; the
other runs must give the serial depths (checked). Prints figures only. Cluster start-up is timed apart
from the fits.
"""
from __future__ import annotations

import argparse
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from ddp_lite.method.config import FitConfig
from ddp_lite.method.profiles import get_profile
from ddp_lite.world.scenes import make_scene
from ddp_lite.evaluation.metrics import cloud_scores
from ddp_lite.evaluation.experiments import sgm_depth_at_scale
from ddp_lite.data.formats import load_sequence
from ddp_lite.evaluation.fusion import fuse_depths, points_from_depth
from ddp_lite.method.runtime.side_by_side import torch_threads
from ddp_lite.sequences.runner import open_client
from ddp_lite.sequences.sequence import run_sequence
from ddp_lite.sequences.sequence_cost import estimate_sequence, format_estimate
from ddp_lite.sequences.sequence_files import read_manifest
from ddp_lite.data.tum import write_tum
from _common import parse_args, positive_int, positive_float


def _depths(out: Path) -> dict:
    return {n: np.load(out / e["files"]["npy"]) for n, e in read_manifest(out)["views"].items()}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="ci", choices=("ci", "class", "paper"))
    parser.add_argument("--views", type=positive_int, default=6)
    parser.add_argument("--gpu-tflops", type=positive_float, default=5.0)
    parser.add_argument("--threads", type=positive_int, default=2, help="torch threads in-process: views side by side")
    args = parse_args(parser, argv)
    profile = get_profile(args.profile)
    root = Path(tempfile.mkdtemp())
    scene = make_scene("desk", size=profile.size, n_views=args.views)
    sgm = sgm_depth_at_scale("desk", profile.size, args.views, seed=0, ref=range(args.views), params="dense")
    write_tum(scene, root / "tum", depths=sgm)
    sequence = load_sequence(root / "tum", "tum")
    config = FitConfig.for_profile(profile, variant="rgbd+warp")  # run_sequence shows no bar per view
    quiet = lambda *_: None  # noqa: E731
    print(f"{platform.processor() or platform.machine()}; {sequence}; profile '{profile.name}', "
          f"{config.paper.iterations} iterations per view, one thread per fit")

    with torch_threads(1):  # one view at a time
        start = time.perf_counter()
        run_sequence(sequence, root / "serial", config, fuse=False, log=quiet)
        serial = time.perf_counter() - start
    with torch_threads(args.threads):  # as many views at once as threads
        start = time.perf_counter()
        run_sequence(sequence, root / "side", config, fuse=False, log=quiet)
        side = time.perf_counter() - start
    start = time.perf_counter()
    with open_client(workers=2) as client:
        started = time.perf_counter() - start
        start = time.perf_counter()
        run_sequence(sequence, root / "dask", config, client=client, fuse=False, log=quiet)
        parallel = time.perf_counter() - start
    reference = _depths(root / "serial")
    same = {name: all(np.array_equal(reference[n], other[n], equal_nan=True) for n in reference)
            for name, other in (("side", _depths(root / "side")), ("dask", _depths(root / "dask")))}
    n = len(sequence)
    print(f"\nviews per minute ({n} views)")
    print(f"  in-process, serial        {60 * n / serial:6.1f}   ({serial:.1f} s)")
    print(f"  in-process, side by side  {60 * n / side:6.1f}   ({side:.1f} s; {args.threads} threads; depths identical "
          f"to serial: {same['side']})")
    print(f"  Dask LocalCluster, 2 × 1  {60 * n / parallel:6.1f}   ({parallel:.1f} s; cluster start-up {started:.1f} s "
          f"more; depths identical to serial: {same['dask']})")

    print("\ndry run: a 150-view Tanks and Temples scene at paper size")
    print(format_estimate(estimate_sequence(150, get_profile("paper").size, "paper", gpu_tflops=args.gpu_tflops)))

    sky = [labels == 0 for labels in scene.labels]
    gt = np.concatenate([points_from_depth(np.where(s, np.nan, v.depth), v.camera) for v, s in zip(scene, sky)])
    tau = 0.01 * float(np.median(gt[:, 2]))
    cameras = [v.camera for v in sequence]
    print(f"\nfused cloud vs the synthetic truth (C = 1, D = {0.25 * profile.size[1] / 64:.2f} px, τ = {100 * tau:.1f} cm)")
    for name, depths in (("SGM", [v.depth for v in sequence]), ("SGM+DDP", [reference[v.name] for v in sequence])):
        depths = [np.where(s, np.nan, d) for d, s in zip(depths, sky)]
        cloud = fuse_depths(depths, cameras, min_views=1, disp_threshold=0.25 * profile.size[1] / 64)
        s = cloud_scores(np.asarray(cloud.points), gt, tau)
        print(f"  {name:<8} {len(cloud.points):6d} points   P {s['P']:5.1f}   R {s['R']:5.1f}   F {s['F']:5.1f}")


if __name__ == "__main__":
    main()
