"""``ddp-lite``: the kit's main job without a browser.

Here: the parser (every subcommand's ``--help`` carries its examples) and ``main``. The arguments
are parsed before anything heavy is imported: each subcommand names its handler as
``"module:function"`` and only that module is imported, so ``--help`` and a refused argument
answer at once. Handlers take the parsed namespace and return the exit code: 0 done, 1 a failure
at run time (an ``OSError``, a diverged fit, a failed view), 2 a usage error (argparse's, or a
``ValueError``/``TypeError`` from a check before the work), 130 interrupted (Ctrl-C).
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
import warnings

from .. import __version__

PROFILES = ("ci", "class", "paper")
PROFILE_SIZES = "size and budget: ci (seconds), class (minutes on a laptop CPU), paper (the paper's sizes, a GPU)"
RECIPE_NAMES = ("kit", "paper", "photo")  # ddp_lite.method.kit.recipes.RECIPES, without importing the method here
RECIPE_HELP = ("the method: kit = the paper's losses plus the kit's hole terms and net inputs, and (variants with "
               "colour) a share of a colour-guided fill; paper = the paper's method alone; photo = for real "
               "photographs, the kit's fit without its hole terms, made sharp by an image-guided bilateral "
               "solve, with the kit's share of the fill (complete runs that solve at the photo's full size with either) "
               "(default: $DDP_RECIPE, else kit)")
# ddp_lite.method.runtime.device.resolve_device's order for no --device
DEVICE_HELP = "cpu, cuda[:N] or mps (default: cuda when present, else mps when present, else cpu)"
EXIT_CODES = ("exit codes: 0 done, 1 failed at run time (nothing half-written), 2 usage error "
              "(the message names the option), 130 interrupted (Ctrl-C)")

# What an interrupted command leaves behind, and what to run next (one line each).
INTERRUPTED = {
    "demo": "nothing was written (the figure is written at the end); re-run the same command",
    "complete": "nothing was written (outputs are written at the end); re-run the same command",
    "sequence": "the views finished so far are kept in --out (see its manifest.json); re-run the same "
                "command to fit only the others",
    "student": "the notebooks listed as written are complete; re-run the same command for all of them",
    "solutions": "the notebooks listed as written are complete; re-run with --only NN ... for the others",
    "grade": "no grades were written (they are written at the end); re-run the same command",
    "scenes": "nothing was written",
}

EXAMPLES = {
    "demo": """examples:
  ddp-lite demo                                  # house scene, the profile's size, figure ddp_demo.png
  DDP_PROFILE=ci ddp-lite demo --out quick.png   # seconds
  ddp-lite demo --scene hills --holes sgm --iterations 600""",
    "scenes": """examples:
  ddp-lite scenes""",
    "complete": """examples:
  ddp-lite complete --rgb rgb.png --depth depth.png --depth-scale 0.001 --out filled.npy
  ddp-lite complete --rgb rgb.png --depth depth.npy --out filled.png --gt gt.npy   # also the hole RMSE
  ddp-lite complete --rgb rgb.png --depth depth.pfm --out filled.pfm --max-side 256 --raw
  ddp-lite complete --rgb left.png --depth sgbm.pfm --out filled.pfm --depth-source stereo  # a matcher's depth
  ddp-lite complete --rgb rgb.png --depth depth.png --depth-scale 0.001 --out filled.npy \\
                    --intrinsics 615.2,615.0,320.5,240.1                  # + filled.ply, one RGB-D frame
  ddp-lite complete --scene Plastic --out plastic.pfm          # DepthComp's holes on a Middlebury scene, scored
  ddp-lite complete --scene Art --holes sgbm --out art.pfm     # SGBM's depth on the scene's own stereo pair
  ddp-lite complete --scene ~/data/HalfSize/Baby1 --holes blobs --variant rgbd --out baby.npy""",
    "sequence": """examples:
  ddp-lite sequence rgbd_dataset_freiburg1_desk --format tum --out desk --every 10 --max-frames 5
  ddp-lite sequence capture --format tum --depth-scale 0.001 --out out   # millimetre PNGs
  ddp-lite sequence workspace --format colmap --out out --dry-run --profile paper
  ddp-lite sequence workspace --format colmap --out out --scheduler tcp://host:8786""",
    "student": """examples:
  ddp-lite student                               # notebooks/ -> build/student/""",
    "solutions": """examples:
  ddp-lite solutions --profile ci --only 01 05   # execute two notebooks, keep their outputs""",
    "grade": """examples:
  ddp-lite grade submissions                     # one row per student, grades.csv
  ddp-lite grade submissions --details --executed feedback --feedback feedback
  ddp-lite grade submissions --points hand_points.csv   # merge hand-given points of open exercises""",
}


