"""Bad installs with data_fetch: corrupt and hostile archives, damaged registries, destinations that are files,
FIFOs, bad numbers, names and links that lead out of the dataset's folder, and downloads judged for the right
reason (one hash normalisation, one content verdict). No network: a local folder, or a server on 127.0.0.1
(``test_data_fetch``). The refusals use ``bad_input_harness``.
"""
from __future__ import annotations

import gzip
import io
import json
import os
import tarfile
import zipfile

import pytest

from bad_input_harness import CaseList, Refused, fifo, refusal_test, run_cli, with_env
from data_fetch import Dataset, FetchError, RemoteFile, fetch, safe_extract
from data_fetch.__main__ import main as fetch_main
from data_fetch.local import install_from
from test_data_fetch import PAYLOAD, run, server, sha, toy  # noqa: F401  (server: the fixture)

CASES = CaseList()
case = CASES.case

# --------------------------------------------------------------------------- files and data_fetch

def _manual(tmp, name, data):
    (tmp / "d" / "m").mkdir(parents=True)
    (tmp / "d" / "m" / name).write_bytes(data)
    dataset = Dataset("m", "manual", (RemoteFile(name, None, None, None, True),), "CC0", "tests", "-", "-",
                      manual="put it in {dest}")
    return lambda: fetch(dataset, dest=tmp / "d", trust_first_download=True, say=lambda *a: None)


def _zip(members, method=zipfile.ZIP_STORED):
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", method) as zf:
        for name, data in members:
            zf.writestr(name, data)
    return buffer.getvalue()


def _bad_crc():
    data = bytearray(_zip([("S/calib.txt", b"ndisp=1\n" * 50)]))
    data[bytes(data).index(b"ndisp") + 3] ^= 0xFF
    return bytes(data)


def _tar(members, gz=True):
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w") as tf:
        for name, data in members:
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tf.addfile(info, io.BytesIO(data))
    return gzip.compress(buffer.getvalue()) if gz else buffer.getvalue()


_big = bytes(range(256)) * 400
for _id, _name, _data, _msg in (
        ("corrupt zip", "S.zip", _bad_crc(), "S.zip"),
        ("truncated tar.gz", "S.tar.gz", _tar([("a", _big)])[:600], "S.tar.gz"),
        ("truncated tar", "S.tar", _tar([("a", _big)], gz=False)[:3000], "S.tar"),
        ("zip bomb", "B.zip", _zip([("zeros", b"\0" * (4 << 20))], zipfile.ZIP_DEFLATED), "B.zip"),
        ("not an archive", "N.zip", b"just text", "N.zip")):
    case(f"fetch {_id}", FetchError, _msg)(lambda tmp, n=_name, d=_data: _manual(tmp, n, d))


def _toy():
    return Dataset("toy", "toy", (RemoteFile("a.bin", "http://127.0.0.1:9/a.bin"),), "CC0", "tests", "-", "-")


def _registry(text):
    def setup(tmp):
        (tmp / "toy").mkdir()
        (tmp / "toy" / "registry.json").write_text(text)
        return lambda: fetch(_toy(), dest=tmp, trust_first_download=True, say=lambda *a: None, retries=0)
    return setup


for _id, _text in (("entry a string", '{"a.bin": "abc"}'), ("a list", '["a.bin"]'), ("bad JSON", "{"),
                   ("sha256 a number", '{"a.bin": {"sha256": 5}}')):
    case(f"fetch registry.json {_id}", FetchError, "registry.json")(_registry(_text))


def _dest_file(tmp):
    (tmp / "f").write_text("x")
    return lambda: fetch(_toy(), dest=tmp / "f", trust_first_download=True, say=lambda *a: None, retries=0)


case("fetch --dest a file", FetchError, "dest")(_dest_file)
case("fetch unknown name", ValueError, "name")(lambda tmp: (lambda: fetch("nope", dest=tmp)))
case("fetch dataset an int", TypeError, "dataset")(lambda tmp: (lambda: fetch(3, dest=tmp)))
case("fetch only matches nothing", ValueError, "only")(lambda tmp: (lambda: fetch("nyu", dest=tmp, only="x*")))
case("fetch retries -1", ValueError, "retries")(lambda tmp: (lambda: fetch(_toy(), dest=tmp, retries=-1,
                                                                           trust_first_download=True)))
case("fetch retries 1.5", ValueError, "retries")(lambda tmp: (lambda: fetch(_toy(), dest=tmp, retries=1.5,
                                                                            trust_first_download=True)))


