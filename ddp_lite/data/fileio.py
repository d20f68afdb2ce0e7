"""Image and depth-map files ↔ arrays: PNG colour, 16-bit depth PNG, ``.npy``, PFM, COLMAP ``.bin``.

Conventions: colour comes back as float32 (H, W, 3) RGB in [0, 1] (8- or 16-bit files; grey is
repeated to 3 channels); depth as float32 (H, W) with 0, negative and non-finite values turned
into NaN (a file's "no value" marker becomes NaN here). Writers work on bytes (``*_bytes``) so a
caller writes them atomically (``atomic.write_bytes_atomic``); ``write_*`` do that themselves.
A missing file raises ``FileNotFoundError`` naming the argument it came from.

* **PFM** (Middlebury 2014 disparities): header ``PF`` (3 channels) or ``Pf`` (1 channel), then
  ``width height``, then a scale whose *sign* gives the byte order (negative = little-endian),
  each ending in one whitespace byte; float32 rows follow **bottom to top**.
* **16-bit depth PNG**: integer value = depth × factor (1000 for millimetres, 5000 for TUM), 0 = none.
* **COLMAP dense maps** (``stereo/depth_maps/NAME.geometric.bin``): an ASCII header
  ``width&height&channels&`` then float32 values, column by column; 0 = no depth.
"""
from __future__ import annotations

import io
import re
import warnings
from pathlib import Path

import cv2
import numpy as np

from ..core.files import regular_file, write_bytes_atomic

from .textparse import parse_error


def existing_path(path, name: str) -> Path:
    """``path`` as a Path if it exists; ``FileNotFoundError`` naming ``name`` otherwise."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{name}: {path} does not exist")
    return path


def read_text_file(path, name: str) -> str:
    """A small text file (calibration) → str; a clear error naming it if it is not UTF-8 text."""
    path = regular_file(path, name)
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"{name}: {path} is not a UTF-8 text file (byte {error.start}); is it the right file?") from None


_ORIENTATIONS = {2: "mirrored", 3: "rotated 180°", 4: "flipped", 5: "mirrored and rotated 90°", 6: "rotated 90°",
                 7: "mirrored and rotated 270°", 8: "rotated 270°"}


def exif_orientation(data: bytes) -> int | None:
    """The EXIF orientation tag (1–8) of an encoded image, or None when it carries none (or is unreadable)."""
    try:
        from PIL import Image  # matplotlib's dependency: always there

        with Image.open(io.BytesIO(data)) as image:
            value = image.getexif().get(0x0112)
    except Exception:  # noqa: BLE001: not an image PIL knows (PFM, EXR): it has no EXIF either
        return None
    return int(value) if isinstance(value, int) and 1 <= value <= 8 else None


def _jpeg_truncated(data: bytes) -> bool:
    """True for a JPEG whose entropy-coded data has no end marker (EOI): a cut-off file, which libjpeg
    decodes anyway (grey below the cut) with only a warning on stderr. The markers up to the first
    scan are walked, so an EXIF thumbnail's own EOI (inside APP1) does not count; bytes appended after
    the EOI (phones' "motion photos") are fine."""
    i = 2
    while i + 4 <= len(data) and data[i] == 0xFF:
        marker = data[i + 1]
        if marker == 0xDA:  # start of scan: the image data follows
            return data.find(b"\xff\xd9", i) < 0
        if marker == 0xFF:  # fill byte
            i += 1
            continue
        i += 2 + int.from_bytes(data[i + 2:i + 4], "big")
    return True  # no scan at all


def read_image_file(path, name: str = "path", flags: int = cv2.IMREAD_UNCHANGED) -> np.ndarray:
    """Any image file → the array OpenCV decodes (``flags``; BGR order), the pixels **as stored**.

    Every reader of the kit goes through here, so colour and depth are read the same way: a
    regular file only; a truncated JPEG refused; EXIF orientation never applied (depth maps carry
    none, and OpenCV's ``IMREAD_COLOR`` would rotate the colour alone, misregistering it against
    its depth), with a warning naming the file when it carries an orientation other than upright."""
    path = regular_file(path, name)
    data = path.read_bytes()
    if data[:2] == b"\xff\xd8" and _jpeg_truncated(data):
        raise ValueError(f"{name}: {path} is a truncated JPEG (its image data has no end marker); the part "
                         f"below the cut would be read as grey. Copy or export the file again")
    if not data:
        raise ValueError(f"{name}: {path} is empty (0 bytes); was it copied or downloaded completely?")
    try:
        image = cv2.imdecode(np.frombuffer(data, np.uint8), flags | cv2.IMREAD_IGNORE_ORIENTATION)
    except cv2.error as error:  # OpenCV raises for a codec it was built without or left off (EXR)
        hint = (" OpenCV reads .exr only with OPENCV_IO_ENABLE_OPENEXR=1 set before it is imported; or store "
                "the depth as .npy or .pfm" if data[:4] == b"\x76\x2f\x31\x01" else "")
        raise ValueError(f"{name}: {path}: OpenCV cannot decode it ({str(error).strip().splitlines()[-1]})."
                         f"{hint}") from None
    if image is None:
        raise ValueError(f"{name}: {path} is not an image OpenCV can read")
    orientation = exif_orientation(data)
    if orientation is not None and orientation != 1:
        warnings.warn(f"{name}: {path} carries EXIF orientation {orientation} ({_ORIENTATIONS[orientation]}); "
                      f"ddp-lite reads every image as stored, unrotated (as its depth readers do), so colour and "
                      f"depth stay registered. If your viewer shows it otherwise, rotate colour and depth alike "
                      f"before giving them to the kit", stacklevel=3)
    return image


def read_rgb(path, name: str = "path") -> np.ndarray:
    """An 8- or 16-bit image file → (H, W, 3) float32 RGB in [0, 1], pixels as stored (no EXIF rotation;
    see :func:`read_image_file`); grey is repeated to 3 channels, alpha dropped."""
    image = read_image_file(path, name)
    if image.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"{name}: {path} must be an 8- or 16-bit image, got {image.dtype}")
    scale = 255.0 if image.dtype == np.uint8 else 65535.0
    if image.ndim == 2:
        image = np.repeat(image[:, :, None], 3, axis=2)
    elif image.shape[2] == 1:
        image = np.repeat(image, 3, axis=2)
    else:
        image = cv2.cvtColor(image[:, :, :3], cv2.COLOR_BGR2RGB)
    return (image.astype(np.float32) / np.float32(scale))


