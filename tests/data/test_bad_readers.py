"""Bad files for the readers and loaders: PFM, Middlebury and KITTI calibrations and disparities, depth images,
JPEGs, COLMAP and TUM folders, saved scenes, FIFOs and folders where a file belongs, image headers that declare
a huge image; each refused naming the file or argument, and what is odd but meaningful (an EXIF orientation,
unpaired frames) reported. The refusals use ``bad_input_harness``.
"""
from __future__ import annotations

import os
import warnings

import cv2
import numpy as np
import pytest

from bad_input_harness import (H, W, CaseList, colmap_workspace, desk_scene, fifo, refusal_test,
                               tum_capture)
from ddp_lite.classical.stereo import disparity_to_depth
from ddp_lite.data import datasets as ds
from ddp_lite.data import fileio
from ddp_lite.data.colmap import read_colmap
from ddp_lite.data.file_writers import write_pfm
from ddp_lite.data.fileio import read_depth_image, read_pfm
from ddp_lite.data.formats import read_scene
from ddp_lite.data.middlebury import (load_middlebury, make_middlebury_fixture, parse_middlebury_calib,
                                      read_middlebury_calib)
from ddp_lite.data.resample import resize_scene
from ddp_lite.data.tum import read_tum

CASES = CaseList()
case = CASES.case

# --------------------------------------------------------------------------- loaders

PFM_HEAD = b"Pf\n2 2\n-1.0\n"
PFM_BODY = np.ones(4, "<f4").tobytes()


def _pfm(data):
    def setup(tmp):
        (tmp / "x.pfm").write_bytes(data)
        return lambda: read_pfm(tmp / "x.pfm")
    return setup


for _id, _data in (("not a PFM", b"P6\n2 2\n255\n" + PFM_BODY), ("truncated", PFM_HEAD + PFM_BODY[:7]),
                   ("zero scale", b"Pf\n2 2\n0.0\n" + PFM_BODY), ("nan scale", b"Pf\n2 2\nnan\n" + PFM_BODY)):
    case(f"read_pfm {_id}", ValueError, "path")(_pfm(_data))

CALIB = {"cam0": "[30 0 15.5; 0 30 11.5; 0 0 1]", "cam1": "[30 0 15.5; 0 30 11.5; 0 0 1]", "doffs": "0",
         "baseline": "100", "width": "32", "height": "24", "ndisp": "16"}


def _calib(**changes):
    entries = {**CALIB, **changes}
    text = "\n".join(f"{k}={v}" for k, v in entries.items() if v is not None)
    return lambda tmp: (lambda: parse_middlebury_calib(text))


for _id, _kw, _name in (("baseline nan", dict(baseline="nan"), "baseline"), ("baseline inf", dict(baseline="inf"), "baseline"),
                        ("baseline -1", dict(baseline="-1"), "baseline"), ("doffs nan", dict(doffs="nan"), "doffs"),
                        ("width 0", dict(width="0"), "width"), ("width 2.5", dict(width="2.5"), "width"),
                        ("ndisp missing", dict(ndisp=None), "ndisp"), ("cam0 2×2", dict(cam0="[1 0; 0 1]"), "cam0"),
                        ("height inf", dict(height="inf"), "height")):
    case(f"calib {_id}", ValueError, _name)(_calib(**_kw))
case("calib not text", ValueError, "text")(lambda tmp: (lambda: parse_middlebury_calib(b"cam0=[1]")))


def _latin1_calib(tmp):
    (tmp / "calib.txt").write_bytes("cam0=[30 0 15.5; 0 30 11.5; 0 0 1] # f\xe9\n".encode("latin-1"))
    return lambda: read_middlebury_calib(tmp / "calib.txt")


case("calib.txt not UTF-8", ValueError, "calib.txt")(_latin1_calib)

P2 = "P_rect_02: 700 0 600 45 0 700 180 0 0 0 1 0"
P3 = "P_rect_03: 700 0 600 -340 0 700 180 0 0 0 1 0"


def _kitti_calib(text):
    def setup(tmp):
        (tmp / "c.txt").write_bytes(text if isinstance(text, bytes) else text.encode())
        return lambda: ds.read_kitti_calib(tmp / "c.txt")
    return setup


for _id, _text in (("focal 0", P2.replace("700 0 600 45", "0 0 600 45") + "\n" + P3),
                   ("P2 = P3", P2 + "\n" + P2.replace("02", "03")), ("no P_rect_03", P2),
                   ("not UTF-8", (P2 + "\n" + P3 + "\n# caf\xe9").encode("latin-1"))):
    case(f"kitti calib {_id}", ValueError, "c.txt")(_kitti_calib(_text))


