"""Bad and edge-case inputs, second round: what a user gave is never overwritten, nothing wrong passes in silence.

Two kinds of case. **Refusals** (``CASES``), as in ``test_bad_inputs.py``: each builds its inputs in
a fresh folder, acts, and must raise the named exception with a message naming the argument,
leaving every file and every array the caller gave unchanged. **Rules** (the ``test_*`` functions
below): what an input that is odd but meaningful must do instead (a masked array's mask is a hole,
an EXIF orientation is reported and not applied, unpaired frames are reported).

``python tests/test_bad_inputs_more.py`` prints each refusal's verdict (clear / unclear / silent)
against whatever ``ddp_lite`` is on the path.
"""
from __future__ import annotations

import io
import json
import os
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

if __name__ != "__main__":
    os.environ.setdefault("DDP_PROFILE", "ci")

import cv2  # noqa: E402

from data_fetch import Dataset, FetchError, RemoteFile, fetch  # noqa: E402
from ddp_lite.data import fileio  # noqa: E402
from ddp_lite.core.camera import Camera, look_at  # noqa: E402
from ddp_lite.core.checks import check_depth  # noqa: E402
from ddp_lite.method.paper.disparity import DisparityTransform  # noqa: E402
from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.dip import fit_image  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.method.result import merge  # noqa: E402
from ddp_lite.data.colmap import read_colmap, write_colmap  # noqa: E402
from ddp_lite.data.formats import read_scene  # noqa: E402
from ddp_lite.data.tum import read_tum, write_tum  # noqa: E402
from ddp_lite.world.scenes import make_scene  # noqa: E402
from ddp_lite.sequences.sequence import run_sequence  # noqa: E402
from ddp_lite.sequences import sequence_files  # noqa: E402
from ddp_lite.sequences.sequence_files import MANIFEST, read_manifest  # noqa: E402

from test_bad_inputs import Case, _WATCHED, camera, depth, rgb, snapshot, tiny, verdicts, watch  # noqa: E402

H, W = 24, 32
BAD = (TypeError, ValueError)
CASES: list[Case] = []


def case(id, exc, name):
    def register(setup):
        CASES.append(Case(id, setup, exc, name))
        return setup
    return register


def _scene(n_views=3):
    return make_scene("desk", size=(H, W), n_views=n_views, seed=0)


def _tum(tmp):
    return write_tum(_scene(), tmp / "capture")


def _colmap(tmp, depth_format="png"):
    return write_colmap(_scene(), tmp / "workspace", depth_format=depth_format)


def _run(scene, out):
    return lambda: run_sequence(scene, out, tiny(iterations=1), fuse=False, log=lambda *a: None)