def load_npy(path, name: str = "path") -> np.ndarray:
    """A ``.npy`` file → its array (no pickles); a corrupt or truncated file → ``ValueError`` naming it."""
    path = regular_file(path, name)
    try:
        return np.load(path, allow_pickle=False)
    except (ValueError, EOFError, OSError) as error:
        raise ValueError(f"{name}: {path} is not a readable .npy file ({error}); is it truncated or "
                         f"another kind of file?") from None


def rgb_png_bytes(rgb: np.ndarray) -> bytes:
    """(H, W, 3) float image in [0, 1] → 8-bit PNG bytes."""
    bgr = cv2.cvtColor(np.clip(rgb * 255.0 + 0.5, 0, 255).astype(np.uint8), cv2.COLOR_RGB2BGR)
    ok, buffer = cv2.imencode(".png", bgr)
    if not ok:
        raise RuntimeError("OpenCV could not encode a PNG")
    return buffer.tobytes()


def _pfm_header(data: bytes, path) -> tuple[int, int, int, float, int]:
    """(channels, width, height, scale, data offset) of a PFM: three header lines (``\n`` or
    ``\r\n`` line ends; ``#`` comment lines skipped), or the same tokens on fewer lines."""
    tokens, offset = [], 0
    while len(tokens) < 4:
        end = data.find(b"\n", offset, offset + 256)
        if end < 0:
            raise ValueError(f"path: {path} is not a PFM file (expected 'PF' or 'Pf', width, height, scale)")
        line, offset = data[offset:end].strip(), end + 1
        if not line.startswith(b"#"):
            tokens += line.split()
    kind, width, height, scale = tokens[:4] if len(tokens) == 4 else (None,) * 4
    if kind not in (b"PF", b"Pf") or not (width.isdigit() and height.isdigit()):
        raise ValueError(f"path: {path} is not a PFM file (expected 'PF' or 'Pf', width, height, scale)")
    try:
        scale = float(scale)
    except ValueError:
        raise ValueError(f"path: {path} has a PFM scale that is not a number: {scale!r}") from None
    if int(width) == 0 or int(height) == 0 or scale == 0.0 or not np.isfinite(scale):
        raise ValueError(f"path: {path} has an empty size or a zero or non-finite scale in its PFM header")
    return 3 if kind == b"PF" else 1, int(width), int(height), scale, offset


