"""Bad and odd inputs, fourth round: one rule per class, each where its class lives.

Paths that escape their folder (one path guard: ``ddp_lite.core.files.path_inside``), NaN that passes a
comparison (one finite-result rule in the checks, degenerate geometry refused), downloads judged for
the wrong reason (one hash normalisation, one content verdict, bad numbers up front), a finished fit
thrown away by a late error, and silent mistakes.
"""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

os.environ.setdefault("DDP_PROFILE", "ci")

from data_fetch import Dataset, FetchError, RemoteFile, fetch  # noqa: E402
from data_fetch.__main__ import main as fetch_main  # noqa: E402
from data_fetch.local import install_from  # noqa: E402
from test_data_fetch import PAYLOAD, run, server, sha, toy  # noqa: E402,F401  (server: the fixture)

from ddp_lite.core import files  # noqa: E402
from ddp_lite.core.outpaths import output_lock  # noqa: E402


# ------------------------------------------------------------------ 1. paths that escape their folder

def _linked_subfolder(tmp_path):
    """An output folder whose ``depth`` sub-folder is a link to the user's own files."""
    mine = tmp_path / "my-files"
    mine.mkdir()
    (mine / "v0.npy").write_bytes(b"precious")
    out = tmp_path / "out"
    out.mkdir()
    (out / "depth").symlink_to(mine, target_is_directory=True)
    return out, mine


def test_no_writer_writes_through_a_link_inside_its_output_folder(tmp_path):
    out, mine = _linked_subfolder(tmp_path)
    with output_lock([out], "--out"):
        with pytest.raises(ValueError, match="symbolic link"):
            files.write_bytes_atomic(out / "depth" / "v0.npy", b"overwritten")
        with pytest.raises(ValueError, match="symbolic link"):
            with files.atomic_path(out / "depth" / "new.png") as tmp:
                open(tmp, "wb").close()
        files.write_bytes_atomic(out / "manifest.json", b"{}")  # a plain file of the folder: fine
    assert (mine / "v0.npy").read_bytes() == b"precious" and sorted(os.listdir(mine)) == ["v0.npy"]


def test_a_sequence_output_folder_with_a_linked_subfolder_is_refused_before_any_fit(tmp_path):
    from ddp_lite.sequences.sequence_files import check_out_folder, write_view  # noqa: F401
    out, mine = _linked_subfolder(tmp_path)
    with pytest.raises(ValueError, match="out: .*depth.*symbolic link"):
        check_out_folder(out, [])
    assert (mine / "v0.npy").read_bytes() == b"precious"


def test_the_output_folder_itself_may_be_a_link(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "link").symlink_to(real, target_is_directory=True)
    with output_lock([tmp_path / "link"], "--out"):
        files.write_bytes_atomic(tmp_path / "link" / "depth" / "a.npy", b"x")
    assert (real / "depth" / "a.npy").read_bytes() == b"x"


@pytest.mark.parametrize("name", ["../../escaped.bin", "sub/../../escaped.bin", "ABSOLUTE"])
def test_a_registry_name_outside_the_dataset_folder_is_refused(server, tmp_path, name):
    if name == "ABSOLUTE":
        name = str(tmp_path / "elsewhere" / "escaped.bin")
    server.files["/x.bin"] = PAYLOAD
    dataset = Dataset("toy", "toy", (RemoteFile(name, f"{server.url}/x.bin", sha(PAYLOAD)),), "CC0", "t", "1", "h")
    with pytest.raises(FetchError, match="toy entry") as caught:
        run(dataset, tmp_path / "data")
    assert isinstance(caught.value, ValueError) and name in str(caught.value)
    assert server.log == []  # nothing downloaded
    assert not any(p.name == "escaped.bin" for p in tmp_path.rglob("*"))
    source = tmp_path / "from"
    (source / "a").mkdir(parents=True)
    with pytest.raises(FetchError, match="toy entry"):
        install_from(dataset, source / "a", dest=tmp_path / "data", say=lambda *a: None)


