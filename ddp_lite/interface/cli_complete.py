"""``ddp-lite complete``: fill the holes of your own RGB-D image, with every check before the fit.

Input: ``--rgb`` an 8-bit colour image OpenCV reads (one channel or 16 bits, a depth map's look, is refused:
"did you swap --rgb and --depth?"), pixels as stored (no EXIF rotation, like the depth);
``--depth`` ``.npy``/``.pfm`` (metres, or × ``--depth-scale``) or a 16-bit image (needs ``--depth-scale``,
metres per stored unit), read by the kit's one depth reader (``fileio.read_depth``: 8-bit pictures
refused); 0, ≤ 0, inf and NaN are holes (NaN). ``--rgb`` and ``--depth`` must be the same size;
``--intrinsics`` must fit it (``camera.check_intrinsics``). A depth range no camera produces at that scale (kilometres from a millimetre PNG
read as metres) is refused with the scale that would make it plausible.

The fit runs at a working size (``--max-side``, default the profile's longer side) and its
completed depth is brought back to full size in disparity, in the holes only: the valid input
pixels keep their exact values (``--raw``: the net's own output everywhere, without the share of a
colour-guided fill the ``kit`` recipe mixes in), see ``ddp_lite.sequences.working_size``. The
up-sampled fill is then sharpened at full size (``ddp_lite.classical.full_resolution``): an edge-aware
solve guided by the full-size photo, pulled to the valid input (confidence 1) and to the fit in the
holes (lower confidence), so that depth edges inside the holes follow the photo's edges instead of the
working size's blur (``--no-refine``: up-sampling alone; ``--raw`` implies it). ``--depth-source stereo``
(a stereo matcher's depth): the fill and the solves do not read the rim of its holes (1 px at the working
size, as many at full size as it is times larger; ``kit.blend.rim_width``) and the solve reaches twice as
far (``full_resolution.FULL_SIZE_SOLVE``; its reach grows with a photo's short side above 555 px,
``full_resolution.full_size_solve``). The ``photo`` recipe's own
solve (``refine``) is this one, so it runs once, at full size, not also at the working size (on six
Middlebury scenes and Motorcycle at full size that costs: 1.05× the best fill against 0.95×), and ``complete``
keeps the ``kit`` recipe by default: without its hole terms, as ``photo`` fits on the real suite, the full-size
fill there was 1.6 % worse over three seeds (0.98× the best fill against 0.96×; ``docs/studies/real_suite.md``); the
first line names the recipe that runs. Then one line compares
the fill with a classical one computed here at full size (linear interpolation; their mean absolute
difference in the holes), or, with ``--gt``, prints the hole RMSE of DDP, linear, Navier-Stokes and the
colour-guided fills; and a preview figure (input, filled with the holes outlined, the hole mask, and
with ``--gt`` DDP's error map and the RMSEs) is written beside ``--out``.

``--scene DIR|NAME`` instead of ``--rgb``/``--depth``: a Middlebury scene (``data.installed.resolve_scene``: a
folder, else the copy installed in the data root, else a shipped sample), its input depth made by ``--holes``
(``data.scene_input``: SGBM on its own stereo pair, blobs, or a hole file; default the scene's DepthComp holes
where it has them, else SGBM), its truth in place of ``--gt`` (also scored in disparity px at the scene's
size), ``rgbd+warp`` with its calibrated neighbours by default; the first line says which data it reads.

Output by the suffix of ``--out``: ``.npy``/``.pfm`` float32 metres, ``.png`` 16-bit
millimetres (0 = none, at most ``PNG_MAX_METRES``), ``.exr`` if OpenCV has the codec. Every file
is written atomically, and every path and input is checked before the fit (``ValueError`` naming
the flag).
"""
from __future__ import annotations

import os
import time
import warnings
from dataclasses import dataclass

import cv2
import numpy as np

from ..core.files import regular_file, write_bytes_atomic
from ..data.installed import SceneCopy, data_line, depthcomp_hole_file, resolve_scene
from ..data.samples import SAMPLE_DATASETS
from ..data.file_writers import depth_png_bytes, npy_bytes, pfm_bytes
from ..data.fileio import check_plausible_depth, check_same_size, read_depth, read_image_file, read_rgb
from ..core.outpaths import check_output_file, output_set


