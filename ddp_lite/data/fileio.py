"""Image and depth-map files → arrays: PNG colour, 16-bit depth PNG, ``.npy``, PFM, COLMAP ``.bin``
(arrays → files: :mod:`ddp_lite.data.file_writers`).

Conventions: colour comes back as float32 (H, W, 3) RGB in [0, 1] (8- or 16-bit files; grey is
repeated to 3 channels), pixels as stored (``read_image_file``); depth through one reader,
``read_depth``, as float32 (H, W) with 0 and non-finite values turned into NaN (a file's "no value"
marker becomes NaN here; one negative marker value too, with a warning; varied negative values are
refused), 8-bit files and lossy formats (a JPEG, whatever its name) refused and sentinels (65535) warned.
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

from ..core.files import read_text, regular_file
from .textparse import parse_error


def existing_path(path, name: str) -> Path:
    """``path`` as a Path if it exists; ``FileNotFoundError`` naming ``name`` otherwise."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{name}: {path} does not exist")
    return path


def read_text_file(path, name: str) -> str:
    """A small text file (calibration) → str, normalised as every text file the kit reads (``files.read_text``:
    a byte-order mark dropped, CRLF → LF); a clear error naming it if it is not text."""
    return read_text(path, name)


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


MAX_IMAGE_PIXELS = 200_000_000  # 200 MP: above any camera the kit reads; a 16-bit RGBA image this size is 1.6 GB