def test_a_link_inside_the_dataset_folder_leading_out_is_refused(server, tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (tmp_path / "data" / "toy").mkdir(parents=True)
    (tmp_path / "data" / "toy" / "sub").symlink_to(outside, target_is_directory=True)
    server.files["/x.bin"] = PAYLOAD
    dataset = Dataset("toy", "toy", (RemoteFile("sub/x.bin", f"{server.url}/x.bin", sha(PAYLOAD)),), "CC0", "t", "1",
                      "h")
    with pytest.raises(FetchError, match="symbolic link"):
        run(dataset, tmp_path / "data")
    assert list(outside.iterdir()) == [] and server.log == []


# ------------------------------------------------------------------ 3. NaN that passes a comparison

def test_a_student_function_returning_nan_never_passes_a_check(capsys):
    from ddp_lite.interface import exercises
    assert exercises.check_warp(lambda image, depth, ref, nbr: np.full((24, 32, 3), np.nan)) is False
    assert "finite" in capsys.readouterr().out
    assert exercises.check_fscore(lambda p, r: float("nan")) is False
    assert exercises.check_psnr(lambda a, b: np.inf) is False
    assert exercises.check_paired_change(lambda before, after: (np.nan, np.nan, np.nan)) is False
    assert "finite" in capsys.readouterr().out


def test_a_nan_where_the_reference_is_nan_is_still_right(capsys):
    from ddp_lite.interface import exercises
    from ddp_lite.interface.exercises import _not_finite
    assert _not_finite(np.array([np.nan, 1.0]), np.array([np.nan, 2.0])) is None
    assert "finite" in _not_finite(np.array([np.nan, 1.0]), np.array([1.0, 2.0]))
    assert exercises.check_fscore(lambda p, r: 0.0 if p + r == 0 else 2 * p * r / (p + r)) is True


@pytest.mark.parametrize("args, name", [(([0, 0, 1], [0, 0, 1]), "target"), (([0, 0, 0], [0, 5, 0]), "up"),
                                        (([0, np.nan, 0], [0, 0, 1]), "eye"), (([0, 0, 0], [0, 0, np.inf]), "target"),
                                        (([0, 0, 0], [0, 0, 1], [0, 0, 0]), "up")])
def test_look_at_refuses_degenerate_input_instead_of_a_nan_pose(args, name):
    from ddp_lite.core.camera import look_at
    with pytest.raises(ValueError, match=name):
        look_at(*args)


# ------------------------------------------------------------------ 4. downloads judged for the wrong reason

def test_an_upper_case_pin_is_the_same_pin(server, tmp_path):
    [path] = run(toy(server, sha256=sha(PAYLOAD).upper()), tmp_path)
    assert path.read_bytes() == PAYLOAD
    manual = Dataset("hand", "hand", (RemoteFile("m.bin", None, "SHA256:" + sha(PAYLOAD).upper()),), "CC0", "t", "1",
                     "h", manual="put it in {dest}")
    (tmp_path / "hand").mkdir()
    (tmp_path / "hand" / "m.bin").write_bytes(PAYLOAD)
    [path] = run(manual, tmp_path)
    assert path.read_bytes() == PAYLOAD and sorted(os.listdir(tmp_path / "hand")) == ["m.bin"]  # not set aside


def test_an_upper_case_recorded_hash_is_read(server, tmp_path):
    dataset = toy(server, sha256=None)
    run(dataset, tmp_path, trust_first_download=True)
    registry = tmp_path / "toy" / "registry.json"
    records = json.loads(registry.read_text())
    records["a.bin"]["sha256"] = records["a.bin"]["sha256"].upper()
    registry.write_text(json.dumps(records))
    assert run(dataset, tmp_path)[0].read_bytes() == PAYLOAD


HTML = b"<!DOCTYPE html>\n<html><body><h1>404 Not Found</h1></body></html>\n"


def test_trust_first_download_never_records_an_html_page_as_an_image(server, tmp_path):
    dataset = toy(server, name="view1.png", data=HTML, sha256=None)
    with pytest.raises(FetchError, match="not a PNG.*HTML"):
        run(dataset, tmp_path, trust_first_download=True)
    assert not (tmp_path / "toy" / "registry.json").exists() and not (tmp_path / "toy" / "view1.png").exists()
    source = tmp_path / "from"
    source.mkdir()
    (source / "view1.png").write_bytes(HTML)
    with pytest.raises(FetchError, match="not a PNG"):
        install_from(dataset, source, dest=tmp_path, trust_first_download=True, say=lambda *a: None)
    assert not (tmp_path / "toy" / "registry.json").exists()


@pytest.mark.parametrize("name, data, ok", [("a.zip", b"PK\x03\x04rest", True), ("a.zip", HTML, False),
                                            ("a.tar.gz", b"\x1f\x8brest", True), ("a.tar.gz", b"plain", False),
                                            ("a.jpg", b"\xff\xd8\xff\xe0", True), ("d.pfm", b"Pf\n4 3\n-1\n", True),
                                            ("d.pfm", b"P5\n", False), ("x.mat", b"MATLAB 5.0 MAT-file", True),
                                            ("x.mat", HTML, False), ("notes.txt", b"hello", True),
                                            ("notes.txt", HTML, False), ("empty.bin", b"", False)])
def test_the_content_verdict(tmp_path, name, data, ok):
    from data_fetch.download import content_problem
    path = tmp_path / name
    path.write_bytes(data)
    assert (content_problem(path, name) is None) == ok


@pytest.mark.parametrize("bad", [{"retries": -1}, {"retries": 1.5}, {"retries": True}, {"backoff": -1.0},
                                 {"backoff": float("nan")}])
def test_bad_numbers_are_refused_before_any_request(server, tmp_path, bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        run(toy(server), tmp_path, **bad)
    assert server.log == []


def test_cli_refuses_negative_retries(tmp_path, capsys):
    assert fetch_main(["fetch", "middlebury2006", "--dest", str(tmp_path), "--retries", "-1"]) == 1
    assert "--retries" in capsys.readouterr().err


# ------------------------------------------------------------------ 5. a finished fit thrown away by a late error

def _complete_argv(tmp_path, out="filled.npy"):
    return ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
            "--out", f"{tmp_path}/{out}", "--profile", "ci", "--iterations", "5", "--max-side", "16"]


def test_a_terminal_that_cannot_print_an_arrow_still_gets_its_files(tmp_path, monkeypatch):
    import io
    import sys
    from test_cli import _pair
    from ddp_lite.interface.cli import main
    _pair(tmp_path)
    terminal = io.TextIOWrapper(io.BytesIO(), encoding="ascii")
    monkeypatch.setattr(sys, "stdout", terminal)
    assert main(_complete_argv(tmp_path)) == 0
    assert np.load(tmp_path / "filled.npy").shape == (60, 90) and (tmp_path / "filled.preview.png").exists()
    terminal.flush()
    assert b"? " in terminal.buffer.getvalue() or b"?" in terminal.buffer.getvalue()  # the arrow, replaced
    assert terminal.errors == "strict"  # the caller's stream as it was


def test_an_out_that_names_a_folder_or_is_given_twice_is_refused_before_the_fit(tmp_path, capsys, monkeypatch):
    from test_cli import _pair
    from ddp_lite.interface import cli_complete
    from ddp_lite.interface.cli import main
    _pair(tmp_path)
    monkeypatch.setattr(cli_complete, "_complete", lambda *a: pytest.fail("the fit started"))
    assert main(_complete_argv(tmp_path, "o.npy/")) == 2
    assert "folder" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(_complete_argv(tmp_path) + ["--out", str(tmp_path / "second.npy")])
    assert "--out was given twice" in capsys.readouterr().err
    assert not (tmp_path / "o.npy").exists() and not (tmp_path / "second.npy").exists()


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


def test_an_empty_point_cloud_is_refused_clearly_and_colours_are_scaled_or_refused(tmp_path):
    from ddp_lite.core.camera import Camera
    from ddp_lite.evaluation.fusion import fuse_depths, points_from_depth, save_ply
    camera = Camera.from_fov(8, 6, 60.0)
    empty = fuse_depths([np.full((6, 8), np.nan)], [camera], min_views=0)
    with pytest.raises(ValueError, match="no points"):
        save_ply(empty, tmp_path / "empty.ply")
    assert not (tmp_path / "empty.ply").exists()
    depth = np.full((6, 8), 2.0)
    points, colours = points_from_depth(depth, camera, np.full((6, 8, 3), 255, np.uint8))
    assert np.allclose(colours, 1.0)
    _, half = points_from_depth(depth, camera, np.full((6, 8, 3), 128, np.uint8))
    assert np.allclose(half, 128 / 255)
    with pytest.raises(ValueError, match="divide it by 255"):
        points_from_depth(depth, camera, np.full((6, 8, 3), 200.0))


def test_a_tum_list_naming_one_file_for_every_frame_is_refused(tmp_path):
    from ddp_lite.data.tum import read_tum_list
    path = tmp_path / "depth.txt"
    path.write_text("# timestamp filename\n1.0 depth/1.png\n1.1 depth/1.png\n1.2 depth/1.png\n")
    with pytest.raises(ValueError, match="depth/1.png was already listed on line 2"):
        read_tum_list(path)
    path.write_text("1.0 depth/1.png\n1.1 depth/2.png\n")
    assert len(read_tum_list(path)) == 2