def _exr_available() -> bool:
    if os.environ.get("OPENCV_IO_ENABLE_OPENEXR", "").lower() not in ("1", "true", "on", "yes"):
        return False  # OpenCV's EXR codec is off by default (and probing it prints a warning)
    try:
        return bool(cv2.imencode(".exr", np.zeros((1, 1), np.float32))[0])
    except cv2.error:
        return False


def _writers() -> dict:
    """Output writers by suffix: filled depth (H, W) float32 metres → bytes."""
    def png(depth):  # 16-bit millimetres, 0 = no value; complete_command refuses depth beyond PNG_MAX_METRES first
        return depth_png_bytes(depth)[0]

    def exr(depth):
        return cv2.imencode(".exr", depth.astype(np.float32))[1].tobytes()
    return {".npy": npy_bytes, ".png": png, ".pfm": pfm_bytes, ".exr": exr}


PNG_MAX_METRES = 65.535  # uint16 millimetres


def _preview_path(args) -> str:
    return args.preview if args.preview else os.path.splitext(args.out)[0] + ".preview.png"


def _ply_path(args) -> str | None:
    if getattr(args, "scene", None) is not None:  # the scene's calibration gives the camera: a cloud when asked
        return args.ply
    if args.intrinsics is None:
        if args.ply:
            raise ValueError("--ply needs --intrinsics fx,fy,cx,cy (the camera that turns depth into points)")
        return None
    if isinstance(args.intrinsics, str):
        raise ValueError(f"--intrinsics must be fx,fy,cx,cy in pixels, got {args.intrinsics!r}")
    return args.ply if args.ply else os.path.splitext(args.out)[0] + ".ply"


def _check_outputs(args, writers: dict, source=None) -> None:
    """Refuse a bad --out, --preview or --ply before any work: unknown suffix, a folder, an input (a file of
    the ``--scene`` folder among them), a read-only file, an unwritable folder."""
    from .cli_demo import figure_suffixes
    if source is None:
        inputs = {"--depth": args.depth, "--rgb": args.rgb, **({"--gt": args.gt} if args.gt else {})}
    else:
        inputs = {f"--scene ({path.name})": path for path in sorted(source.copy.folder.iterdir()) if path.is_file()}
        if os.path.isfile(source.holes):
            inputs["--holes"] = source.holes
    check_output_file(args.out, "--out", suffixes=tuple(writers), inputs=inputs, force=args.force,
                      example="filled.npy")
    if args.out.lower().endswith(".exr") and not _exr_available():
        raise ValueError("--out: this OpenCV cannot write .exr (set OPENCV_IO_ENABLE_OPENEXR=1, or use .npy/.pfm)")
    check_output_file(_preview_path(args), "--preview", suffixes=figure_suffixes(),
                      inputs={**inputs, "--out": args.out}, example="preview.png")
    if _ply_path(args):
        check_output_file(_ply_path(args), "--ply", suffixes=(".ply",),
                          inputs={**inputs, "--out": args.out, "--preview": _preview_path(args)}, example="filled.ply")


def _read_depth(path: str, scale: float | None, flag: str = "--depth") -> np.ndarray:
    """``path`` as float32 metres, NaN where the file has no value (0, ≤ 0, inf, NaN), read by the kit's one
    depth reader (``fileio.read_depth``: 8-bit pictures refused, sentinels reported); a scale that gives an
    implausible depth range is refused (:func:`check_plausible_depth`)."""
    _input_file(path, flag)
    try:
        depth = read_depth(path, scale, flag, scale_name="--depth-scale")
    except ValueError as error:
        if flag == "--depth" and _looks_like_colour(path):
            raise ValueError(f"{error}. {path!r} is a 3-channel 8-bit image, a colour picture: {SWAPPED}") from None
        if _looks_like_disparity(path):
            raise ValueError(f"{error}. A 1-channel 8-bit PNG is how Middlebury stores disparity (disp1.png, "
                             f"DepthComp's hole files), which needs the scene's calibration: complete the scene with "
                             f"--scene FOLDER (the folder holding view1.png, disp1.png and dmin.txt, or a scene's "
                             f"name such as --scene Plastic), and --holes FILE for a hole file") from None
        raise
    valid = np.isfinite(depth)
    if not valid.any():
        raise ValueError(f"{flag}: {path!r} holds no depth at all (every pixel is 0, negative, NaN or inf"
                         + (f" at --depth-scale {scale:g}" if scale is not None else "") + ")")
    check_plausible_depth(depth[valid], 1.0 if scale is None else scale, flag)
    return depth


