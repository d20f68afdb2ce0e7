"""``ddp-lite complete``: fill the holes of your own RGB-D image, with every check before the fit.

Input: ``--rgb`` any image OpenCV reads; ``--depth`` ``.npy``/``.pfm`` (metres, or × ``--depth-scale``)
or an integer image (needs ``--depth-scale``, metres per stored unit); 0, ≤ 0, inf and NaN are
holes (NaN). A depth range no camera produces at that scale (kilometres from a millimetre PNG
read as metres) is refused with the scale that would make it plausible.

The fit runs at a working size (``--max-side``, default the profile's longer side) and its
completed depth is brought back to full size in disparity, in the holes only: the valid input
pixels keep their exact values (``--raw``: the net's own output everywhere, without the share of a
colour-guided fill the ``kit`` recipe mixes in), see
``ddp_lite.sequences.working_size``. Then one line compares the fill with a classical one computed here at
full size (linear interpolation; their mean absolute difference in the holes), or, with ``--gt``,
prints the hole RMSE of DDP, linear and Navier-Stokes fills; and a preview figure (input, filled,
holes) is written beside ``--out``.

Output by the suffix of ``--out``: ``.npy``/``.pfm`` float32 metres, ``.png`` 16-bit
millimetres (0 = none, at most ``PNG_MAX_METRES``), ``.exr`` if OpenCV has the codec. Every file
is written atomically, and every path and input is checked before the fit (``ValueError`` naming
the flag).
"""
from __future__ import annotations

import os
import time

import cv2
import numpy as np

from ..core.files import regular_file, write_bytes_atomic
from ..data.fileio import depth_png_bytes, npy_bytes, pfm_bytes, read_image_file, read_pfm, read_rgb
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
    if args.intrinsics is None:
        if args.ply:
            raise ValueError("--ply needs --intrinsics fx,fy,cx,cy (the camera that turns depth into points)")
        return None
    if isinstance(args.intrinsics, str):
        raise ValueError(f"--intrinsics must be fx,fy,cx,cy in pixels, got {args.intrinsics!r}")
    return args.ply if args.ply else os.path.splitext(args.out)[0] + ".ply"


def _check_outputs(args, writers: dict) -> None:
    """Refuse a bad --out, --preview or --ply before any work: unknown suffix, a folder, an input, a
    read-only file, an unwritable folder."""
    from .cli_demo import figure_suffixes
    inputs = {"--depth": args.depth, "--rgb": args.rgb, **({"--gt": args.gt} if args.gt else {})}
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
    """``path`` as float32 metres, NaN where the file has no value (0, ≤ 0, inf, NaN); a scale that
    gives an implausible depth range is refused (:func:`check_plausible_depth`)."""
    _input_file(path, flag)
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".npy":
        try:
            raw = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as error:
            raise ValueError(f"{flag}: cannot read {path!r} as a .npy array ({error})") from None
    elif suffix == ".pfm":
        raw = read_pfm(path)
    else:
        raw = read_image_file(path, flag)  # as stored: no EXIF rotation, like the colour below
    if raw.ndim != 2 or raw.dtype == bool or not (np.issubdtype(raw.dtype, np.integer) or np.issubdtype(raw.dtype, np.floating)):
        raise ValueError(f"{flag}: {path!r} must hold one channel of numbers (H, W), got {raw.dtype} {raw.shape}")
    if scale is None:
        if np.issubdtype(raw.dtype, np.integer):
            raise ValueError(f"{flag}: {path!r} stores integers ({raw.dtype}); give --depth-scale, the metres per "
                             f"stored unit (0.001 for millimetres, as in most 16-bit depth PNGs)")
        scale = 1.0
    stored = raw.astype(np.float64)
    depth = stored * scale
    valid = np.isfinite(depth) & (depth > 0)
    if (np.isfinite(stored) & (stored > 0)).any() and not valid.any():
        raise ValueError(f"--depth-scale {scale!r} turns every depth into 0")
    if valid.any():
        check_plausible_depth(stored[valid], scale, flag)
    return np.where(valid, depth, np.nan).astype(np.float32)


DEPTH_RANGE_M = (1e-3, 1e4)  # no depth outside it, whatever the scene
MEDIAN_RANGE_M = (0.05, 300.0)  # a depth map's median: a cup from 5 cm up to a street scene's far side
COMMON_SCALES = (1.0, 1e-3, 1.0 / 5000, 1e-4, 1e-2)  # metres, mm, TUM's 1/5000 m, 0.1 mm, cm


