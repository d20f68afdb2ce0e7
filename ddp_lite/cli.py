"""``ddp-lite``: the kit's main job without a browser.

    ddp-lite demo [--out ddp_demo.png] [--scene house] [--holes edge|sgm|random] [--iterations 300]
                  [--profile ci|class|paper]
    ddp-lite scenes
    ddp-lite complete --rgb image.png --depth depth.png --depth-scale 0.001 --out filled.npy|.png|.pfm|.exr
    ddp-lite sequence PATH --format tum|colmap|scene --out DIR [--views ...] [--workers N | --scheduler tcp://...]
                      [--profile ci|class|paper] [--dry-run]
    ddp-lite student [--source notebooks] [--out build/student]
    ddp-lite solutions [--profile class] [--out build/solutions] [--only 01 05]
    ddp-lite grade SUBMISSIONS_DIR [--csv grades.csv] [--timeout 600]
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import tempfile
import time

import cv2
import numpy as np
from matplotlib.figure import Figure  # no pyplot: no backend to choose, no global figure state

from .atomic import write_bytes_atomic
from .baselines import fill_colorization, fill_linear
from .classroom import build_solutions, build_student, format_grades, grade, write_csv
from .experiments import error_table, format_table, make_case
from .fileio import depth_png_bytes, npy_bytes, pfm_bytes, read_pfm
from .fit import FitConfig, complete_depth
from .formats import load_sequence
from .metrics import hole_rmse
from .profiles import get_profile
from .runner import open_client
from .scenes import list_scenes
from .sequence import VARIANT, estimate_sequence, format_estimate, run_sequence
from .tum import TUM_INTRINSICS
from .viz import save_figure, show_depth, show_error, show_image


def _demo(args) -> int:
    start = time.perf_counter()
    profile = get_profile(args.profile)  # --profile, else DDP_PROFILE, else class
    profile = dataclasses.replace(profile, size=tuple(args.size)) if args.size else profile
    case = make_case(args.scene, profile, holes=args.holes, seed=args.seed)
    print(f"{case.scene}\n{args.holes} holes: {np.isnan(case.depth).mean():.0%} of the reference view; "
          f"warp loss uses views {[n.name for n in case.neighbors]}")
    config = FitConfig.for_profile(profile, variant="rgbd+warp", iterations=args.iterations, seed=args.seed,
                                   device=args.device)
    result = complete_depth(case.rgb, case.depth, case.camera, case.neighbors, variant="rgbd+warp", config=config,
                            gt_depth=case.scored_gt, transform=case.transform)
    estimates = {"linear": fill_linear(case.depth), "colorization": fill_colorization(case.depth, case.rgb),
                 "DDP rgbd+warp": result.depth}
    table = error_table(case, estimates)
    for name, depth in estimates.items():
        table[name]["holes (m)"] = hole_rmse(depth, case.gt, case.holes)
    print(format_table(table, 3, f"RMSE in the holes (sky not scored), DDP after {result.iterations} iterations"
                                 + (f" (the mean of {result.fits} fits)" if result.fits > 1 else "") + ": "
                                 "normalised disparity ×100, its part near depth edges, metres"))

    ddp_error, linear_error = table["DDP rgbd+warp"]["holes (m)"], table["linear"]["holes (m)"]
    vmin, vmax = float(np.nanmin(case.gt)), float(np.nanmax(case.scored_gt))
    fig = Figure(figsize=(13, 6.5))
    axes = fig.subplots(2, 3)
    show_image(axes[0, 0], case.rgb, f"'{case.name}' reference view")
    show_depth(axes[0, 1], case.depth, f"input ({np.isnan(case.depth).mean():.0%} holes)", vmin, vmax)
    show_depth(axes[0, 2], case.gt, "ground truth", vmin, vmax)
    show_depth(axes[1, 0], result.depth, f"DDP (hole RMSE {ddp_error:.3f} m)", vmin, vmax)
    error_vmax = float(np.nanpercentile(np.abs(result.depth - case.gt)[case.holes], 99))
    show_error(axes[1, 1], result.depth, case.gt, "DDP |error| in holes", mask=case.holes, vmax=error_vmax)
    show_error(axes[1, 2], estimates["linear"], case.gt, f"linear fill |error| (RMSE {linear_error:.3f} m)",
               mask=case.holes, vmax=error_vmax)
    fig.tight_layout()
    save_figure(fig, args.out)
    print(f"figure written to {os.path.abspath(args.out)}; took {time.perf_counter() - start:.1f} s")
    return 0


def _scenes(args) -> int:
    for name, description in list_scenes().items():
        print(f"{name:<8} {description}")
    return 0


def _number(kind, minimum: float, name: str):
    """An argparse type: a finite ``kind`` (int or float) ≥ ``minimum``, else an error naming the flag."""
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be {'an integer' if kind is int else 'a number'}, "
                                             f"got {text!r}") from None
        if not np.isfinite(value) or value < minimum or (kind is float and value <= 0):
            raise argparse.ArgumentTypeError(f"{name} must be a finite number {'≥' if kind is int else '>'} "
                                             f"{minimum:g}, got {text!r}")
        return value
    return parse


def _exr_available() -> bool:
    if os.environ.get("OPENCV_IO_ENABLE_OPENEXR", "").lower() not in ("1", "true", "on", "yes"):
        return False  # OpenCV's EXR codec is off by default (and probing it prints a warning)
    try:
        return bool(cv2.imencode(".exr", np.zeros((1, 1), np.float32))[0])
    except cv2.error:
        return False


def _writers() -> dict:
    """Output writers by suffix: filled depth (H, W) float32 metres → bytes."""
    def png(depth):  # 16-bit millimetres, 0 = no value; _complete refuses depth beyond PNG_MAX_METRES first
        return depth_png_bytes(depth)[0]

    def exr(depth):
        return cv2.imencode(".exr", depth.astype(np.float32))[1].tobytes()
    return {".npy": npy_bytes, ".png": png, ".pfm": pfm_bytes, ".exr": exr}


PNG_MAX_METRES = 65.535  # uint16 millimetres


def _check_out(args, writers: dict) -> None:
    """Refuse a bad --out before any work: unknown suffix, a folder, an input, a read-only file, an
    unwritable folder."""
    out = os.path.abspath(args.out)
    suffix = os.path.splitext(out)[1].lower()
    if os.path.isdir(out):
        raise ValueError(f"--out {args.out!r} is a folder; give a file name such as filled.npy")
    if suffix not in writers:
        raise ValueError(f"--out must end in {', '.join(sorted(writers))} (the format follows the suffix), got {args.out!r}")
    if suffix == ".exr" and not _exr_available():
        raise ValueError("--out: this OpenCV cannot write .exr (set OPENCV_IO_ENABLE_OPENEXR=1, or use .npy/.pfm)")
    for flag, path in (("--depth", args.depth), ("--rgb", args.rgb)):
        if os.path.abspath(path) == out or (os.path.exists(out) and os.path.exists(path) and os.path.samefile(path, out)):
            raise ValueError(f"--out is the same file as {flag} ({path!r}); refusing to overwrite an input")
    if os.path.exists(out) and not os.stat(out).st_mode & 0o222 and not args.force:
        raise ValueError(f"--out {args.out!r} exists and is read-only; pass --force to replace it")
    folder = os.path.dirname(out)
    while not os.path.exists(folder):
        folder = os.path.dirname(folder)
    if not os.path.isdir(folder):
        raise ValueError(f"--out {args.out!r}: {folder} is a file, not a folder")
    try:  # the one sure test (permissions, read-only mounts, quotas): create a file there
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".ddp-lite-probe-")
    except OSError as error:
        raise ValueError(f"--out {args.out!r}: cannot write in {folder} ({error.strerror})") from None
    os.close(fd)
    os.remove(probe)


def _read_depth(path: str, scale: float | None) -> np.ndarray:
    """--depth as float32 metres, NaN where the file has no value (0, ≤ 0, inf, NaN)."""
    if not os.path.isfile(path):
        raise ValueError(f"--depth: no such file {path!r}")
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".npy":
        try:
            raw = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as error:
            raise ValueError(f"--depth: cannot read {path!r} as a .npy array ({error})") from None
    elif suffix == ".pfm":
        raw = read_pfm(path)
    else:
        raw = cv2.imread(path, cv2.IMREAD_UNCHANGED)
        if raw is None:
            raise ValueError(f"--depth: cannot read {path!r} as an image")
    if raw.ndim != 2 or raw.dtype == bool or not (np.issubdtype(raw.dtype, np.integer) or np.issubdtype(raw.dtype, np.floating)):
        raise ValueError(f"--depth: {path!r} must hold one channel of numbers (H, W), got {raw.dtype} {raw.shape}")
    if scale is None:
        if np.issubdtype(raw.dtype, np.integer):
            raise ValueError(f"--depth: {path!r} stores integers ({raw.dtype}); give --depth-scale, the metres per "
                             f"stored unit (0.001 for millimetres, as in most 16-bit depth PNGs)")
        scale = 1.0
    stored = raw.astype(np.float64)
    depth = stored * scale
    valid = np.isfinite(depth) & (depth > 0)
    if (np.isfinite(stored) & (stored > 0)).any() and not valid.any():
        raise ValueError(f"--depth-scale {scale!r} turns every depth into 0")
    if valid.any():
        low, high = depth[valid].min(), depth[valid].max()
        if low < DEPTH_RANGE_M[0] or high > DEPTH_RANGE_M[1]:
            raise ValueError(f"--depth-scale {scale!r}: depths would range {low:.3g}–{high:.3g} m, outside "
                             f"{DEPTH_RANGE_M[0]:g}–{DEPTH_RANGE_M[1]:g} m; is it metres per stored unit?")
    return np.where(valid, depth, np.nan).astype(np.float32)


DEPTH_RANGE_M = (1e-3, 1e4)  # plausible metres; outside it the scale is almost surely wrong


def _complete(args) -> int:
    writers = _writers()
    _check_out(args, writers)
    config = FitConfig.for_profile(args.profile, variant=args.variant, device=args.device,
                                   max_memory_gb=args.max_memory_gb,
                                   **({"iterations": args.iterations} if args.iterations else {}))
    config.validate()  # --device, before the inputs are read
    if not os.path.isfile(args.rgb):
        raise ValueError(f"--rgb: no such file {args.rgb!r}")
    bgr = cv2.imread(args.rgb, cv2.IMREAD_COLOR)
    if bgr is None:
        raise ValueError(f"--rgb: cannot read {args.rgb!r} as an image")
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB).astype(np.float32) / 255.0
    depth = _read_depth(args.depth, args.depth_scale)
    if os.path.splitext(args.out)[1].lower() == ".png" and np.nanmax(depth, initial=0) * config.disparity_margin > PNG_MAX_METRES:
        raise ValueError(f"--out: a 16-bit millimetre PNG holds at most {PNG_MAX_METRES} m, and this depth reaches "
                         f"{np.nanmax(depth):.1f} m; use .npy, .pfm or .exr")
    result = complete_depth(rgb, depth, variant=args.variant, config=config)
    filled = result.merged(depth) if args.keep_input else result.depth
    write_bytes_atomic(args.out, writers[os.path.splitext(args.out)[1].lower()](filled), overwrite_readonly=args.force)
    print(f"filled {np.isnan(depth).mean():.1%} holes in {result.seconds:.1f} s → {args.out}")
    return 0


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


def _student(args) -> int:
    for path in build_student(args.source, args.out):
        print(f"wrote {path}")
    return 0


def _solutions(args) -> int:
    written = build_solutions(args.source, args.out, profile=args.profile, timeout=args.timeout, names=args.only)
    print(f"{len(written)} executed notebooks in {os.path.abspath(args.out)} ({args.profile})")
    return 0


def _grade(args) -> int:
    scores = grade(args.submissions, args.source, timeout=args.timeout, profile=args.profile,
                   executed_dir=args.executed)
    print()
    print(format_grades(scores))
    write_csv(scores, args.csv)
    print(f"per-exercise scores written to {os.path.abspath(args.csv)}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ddp-lite", description="Depth completion with a Deep Depth Prior.")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="fill the holes of a synthetic scene with DDP; compare with classical fills")
    demo.add_argument("--out", default="ddp_demo.png", help="figure path (default: ddp_demo.png)")
    demo.add_argument("--scene", default="house")
    demo.add_argument("--holes", choices=("edge", "sgm", "random"), default="edge",
                      help="a band across a depth edge plus blobs (default), real SGM holes, or blobs")
    demo.add_argument("--iterations", type=_number(int, 1, "--iterations"), default=300,
                      help="iteration cap of each fit (default 300; the profile's auto-stop may end it sooner)")
    demo.add_argument("--size", type=int, nargs=2, default=None, metavar=("H", "W"),
                      help="image size (default: the profile's; class: 96 128)")
    demo.add_argument("--profile", default=None, help="ci, class or paper (default: $DDP_PROFILE or class)")
    demo.add_argument("--seed", type=int, default=0)
    demo.add_argument("--device", default=None)
    demo.set_defaults(run=_demo)
    scenes = sub.add_parser("scenes", help="list the built-in synthetic scenes")
    scenes.set_defaults(run=_scenes)
    complete = sub.add_parser("complete", help="fill the holes of your own RGB-D image (no neighbours)")
    complete.add_argument("--rgb", required=True)
    complete.add_argument("--depth", required=True, help=".npy (metres), .pfm, or 16-bit PNG (see --depth-scale)")
    complete.add_argument("--depth-scale", type=_number(float, 0.0, "--depth-scale"), default=None,
                          help="metres per stored unit: required for integer files (0.001 for a mm PNG); 1 for float files")
    complete.add_argument("--variant", choices=("d", "rgbd"), default="rgbd")
    complete.add_argument("--profile", default=None, help="ci, class or paper (default: $DDP_PROFILE or class)")
    complete.add_argument("--iterations", type=_number(int, 1, "--iterations"), default=None)
    complete.add_argument("--keep-input", action="store_true", help="keep valid input depth (SGM+DDP style)")
    complete.add_argument("--out", required=True,
                          help="filled depth: .npy or .pfm (metres), .png (16-bit millimetres), .exr (if OpenCV has it)")
    complete.add_argument("--force", action="store_true", help="replace --out even if it is read-only")
    complete.add_argument("--max-memory-gb", type=_number(float, 0.0, "--max-memory-gb"), default=None,
                          help="refuse fits estimated to need more (default: 75%% of RAM); raise it to override")
    complete.add_argument("--device", default=None)
    complete.set_defaults(run=_complete)
    seq = sub.add_parser("sequence", help="complete every view of a sequence (TUM, COLMAP, saved scene) and fuse them")
    seq.add_argument("path", help="a TUM RGB-D folder, a COLMAP workspace, or a Scene.save .npz (or its folder)")
    seq.add_argument("--format", required=True, choices=("tum", "colmap", "scene"))
    seq.add_argument("--out", required=True, help="output folder: depth/, preview/, fused.ply, manifest.json")
    seq.add_argument("--views", nargs="+", default=None, help="view indices or names (default: all)")
    seq.add_argument("--workers", type=_number(int, 0, "--workers"), default=0,
                     help="start a Dask LocalCluster of N one-thread worker processes (default 0: in this process)")
    seq.add_argument("--scheduler", default=None, help="join a running Dask cluster, e.g. tcp://host:8786")
    seq.add_argument("--profile", default=None, help="ci, class or paper: the fit's schedule (default: $DDP_PROFILE "
                                                     "or class); images keep their size unless --size")
    seq.add_argument("--dry-run", action="store_true", help="print jobs, compute and memory estimates; fit nothing")
    seq.add_argument("--size", type=int, nargs=2, metavar=("H", "W"), default=None, help="resample every view")
    seq.add_argument("--iterations", type=_number(int, 1, "--iterations"), default=None)
    seq.add_argument("--seed", type=_number(int, 0, "--seed"), default=0)
    seq.add_argument("--threads", type=_number(int, 1, "--threads"), default=1, help="torch threads per fit (default 1)")
    seq.add_argument("--retries", type=_number(int, 0, "--retries"), default=2, help="Dask retries of a failed fit")
    seq.add_argument("--device", default=None)
    seq.add_argument("--intrinsics", type=_intrinsics, default=None,
                     help="TUM: fr1, fr2, fr3, ros, or fx,fy,cx,cy (default: from the folder name)")
    seq.add_argument("--every", type=_number(int, 1, "--every"), default=None, help="TUM: keep every N-th frame")
    seq.add_argument("--max-frames", type=_number(int, 1, "--max-frames"), default=None, help="TUM: at most N frames")
    seq.add_argument("--depth-scale", type=_number(float, 0.0, "--depth-scale"), default=None,
                     help="COLMAP: metres per stored depth unit (0.001 for millimetre PNGs; float files default 1)")
    seq.add_argument("--undistort", action="store_true", help="COLMAP: undistort OPENCV/RADIAL cameras with OpenCV")
    seq.add_argument("--gpu-tflops", type=_number(float, 0.0, "--gpu-tflops"), default=5.0,
                     help="--dry-run: the sustained GPU rate to assume (default 5 TFLOP/s)")
    seq.set_defaults(run=_sequence)

    student = sub.add_parser("student", help="write the student copies of the notebooks (solutions and outputs removed)")
    student.add_argument("--source", default="notebooks", help="the instructor notebooks (default: notebooks)")
    student.add_argument("--out", default="build/student")
    student.set_defaults(run=_student)
    solutions = sub.add_parser("solutions", help="execute the instructor notebooks and keep their outputs")
    solutions.add_argument("--source", default="notebooks")
    solutions.add_argument("--out", default="build/solutions")
    solutions.add_argument("--profile", choices=("ci", "class", "paper"), default="class")
    solutions.add_argument("--only", nargs="+", default=None, metavar="NN", help="only these notebooks (01 05 ...)")
    solutions.add_argument("--timeout", type=_number(int, 1, "--timeout"), default=3600, help="seconds per cell")
    solutions.set_defaults(run=_solutions)
    grade = sub.add_parser("grade", help="run submitted notebooks at ci and score their exercise checks")
    grade.add_argument("submissions", help="a folder with one sub-folder per student holding their .ipynb files")
    grade.add_argument("--source", default="notebooks", help="the instructor notebooks the checks come from")
    grade.add_argument("--csv", default="grades.csv", help="per-exercise scores (default: grades.csv)")
    grade.add_argument("--profile", choices=("ci", "class", "paper"), default="ci")
    grade.add_argument("--timeout", type=_number(int, 1, "--timeout"), default=600,
                       help="seconds one cell may run before it is interrupted and scored 0 (default: 600)")
    grade.add_argument("--executed", default=None, metavar="DIR",
                       help="also write each executed notebook, with its outputs, to DIR/<student>/ (feedback)")
    grade.set_defaults(run=_grade)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except (ValueError, TypeError, FloatingPointError, OSError) as error:
        print(f"ddp-lite {args.command}: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
