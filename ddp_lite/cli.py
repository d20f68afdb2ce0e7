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

Here: the parser, ``main`` (a ``ValueError``/``TypeError``/``OSError`` becomes one line on stderr and
exit code 2) and the classroom commands, which call ``classroom``. The other commands' handlers
live in ``cli_demo``, ``cli_complete`` and ``cli_sequence``; each takes the parsed namespace and
returns the exit code.
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from .classroom import build_solutions, build_student, format_grades, grade, write_csv
from .cli_complete import _complete
from .cli_complete import DEPTH_RANGE_M, PNG_MAX_METRES, _read_depth  # re-exported: their old home
from .cli_demo import _demo, _scenes
from .cli_sequence import _intrinsics, _sequence


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