def _kitti_disp8(tmp):
    cv2.imwrite(str(tmp / "d.png"), np.ones((4, 4), np.uint8))
    return lambda: ds.read_kitti_disparity(tmp / "d.png")


case("kitti disparity 8-bit", ValueError, "path")(_kitti_disp8)


def _mb_all_inf(tmp):
    folder = make_middlebury_fixture(tmp / "mb", size=(24, 32))
    write_pfm(folder / "disp0.pfm", np.full((24, 32), np.inf, np.float32))
    return lambda: load_middlebury(folder)


case("middlebury all-invalid disparity", ValueError, "disp0.pfm")(_mb_all_inf)


def _kitti_tree(tmp, disparity=None):
    base = tmp / "kitti" / "training"
    for sub in ("image_2", "image_3", "calib_cam_to_cam", "disp_occ_0"):
        (base / sub).mkdir(parents=True)
    for sub in ("image_2", "image_3"):
        cv2.imwrite(str(base / sub / "000000_10.png"), np.zeros((H, W, 3), np.uint8))
    small = {"700 0 600": "30 0 15.5", "0 700 180": "0 30 11.5"}  # K of a 32×24 image
    (base / "calib_cam_to_cam" / "000000.txt").write_text("\n".join(
        text.replace("700 0 600", small["700 0 600"]).replace("0 700 180", small["0 700 180"]) for text in (P2, P3)))
    cv2.imwrite(str(base / "disp_occ_0" / "000000_10.png"),
                np.zeros((H, W), np.uint16) if disparity is None else disparity)
    return tmp / "kitti"


case("kitti all-zero disparity", ValueError, "disp_occ_0")(lambda tmp: (lambda root=_kitti_tree(tmp): ds.load_kitti(root)))
case("kitti index -1", ValueError, "index")(lambda tmp: (lambda: ds.load_kitti(tmp, index=-1)))
case("kitti split val", ValueError, "split")(lambda tmp: (lambda: ds.load_kitti(tmp, split="val")))

for _id, _kw, _name in (("focal 0", dict(focal=0.0, baseline=0.1), "focal"),
                        ("baseline nan", dict(focal=30.0, baseline=float("nan")), "baseline"),
                        ("doffs inf", dict(focal=30.0, baseline=0.1, doffs=float("inf")), "doffs")):
    case(f"disparity_to_depth {_id}", ValueError, _name)(
        lambda tmp, kw=_kw: (lambda: disparity_to_depth(np.ones((4, 4)), **kw)))
case("disparity_to_depth 3-D", ValueError, "disparity")(
    lambda tmp: (lambda: disparity_to_depth(np.ones((4, 4, 1)), 30.0, 0.1)))
case("read_depth_image scale 0", ValueError, "scale")(lambda tmp: (lambda: read_depth_image(tmp / "x.png", 0.0)))


def _depth8(tmp):
    cv2.imwrite(str(tmp / "d8.png"), np.ones((4, 4), np.uint8))
    return lambda: read_depth_image(tmp / "d8.png")


case("read_depth_image 8-bit", ValueError, "path")(_depth8)
case("resize_scene not a Scene", TypeError, "scene")(lambda tmp: (lambda: resize_scene("scene", (8, 8))))
case("write_pfm bool", ValueError, "array")(lambda tmp: (lambda: write_pfm(tmp / "b.pfm", np.ones((2, 2), bool))))
case("write_pfm 4-D", ValueError, "array")(lambda tmp: (lambda: write_pfm(tmp / "b.pfm", np.ones((2, 2, 2, 2)))))


# --------------------------------------------------------------------------- found while hardening
case("calib a key twice", ValueError, "baseline")(
    lambda tmp: (lambda: parse_middlebury_calib("\n".join(f"{k}={v}" for k, v in CALIB.items()) + "\nbaseline=5")))


def _colmap_two_depths(tmp):
    folder = colmap_workspace(tmp)
    stem = sorted((folder / "depth").iterdir())[0]
    (folder / "depth" / (stem.stem + ".png.png")).write_bytes(stem.read_bytes())  # a run's output beside it
    return lambda: read_colmap(folder, depth_scale=0.001)


case("COLMAP depth NAME.png beside STEM.png", FileNotFoundError, "two depth maps")(_colmap_two_depths)


