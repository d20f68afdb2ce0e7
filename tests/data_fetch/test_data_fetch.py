"""Offline tests of data_fetch against a local HTTP server on 127.0.0.1 (Range support, dropped connections)."""
import hashlib
import io
import json
import re
import socket
import tarfile
import threading
import zipfile
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from data_fetch import (DATASETS, ChecksumError, Dataset, FetchError, ManualDownloadRequired, RemoteFile,
                        UnpinnedFileError, UnsafeArchiveError, data_dir, fetch, safe_extract)
from data_fetch.__main__ import main

PAYLOAD = bytes(range(256)) * 40  # 10240 bytes


def sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


class Server:
    """Serves ``files`` {path: bytes}; logs (path, Range header); ``drop`` {path: n} cuts the next
    response to that path after n bytes (Content-Length still announces the full size). Like a real
    server it sends an ETag (the content's hash) and honours If-Range (a stale validator → the whole
    file, 200); ``validators=False`` sends none, ``if_range=False`` ignores If-Range."""

    def __init__(self):
        self.files, self.log, self.drop = {}, [], {}
        self.validators, self.if_range = True, True
        owner = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def do_GET(self):
                owner.log.append((self.path, self.headers.get("Range")))
                data = owner.files.get(self.path)
                if data is None:
                    self.send_error(404)
                    return
                start, status = 0, 200
                etag = f'"{sha(data)[:16]}"'
                match = re.fullmatch(r"bytes=(\d+)-", self.headers.get("Range") or "")
                stale = owner.if_range and self.headers.get("If-Range") not in (None, etag)
                if match and not stale:
                    start, status = int(match.group(1)), 206
                    if start >= len(data):
                        self.send_response(416)
                        self.send_header("Content-Range", f"bytes */{len(data)}")
                        self.end_headers()
                        return
                self.send_response(status)
                if owner.validators:
                    self.send_header("ETag", etag)
                self.send_header("Content-Length", str(len(data) - start))
                if status == 206:
                    self.send_header("Content-Range", f"bytes {start}-{len(data) - 1}/{len(data)}")
                self.end_headers()
                body = data[start:]
                cut = owner.drop.pop(self.path, None)
                self.wfile.write(body if cut is None else body[:cut])
                self.wfile.flush()

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}"
        self.thread = threading.Thread(target=self.httpd.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True)
        self.thread.start()


@pytest.fixture
def server():
    s = Server()
    yield s
    s.httpd.shutdown()
    s.httpd.server_close()


def toy(server, name="a.bin", data=PAYLOAD, sha256="auto", unpack=False, dataset="toy"):
    server.files[f"/{name}"] = data
    digest = sha(data) if sha256 == "auto" else sha256
    return Dataset(dataset, "toy", (RemoteFile(name, f"{server.url}/{name}", digest, len(data), unpack),),
                   "CC0", "tests", "10 kB", "http://127.0.0.1/")


def run(dataset, dest, **kw):
    kw.setdefault("progressbar", False)
    kw.setdefault("backoff", 0.0)
    return fetch(dataset, dest=dest, say=lambda *a: None, **kw)


def test_fetch_verifies_and_never_fetches_twice(server, tmp_path):
    dataset = toy(server)
    [path] = run(dataset, tmp_path)
    assert path == tmp_path / "toy" / "a.bin" and path.read_bytes() == PAYLOAD
    assert len(server.log) == 1 and server.log[0][1] is None
    assert run(dataset, tmp_path) == [path]
    assert len(server.log) == 1  # the second fetch made no request
    assert sorted(p.name for p in path.parent.iterdir()) == ["a.bin"]


def test_interrupted_download_resumes_with_range(server, tmp_path):
    dataset = toy(server)
    server.drop["/a.bin"] = 3000
    with pytest.raises(FetchError, match="resumes"):
        run(dataset, tmp_path, retries=0)
    folder = tmp_path / "toy"
    assert not (folder / "a.bin").exists()
    assert (folder / "a.bin.part").read_bytes() == PAYLOAD[:3000]
    [path] = run(dataset, tmp_path)
    assert server.log[-1] == ("/a.bin", "bytes=3000-")
    assert path.read_bytes() == PAYLOAD and not (folder / "a.bin.part").exists()