def _fifo(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    os.mkfifo(path)
    return path


# --------------------------------------------------------------------------- serious: outputs over inputs

case("sequence out = the TUM capture", ValueError, "out")(
    lambda tmp: _run(read_tum(_tum(tmp)), tmp / "capture"))
case("sequence out = the TUM capture's depth folder", ValueError, "out")(
    lambda tmp: _run(read_tum(_tum(tmp)), tmp / "capture" / "depth"))
case("sequence out = a folder holding the capture", ValueError, "out")(
    lambda tmp: _run(read_tum(_tum(tmp)), tmp))
case("sequence out = the COLMAP workspace", ValueError, "out")(
    lambda tmp: _run(read_colmap(_colmap(tmp), depth_scale=0.001), tmp / "workspace"))
case("sequence out = a saved scene's folder", ValueError, "out")(
    lambda tmp: (_scene().save(tmp / "s" / "scene.npz"), _run(read_scene(tmp / "s"), tmp / "s"))[1])
case("sequence out = a path given as source", ValueError, "out")(
    lambda tmp: (lambda: run_sequence(_scene(), tmp / "data" / "out", tiny(iterations=1),
                                      source={"path": str(tmp / "data")}, log=lambda *a: None)))
case("sequence out is a file", ValueError, "out")(
    lambda tmp: ((tmp / "out").write_text("x"), _run(_scene(), tmp / "out"))[1])


def _colmap_two_depths(tmp):
    folder = _colmap(tmp)
    stem = sorted((folder / "depth").iterdir())[0]
    (folder / "depth" / (stem.stem + ".png.png")).write_bytes(stem.read_bytes())  # a run's output beside it
    return lambda: read_colmap(folder, depth_scale=0.001)


case("COLMAP depth NAME.png beside STEM.png", FileNotFoundError, "two depth maps")(_colmap_two_depths)


# --------------------------------------------------------------------------- serious: data_fetch trust and FIFOs

def _toy():
    return Dataset("toy", "toy", (RemoteFile("a.bin", "http://127.0.0.1:9/a.bin"),), "CC0", "tests", "-", "-")


def _manual():
    return Dataset("hand", "hand", (RemoteFile("a.bin"),), "CC0", "tests", "-", "-", manual="put a.bin in {dest}")


def _garbage_under_final_name(tmp):
    (tmp / "toy").mkdir()
    (tmp / "toy" / "a.bin").write_bytes(b"garbage, never downloaded")
    return lambda: fetch(_toy(), dest=tmp, trust_first_download=True, say=lambda *a: None, retries=0)


case("fetch --trust-first-download, garbage already there", FetchError, "trusts only bytes this fetch downloads")(
    _garbage_under_final_name)
case("fetch manual file is a FIFO (trusted)", ValueError, "FIFO")(
    lambda tmp: (_fifo(tmp / "hand" / "a.bin"),
                 lambda: fetch(_manual(), dest=tmp, trust_first_download=True, say=lambda *a: None))[1])
case("fetch registry.json a FIFO", ValueError, "registry")(
    lambda tmp: ((tmp / "hand").mkdir(), (tmp / "hand" / "a.bin").write_bytes(b"x"), _fifo(tmp / "hand" / "registry.json"),
                 lambda: fetch(_manual(), dest=tmp, trust_first_download=True, say=lambda *a: None))[-1])
case("fetch unpack marker a FIFO", ValueError, "unpack marker")(
    lambda tmp: ((tmp / "hand").mkdir(), (tmp / "hand" / "a.zip").write_bytes(b"x"), _fifo(tmp / "hand" / ".a.zip.unpacked"),
                 lambda: fetch(Dataset("hand", "hand", (RemoteFile("a.zip", sha256=__import__("hashlib").sha256(b"x").hexdigest(),
                                                        unpack=True),), "CC0", "tests",
                                       "-", "-", manual="put a.zip in {dest}"), dest=tmp, say=lambda *a: None))[-1])
case("fetch partial download a FIFO", FetchError, "a.bin.part")(
    lambda tmp: (_fifo(tmp / "toy" / "a.bin.part"),
                 lambda: fetch(_toy(), dest=tmp, trust_first_download=True, say=lambda *a: None, retries=0))[-1])
case("fetch trusts an empty manual download", FetchError, "empty (0 bytes)")(
    lambda tmp: ((tmp / "hand").mkdir(), (tmp / "hand" / "a.bin").write_bytes(b""),
                 lambda: fetch(_manual(), dest=tmp, trust_first_download=True, say=lambda *a: None))[-1])
case("fetch manual file is a folder", IsADirectoryError, "a.bin")(
    lambda tmp: ((tmp / "hand" / "a.bin").mkdir(parents=True),
                 lambda: fetch(_manual(), dest=tmp, trust_first_download=True, say=lambda *a: None))[1])


def _env(name, value, act):
    def run():
        saved = os.environ.get(name)
        os.environ[name] = value
        try:
            act()
        finally:
            os.environ.pop(name) if saved is None else os.environ.__setitem__(name, saved)
    return run


case("DDP_DATA blank", ValueError, "DDP_DATA")(
    lambda tmp: _env("DDP_DATA", "  ", lambda: fetch(_toy(), trust_first_download=True, say=lambda *a: None)))

for _reader, _suffix in (("read_rgb", ".png"), ("read_pfm", ".pfm"), ("read_depth_image", ".npy"),
                         ("read_colmap_depth", ".bin")):
    case(f"{_reader} of a FIFO", ValueError, "FIFO")(
        lambda tmp, r=_reader, s=_suffix: (_fifo(tmp / f"x{s}"), lambda: getattr(fileio, r)(tmp / f"x{s}"))[1])
    case(f"{_reader} of a folder", IsADirectoryError, "folder")(
        lambda tmp, r=_reader, s=_suffix: ((tmp / f"x{s}").mkdir(), lambda: getattr(fileio, r)(tmp / f"x{s}"))[1])
case("TUM rgb.txt a FIFO", ValueError, "FIFO")(
    lambda tmp: ((tmp / "capture" / "rgb.txt").unlink() if _tum(tmp) else None, _fifo(tmp / "capture" / "rgb.txt"),
                 lambda: read_tum(tmp / "capture"))[2])


# --------------------------------------------------------------------------- serious: masked arrays, transforms, EXIF

case("masked colour", TypeError, "rgb")(
    lambda tmp: (lambda: complete_depth(np.ma.masked_less(rgb(), 0.5), depth(), variant="rgbd", config=tiny())))
case("masked integer depth", TypeError, "depth")(
    lambda tmp: (lambda: check_depth(np.ma.masked_equal(np.full((H, W), 2, np.int32), 0))))
case("transform narrower than the valid depth", ValueError, "transform")(
    lambda tmp: (lambda: complete_depth(rgb(), watch(np.linspace(1.0, 3.0, H * W, dtype=np.float32).reshape(H, W)),
                                        variant="d", config=tiny(), transform=DisparityTransform(1.0, 2.0))))


def _jpeg(path, orientation=None, size=(H, W)):
    from PIL import Image
    image = Image.fromarray(np.random.default_rng(0).integers(0, 255, (*size, 3), dtype=np.uint8))
    exif = Image.Exif()
    if orientation is not None:
        exif[0x0112] = orientation
    image.save(path, "JPEG", exif=exif.tobytes())
    return path


case("truncated JPEG", ValueError, "truncated")(
    lambda tmp: ((tmp / "cut.jpg").write_bytes(_jpeg(tmp / "whole.jpg").read_bytes()[:-300]),
                 lambda: fileio.read_rgb(tmp / "cut.jpg"))[1])


# --------------------------------------------------------------------------- scale and range

case("depth 1e-30 m beside 2 m", ValueError, "depth")(
    lambda tmp: (lambda: complete_depth(rgb(), watch(np.where(np.eye(H, W, dtype=bool), 1e-30, 2.0).astype(np.float32)),
                                        variant="d", config=tiny())))
case("float64 depth beyond float32", ValueError, "depth")(
    lambda tmp: (lambda: complete_depth(rgb(), watch(np.where(np.eye(H, W, dtype=bool), 1e300, 2.0)),
                                        variant="d", config=tiny())))
case("8-bit picture as depth", ValueError, "8-bit")(
    lambda tmp: (cv2.imwrite(str(tmp / "vis.png"), np.full((H, W), 128, np.uint8)),
                 lambda: fileio.read_depth_file(tmp / "vis.png", 0.001))[1])


# --------------------------------------------------------------------------- neighbours that add nothing

def _neighbour(pose):
    return (rgb(), camera(pose))


_SIDE = look_at((0.2, 0.0, 0.0), (0.0, 0.0, 2.0))
_K_640x480 = np.array([[525.0, 0.0, 319.5], [0.0, 525.0, 239.5], [0.0, 0.0, 1.0]])  # TUM fr1's K, for 640×480
case("intrinsics for 640×480 on a 32×24 image", ValueError, "K: the principal point")(  # refused by Camera itself
    lambda tmp: (lambda: complete_depth(rgb(), depth(), Camera(_K_640x480, np.eye(4), W, H), variant="rgbd",
                                        config=tiny())))
case("a neighbour's intrinsics for 640×480 on a 32×24 image", ValueError, "K: the principal point")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), camera(), [(rgb(), Camera(_K_640x480, _SIDE, W, H))],
                                        config=tiny())))