def read_pfm(path) -> np.ndarray:
    """A PFM file → float32 (H, W) or (H, W, 3), top row first, native byte order (either file endianness)."""
    data = regular_file(path, "path").read_bytes()
    channels, width, height, scale, offset = _pfm_header(data, path)
    count = width * height * channels
    if len(data) - offset < 4 * count:
        raise ValueError(f"path: {path} is truncated: {len(data) - offset} data bytes, expected {4 * count}")
    array = np.frombuffer(data, dtype="<f4" if scale < 0 else ">f4", count=count, offset=offset)
    shape = (height, width, 3) if channels == 3 else (height, width)
    return np.flipud(array.reshape(shape)).astype(np.float32)


def write_pfm(path, array) -> None:
    """Write (H, W), (H, W, 1) or (H, W, 3) real values as a little-endian float32 PFM, atomically."""
    values = np.asarray(array)
    if values.dtype == bool or not (np.issubdtype(values.dtype, np.integer) or np.issubdtype(values.dtype, np.floating)):
        raise ValueError(f"array must hold real numbers, got dtype {values.dtype}")
    if values.ndim == 3 and values.shape[2] == 1:
        values = values[:, :, 0]
    if not (values.ndim == 2 or (values.ndim == 3 and values.shape[2] == 3)) or min(values.shape[:2]) == 0:
        raise ValueError(f"array must be (H, W), (H, W, 1) or (H, W, 3), got shape {np.shape(array)}")
    write_bytes_atomic(path, pfm_bytes(values))


def npy_bytes(values) -> bytes:
    """Any array → the bytes of a ``.npy`` file (``np.load`` reads them back)."""
    buffer = io.BytesIO()
    np.save(buffer, values)
    return buffer.getvalue()


def depth_png_bytes(depth, factor: float = 1000.0) -> tuple[bytes, int]:
    """(H, W) depth × ``factor`` (1000: millimetres) → (16-bit PNG bytes, how many pixels did not fit).
    NaN becomes 0 (the usual depth-PNG "no value"); values beyond 65535 are written as 0 too."""
    scaled = np.round(np.nan_to_num(np.asarray(depth, np.float64), nan=0.0) * factor)
    overflow = scaled > 65535
    ok, buffer = cv2.imencode(".png", np.where(overflow, 0, scaled).astype(np.uint16))
    if not ok:
        raise RuntimeError("OpenCV could not encode a 16-bit PNG")
    return buffer.tobytes(), int(overflow.sum())


def pfm_bytes(values) -> bytes:
    """(H, W) or (H, W, 3) real values → the bytes of a little-endian float32 PFM file."""
    height, width = values.shape[:2]
    header = f"{'PF' if values.ndim == 3 else 'Pf'}\n{width} {height}\n-1.0\n".encode("ascii")
    return header + np.ascontiguousarray(np.flipud(values).astype("<f4")).tobytes()  # a copy: the input is untouched


def read_depth_image(path, scale: float = 0.001) -> np.ndarray:
    """A 16-bit depth PNG or a ``.npy`` (millimetres by default) → (H, W) float32 metres = value·scale;
    0 and non-finite → NaN."""
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f"scale must be a positive number (metres per unit), got {scale!r}")
    path = regular_file(path, "path")
    if path.suffix.lower() == ".npy":
        raw = load_npy(path, "path")
    else:
        raw = read_image_file(path, "path")
        if raw.dtype != np.uint16:
            raise ValueError(f"path: {path} must be a 16-bit depth PNG or a .npy")
    if raw.ndim != 2:
        raise ValueError(f"path: {path} must hold an (H, W) depth map, got shape {raw.shape}")
    depth = raw.astype(np.float64) * float(scale)
    return np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float32)