def test_dropped_connection_is_retried_within_one_fetch(server, tmp_path):
    dataset = toy(server)
    server.drop["/a.bin"] = 5000
    [path] = run(dataset, tmp_path, retries=2)
    assert [r for _, r in server.log] == [None, "bytes=5000-"]
    assert path.read_bytes() == PAYLOAD


def test_wrong_checksum_is_refused_and_leaves_nothing(server, tmp_path):
    dataset = toy(server, sha256=sha(b"something else"))
    with pytest.raises(ChecksumError, match="does not match"):
        run(dataset, tmp_path)
    assert list((tmp_path / "toy").iterdir()) == []  # neither the final name nor a .part nor a temp file


def test_unpinned_file_needs_trust_then_is_recorded_and_verified(server, tmp_path):
    dataset = toy(server, sha256=None)
    with pytest.raises(UnpinnedFileError, match="--trust-first-download"):
        run(dataset, tmp_path)
    assert server.log == []
    [path] = run(dataset, tmp_path, trust_first_download=True)
    records = json.loads((tmp_path / "toy" / "registry.json").read_text())
    assert records["a.bin"]["sha256"] == sha(PAYLOAD) and records["a.bin"]["how"] == "trust-first-download"
    run(dataset, tmp_path)  # the recorded hash now stands in for a pin: no flag, no request
    assert len(server.log) == 1
    server.files["/a.bin"] = PAYLOAD[::-1]  # the server's copy changes ...
    path.unlink()
    with pytest.raises(ChecksumError):  # ... and the recorded hash catches it
        run(dataset, tmp_path)
    assert not path.exists() and not path.with_name("a.bin.part").exists()


def test_offline_gives_a_clear_message(tmp_path):
    with socket.socket() as sock:  # a port nobody listens on
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    dataset = Dataset("toy", "toy", (RemoteFile("a.bin", f"http://127.0.0.1:{port}/a.bin", sha(PAYLOAD)),),
                      "CC0", "tests", "-", "-")
    with pytest.raises(FetchError, match="offline"):
        run(dataset, tmp_path, retries=0)


def zip_bytes(members) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as zf:
        for name, data, mode in members:
            info = zipfile.ZipInfo(name)
            if mode:
                info.external_attr = mode << 16
            zf.writestr(info, data)
    return buffer.getvalue()


def tar_bytes(members) -> bytes:
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tf:
        for name, data, kind in members:
            info = tarfile.TarInfo(name)
            if kind == "file":
                info.size = len(data)
                tf.addfile(info, io.BytesIO(data))
            else:
                info.type = tarfile.SYMTYPE if kind == "symlink" else tarfile.LNKTYPE
                info.linkname = data
                tf.addfile(info)
    return buffer.getvalue()


def test_archive_is_unpacked_once(server, tmp_path):
    data = zip_bytes([("Scene-perfect/calib.txt", b"ndisp=1\n", 0), ("Scene-perfect/im0.png", b"png", 0)])
    dataset = toy(server, "Scene-perfect.zip", data, unpack=True)
    run(dataset, tmp_path)
    folder = tmp_path / "toy"
    assert (folder / "Scene-perfect" / "calib.txt").read_bytes() == b"ndisp=1\n"
    (folder / "Scene-perfect" / "calib.txt").write_bytes(b"edited")
    run(dataset, tmp_path)
    assert len(server.log) == 1 and (folder / "Scene-perfect" / "calib.txt").read_bytes() == b"edited"