case("neighbour at the reference's pose", ValueError, "neighbors[0]")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), camera(np.eye(4)), [_neighbour(np.eye(4))], config=tiny())))
case("the same neighbour twice", ValueError, "neighbors[1]")(
    lambda tmp: (lambda n: (lambda: complete_depth(rgb(), depth(), camera(look_at((0, 0, 0), (0, 0, 2))), [n, n],
                                                   config=tiny())))(_neighbour(_SIDE)))


# --------------------------------------------------------------------------- conventions

case("gt_depth with 0 for unknown", ValueError, "gt_depth")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), variant="d", config=tiny(),
                                        gt_depth=watch(np.where(np.isnan(depth()), 0.0, 2.0).astype(np.float32)))))
case("merge() with 0 for holes", ValueError, "input_depth")(
    lambda tmp: (lambda: merge(watch(np.nan_to_num(depth(), nan=0.0)), depth())))
case("merge() with a string for ddp_depth", TypeError, "ddp_depth")(
    lambda tmp: (lambda: merge(depth(), "filled.npy")))
case("neighbors=None for rgbd+warp", ValueError, "neighbor")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), camera(), None, config=tiny())))
case("seed 2**63", ValueError, "config.seed")(lambda tmp: (lambda: tiny(seed=2**63).validate()))
case("seed near 2**63 with an ensemble", ValueError, "config.seed")(
    lambda tmp: (lambda: tiny(seed=2**63 - 2, ensemble=3).validate()))