def check_plausible_depth(stored, scale: float, flag: str = "--depth") -> None:
    """Refuse a scale under which the valid ``stored`` values (> 0, finite) are no plausible depth
    map in metres: any depth outside ``DEPTH_RANGE_M``, or a median outside ``MEDIAN_RANGE_M``.
    The message names the common scale (``COMMON_SCALES``) that would make it plausible, if any."""
    stored = np.asarray(stored, dtype=np.float64)
    low, high, median = (float(v) * scale for v in (stored.min(), stored.max(), np.median(stored)))

    def plausible(lo, hi, mid):
        return DEPTH_RANGE_M[0] <= lo and hi <= DEPTH_RANGE_M[1] and MEDIAN_RANGE_M[0] <= mid <= MEDIAN_RANGE_M[1]
    if plausible(low, high, median):
        return
    fits = [c for c in COMMON_SCALES if plausible(low / scale * c, high / scale * c, median / scale * c)]
    better = min(fits, key=lambda c: abs(np.log(median / scale * c / 3.0)), default=None)
    hint = (f"; --depth-scale {better:g} would give {low / scale * better:.3g}–{high / scale * better:.3g} m "
            f"(median {median / scale * better:.3g} m)" if better is not None else "")
    raise ValueError(f"--depth-scale {scale:g}: {flag} would range {low:.3g}–{high:.3g} m (median {median:.3g} m), "
                     f"not a plausible depth map in metres (depths within {DEPTH_RANGE_M[0]:g}–{DEPTH_RANGE_M[1]:g} m, "
                     f"median within {MEDIAN_RANGE_M[0]:g}–{MEDIAN_RANGE_M[1]:g} m){hint}. --depth-scale is the "
                     f"metres per stored unit")


def _input_file(path: str, flag: str) -> None:
    """Refuse an input that is missing, a folder, or not a regular file (a FIFO would block the read),
    as a usage error (``ValueError``) naming ``flag``."""
    if not os.path.exists(path):
        raise ValueError(f"{flag}: no such file {path!r}")
    try:
        regular_file(path, flag)
    except IsADirectoryError as error:
        raise ValueError(str(error)) from None


def _read_rgb(path: str) -> np.ndarray:
    _input_file(path, "--rgb")
    return read_rgb(path, "--rgb")  # pixels as stored, the same way as the depth: a phone's EXIF rotation is not applied


def _write_preview(path: str, depth: np.ndarray, filled: np.ndarray, summary: str) -> None:
    """Input (holes coloured), filled depth, and the holes: one figure, same colour scale, atomically."""
    from matplotlib.figure import Figure

    from ..evaluation.viz import save_figure, show_depth
    holes = ~np.isfinite(depth)
    vmin, vmax = float(np.nanpercentile(filled, 1)), float(np.nanpercentile(filled, 99))
    H, W = depth.shape
    fig = Figure(figsize=(15, 15 * H / W / 3 + 1.2))
    axes = fig.subplots(1, 3)
    show_depth(axes[0], depth, f"input ({holes.mean():.1%} holes)", vmin, vmax)
    show_depth(axes[1], filled, "filled", vmin, vmax)
    shown = axes[2].imshow(holes, cmap="gray_r", vmin=0, vmax=1, interpolation="nearest")
    bar = fig.colorbar(shown, ax=axes[2], fraction=0.046, pad=0.04, ticks=[0.25, 0.75])  # same panel size as the others
    bar.ax.set_yticklabels(["valid", "hole"])
    axes[2].set_title("holes")
    axes[2].axis("off")
    fig.suptitle(summary, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)


def _comparison(depth, rgb, filled, gt) -> str:
    """The line that puts DDP's fill beside classical ones at full size."""
    from ..classical.baselines import fill_linear, fill_navier_stokes
    holes = ~np.isfinite(depth)
    linear = fill_linear(depth)
    if gt is None:
        difference = float(np.mean(np.abs(filled[holes] - linear[holes])))
        return (f"holes at full size: DDP vs a linear fill (computed here) differ by {difference:.3g} m on average "
                f"(mean |difference| over {holes.sum()} hole pixels; their error is unknown without --gt)")
    scored = holes & np.isfinite(gt)
    if not scored.any():
        raise ValueError("--gt has no valid value in the holes of --depth; nothing to score")
    fills = {"DDP": filled, "linear": linear, "navier-stokes": fill_navier_stokes(depth)}
    rmse = {name: float(np.sqrt(np.mean((f[scored] - gt[scored]) ** 2))) for name, f in fills.items()}
    return (f"hole RMSE at full size ({scored.sum()} pixels with ground truth): "
            + ", ".join(f"{name} {value:.4g} m" for name, value in rmse.items()))