UNSAFE = {
    "zip-dotdot": ("zip", [("ok.txt", b"ok", 0), ("../evil.txt", b"x", 0)]),
    "zip-absolute": ("zip", [("ok.txt", b"ok", 0), ("/tmp/evil.txt", b"x", 0)]),
    "zip-symlink": ("zip", [("ok.txt", b"ok", 0), ("link", b"../../outside", 0o120777)]),
    "tar-dotdot": ("tar", [("ok.txt", b"ok", "file"), ("sub/../../evil.txt", b"x", "file")]),
    "tar-absolute": ("tar", [("ok.txt", b"ok", "file"), ("/tmp/evil.txt", b"x", "file")]),
    "tar-symlink": ("tar", [("ok.txt", b"ok", "file"), ("link", "../outside", "symlink")]),
    "tar-hardlink": ("tar", [("ok.txt", b"ok", "file"), ("hard", "/etc/passwd", "hardlink")]),
}


@pytest.mark.parametrize("case", sorted(UNSAFE))
def test_unsafe_archives_are_refused_and_write_nothing(tmp_path, case):
    kind, members = UNSAFE[case]
    archive = tmp_path / f"bad.{'zip' if kind == 'zip' else 'tar.gz'}"
    archive.write_bytes(zip_bytes(members) if kind == "zip" else tar_bytes(members))
    target = tmp_path / "out" / "target"
    with pytest.raises(UnsafeArchiveError):
        safe_extract(archive, target)
    assert not target.exists() and not (tmp_path / "out").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == [archive.name]


def test_unsafe_archive_through_fetch(server, tmp_path):
    dataset = toy(server, "bad.zip", zip_bytes([("../evil.txt", b"x", 0)]), unpack=True)
    with pytest.raises(UnsafeArchiveError, match=r"\.\."):
        run(dataset, tmp_path)
    assert not (tmp_path / "evil.txt").exists() and not (tmp_path / "toy" / ".bad.zip.unpacked").exists()


def test_manual_dataset_prints_steps_then_verifies_and_unpacks(tmp_path):
    data = zip_bytes([("training/calib.txt", b"P_rect_02: 1\n", 0)])
    manual = Dataset("hand", "by hand", (RemoteFile("data.zip", None, None, None, True),), "CC BY-NC-SA 3.0",
                     "tests", "-", "-", manual="Download data.zip and put it in {dest}")
    with pytest.raises(ManualDownloadRequired) as info:
        run(manual, tmp_path)
    assert str(tmp_path / "hand") in str(info.value) and "data.zip" in str(info.value)
    (tmp_path / "hand").mkdir()
    (tmp_path / "hand" / "data.zip").write_bytes(data)
    with pytest.raises(UnpinnedFileError):
        run(manual, tmp_path)
    run(manual, tmp_path, trust_first_download=True)
    assert (tmp_path / "hand" / "training" / "calib.txt").exists()
    pinned = Dataset("hand", "by hand", (RemoteFile("data.zip", None, sha(b"other"), None, True),), "-", "-", "-",
                     "-", manual="put it in {dest}")
    with pytest.raises(ChecksumError, match="rejected"):
        run(pinned, tmp_path)
    assert not (tmp_path / "hand" / "data.zip").exists() and (tmp_path / "hand" / "data.zip.rejected").exists()


def test_registry_is_honest_and_complete():
    assert {"middlebury2014", "middlebury2006", "tnt", "nyu", "kitti2015"} <= set(DATASETS)
    for d in DATASETS.values():
        assert d.licence and d.use and d.size_note and d.homepage
        for f in d.files:
            assert f.sha256 is None or re.fullmatch(r"[0-9a-f]{64}", f.sha256)
    assert not DATASETS["kitti2015"].automatic and DATASETS["kitti2015"].manual
    assert DATASETS["middlebury2014"].automatic
    names = {f.name for f in DATASETS["middlebury2014"].files}
    assert {"Adirondack-perfect.zip", "Adirondack-imperfect.zip"} <= names
    assert {"FullSize/Plastic/disp1.png", "HalfSize/Baby1/view1.png", "ThirdSize/Bowling1/dmin.txt"} <= \
        {f.name for f in DATASETS["middlebury2006"].files}