def header_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) a PNG or JPEG header declares (None for another format, or none found): read
    before decoding, so a file whose header claims a huge image is refused before memory is spent on it."""
    if data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) >= 24 and data[12:16] == b"IHDR":
        return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    if data[:2] == b"\xff\xd8":
        at = 2
        while at + 9 < len(data):
            if data[at] != 0xFF:
                return None
            marker = data[at + 1]
            if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:
                at += 2
                continue
            length = int.from_bytes(data[at + 2:at + 4], "big")
            if 0xC0 <= marker <= 0xCF and marker not in (0xC4, 0xC8, 0xCC):  # a start of frame
                return int.from_bytes(data[at + 7:at + 9], "big"), int.from_bytes(data[at + 5:at + 7], "big")
            at += 2 + length
    return None


def check_pixel_limit(data: bytes, path, name: str) -> None:
    """Refuse (ValueError naming ``name``) an image whose header declares more than
    :data:`MAX_IMAGE_PIXELS` pixels: a decompression bomb, refused by its header."""
    size = header_size(data)
    if size is not None and size[0] * size[1] > MAX_IMAGE_PIXELS:
        raise ValueError(f"{name}: {path} declares a {size[0]}×{size[1]} image ({size[0] * size[1] / 1e6:.0f} MP), "
                         f"more than the {MAX_IMAGE_PIXELS / 1e6:.0f} MP the kit reads; refused before decoding "
                         f"(a damaged or hostile file; resize it first if it is real)")


# What a file is, by its first bytes (its name may say otherwise): signature → format
_SIGNATURES = ((b"\x89PNG\r\n\x1a\n", "PNG"), (b"\xff\xd8\xff", "JPEG"), (b"II*\x00", "TIFF"), (b"MM\x00*", "TIFF"),
               (b"\x76\x2f\x31\x01", "OpenEXR"), (b"BM", "BMP"), (b"GIF8", "GIF"), (b"\x00\x00\x00\x0cjP  ", "JPEG 2000"),
               (b"\xff\x4f\xff\x51", "JPEG 2000"), (b"P5", "PGM"), (b"P2", "PGM"), (b"P6", "PPM"), (b"P3", "PPM"))
_SUFFIX_FORMATS = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG", ".tif": "TIFF", ".tiff": "TIFF", ".exr": "OpenEXR",
                   ".bmp": "BMP", ".gif": "GIF", ".webp": "WebP", ".jp2": "JPEG 2000", ".pgm": "PGM", ".ppm": "PPM"}


def image_format(data: bytes) -> str | None:
    """The format an encoded image really is, by its first bytes ('PNG', 'JPEG', 'TIFF', 'WebP', ...; 'WebP
    (lossy)' for a lossy WebP), whatever its name says; None when no known signature fits."""
    if data[:4] == b"RIFF" and data[8:12] == b"WEBP":
        return "WebP" if data[12:16] == b"VP8L" else "WebP (lossy)"
    return next((kind for signature, kind in _SIGNATURES if data.startswith(signature)), None)


LOSSY_FORMATS = ("JPEG", "WebP (lossy)", "JPEG 2000")  # JPEG 2000 may be either: no truth is kept in it


def check_image_format(data: bytes, path, name: str, truth: bool) -> None:
    """The file's real format (:func:`image_format`) against its name and its use. ``truth`` (a depth map, a
    ground-truth disparity, a mask): a lossy format is refused, whatever the file is called (its values were
    changed by the compression: they are no measurement); a colour image: a name that says another format
    than the content is warned about (a ``.png`` that is really a JPEG has lost detail to compression)."""
    real = image_format(data)
    claimed = _SUFFIX_FORMATS.get(Path(path).suffix.lower())
    mismatch = claimed is not None and real is not None and not real.startswith(claimed)
    named = f" (named {Path(path).suffix} but its content is {real})" if mismatch else ""
    if truth and real in LOSSY_FORMATS:
        raise ValueError(f"{name}: {path} is a {real} file{named}: lossy compression changed its values, so it "
                         f"holds no depth or ground truth to trust. Give the lossless file it came from (PNG, "
                         f"TIFF, .pfm, .npy)")
    if mismatch:
        warnings.warn(f"{name}: {path} is a {real} file, not the {claimed} its name says; read as the {real} it is"
                      + (" (lossy: its values carry compression artefacts)" if real in LOSSY_FORMATS else ""),
                      stacklevel=4)


def read_image_file(path, name: str = "path", flags: int = cv2.IMREAD_UNCHANGED, truth: bool = False) -> np.ndarray:
    """Any image file → the array OpenCV decodes (``flags``; BGR order), the pixels **as stored**.

    Every reader of the kit goes through here, so colour and depth are read the same way: a
    regular file only; a truncated JPEG refused; EXIF orientation never applied (depth maps carry
    none, and OpenCV's ``IMREAD_COLOR`` would rotate the colour alone, misregistering it against
    its depth), with a warning naming the file when it carries an orientation other than upright.
    The format is the content's, not the name's (:func:`check_image_format`): ``truth=True`` for a
    depth map, ground truth or mask, where a lossy file (a JPEG, whatever it is called) is refused."""
    path = regular_file(path, name)
    data = path.read_bytes()
    check_image_format(data, path, name, truth)
    if data[:2] == b"\xff\xd8" and _jpeg_truncated(data):
        raise ValueError(f"{name}: {path} is a truncated JPEG (its image data has no end marker); the part "
                         f"below the cut would be read as grey. Copy or export the file again")
    if not data:
        raise ValueError(f"{name}: {path} is empty (0 bytes); was it copied or downloaded completely?")
    check_pixel_limit(data, path, name)  # the header's size, before any pixel is decoded
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


def check_same_size(rgb_shape, other_shape, rgb_path, rgb_name: str, other_name: str) -> None:
    """Refuse colour and depth (or a camera) of different sizes: ``rgb_shape`` / ``other_shape`` are (H, W, ...)
    shapes, ``rgb_name`` / ``other_name`` what the message calls them (the flag or file). When the colour file
    carries an EXIF orientation that swaps its axes and its rotated size is the other's, the message says
    so: the kit reads every image as stored (:func:`read_image_file`), so colour and depth must be stored alike."""
    H, W = rgb_shape[:2]
    h, w = other_shape[:2]
    if (H, W) == (h, w):
        return
    hint = ""
    if rgb_path is not None and (H, W) == (w, h):
        try:
            orientation = exif_orientation(Path(rgb_path).read_bytes())
        except OSError:
            orientation = None
        if orientation in (5, 6, 7, 8):
            hint = (f". {rgb_name} carries EXIF orientation {orientation} ({_ORIENTATIONS[orientation]}): a viewer shows "
                    f"it {W}×{H} (H×W), ddp-lite reads its pixels as stored ({H}×{W}), as it reads depth. Store colour "
                    f"and depth the same way up (e.g. PIL.ImageOps.exif_transpose on the colour, if the depth was "
                    f"saved upright)")
    raise ValueError(f"{rgb_name} is {H}×{W} (H×W) but {other_name} is {h}×{w}; they must be the same size, pixel "
                     f"for pixel{hint}")


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


def _pfm_header(data: bytes, path, name: str = "path") -> tuple[int, int, int, float, int]:
    """(channels, width, height, scale, data offset) of a PFM: three header lines (``\n`` or
    ``\r\n`` line ends; ``#`` comment lines skipped), or the same tokens on fewer lines."""
    tokens, offset = [], 0
    while len(tokens) < 4:
        end = data.find(b"\n", offset, offset + 256)
        if end < 0:
            raise ValueError(f"{name}: {path} is not a PFM file (expected 'PF' or 'Pf', width, height, scale)")
        line, offset = data[offset:end].strip(), end + 1
        if not line.startswith(b"#"):
            tokens += line.split()
    kind, width, height, scale = tokens[:4] if len(tokens) == 4 else (None,) * 4
    if kind not in (b"PF", b"Pf") or not (width.isdigit() and height.isdigit()):
        raise ValueError(f"{name}: {path} is not a PFM file (expected 'PF' or 'Pf', width, height, scale)")
    try:
        scale = float(scale)
    except ValueError:
        raise ValueError(f"{name}: {path} has a PFM scale that is not a number: {scale!r}") from None
    if int(width) == 0 or int(height) == 0 or scale == 0.0 or not np.isfinite(scale):
        raise ValueError(f"{name}: {path} has an empty size or a zero or non-finite scale in its PFM header")
    return 3 if kind == b"PF" else 1, int(width), int(height), scale, offset


def _garbled(values: np.ndarray) -> float:
    """The share of ``values`` that no depth or disparity map holds: NaN, or a magnitude below 1e-10 or beyond
    1e10 (0 and ±inf, a PFM's 'unknown' markers, count as fine). Float bytes read in the wrong order have
    random exponents: about three quarters of them land there."""
    if not values.size:
        return 0.0
    with np.errstate(invalid="ignore", over="ignore"):
        size = np.abs(values.astype(np.float64))
        bad = np.isnan(size) | (np.isfinite(size) & ((size > 1e10) | ((size > 0) & (size < 1e-10))))
    return float(bad.mean())


def read_pfm(path, name: str = "path") -> np.ndarray:
    """A PFM file → float32 (H, W) or (H, W, 3), top row first, native byte order (either file endianness);
    errors name ``name`` (the argument the path came from)."""
    data = regular_file(path, name).read_bytes()
    channels, width, height, scale, offset = _pfm_header(data, path, name)
    count = width * height * channels
    if len(data) - offset < 4 * count:
        raise ValueError(f"{name}: {path} is truncated: {len(data) - offset} data bytes, expected {4 * count}")
    order = "<f4" if scale < 0 else ">f4"  # the scale's sign is the byte order: negative = little-endian
    array = np.frombuffer(data, dtype=order, count=count, offset=offset)
    if _garbled(array) > 0.5 and _garbled(array.view(array.dtype.newbyteorder())) < 0.01:
        raise ValueError(f"{name}: {path}: its PFM scale {scale:g} says {'little' if scale < 0 else 'big'}-endian, but "
                         f"its values read so are mostly NaN, below 1e-10 or beyond 1e10, and read in the other byte "
                         f"order they are ordinary numbers: the scale's sign is wrong (negative = little-endian, "
                         f"positive = big-endian). Fix the header's sign (or the writer), then read it again")
    shape = (height, width, 3) if channels == 3 else (height, width)
    return np.flipud(array.reshape(shape)).astype(np.float32)


def read_depth_image(path, scale: float = 0.001) -> np.ndarray:
    """A depth file (16-bit PNG in millimetres by default, ``.npy``, ...) → (H, W) float32 metres; see :func:`read_depth`."""
    return read_depth(path, scale, "path", scale_name="scale")


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
        raise parse_error(path, None, f"holds {len(body)} data bytes, expected {4 * count} for {height}×{width} (H×W)")
    return np.frombuffer(body, dtype="<f4").reshape(width, height).T.astype(np.float32)


def read_depth_file(path: Path, scale: float | None, name: str = "path") -> np.ndarray:
    """A depth map file → (H, W) float32 × ``scale``; see :func:`read_depth` (its older name)."""
    return read_depth(path, scale, name)


DEPTH_RANGE_M = (1e-3, 1e4)  # no depth outside it, whatever the scene
MEDIAN_RANGE_M = (0.05, 300.0)  # a depth map's median: a cup from 5 cm up to a street scene's far side
COMMON_SCALES = (1.0, 1e-3, 1.0 / 5000, 1e-4, 1e-2)  # metres, mm, TUM's 1/5000 m, 0.1 mm, cm


def check_plausible_depth(depth, scale: float, flag: str = "--depth", scale_name: str = "--depth-scale") -> None:
    """Refuse a scale under which the valid depths (metres, > 0, finite; ``depth`` = stored values ×
    ``scale``) are no plausible depth map: any depth outside ``DEPTH_RANGE_M``, or a median outside
    ``MEDIAN_RANGE_M``. The message names the common scale (``COMMON_SCALES``) that would make it
    plausible, if any. Depth in metres only: a reconstruction's own units (COLMAP) are not checked.
    ``flag``/``scale_name``: what the message calls the file and the scale."""
    metres = np.asarray(depth, dtype=np.float64)
    low, high, median = (float(v) for v in (metres.min(), metres.max(), np.median(metres)))

    def plausible(lo, hi, mid):
        return DEPTH_RANGE_M[0] <= lo and hi <= DEPTH_RANGE_M[1] and MEDIAN_RANGE_M[0] <= mid <= MEDIAN_RANGE_M[1]
    if plausible(low, high, median):
        return
    fits = [c for c in COMMON_SCALES if plausible(low / scale * c, high / scale * c, median / scale * c)]
    better = min(fits, key=lambda c: abs(np.log(median / scale * c / 3.0)), default=None)
    hint = (f"; {scale_name} {better:g} would give {low / scale * better:.3g}–{high / scale * better:.3g} m "
            f"(median {median / scale * better:.3g} m)" if better is not None else "")
    raise ValueError(f"{scale_name} {scale:g}: {flag} would range {low:.3g}–{high:.3g} m (median {median:.3g} m), "
                     f"not a plausible depth map in metres (depths within {DEPTH_RANGE_M[0]:g}–{DEPTH_RANGE_M[1]:g} m, "
                     f"median within {MEDIAN_RANGE_M[0]:g}–{MEDIAN_RANGE_M[1]:g} m){hint}. {scale_name} is the "
                     f"metres per stored unit")


# The values a depth file may hold that are no depth although they are valid numbers: a sensor's
# "no reading" / saturated marker. Integer files: the type's largest value (65535 in a 16-bit PNG);
# float files: 65535 carried over from such a PNG, and absurd finite magnitudes (float max, 1e10, ...); inf is
# a float file's own "unknown" marker (Middlebury's PFMs) and becomes a hole without a word.
FLOAT_SENTINEL_MIN = 1e9


def _sentinels(raw: np.ndarray) -> tuple[int, str]:
    """How many pixels of ``raw`` hold a common "no reading" marker, and which value it is."""
    if np.issubdtype(raw.dtype, np.integer):
        top = np.iinfo(raw.dtype).max
        return int((raw == top).sum()), f"{top}, the largest {raw.dtype} value"
    with np.errstate(invalid="ignore"):
        count = int(((raw == 65535) | (np.isfinite(raw) & (np.abs(raw) >= FLOAT_SENTINEL_MIN))).sum())
    return count, f"65535 or ≥ {FLOAT_SENTINEL_MIN:g}"


def _check_negative(raw: np.ndarray, path, name: str) -> None:
    """Negative values in a depth file: one value throughout (a tool's "no value" marker, e.g. -1) is read as
    holes with a warning; varied ones (a depth with another sign convention, a disparity, a height map) are
    refused. Either way the file, the count and the share are named: silence would make them holes unseen."""
    if not np.issubdtype(raw.dtype, np.signedinteger) and not np.issubdtype(raw.dtype, np.floating):
        return
    with np.errstate(invalid="ignore"):
        negative = np.isfinite(raw) & (raw < 0)
    count = int(negative.sum())
    if not count:
        return
    low, high = float(raw[negative].min()), float(raw[negative].max())
    if low == high:
        warnings.warn(f"{name}: {path}: {count} pixel(s) ({count / raw.size:.1%}) hold {low:g}, read as a 'no value' "
                      f"marker: they become holes. If they are depths, the file's sign convention is another",
                      stacklevel=4)
        return
    raise ValueError(f"{name}: {path} holds {count} negative value(s) ({count / raw.size:.1%} of its pixels, "
                     f"{low:.4g} to {high:.4g}): a depth is positive (metres in front of the camera), and varied "
                     f"negative values are no 'no value' marker. Is its sign convention another (OpenGL cameras "
                     f"look down −z), or is it not a depth map (a disparity, a height)? Store 0 or NaN where there "
                     f"is no depth")


def read_depth(path, scale: float | None = None, name: str = "path", scale_name: str = "depth_scale") -> np.ndarray:
    """Every depth map the kit reads, of every command and format → (H, W) float32 metres = stored × ``scale``,
    NaN where the file has no depth (0, negative, NaN, inf).

    Files: ``.npy``, ``.pfm``, COLMAP ``.bin`` (floats: ``scale`` defaults to 1) and any one-channel image
    OpenCV reads, as stored (16-bit PNG/TIFF: integers, ``scale`` required, e.g. 0.001 for millimetres;
    float TIFF/EXR). One rule for all of them, so every command agrees:

    * an 8-bit file (a picture, e.g. a depth visualisation: 256 levels are no depth) is refused;
    * integers need ``scale`` (``scale_name``: the argument the caller calls it);
    * a pixel that holds a common "no reading" marker (65535 in a 16-bit file) is reported with a warning
      naming the file and the depth it becomes.

    Errors name ``name`` (the argument the path came from) and the file."""
    if scale is not None and (isinstance(scale, bool) or not isinstance(scale, (int, float, np.floating, np.integer))
                              or not np.isfinite(scale) or scale <= 0):
        raise ValueError(f"{scale_name} must be a positive number (metres per stored unit), got {scale!r}")
    path = regular_file(path, name)
    suffix = path.suffix.lower()
    if suffix == ".bin":
        raw = read_colmap_depth(path)
    elif suffix == ".npy":
        raw = load_npy(path, name)
    elif suffix == ".pfm":
        raw = read_pfm(path, name)
    else:  # as stored: no EXIF rotation, like every colour image; a lossy file (a JPEG) holds no depth
        raw = read_image_file(path, name, truth=True)
    if raw.dtype in (np.uint8, np.int8):
        raise ValueError(f"{name}: {path} is an 8-bit {'array' if suffix == '.npy' else 'image'}, a picture (e.g. a "
                         f"depth visualisation), not a depth map: 256 levels hold no depth. Give the 16-bit PNG, "
                         f".npy, .pfm or .bin the depth was saved as")
    if raw.ndim != 2 or raw.dtype == bool or not np.issubdtype(raw.dtype, np.number) \
            or np.issubdtype(raw.dtype, np.complexfloating):
        raise ValueError(f"{name}: {path} must hold one (H, W) map of real numbers (one channel), got {raw.dtype} "
                         f"{raw.shape}")
    if min(raw.shape) == 0:
        raise ValueError(f"{name}: {path} holds an empty {raw.shape[0]}×{raw.shape[1]} map")
    if scale is None:
        hint = " (CLI: --depth-scale)" if scale_name == "depth_scale" else ""
        if np.issubdtype(raw.dtype, np.integer):
            raise ValueError(f"{name}: {path} stores integers; give {scale_name}{hint}, the metres per stored unit of its "
                             f"{raw.dtype} values (0.001 for millimetres, as in most 16-bit depth PNGs; 1/5000 for TUM)")
        scale = 1.0
    _check_negative(raw, path, name)
    count, marker = _sentinels(raw)
    if count:
        example = float(raw[(raw == np.iinfo(raw.dtype).max) if np.issubdtype(raw.dtype, np.integer)
                            else ((raw == 65535) | (np.isfinite(raw) & (np.abs(raw) >= FLOAT_SENTINEL_MIN)))][0])
        warnings.warn(f"{name}: {path}: {count} pixel(s) hold {marker}, which depth cameras write for 'no reading' "
                      f"or 'out of range'; they are read as depth ({example * float(scale):.4g} m at {scale_name} "
                      f"{float(scale):g}). If they mean 'no value', store 0 there", stacklevel=3)
    with np.errstate(over="ignore", invalid="ignore"):
        depth = raw.astype(np.float64) * float(scale)
    return np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float32)