def _fetch_cli_dest_file(tmp):
    (tmp / "f").write_text("x")
    return lambda: run_cli(fetch_main, ["fetch", "nyu", "--dest", str(tmp / "f"), "--no-progress"])


case("fetch cli --dest a file", Refused, "dest")(_fetch_cli_dest_file)
case("fetch cli unknown name", Refused, "name")(lambda tmp: (lambda: run_cli(fetch_main, ["fetch", "nope"])))
case("safe_extract a text file", FetchError, "x.txt")(
    lambda tmp: ((tmp / "x.txt").write_text("x"), lambda: safe_extract(tmp / "x.txt", tmp / "out"))[1])


# --------------------------------------------------------------------------- found while hardening
case("fetch dest ''", ValueError, "dest")(lambda tmp: (lambda: fetch(_toy(), dest="", trust_first_download=True)))
case("safe_extract duplicate members", FetchError, "more than once")(
    lambda tmp: ((tmp / "dup.zip").write_bytes(_zip([("a", b"1"), ("a", b"22")])),
                 lambda: safe_extract(tmp / "dup.zip", tmp / "out"))[1])


# --------------------------------------------------------------------------- trust and FIFOs
def _hand():
    return Dataset("hand", "hand", (RemoteFile("a.bin"),), "CC0", "tests", "-", "-", manual="put a.bin in {dest}")


def _garbage_under_final_name(tmp):
    (tmp / "toy").mkdir()
    (tmp / "toy" / "a.bin").write_bytes(b"garbage, never downloaded")
    return lambda: fetch(_toy(), dest=tmp, trust_first_download=True, say=lambda *a: None, retries=0)


case("fetch --trust-first-download, garbage already there", FetchError, "trusts only bytes this fetch downloads")(
    _garbage_under_final_name)
case("fetch manual file is a FIFO (trusted)", ValueError, "FIFO")(
    lambda tmp: (fifo(tmp / "hand" / "a.bin"),
                 lambda: fetch(_hand(), dest=tmp, trust_first_download=True, say=lambda *a: None))[1])
case("fetch registry.json a FIFO", ValueError, "registry")(
    lambda tmp: ((tmp / "hand").mkdir(), (tmp / "hand" / "a.bin").write_bytes(b"x"), fifo(tmp / "hand" / "registry.json"),
                 lambda: fetch(_hand(), dest=tmp, trust_first_download=True, say=lambda *a: None))[-1])
case("fetch unpack marker a FIFO", ValueError, "unpack marker")(
    lambda tmp: ((tmp / "hand").mkdir(), (tmp / "hand" / "a.zip").write_bytes(b"x"), fifo(tmp / "hand" / ".a.zip.unpacked"),
                 lambda: fetch(Dataset("hand", "hand", (RemoteFile("a.zip", sha256=__import__("hashlib").sha256(b"x").hexdigest(),
                                                        unpack=True),), "CC0", "tests",
                                       "-", "-", manual="put a.zip in {dest}"), dest=tmp, say=lambda *a: None))[-1])
case("fetch partial download a FIFO", FetchError, "a.bin.part")(
    lambda tmp: (fifo(tmp / "toy" / "a.bin.part"),
                 lambda: fetch(_toy(), dest=tmp, trust_first_download=True, say=lambda *a: None, retries=0))[-1])
case("fetch trusts an empty manual download", FetchError, "empty (0 bytes)")(
    lambda tmp: ((tmp / "hand").mkdir(), (tmp / "hand" / "a.bin").write_bytes(b""),
                 lambda: fetch(_hand(), dest=tmp, trust_first_download=True, say=lambda *a: None))[-1])
case("fetch manual file is a folder", IsADirectoryError, "a.bin")(
    lambda tmp: ((tmp / "hand" / "a.bin").mkdir(parents=True),
                 lambda: fetch(_hand(), dest=tmp, trust_first_download=True, say=lambda *a: None))[1])


case("DDP_DATA blank", ValueError, "DDP_DATA")(
    lambda tmp: with_env("DDP_DATA", "  ", lambda: fetch(_toy(), trust_first_download=True, say=lambda *a: None)))


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)


def test_trust_first_download_records_whose_bytes(tmp_path):
    """A trusted manual download is recorded as the user's file, not as a download."""
    (tmp_path / "hand").mkdir()
    (tmp_path / "hand" / "a.bin").write_bytes(b"placed by hand")
    fetch(_hand(), dest=tmp_path, trust_first_download=True, say=lambda *a: None)
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