def read_colmap_depth(path) -> np.ndarray:
    """A COLMAP dense depth map (``*.geometric.bin`` / ``*.photometric.bin``) → (H, W) float32, as stored (0 = none).

    The file: ASCII ``width&height&channels&``, then width·height·channels little-endian float32
    values in column-major order (x fastest is *not* the order: the first column comes first)."""
    data = regular_file(path, "path").read_bytes()
    header = re.match(rb"(\d+)&(\d+)&(\d+)&", data[:64])
    if header is None:
        raise parse_error(path, 1, "not a COLMAP dense map: expected the header 'width&height&channels&'")
    width, height, channels = (int(v) for v in header.groups())
    count = width * height * channels
    if channels != 1 or count == 0:
        raise parse_error(path, 1, f"a depth map has 1 channel and a positive size, got {width}&{height}&{channels}&")
    body = data[header.end():]
    if len(body) != 4 * count:
        raise parse_error(path, None, f"holds {len(body)} data bytes, expected {4 * count} for {width}×{height}")
    return np.frombuffer(body, dtype="<f4").reshape(width, height).T.astype(np.float32)


def colmap_depth_bytes(depth) -> bytes:
    """(H, W) depth → the bytes of a COLMAP dense ``.bin`` map (NaN stored as 0, COLMAP's 'no depth')."""
    values = np.nan_to_num(np.asarray(depth, np.float32), nan=0.0)
    H, W = values.shape
    return f"{W}&{H}&1&".encode("ascii") + np.ascontiguousarray(values.T).astype("<f4").tobytes()


def write_colmap_depth(path, depth) -> None:
    """Write (H, W) depth as a COLMAP dense ``.bin`` map, atomically."""
    write_bytes_atomic(path, colmap_depth_bytes(depth))


def checked_depth_png_bytes(depth: np.ndarray, factor: float, path_for_errors) -> bytes:
    """(H, W) depth × ``factor`` → 16-bit PNG bytes, NaN → 0; refuse values the format cannot hold."""
    png, overflow = depth_png_bytes(depth, factor)
    if overflow:
        raise ValueError(f"{path_for_errors}: depth up to {np.nanmax(depth):.3f} does not fit a 16-bit PNG at "
                         f"{factor:g} units per metre (max {65535 / factor:.3f}); use .npy, .pfm or .bin")
    return png


def read_depth_file(path: Path, scale: float | None) -> np.ndarray:
    """A depth map file → (H, W) float32 × ``scale``; 0, negative and non-finite → NaN.

    ``.bin`` (COLMAP dense), ``.npy``, ``.pfm`` store floats (scale defaults to 1); 16-bit ``.png``
    stores integers and needs ``scale`` (metres per unit: 0.001 for millimetres, 1/5000 for TUM)."""
    path = regular_file(path, "path")
    suffix = path.suffix.lower()
    if suffix == ".bin":
        raw = read_colmap_depth(path)
    elif suffix == ".npy":
        raw = load_npy(path, "path")
    elif suffix == ".pfm":
        raw = read_pfm(path)
    elif suffix == ".png":
        raw = read_image_file(path, "path")
        if raw.dtype != np.uint16 or raw.ndim != 2:
            raise ValueError(f"{path}: a depth PNG must be 1-channel 16-bit, got {raw.dtype} {raw.shape}"
                             + (" (an 8-bit picture, e.g. a visualisation, is not depth)" if raw.dtype == np.uint8
                                else ""))
        if scale is None:
            raise ValueError(f"{path} stores integers; give depth_scale (CLI: --depth-scale), the metres per stored "
                             f"unit (0.001 for millimetres)")
    else:
        raise ValueError(f"{path}: depth maps must be .bin (COLMAP), .png (16-bit), .npy or .pfm")
    if raw.ndim != 2 or not np.issubdtype(raw.dtype, np.number):
        raise ValueError(f"{path} must hold one (H, W) map of numbers, got {raw.dtype} {raw.shape}")
    depth = raw.astype(np.float64) * (1.0 if scale is None else float(scale))
    return np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float32)