def _input_file(path: str, flag: str) -> None:
    """Refuse an input that is missing, a folder, or not a regular file (a FIFO would block the read),
    as a usage error (``ValueError``) naming ``flag``."""
    if not os.path.exists(path):
        raise ValueError(f"{flag}: no such file {path!r}")
    try:
        regular_file(path, flag)
    except IsADirectoryError as error:
        raise ValueError(str(error)) from None


SWAPPED = "did you swap --rgb and --depth?"


def _eight_bit_channels(path: str) -> int | None:
    """How many channels of 8 bits the image file ``path`` holds as OpenCV reads it (1, 3 or 4); None for an
    array file, a file it cannot read, or a deeper image."""
    if os.path.splitext(path)[1].lower() in (".npy", ".pfm", ".bin"):
        return None
    try:
        raw = read_image_file(path, "--depth")
    except ValueError:
        return None
    return (raw.shape[2] if raw.ndim == 3 else 1) if raw.dtype == np.uint8 else None


def _looks_like_colour(path: str) -> bool:
    """``path`` is an image file of 3 or 4 channels of 8 bits: a colour picture."""
    return _eight_bit_channels(path) in (3, 4)


def _looks_like_disparity(path: str) -> bool:
    """``path`` is a 1-channel 8-bit image: how Middlebury 2005/2006 and DepthComp store disparity."""
    return _eight_bit_channels(path) == 1


def _read_rgb(path: str) -> np.ndarray:
    """``--rgb``: an 8-bit colour image; one channel or 16 bits is what a depth map looks like, refused."""
    _input_file(path, "--rgb")
    raw = read_image_file(path, "--rgb")
    channels = 1 if raw.ndim == 2 else raw.shape[2]
    if channels == 1 or raw.dtype != np.uint8:
        what = ", ".join(w for w, bad in (("one channel", channels == 1), (f"{raw.dtype} values", raw.dtype != np.uint8))
                         if bad)
        raise ValueError(f"--rgb: {path!r} has {what} ({raw.shape[0]}×{raw.shape[1]} (H×W)), as a depth map has; "
                         f"--rgb takes the 8-bit colour photograph (3 channels): {SWAPPED}")
    return read_rgb(path, "--rgb")  # pixels as stored, the same way as the depth: a phone's EXIF rotation is not applied


def _write_preview(path: str, depth: np.ndarray, filled: np.ndarray, summary: str, scores=None) -> None:
    """Input (holes coloured), filled depth (the holes outlined), the hole mask (two colours), and with
    ``scores`` = (gt (H, W) metres, {method: hole RMSE m}) the fill's error in the holes with every
    method's RMSE: one figure, input and fill on one depth colour scale with one bar, written atomically."""
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from ..evaluation.viz import HOLE_COLOUR, outline, save_figure, shared_colorbar, show_depth, show_errors
    holes = ~np.isfinite(depth)
    vmin, vmax = float(np.nanpercentile(filled, 1)), float(np.nanpercentile(filled, 99))
    H, W = depth.shape
    panels = 3 if scores is None else 4
    fig = Figure(figsize=(5 * panels, 15 * H / W / 3 + 1.6))
    axes = fig.subplots(1, panels)
    show_depth(axes[0], depth, f"input ({holes.mean():.1%} holes)", vmin, vmax, colorbar=False)
    image = show_depth(axes[1], filled, "filled (holes outlined)", vmin, vmax, colorbar=False)
    shared_colorbar(image, axes[1], label="depth (m)")  # one scale for the input and the fill, one bar
    outline(axes[1], holes, colour="white")
    axes[2].imshow(holes, cmap=ListedColormap(["lightgrey", HOLE_COLOUR]), vmin=0, vmax=1, interpolation="nearest")
    axes[2].legend(handles=[Patch(color="lightgrey", label="valid"), Patch(color=HOLE_COLOUR, label="hole")],
                   loc="upper center", bbox_to_anchor=(0.5, -0.02), ncol=2, fontsize=8, frameon=False)
    axes[2].set_title("holes")
    axes[2].axis("off")
    if scores is not None:
        gt, rmse = scores
        show_errors([axes[3]], {"": filled}, gt, mask=holes & np.isfinite(gt), label="|DDP − truth| (m)")
        axes[3].set_title(_error_title(rmse), fontsize=9)
    fig.tight_layout()
    # the summary sits just above the tallest panel title: tight_layout centres the fixed-aspect panels in
    # their rows, so a suptitle at the figure's top would leave a blank band the height of that slack
    fig.draw_without_rendering()
    top = max(ax.title.get_window_extent().y1 for ax in axes) / fig.bbox.height
    fig.suptitle(summary, fontsize=10, y=top + 0.01, va="bottom")
    save_figure(fig, path)


