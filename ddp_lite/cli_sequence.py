"""``ddp-lite sequence``: complete every view of a TUM / COLMAP / saved sequence and fuse them.

The flags that apply to ``--format`` become the reader's options (``formats.load_sequence``);
others are refused. ``--views`` takes indices or view names. ``--dry-run`` prints the jobs and
compute/memory estimates and fits nothing; otherwise ``sequence.run_sequence`` runs the fits on
a Dask client (``--workers`` local processes, or ``--scheduler``) and the exit code is 1 if a
view failed (re-running retries only those).
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from .fit import FitConfig
from .formats import load_sequence
from .profiles import get_profile
from .runner import open_client
from .sequence import run_sequence
from .sequence_cost import estimate_sequence, format_estimate
from .sequence_jobs import VARIANT
from .tum import TUM_INTRINSICS


def _intrinsics(text: str):
    """--intrinsics: a TUM camera name, or "fx,fy,cx,cy" in pixels (pixel (0, 0) = centre of the top-left pixel)."""
    if text in TUM_INTRINSICS:
        return text
    try:
        fx, fy, cx, cy = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--intrinsics must be one of {', '.join(TUM_INTRINSICS)} or fx,fy,cx,cy "
                                         f"(pixels), got {text!r}") from None
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def _sequence_options(args) -> dict:
    """The reader's options from the flags that apply to ``--format``; refuse the ones that do not."""
    given = {"intrinsics": args.intrinsics, "every": args.every, "max_frames": args.max_frames,
             "depth_scale": args.depth_scale, "undistort": args.undistort or None}
    allowed = {"tum": ("intrinsics", "every", "max_frames"), "colmap": ("depth_scale", "undistort"), "scene": ()}
    for name, value in given.items():
        if value is not None and name not in allowed[args.format]:
            raise ValueError(f"--{name.replace('_', '-')} does not apply to --format {args.format}")
    options = {k: v for k, v in given.items() if v is not None}
    if args.size:
        options["size"] = tuple(args.size)
    return options


def _view_indices(scene, tokens):
    """--views: indices or view names → indices."""
    if not tokens:
        return None
    names = {view.name: i for i, view in enumerate(scene.views)}
    indices = []
    for token in tokens:
        if token in names:
            indices.append(names[token])
        elif token.lstrip("-").isdigit():
            indices.append(int(token))
        else:
            raise ValueError(f"--views: {token!r} is neither a view index nor a view name (first names: "
                             f"{', '.join(list(names)[:5])})")
    return indices


def _sequence(args) -> int:
    profile = get_profile(args.profile)  # a bad --profile fails here, before the data is read
    options = _sequence_options(args)
    scene = load_sequence(args.path, args.format, **options)
    indices = _view_indices(scene, args.views)
    config = FitConfig.for_profile(profile, variant=VARIANT, seed=args.seed, device=args.device, progress=False,
                                   **({"iterations": args.iterations} if args.iterations else {}))
    config.validate()
    print(f"{scene}; profile '{profile.name}'")
    if args.dry_run:
        n_views = len(scene) if indices is None else len(indices)
        command = (f"ddp-lite sequence {args.path} --format {args.format} --out {args.out} --profile {profile.name} "
                   f"--scheduler tcp://SCHEDULER:8786" + "".join(f" --{k.replace('_', '-')} {v}" for k, v in
                                                                  options.items() if k in ("every", "max_frames")))
        print(format_estimate(estimate_sequence(n_views, scene.size, profile, gpu_tflops=args.gpu_tflops), command))
        return 0
    source = {"path": os.path.abspath(args.path), "format": args.format,
              "options": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in options.items()},
              "profile": profile.name}
    with open_client(args.workers, args.scheduler) as client:
        summary = run_sequence(scene, args.out, config, indices, client=client, threads=args.threads,
                               retries=args.retries, source=source)
    if summary["failed"]:
        print(f"{len(summary['failed'])} view(s) failed; see {summary['manifest']}. Re-run to retry them.",
              file=sys.stderr)
        return 1
    return 0