def complete_command(args) -> int:
    """``ddp-lite complete``: fill the holes of one depth map from its files. Its outputs are written
    as one set under a lock taken before the fit (``ddp_lite.core.outpaths.output_set``)."""
    start = time.perf_counter()
    writers = _writers()
    _check_outputs(args, writers)
    outputs = [args.out, _preview_path(args)] + ([_ply_path(args)] if args.intrinsics is not None else [])
    with output_set(outputs, "--out", overwrite_readonly=args.force) as staged:
        return _complete(args, writers, staged, start)


def _complete(args, writers, staged, start) -> int:
    from ..method.config import FitConfig
    from ..method.fit import complete_depth
    from ..method.profiles import get_profile
    from ..core.progress import command_progress
    from ..sequences.working_size import fill_holes_at_full_size, shrink, working_shape
    profile = get_profile(args.profile)
    config = FitConfig.for_profile(profile, variant=args.variant, recipe=args.recipe, device=args.device,
                                   seed=args.seed, max_memory_gb=args.max_memory_gb,
                                   **({"iterations": args.iterations} if args.iterations else {}),
                                   **({"blend_fill": 0.0} if args.raw else {}))  # the net's alone: no fill's share
    config.validate()  # --device, before the inputs are read
    rgb = _read_rgb(args.rgb)
    depth = _read_depth(args.depth, args.depth_scale)
    if rgb.shape[:2] != depth.shape:
        raise ValueError(f"--rgb is {rgb.shape[0]}×{rgb.shape[1]} (H×W) but --depth is "
                         f"{depth.shape[0]}×{depth.shape[1]}; they must be the same size")
    gt = None
    if args.gt:
        gt = _read_depth(args.gt, args.depth_scale, "--gt")
        if gt.shape != depth.shape:
            raise ValueError(f"--gt is {gt.shape[0]}×{gt.shape[1]} but --depth is {depth.shape[0]}×{depth.shape[1]}")
    camera = None
    if args.intrinsics is not None:
        from ..core.camera import Camera
        from ..method.fit_inputs import check_principal_point
        camera = Camera(np.array(args.intrinsics, dtype=np.float64), np.eye(4), depth.shape[1], depth.shape[0])
        check_principal_point(camera, "--intrinsics")  # K of another image size would bend the point cloud
    holes = ~np.isfinite(depth)
    if not holes.any():
        raise ValueError(f"--depth {args.depth!r} has no holes (0, inf or NaN pixels): nothing to fill")
    if os.path.splitext(args.out)[1].lower() == ".png" and np.nanmax(depth, initial=0) * config.disparity_margin > PNG_MAX_METRES:
        raise ValueError(f"--out: a 16-bit millimetre PNG holds at most {PNG_MAX_METRES} m, and this depth reaches "
                         f"{np.nanmax(depth):.1f} m; use .npy, .pfm or .exr")
    max_side = args.max_side or max(profile.size)
    shape = working_shape(depth.shape, max_side)
    small_rgb, small_depth = shrink(rgb, depth, shape)
    print(f"{depth.shape[0]}×{depth.shape[1]} (H×W), {holes.mean():.1%} holes; fitting at "
          f"{shape[0]}×{shape[1]} (--max-side {max_side}), profile '{profile.name}'", flush=True)
    with command_progress(config.resolved_iterations(args.variant) * config.fit_count()):  # every fit of the command
        result = complete_depth(small_rgb, small_depth, variant=args.variant, config=config)
    filled = fill_holes_at_full_size(depth, result.depth, raw=args.raw)
    comparison = _comparison(depth, rgb, filled, gt)
    write_bytes_atomic(staged(args.out), writers[os.path.splitext(args.out)[1].lower()](filled))
    _write_preview(staged(_preview_path(args)), depth, filled,
                   f"{os.path.basename(args.out)}: DDP {args.variant} fitted at {shape[0]}×{shape[1]}, "
                   + ("the net's output everywhere" if args.raw else "valid input kept"))
    if camera is not None:
        from ..evaluation.fusion import fuse_depths, save_ply
        save_ply(fuse_depths([filled], [camera], [rgb], min_views=0), staged(_ply_path(args)))  # one view: every pixel once
    print(comparison)
    share = result.history.get("blend_fill", 0.0)
    print(f"filled {holes.mean():.1%} holes in {time.perf_counter() - start:.1f} s (the fit {result.seconds:.1f} s"
          + (f", with a {share:.0%} share of a colour-guided fill" if share else "") + ") "
          f"→ {args.out}; preview {_preview_path(args)}" + (f"; point cloud {_ply_path(args)}" if camera else ""))
    return 0