def _error_title(rmse: dict) -> str:
    """The error panel's title: every method's hole RMSE in metres, as the console line prints them
    (``{value:.4g}``, the same names), three to a line."""
    entries = [f"{name} {value:.4g}" for name, value in rmse.items()]
    rows = [", ".join(entries[i:i + 3]) for i in range(0, len(entries), 3)]
    return "hole RMSE (m): " + ",\n".join(rows)


COLOUR_FILLS = ("colorization", "guided-filter", "bilateral-solver", "cross-bilateral")


def _classical_fills(depth, rgb, gt) -> dict:
    """The classical fills (H, W) metres the summary line puts DDP beside, computed before the fit (they need
    only the input) so that the fit's time left is the command's, each in disparity (1/Z) as DDP fills:
    linear from the holes' rims, and with ``gt`` Navier-Stokes and every colour-guided fill
    (``COLOUR_FILLS``) too. A ``gt`` with no value in the holes is refused here, before any work."""
    from ..classical.baselines import BASELINES
    from ..classical.depth_fills import fill_linear_from_rim
    holes = ~np.isfinite(depth)
    if gt is not None and not (holes & np.isfinite(gt)).any():
        raise ValueError("--gt has no valid value in the holes of --depth; nothing to score")
    inverse = 1.0 / depth
    fills = {"linear": 1.0 / fill_linear_from_rim(inverse)}  # fill_linear's triangulation of every valid pixel takes 13 s at 500×741
    if gt is not None:
        for name in ("navier-stokes",) + COLOUR_FILLS:
            fills[name] = 1.0 / BASELINES[name](inverse, rgb)
    return fills


def _comparison(depth, filled, gt, classical: dict) -> tuple[str, dict]:
    """The line that puts DDP's fill beside the classical ones (:func:`_classical_fills`) at full size, and
    the hole RMSE (m) of every method that line names, DDP first ({} without ``gt``)."""
    holes = ~np.isfinite(depth)
    if gt is None:
        difference = float(np.mean(np.abs(filled[holes] - classical["linear"][holes])))
        return (f"holes at full size: DDP vs a linear fill (computed here) differ by {difference:.3g} m on average "
                f"(mean |difference| over {holes.sum()} hole pixels; their error is unknown without --gt)"), {}
    scored = holes & np.isfinite(gt)
    fills = {"DDP": filled, **classical}
    rmse = {name: float(np.sqrt(np.mean((f[scored] - gt[scored]) ** 2))) for name, f in fills.items()}
    best = min(COLOUR_FILLS, key=rmse.get)
    return (f"hole RMSE at full size ({scored.sum()} pixels with ground truth): "
            + ", ".join(f"{name} {value:.4g} m" for name, value in rmse.items())
            + f" (best colour-guided fill: {best})"), rmse