case("FitConfig typo'd attribute", AttributeError, "callback_every")(
    lambda tmp: (lambda: setattr(tiny(), "callbak_every", 5)))
case("callback with callback_every=0", ValueError, "callback_every")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), variant="d", config=tiny(), callback=lambda *a: None)))
case("fit_image callback with callback_every=0", ValueError, "callback_every")(
    lambda tmp: (lambda: fit_image(rgb(), config=tiny(), callback=lambda *a: None)))
case("iterations=10**9", ValueError, "config.iterations")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), variant="d", config=tiny(iterations=10**9))))

# --------------------------------------------------------------------------- sizes the net cannot take

for _shape in ((1, 40), (4, 4), (8, 8)):
    case(f"depth {_shape[0]}×{_shape[1]} for the ci net", ValueError, "at least")(
        lambda tmp, s=_shape: (lambda: complete_depth(rgb(*s), watch(np.full(s, 2.0, np.float32)), variant="d",
                                                      config=FitConfig.for_profile("ci", variant="d", iterations=1))))
case("fit_image 8×8 for the ci net", ValueError, "at least")(
    lambda tmp: (lambda: fit_image(rgb(8, 8), config=FitConfig.for_profile("ci", variant="rgbd", iterations=1))))


# --------------------------------------------------------------------------- files

def _manifest(text):
    def setup(tmp):
        (tmp / "out").mkdir()
        (tmp / "out" / MANIFEST).write_text(text)
        return _run(_scene(), tmp / "out")
    return setup


case("manifest.json a JSON list", ValueError, "manifest")(_manifest("[1, 2]"))
case("manifest.json views a list", ValueError, "manifest")(_manifest('{"views": [1]}'))
case("manifest.json a view entry a string", ValueError, "manifest")(_manifest('{"views": {"desk0": "done"}}'))
case("manifest.json not JSON", ValueError, "manifest")(_manifest("{views"))
case("finished view .npy corrupt", ValueError, "bad.npy")(
    lambda tmp: ((tmp / "bad.npy").write_bytes(b"\x93NUMPY garbage"), lambda: sequence_files._load_depth(tmp / "bad.npy"))[1])
case("finished view .npy of the wrong kind", ValueError, "wrong.npy")(
    lambda tmp: (np.save(tmp / "wrong.npy", np.zeros(3)), lambda: sequence_files._load_depth(tmp / "wrong.npy"))[1])


def _truncated_npz(tmp):
    _scene().save(tmp / "full.npz")
    (tmp / "cut.npz").write_bytes((tmp / "full.npz").read_bytes()[:2000])
    return lambda: read_scene(tmp / "cut.npz")