def test_cli_list_and_manual_exit_code(tmp_path, capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in DATASETS) and "--trust-first-download" in out and "licence" in out
    assert main(["fetch", "kitti2015", "--dest", str(tmp_path)]) == 2
    assert "data_scene_flow.zip" in capsys.readouterr().out
    assert main(["fetch", "nyu", "--dest", str(tmp_path)]) == 1
    assert "--trust-first-download" in capsys.readouterr().err


def test_data_dir(monkeypatch, tmp_path):
    monkeypatch.setenv("DDP_DATA", str(tmp_path))
    assert data_dir() == tmp_path and data_dir(tmp_path / "x") == tmp_path / "x"
    monkeypatch.delenv("DDP_DATA")
    assert data_dir().name == "ddp-lite"


# --------------------------------------------------------------------------- resume and archives

def listing(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")) if folder.exists() else []


def test_resume_after_the_server_file_changed_restarts_instead_of_splicing(server, tmp_path):
    old, new = PAYLOAD, bytes(reversed(PAYLOAD))
    dataset = toy(server, data=old, sha256=None)
    server.drop["/a.bin"] = 3000
    with pytest.raises(FetchError, match="resumes"):
        run(dataset, tmp_path, retries=0, trust_first_download=True)
    server.files["/a.bin"] = new  # the file changes on the server between the two fetches
    [path] = run(dataset, tmp_path, trust_first_download=True)
    assert server.log[-1] == ("/a.bin", "bytes=3000-")  # a resume was asked, with If-Range ...
    assert path.read_bytes() == new  # ... and the server's answer (the whole new file) replaced the old bytes
    records = json.loads((tmp_path / "toy" / "registry.json").read_text())
    assert records["a.bin"]["sha256"] == sha(new)
    assert listing(tmp_path / "toy") == ["a.bin", "registry.json"]


def test_resume_without_validators_or_if_range_never_splices(server, tmp_path):
    old, new = PAYLOAD, bytes(reversed(PAYLOAD))
    for validators, if_range in ((False, True), (True, False)):
        server.validators, server.if_range = validators, if_range
        server.files["/a.bin"] = old
        dataset = toy(server, data=old, sha256=None)
        server.drop["/a.bin"] = 3000
        with pytest.raises(FetchError):
            run(dataset, tmp_path / str(validators), retries=0, trust_first_download=True)
        server.files["/a.bin"] = new
        [path] = run(dataset, tmp_path / str(validators), trust_first_download=True)
        assert path.read_bytes() == new, (validators, if_range)


def bad_crc_zip() -> bytes:
    data = bytearray(zip_bytes([("S/calib.txt", b"ndisp=1\n" * 50, 0)]))
    at = bytes(data).index(b"ndisp=1\n" * 50)  # stored, not deflated: the bytes are in the archive as is
    data[at + 5] ^= 0xFF
    return bytes(data)


def test_corrupt_zip_is_a_fetch_error_leaves_nothing_and_is_not_trusted(server, tmp_path, capsys):
    dataset = toy(server, "S.zip", bad_crc_zip(), sha256=None, unpack=True)
    with pytest.raises(FetchError, match="corrupt"):
        run(dataset, tmp_path, trust_first_download=True)
    assert listing(tmp_path / "toy") == []  # no half-extracted member, no archive kept, no recorded hash
    assert listing(tmp_path) == ["toy"]  # no staging folder left beside it


def test_zip_bomb_and_truncated_tars_are_refused(tmp_path):
    bomb = tmp_path / "bomb.zip"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("zeros.bin", b"\0" * (8 << 20))
    with pytest.raises(UnsafeArchiveError, match="expand"):
        safe_extract(bomb, tmp_path / "out")
    full = tar_bytes([("a.txt", bytes(range(256)) * 400, "file")])
    for name, data in (("t.tar.gz", full[: len(full) // 2]), ("t.tar", tar_bytes([("a.txt", b"x" * 5000, "file")]))):
        if name == "t.tar":
            import gzip
            data = gzip.decompress(data)[:3000]
        (tmp_path / name).write_bytes(data)
        with pytest.raises(FetchError, match="corrupt or truncated"):
            safe_extract(tmp_path / name, tmp_path / "out")
    assert listing(tmp_path / "out") == []


def test_dest_naming_a_file_and_bad_registry_entries_are_clear(server, tmp_path):
    dataset = toy(server)
    (tmp_path / "file").write_text("x")
    with pytest.raises(FetchError, match="dest"):
        run(dataset, tmp_path / "file")
    folder = tmp_path / "root" / "toy"
    folder.mkdir(parents=True)
    for text in ('{"a.bin": "abc"}', '["a.bin"]', '{"a.bin": {"sha256": 5}}'):
        (folder / "registry.json").write_text(text)
        with pytest.raises(FetchError, match="registry.json"):
            run(toy(server, sha256=None), tmp_path / "root", trust_first_download=True)
        assert (folder / "registry.json").read_text() == text  # not overwritten


SAME_FILE = {
    "zip-dot-slash": ("zip", [("a.txt", b"1", 0), ("./a.txt", b"2", 0)]),
    "zip-double-slash": ("zip", [("dir/a.txt", b"1", 0), ("dir//a.txt", b"2", 0)]),
    "zip-case": ("zip", [("Scene/im0.png", b"1", 0), ("scene/IM0.png", b"2", 0)]),
    "zip-unicode-form": ("zip", [("caf\u00e9.txt", b"1", 0), ("cafe\u0301.txt", b"2", 0)]),
    "zip-file-under-a-file": ("zip", [("a", b"1", 0), ("a/b.txt", b"2", 0)]),
    "tar-dot-slash": ("tar", [("./a.txt", b"1", "file"), ("a.txt", b"2", "file")]),
    "tar-dot-component": ("tar", [("dir/./a.txt", b"1", "file"), ("dir/a.txt", b"2", "file")]),
}


@pytest.mark.parametrize("case", sorted(SAME_FILE))
def test_members_landing_on_one_file_refuse_the_archive(tmp_path, case):
    kind, members = SAME_FILE[case]
    archive = tmp_path / f"twice.{'zip' if kind == 'zip' else 'tar.gz'}"
    archive.write_bytes(zip_bytes(members) if kind == "zip" else tar_bytes(members))
    with pytest.raises(UnsafeArchiveError, match="same file|lies under|same name"):
        safe_extract(archive, tmp_path / "out")
    assert sorted(p.name for p in tmp_path.iterdir()) == [archive.name]


def test_a_refetch_unpacks_a_missing_file_again_and_names_a_changed_one(server, tmp_path):
    data = zip_bytes([("./Scene/calib.txt", b"ndisp=1\n", 0), ("Scene/im0.png", b"png", 0)])
    dataset = toy(server, "Scene.zip", data, unpack=True)
    run(dataset, tmp_path)
    scene = tmp_path / "toy" / "Scene"
    (scene / "calib.txt").unlink()
    (scene / "im0.png").write_bytes(b"edited by the user")
    said = []
    fetch(dataset, dest=tmp_path, progressbar=False, backoff=0.0, say=said.append)
    assert (scene / "calib.txt").read_bytes() == b"ndisp=1\n"  # back, from the verified archive
    assert (scene / "im0.png").read_bytes() == b"edited by the user"  # the user's edit is kept, and said
    assert any("missing" in line and "Scene/calib.txt" in line for line in said), said
    assert any("differ" in line and "Scene/im0.png" in line for line in said), said
    assert len(server.log) == 1


def test_a_second_rejected_manual_download_does_not_replace_the_first(tmp_path):
    pinned = Dataset("hand", "by hand", (RemoteFile("data.zip", None, sha(b"right"), None, False),), "-", "-", "-",
                     "-", manual="put it in {dest}")
    folder = tmp_path / "hand"
    folder.mkdir()
    for attempt in (b"first wrong", b"second wrong"):
        (folder / "data.zip").write_bytes(attempt)
        with pytest.raises(ChecksumError, match="rejected"):
            run(pinned, tmp_path)
    assert (folder / "data.zip.rejected").read_bytes() == b"first wrong"
    assert (folder / "data.zip.rejected-2").read_bytes() == b"second wrong"