def _number(kind, minimum: float, name: str):
    """An argparse type: a finite ``kind`` (int or float) ≥ ``minimum``, else an error naming the flag."""
    def parse(text: str):
        import math
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be {'an integer' if kind is int else 'a number'}, "
                                             f"got {text!r}") from None
        if not math.isfinite(value) or value < minimum or (kind is float and value <= 0):
            raise argparse.ArgumentTypeError(f"{name} must be a finite number {'≥' if kind is int else '>'} "
                                             f"{minimum:g}, got {text!r}")
        return value
    return parse


def _intrinsics(text: str):
    """--intrinsics: "fx,fy,cx,cy" in pixels → 3×3 K (lists), or a camera name, checked by the reader's list."""
    if "," not in text:
        return text
    try:
        fx, fy, cx, cy = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--intrinsics must be a TUM camera name or fx,fy,cx,cy (pixels), "
                                         f"got {text!r}") from None
    return [[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]


class _StoreOnce(argparse._StoreAction):
    """An option that takes one value refuses a second (``--out a.npy --out b.npy``): argparse would keep
    the last and drop the first in silence."""

    def __call__(self, parser, namespace, values, option_string=None):
        seen = namespace.__dict__.setdefault("_given_once", set())
        if self.dest in seen:
            parser.error(f"{option_string} was given twice; give it once (the first value would be ignored)")
        seen.add(self.dest)
        super().__call__(parser, namespace, values, option_string)


def _subparser(sub, name: str, help: str, run: str) -> argparse.ArgumentParser:
    parser = sub.add_parser(name, help=help, description=help[:1].upper() + help[1:] + ".",
                            epilog=EXAMPLES[name] + "\n\n" + EXIT_CODES,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.register("action", None, _StoreOnce)  # every single-valued option of every command
    parser.register("action", "store", _StoreOnce)
    parser.set_defaults(run=run)
    return parser


def _add_profile(parser, default=None, what: str = PROFILE_SIZES) -> None:
    parser.add_argument("--profile", choices=PROFILES, default=default,
                        help=what + (" (default: $DDP_PROFILE, else class)" if default is None else
                                     f" (default: {default})"))


def _add_recipe(parser, otherwise: str = "kit") -> None:
    parser.add_argument("--recipe", choices=RECIPE_NAMES, default=None,
                        help=f"{RECIPE_HELP} (default: $DDP_RECIPE, else {otherwise})")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ddp-lite", description="Depth completion with a Deep Depth Prior (Ghosh et al., 3DV 2020).",
        epilog="Run 'ddp-lite COMMAND --help' for a command's options and examples.\n\n" + EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"ddp-lite {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    demo = _subparser(sub, "demo", "fill the holes of a synthetic scene with DDP; compare with classical fills",
                      "ddp_lite.interface.cli_demo:demo_command")
    demo.add_argument("--out", default="ddp_demo.png", help="figure path: .png, .pdf, .svg, ... (default: ddp_demo.png)")
    demo.add_argument("--scene", default="house", help="a built-in scene (list them: ddp-lite scenes; default house)")
    demo.add_argument("--holes", choices=("edge", "sgm", "random"), default="edge",
                      help="a band across a depth edge plus blobs (default), real SGM holes, or blobs")
    demo.add_argument("--iterations", type=_number(int, 1, "--iterations"), default=300,
                      help="iteration cap of each fit (default 300; the profile's auto-stop may end it sooner)")
    demo.add_argument("--size", type=_number(int, 1, "--size"), nargs=2, default=None, metavar=("H", "W"),
                      help="image size, height then width (default: the profile's; class: 96 128)")
    _add_profile(demo)
    _add_recipe(demo)
    demo.add_argument("--seed", type=_number(int, 0, "--seed"), default=0,
                      help="seed of the scene's holes and of the fit (default 0; same seed, same numbers on CPU)")
    demo.add_argument("--device", default=None, help=DEVICE_HELP)
    demo.add_argument("--max-memory-gb", type=_number(float, 0.0, "--max-memory-gb"), default=None,
                      help="refuse fits estimated to need more (default: 75%% of RAM); raise it to override")

    _subparser(sub, "scenes", "list the built-in synthetic scenes", "ddp_lite.interface.cli_demo:scenes_command")

    complete = _subparser(sub, "complete", "fill the holes of your own RGB-D image, or of a Middlebury scene",
                          "ddp_lite.interface.cli_complete:complete_command")
    complete.add_argument("--rgb", default=None, help="the colour image (any file OpenCV reads), same size as --depth")
    complete.add_argument("--depth", default=None, help=".npy (metres), .pfm, or 16-bit PNG (see --depth-scale); "
                                                        "0, inf and NaN are holes")
    complete.add_argument("--scene", default=None, metavar="DIR|NAME",
                          help="instead of --rgb/--depth: a Middlebury scene folder (2005/2006: view1.png, disp1.png, "
                               "dmin.txt; 2014: im0.png, im1.png, calib.txt, disp0GT.pfm or disp0.pfm), or a scene's "
                               "name: installed by data_fetch in the data root, else shipped (Plastic, Baby1, "
                               "Bowling1, Art); its truth scores every fill, the output is at its size")
    complete.add_argument("--holes", default=None, metavar="sgbm|blobs|FILE",
                          help="with --scene, the input depth: sgbm (SGBM on the scene's own stereo pair), blobs "
                               "(cut into the truth) or FILE (an image, 0 = hole; DepthComp's plastic-disp-hole.png); "
                               "default: the scene's DepthComp hole file where it has one (Plastic), else sgbm")
    complete.add_argument("--depth-scale", type=_number(float, 0.0, "--depth-scale"), default=None,
                          help="metres per stored unit: required for integer files (0.001 for a mm PNG); 1 for float files")
    complete.add_argument("--out", required=True,
                          help="filled depth: .npy or .pfm (metres), .png (16-bit millimetres), .exr (if OpenCV has it)")
    complete.add_argument("--variant", choices=("d", "rgbd", "rgbd+warp"), default=None,
                          help="the net fits depth only (d), colour and depth (rgbd, the default for --rgb/--depth), "
                               "or also warps the scene's calibrated neighbours (rgbd+warp, --scene only, its default: "
                               "view0 and view2 of a 2005/2006 scene, im1 of a 2014 one)")
    _add_profile(complete)
    _add_recipe(complete)
    complete.add_argument("--iterations", type=_number(int, 1, "--iterations"), default=None,
                          help="iteration cap of the fit (default: the profile's)")
    complete.add_argument("--max-side", type=_number(int, 16, "--max-side"), default=None,
                          help="fit at this longer side (px) and bring the fill back to full size in the holes "
                               "(default: the profile's image size; class 128)")
    complete.add_argument("--raw", action="store_true",
                          help="write the net's own output everywhere, with no colour-guided fill mixed in "
                               "(default: the valid input pixels kept exactly, the recipe's share of the fill "
                               "mixed into the holes)")
    complete.add_argument("--no-refine", action="store_true",
                          help="bring the fit back to full size by up-sampling alone, without sharpening it at "
                               "full size along the photo's edges (default: sharpened; --raw implies this)")
    complete.add_argument("--depth-source", choices=("clean", "stereo"), default=None,
                          help="where --depth came from: 'stereo' for a stereo matcher's depth, whose holes have "
                               "a rim it often got wrong: the fill and the sharpening do not read that rim and "
                               "reach further (default 'clean': every valid pixel trusted; with --scene, stereo "
                               "for --holes sgbm)")
    complete.add_argument("--preview", default=None,
                          help="preview figure: input, filled, holes, and with --gt the error map "
                               "(default: OUT's name with .preview.png)")
    complete.add_argument("--gt", default=None,
                          help="ground-truth depth (same formats and --depth-scale): print hole RMSE of DDP and "
                               "the classical fills")
    complete.add_argument("--intrinsics", type=_intrinsics, default=None, metavar="FX,FY,CX,CY",
                          help="the camera of --rgb/--depth in pixels (full size): also write the filled frame "
                               "as a coloured point cloud (see --ply); no folder layout needed")
    complete.add_argument("--ply", default=None,
                          help="point cloud path with --intrinsics (default: OUT's name with .ply)")
    complete.add_argument("--force", action="store_true", help="replace --out even if it is read-only")
    complete.add_argument("--max-memory-gb", type=_number(float, 0.0, "--max-memory-gb"), default=None,
                          help="refuse fits estimated to need more (default: 75%% of RAM); raise it to override")
    complete.add_argument("--seed", type=_number(int, 0, "--seed"), default=0, help="seed of the fit (default 0)")
    complete.add_argument("--device", default=None, help=DEVICE_HELP)

    seq = _subparser(sub, "sequence", "complete every view of a sequence (TUM, COLMAP, saved scene) and fuse them",
                     "ddp_lite.interface.cli_sequence:sequence_command")
    seq.add_argument("path", help="a TUM RGB-D folder, a COLMAP workspace, or a Scene.save .npz (or its folder)")
    seq.add_argument("--format", required=True, choices=("tum", "colmap", "scene"), help="how PATH is laid out")
    seq.add_argument("--out", required=True, help="output folder: depth/, preview/, fused.ply, manifest.json")
    seq.add_argument("--views", nargs="+", default=None, help="view indices or names (default: all)")
    seq.add_argument("--workers", type=_number(int, 0, "--workers"), default=0,
                     help="start a Dask LocalCluster of N one-thread worker processes, at most the CPU count "
                          "(default 0: in this process, as many views at once as it has torch threads, one thread each)")
    seq.add_argument("--scheduler", default=None, help="join a running Dask cluster, e.g. tcp://host:8786")
    _add_profile(seq, what="the net and budget of each fit: ci (seconds), class (minutes on a laptop CPU), "
                           "paper (the paper's net and schedule, a GPU); the images keep their size unless --size")
    _add_recipe(seq)
    seq.add_argument("--dry-run", action="store_true", help="print jobs, compute and memory estimates; fit nothing")
    seq.add_argument("--size", type=_number(int, 1, "--size"), nargs=2, metavar=("H", "W"), default=None,
                     help="resample every view to height H, width W")
    seq.add_argument("--iterations", type=_number(int, 1, "--iterations"), default=None,
                     help="iteration cap of each fit (default: the profile's)")
    seq.add_argument("--seed", type=_number(int, 0, "--seed"), default=0, help="seed of every fit (default 0)")
    seq.add_argument("--threads", type=_number(int, 1, "--threads"), default=1, help="torch threads per fit (default 1)")
    seq.add_argument("--retries", type=_number(int, 0, "--retries"), default=2, help="Dask retries of a failed fit (default 2)")
    seq.add_argument("--device", default=None, help=DEVICE_HELP)
    seq.add_argument("--intrinsics", type=_intrinsics, default=None,
                     help="TUM: fr1, fr2, fr3, ros, or fx,fy,cx,cy (default: from the folder name)")
    seq.add_argument("--every", type=_number(int, 1, "--every"), default=None, help="TUM: keep every N-th frame")
    seq.add_argument("--max-frames", type=_number(int, 1, "--max-frames"), default=None, help="TUM: at most N frames")
    seq.add_argument("--depth-scale", type=_number(float, 0.0, "--depth-scale"), default=None,
                     help="metres per stored depth unit (0.001 for millimetre PNGs); default: TUM's 1/5000, "
                          "COLMAP's float files 1")
    seq.add_argument("--undistort", action="store_true", help="COLMAP: undistort OPENCV/RADIAL cameras with OpenCV")
    seq.add_argument("--strict", action="store_true",
                     help="refuse a sequence with frames or images that cannot be used (no depth partner, no pose, "
                          "not registered) instead of leaving them out with a warning naming them")
    seq.add_argument("--gpu-tflops", type=_number(float, 0.0, "--gpu-tflops"), default=5.0,
                     help="--dry-run: the sustained GPU rate to assume (default 5 TFLOP/s)")

    student = _subparser(sub, "student", "write the student copies of the notebooks (solutions and outputs removed)",
                         "ddp_lite.interface.cli_classroom:student_command")
    student.add_argument("--source", default="notebooks", help="the instructor notebooks (default: notebooks)")
    student.add_argument("--out", default="build/student",
                         help="folder for the student copies, outside --source (default: build/student)")
    solutions = _subparser(sub, "solutions", "execute the instructor notebooks and keep their outputs",
                           "ddp_lite.interface.cli_classroom:solutions_command")
    solutions.add_argument("--source", default="notebooks", help="the instructor notebooks (default: notebooks)")
    solutions.add_argument("--out", default="build/solutions",
                           help="folder for the executed copies, outside --source (default: build/solutions)")
    _add_profile(solutions, default="class")
    _add_recipe(solutions, otherwise="each notebook's own, as a student runs it: kit, or photo on real photographs")
    solutions.add_argument("--only", nargs="+", default=None, metavar="NN", help="only these notebooks (01 05 ...)")
    solutions.add_argument("--timeout", type=_number(int, 1, "--timeout"), default=3600,
                           help="seconds one cell may run (default 3600)")
    grade = _subparser(sub, "grade", "run submitted notebooks and score their exercise checks",
                       "ddp_lite.interface.cli_classroom:grade_command")
    grade.add_argument("submissions", help="a folder with one sub-folder per student holding their .ipynb files")
    grade.add_argument("--source", default="notebooks", help="the instructor notebooks the checks come from")
    grade.add_argument("--csv", default="grades.csv", help="per-exercise scores (default: grades.csv)")
    _add_profile(grade, default="ci")
    grade.add_argument("--timeout", type=_number(int, 1, "--timeout"), default=600,
                       help="seconds one cell may run before it is interrupted and scored 0 (default: 600)")
    grade.add_argument("--executed", default=None, metavar="DIR",
                       help="also write each executed notebook, with its outputs, to DIR/<student>/ (feedback)")
    grade.add_argument("--feedback", default=None, metavar="DIR",
                       help="write each student's open answers to DIR/<student>.md, for reading and grading by hand")
    grade.add_argument("--points", default=None, metavar="CSV",
                       help="hand-given points of open exercises (columns student, exercise, points) to merge "
                            "into --csv")
    grade.add_argument("--details", action="store_true",
                       help="print a line per student and notebook as it is graded (default: one row per student)")
    return parser


def _handler(target: str):
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


def _warning_printer(command: str):
    """``warnings.showwarning`` for the command line: one line per warning, ``ddp-lite COMMAND: warning: ...``
    on stderr (what was left out, what was read as it is), without Python's file and source line."""
    def show(message, category, filename, lineno, file=None, line=None):
        print(f"ddp-lite {command}: warning: {message}", file=sys.stderr if file is None else file, flush=True)
    return show


def _printable(stream) -> bool:
    """Let ``stream`` print what its encoding cannot (``→`` on an ASCII or cp1252 terminal) as ``?``
    instead of raising after the work is done; whether it was changed (to undo on the way out)."""
    if getattr(stream, "errors", None) == "strict" and hasattr(stream, "reconfigure"):
        try:
            stream.reconfigure(errors="replace")
            return True
        except (ValueError, OSError, AttributeError):
            pass
    return False


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    args.__dict__.pop("_given_once", None)
    changed = [stream for stream in (sys.stdout, sys.stderr) if _printable(stream)]  # one rule for every message
    try:
        return _main(args)
    finally:
        for stream in changed:
            with contextlib.suppress(ValueError, OSError):
                stream.reconfigure(errors="strict")


def _main(args) -> int:
    try:
        with warnings.catch_warnings():  # restores the caller's warning handling on the way out
            warnings.showwarning = _warning_printer(args.command)
            return _handler(args.run)(args)
    except KeyboardInterrupt:
        print(f"\nddp-lite {args.command}: interrupted; {INTERRUPTED[args.command]}.", file=sys.stderr)
        return 130
    except (ValueError, TypeError) as error:  # the checks before the work: a usage error
        print(f"ddp-lite {args.command}: {error}", file=sys.stderr)
        return 2
    except (OSError, FloatingPointError, RuntimeError, MemoryError) as error:  # at run time
        print(f"ddp-lite {args.command}: {type(error).__name__}: {error}", file=sys.stderr)
        return 1
    except Exception as error:  # noqa: BLE001: anything else (an OpenCV or Dask error) still gets one line, no traceback
        print(f"ddp-lite {args.command}: failed: {type(error).__name__}: {error} (an unexpected error: please report "
              f"it with the command line; DDP_TRACEBACK=1 shows where it arose)", file=sys.stderr)
        if os.environ.get("DDP_TRACEBACK", "").strip() not in ("", "0"):
            import traceback
            traceback.print_exc()
        return 1


if __name__ == "__main__":
    sys.exit(main())