case("truncated scene .npz", ValueError, "cut.npz")(_truncated_npz)
case("DDP_CACHE names a file", ValueError, "DDP_CACHE")(
    lambda tmp: ((tmp / "cache").write_text("x"),
                 _env("DDP_CACHE", str(tmp / "cache"), lambda: complete_depth(rgb(), depth(), variant="d",
                                                                              config=tiny())))[1])


# --------------------------------------------------------------------------- sequences

def _tum_duplicate_stamp(tmp):
    folder = _tum(tmp)
    lines = (folder / "rgb.txt").read_text().splitlines()
    stamp = lines[1].split()[0]
    lines[2] = f"{stamp} {lines[2].split()[1]}"
    (folder / "rgb.txt").write_text("\n".join(lines) + "\n")
    return lambda: read_tum(folder)


case("TUM two colour frames with one timestamp", ValueError, "timestamp")(_tum_duplicate_stamp)


# --------------------------------------------------------------------------- the refusal test

@pytest.mark.parametrize("c", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_refused_clearly_and_changes_nothing(c, tmp_path):
    _WATCHED.clear()
    act = c.setup(tmp_path)
    before = snapshot(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a warning on the way is fine; the refusal is what counts
        with pytest.raises(c.exc) as info:
            act()
    assert c.name in str(info.value), f"the message does not name {c.name!r}: {info.value}"
    assert snapshot(tmp_path) == before, "a file was created or changed"
    for array, copy in _WATCHED:
        np.testing.assert_array_equal(np.asarray(array), copy)


# --------------------------------------------------------------------------- the rules behind the refusals

def test_masked_depth_is_a_hole_everywhere():
    """np.ma: masked = hole (NaN), whatever lies under the mask; the same in merge()."""
    raw = np.full((H, W), 2.0, np.float32)
    raw[:5] = 123.0  # garbage under the mask
    masked = np.ma.masked_array(raw, mask=np.zeros((H, W), bool))
    masked[:5] = np.ma.masked
    checked = check_depth(masked)
    assert np.isnan(checked[:5]).all() and (checked[5:] == 2.0).all()
    filled = merge(masked, np.full((H, W), 3.0, np.float32))
    assert (filled[:5] == 3.0).all() and (filled[5:] == 2.0).all()
    half = np.ma.masked_array(np.full((H, W), 3.0), mask=np.zeros((H, W), bool))
    half[:2] = np.ma.masked  # a masked fill: no value there, a hole in the merge too
    merged = merge(masked, half)
    assert np.isnan(merged[:2]).all() and (merged[2:5] == 3.0).all()
    assert (raw[:5] == 123.0).all()  # the caller's data untouched


def test_exif_orientation_is_reported_and_not_applied(tmp_path):
    """A phone JPEG rotated by EXIF is read as stored (as depth is), with a warning naming the file."""
    path = _jpeg(tmp_path / "phone.jpg", orientation=6, size=(H, W))  # stored landscape, shown portrait
    with pytest.warns(UserWarning, match=r"phone\.jpg.*EXIF orientation 6"):
        image = fileio.read_rgb(path)
    assert image.shape == (H, W, 3)  # not rotated to (W, H)
    stored = cv2.imread(str(path), cv2.IMREAD_UNCHANGED | cv2.IMREAD_IGNORE_ORIENTATION)[:, :, ::-1]
    np.testing.assert_allclose(image, stored / 255.0, atol=1e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # upright or no EXIF: no warning
        fileio.read_rgb(_jpeg(tmp_path / "upright.jpg", orientation=1))
        fileio.read_rgb(_jpeg(tmp_path / "plain.jpg"))


def test_jpeg_with_bytes_after_its_end_is_not_truncated(tmp_path):
    """Phones append data after the JPEG's end marker ("motion photos"); that file is whole."""
    path = _jpeg(tmp_path / "motion.jpg", orientation=1)
    path.write_bytes(path.read_bytes() + b"ftypmp42" + bytes(500))
    assert fileio.read_rgb(path).shape == (H, W, 3)


def test_trust_first_download_records_whose_bytes(tmp_path):
    """A trusted manual download is recorded as the user's file, not as a download."""
    (tmp_path / "hand").mkdir()
    (tmp_path / "hand" / "a.bin").write_bytes(b"placed by hand")
    fetch(_manual(), dest=tmp_path, trust_first_download=True, say=lambda *a: None)
    record = json.loads((tmp_path / "hand" / "registry.json").read_text())["a.bin"]
    assert "manual download placed" in record["bytes_from"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes to read-only folders")
def test_read_only_data_root_is_refused_before_downloading(tmp_path):
    tmp_path.chmod(0o555)
    try:
        with pytest.raises(FetchError, match="not writable"):
            fetch(_toy(), dest=tmp_path, trust_first_download=True, say=lambda *a: None, retries=0)
    finally:
        tmp_path.chmod(0o755)


def test_unpaired_tum_frames_are_reported(tmp_path):
    """Uneven rgb/depth lists: the frames left out are counted in a warning, never dropped in silence."""
    folder = _tum(tmp_path)
    lines = (folder / "depth.txt").read_text().splitlines()
    (folder / "depth.txt").write_text("\n".join(lines[:-1]) + "\n")  # the last colour frame loses its depth
    with pytest.warns(UserWarning, match=r"1 of 3 colour frame\(s\) have no depth frame"):
        scene = read_tum(folder)
    assert len(scene) == 2


def test_neighbour_without_parallax_is_warned():
    """Depth in millimetres with poses in metres: 2000 "m" away, a 0.2 m baseline shifts < 0.5 px."""
    from ddp_lite.method.input_checks import check_fit_inputs
    ref = camera(look_at((0, 0, 0), (0, 0, 2)))
    millimetres = depth() * 1000.0
    with pytest.warns(UserWarning, match=r"neighbors\[0\].*px of parallax.*same unit"):
        check_fit_inputs(rgb(), millimetres, ref, [_neighbour(_SIDE)], "rgbd+warp", tiny(), None, None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the same views in metres: parallax of pixels, no warning
        check_fit_inputs(rgb(), depth(), ref, [_neighbour(_SIDE)], "rgbd+warp", tiny(), None, None)


def test_conventions_that_are_accepted():
    """NumPy integer seeds are seeds; neighbors=None means none; a field changes by a copy, read by its section."""
    config = tiny(seed=np.int64(3))
    assert type(config.paper.seed) is int
    a = complete_depth(rgb(), depth(), variant="d", config=config, neighbors=None)
    b = complete_depth(rgb(), depth(), variant="d", config=tiny(seed=3))
    np.testing.assert_array_equal(a.depth, b.depth)
    assert config.replace(lr=1e-2).paper.lr == 1e-2
    with pytest.raises(AttributeError, match=r"config\.replace\(lr="):
        config.lr = 1e-2
    with pytest.raises(AttributeError, match=r"config\.paper\.lr"):
        config.lr
    # the smallest size the ci net takes runs: the SSIM window (11) beats its down-sampling factor + 1 (9)
    ci = FitConfig.for_profile("ci", variant="d", iterations=1)
    complete_depth(rgb(11, 11), np.full((11, 11), 2.0, np.float32), variant="d", config=ci)


def test_corrupt_finished_view_is_redone_not_fused(tmp_path):
    """A finished view whose .npy was damaged is fitted again on the next run (and named nowhere as done)."""
    scene = _scene()
    out = tmp_path / "out"
    config = tiny(iterations=1)
    first = run_sequence(scene, out, config, fuse=False, log=lambda *a: None)
    assert len(first["computed"]) == 3
    npy = out / read_manifest(out)["views"][scene[0].name]["files"]["npy"]
    npy.write_bytes(b"\x93NUMPY broken")
    again = run_sequence(scene, out, config, log=lambda *a: None)
    assert again["computed"] == [scene[0].name] and len(again["skipped"]) == 2
    assert sequence_files._load_depth(npy).shape == (H, W)


def test_the_list_grew():
    assert len(CASES) >= 50 and len({c.id for c in CASES}) == len(CASES)


# --------------------------------------------------------------------------- counting verdicts

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    counts, rows = verdicts(CASES)
    for verdict, id_, note in rows:
        print(f"{verdict:8} {id_:55} {note}")
    print(counts, "of", len(CASES))


def test_masked_arrays_are_honoured_wherever_depth_is_scored_or_warped():
    """A masked array's mask means unknown everywhere, not only in the fit: every metric, the disparity
    range and the warp give exactly what they give for the same array with NaN under the mask."""
    from ddp_lite.evaluation import metrics
    from ddp_lite.method.paper.warp import warp_to_reference
    raw = np.full((H, W), 2.0)
    raw[:, W // 2:] = 3.0  # a depth edge, so edge_band and texture_leakage have something to see
    masked = np.ma.masked_array(raw.copy(), mask=np.zeros((H, W), bool))
    masked[:5] = np.ma.masked
    masked.data[:5] = 99.0  # garbage under the mask
    nan = raw.copy()
    nan[:5] = np.nan  # the reference: the kit's own hole marker
    pred = np.full((H, W), 2.5)
    transform = DisparityTransform(1.0, 4.0)
    assert DisparityTransform.from_depth(masked) == DisparityTransform.from_depth(nan)
    assert metrics.rmse(pred, masked) == metrics.rmse(pred, nan)
    assert metrics.mae(masked, nan, mask=np.isfinite(nan)) == 0.0
    assert metrics.psnr(pred, masked, data_range=1.0) == metrics.psnr(pred, nan, data_range=1.0)
    assert metrics.disparity_rmse(pred, masked, np.ones((H, W), bool), transform) == \
        metrics.disparity_rmse(pred, nan, np.ones((H, W), bool), transform)
    filled = np.where(np.isnan(nan), 2.0, nan)
    assert metrics.texture_leakage(filled, np.ma.masked_array(filled, mask=masked.mask), transform) == \
        metrics.texture_leakage(filled, filled, transform)
    ref, nbr = camera(), camera(_SIDE)
    image = rgb()
    for a, b in zip(warp_to_reference(image, masked, ref, nbr), warp_to_reference(image, nan, ref, nbr)):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(TypeError, match="nbr_image"):
        warp_to_reference(np.ma.masked_less(image, 0.5), nan, ref, nbr)
    assert (masked.data[:5] == 99.0).all()  # the caller's array untouched


def test_an_empty_file_or_an_exr_opencv_cannot_decode_is_a_clear_refusal(tmp_path, capsys):
    """OpenCV raises its own cv2.error (a traceback from the command line) for an empty buffer and for
    an EXR when its codec is off; both are refusals naming the file, and the EXR one says how to read it."""
    if os.environ.get("OPENCV_IO_ENABLE_OPENEXR"):
        pytest.skip("the EXR codec is on here")
    from ddp_lite.interface.cli import main
    (tmp_path / "empty.png").write_bytes(b"")
    (tmp_path / "depth.exr").write_bytes(b"\x76\x2f\x31\x01" + bytes(300))  # EXR's magic number
    with pytest.raises(ValueError, match=r"empty\.png is empty"):
        fileio.read_rgb(tmp_path / "empty.png")
    with pytest.raises(ValueError, match=r"depth\.exr.*OPENCV_IO_ENABLE_OPENEXR"):
        fileio.read_image_file(tmp_path / "depth.exr")
    cv2.imwrite(str(tmp_path / "rgb.png"), np.zeros((H, W, 3), np.uint8))
    for flag, path in (("--depth", tmp_path / "depth.exr"), ("--rgb", tmp_path / "empty.png")):
        argv = {"--rgb": tmp_path / "rgb.png", "--depth": tmp_path / "depth.exr", flag: path}
        assert main(["complete", *[str(a) for item in argv.items() for a in item], "--out", str(tmp_path / "f.npy"),
                     "--profile", "ci"]) == 2
        assert flag in capsys.readouterr().err