def _inert_flags(args, config, max_side: int, shape, full_shape, refine: bool) -> list[str]:
    """What each flag that acts on nothing in this combination would not do, said before the fit: the fit runs
    at ``shape`` (H, W) of the image's ``full_shape``; ``refine``: the fill is sharpened at full size; ``config``:
    the fit's, with the recipe's own solve already moved to full size or dropped."""
    from ..method.kit.recipes import get_recipe
    said = []
    if args.max_side is not None and args.max_side > max(full_shape):
        said.append(f"--max-side {args.max_side} acts on nothing: the image's longer side is {max(full_shape)} px, "
                    f"and the fit runs at the image's own size")
    if args.no_refine and args.raw:
        said.append("--no-refine acts on nothing: --raw implies it (the net's own output everywhere, nothing sharpened)")
    elif args.no_refine and tuple(shape) == tuple(full_shape):
        said.append(f"--no-refine acts on nothing: the fit runs at the image's own size ({shape[0]}×{shape[1]}, "
                    f"--max-side {max_side}), so there is no full-size sharpening to skip"
                    + (" (the recipe's own solve at that size still runs: --recipe kit for none)"
                       if config.combination.refine else ""))
    if getattr(args, "depth_source_given", True) and args.depth_source != "clean" and not (refine or config.combination.blend_fill != 0 or config.combination.refine):
        why = ("--raw writes the net's own output" if args.raw
               else f"--variant {args.variant} mixes in no colour-guided fill" if args.variant == "d"
               else f"recipe {get_recipe(args.recipe).name!r} mixes in no colour-guided fill")
        said.append(f"--depth-source {args.depth_source} acts on nothing: only the fill's share and the sharpening "
                    f"read it, and here there are neither ({why}"
                    + (", and --no-refine" if args.no_refine and not args.raw else "")
                    + (f"; the fit runs at the image's own size" if not args.raw and not args.no_refine else "")
                    + ")")
    return said


@dataclass(frozen=True)
class _SceneSource:
    """``--scene`` resolved before any work: the scene's copy and its holes (a kind or a file path)."""

    copy: SceneCopy
    holes: str


def _scene_source(args) -> _SceneSource | None:
    """Check which input the command was given (``--rgb``/``--depth``, or ``--scene``) and resolve the variant and
    the depth source; ``--scene`` resolved to a folder and its holes. Usage errors (ValueError) before any work."""
    scene = getattr(args, "scene", None)
    holes = getattr(args, "holes", None)
    args.depth_source_given = args.depth_source is not None  # --scene sets it too: only a typed one is said inert
    if scene is None:
        if holes is not None:
            raise ValueError("--holes needs --scene (it says how the input depth of a Middlebury scene is made); "
                             "with --rgb/--depth the holes are those of --depth")
        missing = [flag for flag, value in (("--rgb", args.rgb), ("--depth", args.depth)) if value is None]
        if missing:
            raise ValueError(f"give --rgb and --depth (your own RGB-D image; {' and '.join(missing)} missing), or "
                             f"--scene DIR|NAME (a Middlebury scene folder, or a scene such as Plastic)")
        if args.variant == "rgbd+warp":
            raise ValueError("--variant rgbd+warp needs --scene: the warp term needs calibrated neighbours, which "
                             "--rgb/--depth do not have (use rgbd or d)")
        args.variant = args.variant or "rgbd"
        args.depth_source = args.depth_source or "clean"
        return None
    given = [flag for flag, value in (("--rgb", args.rgb), ("--depth", args.depth), ("--gt", args.gt),
                                      ("--depth-scale", args.depth_scale), ("--intrinsics", args.intrinsics))
             if value is not None]
    if given:
        raise ValueError(f"--scene takes the photo, the truth and the camera from the scene; drop {', '.join(given)} "
                         f"(or drop --scene to complete your own files)")
    from ..data.scene_input import HOLE_KINDS  # with the readers of the scene (they load torch): only for --scene

    copy = resolve_scene(scene, what="--scene")
    if holes is None:
        default = depthcomp_hole_file(copy)
        holes = str(default) if default is not None else "sgbm"
    elif holes not in HOLE_KINDS:
        if not os.path.isfile(os.path.expanduser(holes)):
            raise ValueError(f"--holes must be {', '.join(HOLE_KINDS)} or a hole file (an image, 0 = hole), got "
                             f"{holes!r}: no such file")
        holes = os.path.expanduser(holes)
    args.variant = args.variant or "rgbd+warp"
    args.depth_source = args.depth_source or ("stereo" if holes == "sgbm" else "clean")
    return _SceneSource(copy, holes)


def complete_command(args) -> int:
    """``ddp-lite complete``: fill the holes of one depth map from its files, or of a Middlebury scene
    (``--scene``). Its outputs are written as one set under a lock taken before the fit
    (``ddp_lite.core.outpaths.output_set``)."""
    start = time.perf_counter()
    writers = _writers()
    source = _scene_source(args)
    _check_outputs(args, writers, source)
    outputs = [args.out, _preview_path(args)] + ([_ply_path(args)] if _ply_path(args) else [])
    with output_set(outputs, "--out", overwrite_readonly=args.force) as staged:
        return _complete(args, writers, staged, start, source)


