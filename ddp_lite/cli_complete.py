"""``ddp-lite complete``: fill the holes of your own RGB-D image, with every check before the fit.

Input: ``--rgb`` any image OpenCV reads; ``--depth`` ``.npy``/``.pfm`` (metres, or × ``--depth-scale``)
or an integer image (needs ``--depth-scale``, metres per stored unit); 0, ≤ 0, inf and NaN are
holes (NaN). Output by the suffix of ``--out``: ``.npy``/``.pfm`` float32 metres, ``.png`` 16-bit
millimetres (0 = none, at most ``PNG_MAX_METRES``), ``.exr`` if OpenCV has the codec; written
atomically. A bad ``--out`` or input raises ``ValueError`` naming the flag before any fit starts.
"""
from __future__ import annotations

import os
import tempfile

import cv2
import numpy as np

from .atomic import write_bytes_atomic
from .fileio import depth_png_bytes, npy_bytes, pfm_bytes, read_pfm
from .fit import FitConfig, complete_depth


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