for _reader, _suffix in (("read_rgb", ".png"), ("read_pfm", ".pfm"), ("read_depth_image", ".npy"),
                         ("read_colmap_depth", ".bin")):
    case(f"{_reader} of a FIFO", ValueError, "FIFO")(
        lambda tmp, r=_reader, s=_suffix: (fifo(tmp / f"x{s}"), lambda: getattr(fileio, r)(tmp / f"x{s}"))[1])
    case(f"{_reader} of a folder", IsADirectoryError, "folder")(
        lambda tmp, r=_reader, s=_suffix: ((tmp / f"x{s}").mkdir(), lambda: getattr(fileio, r)(tmp / f"x{s}"))[1])
case("TUM rgb.txt a FIFO", ValueError, "FIFO")(
    lambda tmp: ((tmp / "capture" / "rgb.txt").unlink() if tum_capture(tmp) else None, fifo(tmp / "capture" / "rgb.txt"),
                 lambda: read_tum(tmp / "capture"))[2])


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


case("8-bit picture as depth", ValueError, "8-bit")(
    lambda tmp: (cv2.imwrite(str(tmp / "vis.png"), np.full((H, W), 128, np.uint8)),
                 lambda: fileio.read_depth_file(tmp / "vis.png", 0.001))[1])


def _truncated_npz(tmp):
    desk_scene().save(tmp / "full.npz")
    (tmp / "cut.npz").write_bytes((tmp / "full.npz").read_bytes()[:2000])
    return lambda: read_scene(tmp / "cut.npz")


case("truncated scene .npz", ValueError, "cut.npz")(_truncated_npz)


def _tum_duplicate_stamp(tmp):
    folder = tum_capture(tmp)
    lines = (folder / "rgb.txt").read_text().splitlines()
    stamp = lines[1].split()[0]
    lines[2] = f"{stamp} {lines[2].split()[1]}"
    (folder / "rgb.txt").write_text("\n".join(lines) + "\n")
    return lambda: read_tum(folder)


case("TUM two colour frames with one timestamp", ValueError, "timestamp")(_tum_duplicate_stamp)


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)


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


def test_unpaired_tum_frames_are_reported(tmp_path):
    """Uneven rgb/depth lists: the frames left out are counted in a warning, never dropped in silence."""
    folder = tum_capture(tmp_path)
    lines = (folder / "depth.txt").read_text().splitlines()
    (folder / "depth.txt").write_text("\n".join(lines[:-1]) + "\n")  # the last colour frame loses its depth
    with pytest.warns(UserWarning, match=r"1 of 3 colour frame\(s\) have no depth frame"):
        scene = read_tum(folder)
    assert len(scene) == 2


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


def test_a_png_or_jpeg_declaring_a_huge_image_is_refused_by_its_header(tmp_path):
    import struct
    import zlib
    from ddp_lite.data.fileio import read_image_file

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    bomb = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 100000, 100000, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"\x00" * 1000)) + chunk(b"IEND", b""))
    (tmp_path / "bomb.png").write_bytes(bomb)
    with pytest.raises(ValueError, match=r"rgb: .*100000×100000.*refused before decoding"):
        read_image_file(tmp_path / "bomb.png", "rgb")
    import cv2
    ok, jpeg = cv2.imencode(".jpg", np.zeros((8, 8, 3), np.uint8))
    data = bytearray(jpeg.tobytes())
    at = data.find(b"\xff\xc0")
    data[at + 5:at + 9] = struct.pack(">HH", 60000, 60000)  # height, width
    (tmp_path / "bomb.jpg").write_bytes(bytes(data))
    with pytest.raises(ValueError, match="60000×60000"):
        read_image_file(tmp_path / "bomb.jpg", "rgb")
    cv2.imwrite(str(tmp_path / "fine.png"), np.zeros((5, 7), np.uint8))
    assert read_image_file(tmp_path / "fine.png").shape == (5, 7)


def test_a_tum_list_naming_one_file_for_every_frame_is_refused(tmp_path):
    from ddp_lite.data.tum import read_tum_list
    path = tmp_path / "depth.txt"
    path.write_text("# timestamp filename\n1.0 depth/1.png\n1.1 depth/1.png\n1.2 depth/1.png\n")
    with pytest.raises(ValueError, match="depth/1.png was already listed on line 2"):
        read_tum_list(path)
    path.write_text("1.0 depth/1.png\n1.1 depth/2.png\n")
    assert len(read_tum_list(path)) == 2