def _complete(args, writers, staged, start, source=None) -> int:
    from ..method.config import FitConfig
    from ..method.complete import complete_depth
    from ..method.runtime.options import RunOptions, run_options
    from ..method.profiles import get_profile
    from ..core.progress import command_progress
    from ..method.time_left import earliest_share, expected_share
    from ..core.checks import check_depth, check_same_units
    from ..method.paper.nets import check_input_size
    from ..classical.full_resolution import full_size_solve, refine_full_resolution
    from ..method.kit.blend import rim_width
    from ..sequences.working_size import fill_holes_at_full_size, shrink, working_shape
    from ..method.kit.recipes import get_recipe
    from ..method.inert_settings import InertSettingWarning
    profile, recipe = get_profile(args.profile), get_recipe(args.recipe)  # --recipe, else DDP_RECIPE, else kit
    config = FitConfig.for_profile(profile, variant=args.variant, recipe=recipe, seed=args.seed,
                                   depth_source=args.depth_source,
                                   **({"iterations": args.iterations} if args.iterations else {}),
                                   **({"blend_fill": 0.0} if args.raw else {}))  # the net's alone: no fill's share
    config.validate()
    from ..core.views import View
    from ..data.resample import resize_view
    from ..data.scene_input import scene_input
    options = run_options(RunOptions(device=args.device, max_memory_gb=args.max_memory_gb))  # before the inputs are read
    scene = None
    if source is not None:
        shipped = source.copy.dataset == "shipped"
        print(data_line([] if shipped else [source.copy], f"the shipped quarter-size {source.copy.describe()}" if shipped
                        else "", SAMPLE_DATASETS.get(source.copy.name, ""), [source.copy.name],
                        f"no {source.copy.name} installed in the data root"), flush=True)
        scene = scene_input(source.copy.folder, source.holes, name=source.copy.name)
        rgb, depth, gt = scene.scene[0].rgb, scene.depth, scene.truth
        print(f"input depth: {scene.holes}; the scene's truth scores every fill; variant {args.variant}"
              + (f" (neighbours: {', '.join(v.name for v in scene.neighbors)})" if args.variant == "rgbd+warp" else ""),
              flush=True)
    else:
        rgb = _read_rgb(args.rgb)
        depth = _read_depth(args.depth, args.depth_scale)
        check_same_size(rgb.shape, depth.shape, args.rgb, "--rgb", "--depth")  # names an EXIF rotation if that is why
        gt = None
    if source is None and args.gt:
        gt = _read_depth(args.gt, args.depth_scale, "--gt")
        if gt.shape != depth.shape:
            raise ValueError(f"--gt is {gt.shape[0]}×{gt.shape[1]} but --depth is {depth.shape[0]}×{depth.shape[1]}")
        check_same_units(depth, gt, "--depth", "--gt")  # centimetres against metres would be scored as 100× errors
    camera = None
    if scene is not None:
        camera = scene.scene[0].camera
    elif args.intrinsics is not None:
        from ..core.camera import Camera, check_intrinsics
        K = check_intrinsics(args.intrinsics, depth.shape[1], depth.shape[0], "--intrinsics")  # K of another size bends the cloud
        camera = Camera(K, np.eye(4), depth.shape[1], depth.shape[0])
    holes = ~np.isfinite(depth)
    if not holes.any():
        raise ValueError(f"--depth {args.depth!r} has no holes (0, inf or NaN pixels): nothing to fill")  # a scene's input always has
    farthest = np.nanmax(depth, initial=0) * config.paper.disparity_margin
    if os.path.splitext(args.out)[1].lower() == ".png" and farthest > PNG_MAX_METRES:
        raise ValueError(f"--out: a 16-bit millimetre PNG holds at most {PNG_MAX_METRES} m, and this depth reaches "
                         f"{np.nanmax(depth):.1f} m; use .npy, .pfm or .exr")
    max_side = args.max_side or max(profile.size)
    shape = working_shape(depth.shape, max_side)
    small_rgb, small_depth = shrink(rgb, depth, shape)
    # what the fit will check, checked here with the flags' names: enough valid depth, a size the net can take
    what = f"--scene {args.scene!r}" if scene is not None else f"--depth {args.depth!r}"
    check_depth(small_depth, f"{what} (at the working size {shape[0]}×{shape[1]})")
    check_input_size(config.paper.net, config.paper.channels, shape[0], shape[1],
                     name=f"{what} (at the working size, --max-side {max_side})")
    small_camera, small_neighbors = None, ()
    if args.variant == "rgbd+warp":  # the scene's calibrated neighbours, resampled as the photo is
        small_camera = camera.resized(shape[1], shape[0])
        small_neighbors = [View(*resize_view(v.rgb, v.depth, v.camera, shape), v.name) for v in scene.neighbors]
    refine = not (args.raw or args.no_refine) and shape != depth.shape
    if refine or args.raw:  # the recipe's solve (photo) runs at the photo's full size instead: twice costs
        config = config.replace(refine=False)
    for line in _inert_flags(args, config, max_side, shape, depth.shape, refine):
        warnings.warn(line, InertSettingWarning)  # said before the fit
    if config.combination.blend_fill == 0 and not config.combination.refine:
        # nothing in the fit's own steps reads the source (the full-size solve is given it directly): the same
        # numbers, and the fit is not told of a setting it would call inert
        config = config.replace(depth_source="clean")
    print(f"{depth.shape[0]}×{depth.shape[1]} (H×W), {holes.mean():.1%} holes; fitting at "
          f"{shape[0]}×{shape[1]} (--max-side {max_side}), profile '{profile.name}', recipe '{recipe.name}'"
          + (f", then sharpened at {depth.shape[0]}×{depth.shape[1]} along the photo's edges (off: --no-refine)"
             if refine else ""), flush=True)
    classical = _classical_fills(depth, rgb, gt)
    planned = config.resolved_iterations(args.variant) * config.fit_count()  # every fit of the command
    with command_progress(planned, expected_share(config), earliest_share(config)):
        result = complete_depth(small_rgb, small_depth, small_camera, small_neighbors, variant=args.variant,
                                config=config, options=options)
    refine_seconds = None
    if refine:
        print(f"fit done in {result.seconds:.1f} s; sharpening the fill at {depth.shape[0]}×{depth.shape[1]} ...",
              flush=True)
        started = time.perf_counter()
        filled = refine_full_resolution(depth, rgb, fill_holes_at_full_size(depth, result.depth, raw=True),
                                        rim=rim_width(args.depth_source, scale=depth.shape[1] / shape[1], shape=shape),
                                        **full_size_solve(args.depth_source, depth.shape))  # a matcher's rim not read
        refine_seconds = time.perf_counter() - started
    else:
        filled = fill_holes_at_full_size(depth, result.depth, raw=args.raw)
    comparison, scores = _comparison(depth, filled, gt, classical)
    write_bytes_atomic(staged(args.out), writers[os.path.splitext(args.out)[1].lower()](filled))
    _write_preview(staged(_preview_path(args)), depth, filled,
                   f"{os.path.basename(args.out)}: DDP {args.variant} fitted at {shape[0]}×{shape[1]}"
                   + (f", sharpened at {depth.shape[0]}×{depth.shape[1]}" if refine else "") + ", "
                   + ("the net's output everywhere" if args.raw else "valid input kept"),
                   (gt, scores) if scores else None)
    if _ply_path(args):
        from ..evaluation.fusion import fuse_depths, save_ply
        save_ply(fuse_depths([filled], [camera], [rgb], min_views=0), staged(_ply_path(args)))  # one view: every pixel once
    print(comparison)
    if scene is not None:  # Middlebury's own unit: disparity px at the scene's size (doffs cancels in a difference)
        scored = ~np.isfinite(depth) & np.isfinite(gt)
        px = {name: float(np.sqrt(np.mean((scene.fb / f[scored] - scene.fb / gt[scored]) ** 2)))
              for name, f in {"DDP": filled, **classical}.items()}
        print("hole RMSE in disparity px at the scene's size: " + ", ".join(f"{n} {v:.3f}" for n, v in px.items()))
    share = result.history.get("blend_fill", 0.0)
    print(f"filled {holes.mean():.1%} holes in {time.perf_counter() - start:.1f} s (the fit {result.seconds:.1f} s"
          + (f", with a {share:.0%} share of a colour-guided fill" if share else "")
          + (f"; sharpening at full size {refine_seconds:.1f} s" if refine_seconds is not None else "") + ") "
          f"→ {args.out}; preview {_preview_path(args)}" + (f"; point cloud {_ply_path(args)}" if _ply_path(args) else ""))
    return 0
