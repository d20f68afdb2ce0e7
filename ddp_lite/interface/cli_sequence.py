"""``ddp-lite sequence``: complete every view of a TUM / COLMAP / saved sequence and fuse them.

The flags that apply to ``--format`` become the reader's options (``formats.load_sequence``);
others are refused. ``--views`` takes indices or view names. ``--dry-run`` prints the jobs and
compute/memory estimates and fits nothing; otherwise ``sequence.run_sequence`` runs the fits on
a Dask client (``--workers`` local processes, or ``--scheduler``) and the exit code is 1 if a
view failed (re-running retries only those).
"""
from __future__ import annotations

import os
import sys

import numpy as np

from ..method.config import FitConfig
from ..method.runtime.options import RunOptions, run_options
from ..data.formats import load_sequence
from ..core.outpaths import check_output_folder, output_lock
from ..method.paper.nets import check_input_size
from ..method.profiles import get_profile
from ..method.kit.recipes import get_recipe
from ..sequences.runner import open_client
from ..sequences.sequence import run_sequence
from ..sequences.sequence_files import check_out_folder
from ..sequences.sequence_cost import estimate_sequence, format_estimate
from ..sequences.sequence_jobs import VARIANT
from ..data.tum import TUM_INTRINSICS


def _sequence_options(args) -> dict:
    """The reader's options from the flags that apply to ``--format``; refuse the ones that do not.

    ``--depth-scale`` (metres per stored unit) applies to TUM and COLMAP: TUM's reader takes it as its
    ``depth_factor`` (stored units per metre, 5000 when absent), so a capture in millimetres reads as
    it is."""
    intrinsics = args.intrinsics
    if isinstance(intrinsics, str) and intrinsics not in TUM_INTRINSICS:
        raise ValueError(f"--intrinsics must be one of {', '.join(TUM_INTRINSICS)} or fx,fy,cx,cy (pixels), "
                         f"got {intrinsics!r}")
    given = {"intrinsics": np.array(intrinsics) if isinstance(intrinsics, list) else intrinsics,
             "every": args.every, "max_frames": args.max_frames,
             "depth_scale": args.depth_scale, "undistort": args.undistort or None}
    allowed = {"tum": ("intrinsics", "every", "max_frames", "depth_scale"), "colmap": ("depth_scale", "undistort"),
               "scene": ()}
    for name, value in given.items():
        if value is not None and name not in allowed[args.format]:
            raise ValueError(f"--{name.replace('_', '-')} does not apply to --format {args.format}")
    options = {k: v for k, v in given.items() if v is not None}
    if getattr(args, "strict", False) and args.format in ("tum", "colmap"):  # the readers that can leave frames out
        options["strict"] = True
    if args.format == "tum" and "depth_scale" in options:
        options["depth_factor"] = 1.0 / options.pop("depth_scale")
    if args.size:
        options["size"] = tuple(args.size)
    return options


def _view_indices(scene, tokens):
    """--views: indices (0 … N−1) or view names → indices; anything else (a negative index, an index past
    the end, a name no view has, a view twice) → ``ValueError`` naming ``--views``."""
    if not tokens:
        return None
    names = {view.name: i for i, view in enumerate(scene.views)}
    n = len(scene.views)
    indices = []
    for token in tokens:
        if token in names:
            index = names[token]
        elif token.lstrip("-").isdigit():
            index = int(token)
            if not 0 <= index < n:
                raise ValueError(f"--views: {token} is out of range: the sequence has {n} views, indices 0–{n - 1} "
                                 f"(not counted from the end; or view names; leave --views out for all of them)")
        else:
            raise ValueError(f"--views: {token!r} is neither a view index nor a view name (first names: "
                             f"{', '.join(list(names)[:5])})")
        if index in indices:
            raise ValueError(f"--views: view {index} ({scene.views[index].name}) is listed twice ({token!r}); "
                             f"list each view once")
        indices.append(index)
    return indices


def _workers(requested: int) -> int:
    """--workers, at most the CPU count: more one-thread processes than cores only slow each other."""
    cores = os.cpu_count() or 1
    if requested > cores:
        print(f"--workers {requested}: this machine has {cores} CPU cores; starting {cores} workers", file=sys.stderr)
        return cores
    return requested


def sequence_command(args) -> int:
    """``ddp-lite sequence``: complete every view of a sequence into a folder."""
    profile = get_profile(args.profile)  # a bad --profile fails here, before the data is read
    options = _sequence_options(args)
    check_output_folder(args.out, "--out")
    if os.path.isdir(args.path) and os.path.realpath(args.out) == os.path.realpath(args.path):
        raise ValueError(f"--out {args.out!r} is PATH: the results (depth/, ...) would be written among the "
                         f"inputs; give another folder")
    workers = _workers(args.workers) if args.scheduler is None else args.workers
    try:
        scene = load_sequence(args.path, args.format, **options)
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError) as error:  # an input not there: usage (2)
        raise ValueError(f"PATH {args.path!r}: {error}") from None
    check_out_folder(args.out, list(getattr(scene, "sources", [])) + [os.path.abspath(args.path)])  # a dry run too
    indices = _view_indices(scene, args.views)
    recipe = get_recipe(args.recipe)  # --recipe, else DDP_RECIPE, else kit
    config = FitConfig.for_profile(profile, variant=VARIANT, recipe=recipe, seed=args.seed,
                                   **({"iterations": args.iterations} if args.iterations else {}))
    config.validate()
    fit_options = run_options(RunOptions(device=args.device, progress=False))  # --device, before any fit
    check_input_size(config.paper.net, config.paper.channels, *scene.size, name="--size" if args.size else "each view")
    print(f"{scene}; profile '{profile.name}', recipe '{recipe.name}'")
    if args.dry_run:
        n_views = len(scene) if indices is None else len(indices)
        flags = {"every": args.every, "max_frames": args.max_frames, "depth_scale": args.depth_scale,
                 "size": " ".join(map(str, args.size)) if args.size else None}
        command = (f"ddp-lite sequence {args.path} --format {args.format} --out {args.out} --profile {profile.name} "
                   f"--recipe {recipe.name} "
                   f"--scheduler tcp://SCHEDULER:8786" + "".join(f" --{k.replace('_', '-')} {v}" for k, v in
                                                                  flags.items() if v is not None))
        print(format_estimate(estimate_sequence(n_views, scene.size, profile, gpu_tflops=args.gpu_tflops), command))
        return 0
    source = {"path": os.path.abspath(args.path), "format": args.format,
              "options": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in options.items()},
              "profile": profile.name}
    with output_lock([args.out], "--out"), open_client(workers, args.scheduler) as client:  # one writer at a time
        summary = run_sequence(scene, args.out, config, indices, client=client, threads=args.threads,
                               retries=args.retries, source=source, options=fit_options)
    if summary["failed"]:
        print(f"{len(summary['failed'])} view(s) failed; see {summary['manifest']}. Re-run to retry them.",
              file=sys.stderr)
        return 1
    return 0
