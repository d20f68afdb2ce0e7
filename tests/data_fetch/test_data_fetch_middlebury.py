"""data_fetch's Middlebury entries, decoded-pixel hashes and ``fetch --from DIR`` (local folder; no network)."""
import hashlib
import json
import re
import zipfile
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
import threading

import cv2
import numpy as np
import pytest

from data_fetch import DATASETS, ChecksumError, Dataset, RemoteFile, UnpinnedFileError, fetch
from data_fetch.__main__ import main
from data_fetch.local import install_from, shared_to_registry, source_names
from data_fetch.pixels import pixel_sha256


def reference(kind, array):
    """The documented hash, written out independently: header (kind, dtype, shape) + little-endian C bytes."""
    array = np.ascontiguousarray(array)
    dtype = array.dtype.newbyteorder("<") if array.dtype.itemsize > 1 else array.dtype
    data = array.astype(dtype).tobytes()
    header = f"ddp-lite-pixels-v1\nkind={kind}\ndtype={np.dtype(dtype).str}\nshape={'x'.join(map(str, array.shape))}\n"
    return hashlib.sha256(header.encode() + data).hexdigest()


def write_pfm(path, array):
    """Little-endian PFM, rows bottom to top (as Middlebury writes them)."""
    h, w = array.shape
    path.write_bytes(f"Pf\n{w} {h}\n-1.0\n".encode() + np.flipud(array).astype("<f4").tobytes())


RNG = np.random.default_rng(0)
VIEW = RNG.integers(0, 256, (6, 8, 3), dtype=np.uint8)
DISP = RNG.integers(0, 256, (6, 8), dtype=np.uint8)
GT = RNG.random((5, 7)).astype(np.float32)
GT[0, 0] = np.inf


def tree_digest(folder):
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture
def shared(tmp_path):
    """A small folder laid out like the offline copies, and a Dataset whose pins come from ``reference``."""
    src = tmp_path / "src"
    (src / "2006-Plastic").mkdir(parents=True)
    cv2.imwrite(str(src / "2006-Plastic" / "view1.png"), VIEW)
    cv2.imwrite(str(src / "2006-Plastic" / "disp1.png"), DISP)
    (src / "2006-Plastic" / "dmin.txt").write_text("200")
    (src / "2006-Plastic" / "PROVENANCE.txt").write_text("not a dataset file")
    pins = {"HalfSize/Plastic/view1.png": reference("png", VIEW), "HalfSize/Plastic/disp1.png": reference("png", DISP),
            "HalfSize/Plastic/dmin.txt": reference("text", np.frombuffer(b"200", np.uint8))}
    files = tuple(RemoteFile(name, f"http://127.0.0.1:9/{name}", pixel_sha256=pin) for name, pin in pins.items())
    files += (RemoteFile("FullSize/Plastic/view1.png", "http://127.0.0.1:9/x", pixel_sha256="0" * 64),)
    dataset = Dataset("middlebury2006", "toy 2006", files, "cite", "tests", "tiny", "http://127.0.0.1/")
    return src, dataset


def quiet(*args, **kwargs):
    kwargs.setdefault("say", lambda *a: None)
    return install_from(*args, **kwargs)


def test_pixel_hash_follows_the_documented_header_and_ignores_png_encoding(tmp_path):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    cv2.imwrite(str(a), VIEW, [cv2.IMWRITE_PNG_COMPRESSION, 0])
    cv2.imwrite(str(b), VIEW, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    assert a.read_bytes() != b.read_bytes()
    assert pixel_sha256(a) == pixel_sha256(b) == reference("png", VIEW)
    changed = VIEW.copy()
    changed[2, 3, 1] ^= 1
    cv2.imwrite(str(b), changed)
    assert pixel_sha256(b) != pixel_sha256(a)
    deep = (RNG.integers(0, 65536, (4, 5))).astype(np.uint16)
    cv2.imwrite(str(a), deep)
    assert pixel_sha256(a) == reference("png", deep)
    write_pfm(tmp_path / "d.pfm", GT)  # rows stored bottom to top; hashed top row first
    assert pixel_sha256(tmp_path / "d.pfm") == reference("pfm", GT)
    (tmp_path / "c1.txt").write_text("cam0=[ 713.2 0 356 ; 0 1 2 ]\ndoffs= 31.34\n baseline= 178.089 \n")
    (tmp_path / "c2.txt").write_text("cam0=[713.2 0 356; 0 1 2]\ndoffs=31.34\nbaseline=178.089\n")
    (tmp_path / "c3.txt").write_text("cam0=[713.2 0 356; 0 1 2]\ndoffs=31.35\nbaseline=178.089\n")
    assert pixel_sha256(tmp_path / "c1.txt") == pixel_sha256(tmp_path / "c2.txt") != pixel_sha256(tmp_path / "c3.txt")
    with pytest.raises(ValueError, match="path"):
        pixel_sha256(tmp_path / "x.jpg")


def test_install_from_the_shared_layout_verifies_and_lands_under_dataset_names(shared, tmp_path):
    src, dataset = shared
    before = tree_digest(src)
    lines = []
    result = install_from(dataset, src, dest=tmp_path / "data", say=lines.append)
    folder = tmp_path / "data" / "middlebury2006"
    assert sorted(p.relative_to(folder).as_posix() for p in result.installed) == [
        "HalfSize/Plastic/disp1.png", "HalfSize/Plastic/dmin.txt", "HalfSize/Plastic/view1.png"]
    assert (folder / "HalfSize/Plastic/view1.png").read_bytes() == (src / "2006-Plastic/view1.png").read_bytes()
    assert result.missing == ("FullSize/Plastic/view1.png",)
    assert "installed 3 file(s)" in lines[-1] and "did not have 1 of the 4" in lines[-1]
    assert tree_digest(src) == before  # the source folder is only read
    assert not list(folder.rglob(".*"))  # no temporary left behind
    again = quiet(dataset, src, dest=tmp_path / "data")  # a second run copies nothing, verifies what is there
    assert again.installed == () and len(again.present) == 3


def test_reencoded_png_is_accepted_from_the_dataset_layout(shared, tmp_path):
    _, dataset = shared
    src = tmp_path / "own"
    (src / "HalfSize" / "Plastic").mkdir(parents=True)
    cv2.imwrite(str(src / "HalfSize/Plastic/view1.png"), VIEW, [cv2.IMWRITE_PNG_COMPRESSION, 0])
    result = quiet(dataset, src, dest=tmp_path / "data", only="HalfSize/Plastic/view1.png")
    assert [p.name for p in result.installed] == ["view1.png"] and result.missing == ()


def test_one_changed_pixel_is_refused_and_nothing_is_installed(shared, tmp_path):
    src, dataset = shared
    changed = DISP.copy()
    changed[0, 0] ^= 1
    cv2.imwrite(str(src / "2006-Plastic" / "disp1.png"), changed)
    before = tree_digest(src)
    with pytest.raises(ChecksumError) as error:
        quiet(dataset, src, dest=tmp_path / "data")
    message = str(error.value)
    assert "HalfSize/Plastic/disp1.png" in message and reference("png", DISP) in message
    assert reference("png", changed) in message
    folder = tmp_path / "data" / "middlebury2006"
    assert not [p for p in folder.rglob("*") if p.is_file()]  # not even the files that matched
    assert tree_digest(src) == before
    assert main(["fetch", "middlebury2006", "--from", str(src), "--dest", str(tmp_path / "data"),
                 "--only", "HalfSize/Plastic/disp1.png"]) == 1


def test_unpinned_file_needs_trust_and_is_then_recorded(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    (src / "notes.txt").write_text("hello")
    dataset = Dataset("toy", "toy", (RemoteFile("notes.txt", "http://127.0.0.1:9/n"),), "cc0", "t", "tiny", "h")
    with pytest.raises(UnpinnedFileError, match="--trust-first-download"):
        quiet(dataset, src, dest=tmp_path / "data")
    assert not (tmp_path / "data" / "toy" / "notes.txt").exists()
    quiet(dataset, src, dest=tmp_path / "data", trust_first_download=True)
    record = json.loads((tmp_path / "data" / "toy" / "registry.json").read_text())["notes.txt"]
    assert record["sha256"] == hashlib.sha256(b"hello").hexdigest() and "fetch --from" in record["bytes_from"]
    (src / "notes.txt").write_text("changed")  # the record now verifies later installs
    (tmp_path / "data" / "toy" / "notes.txt").unlink()
    with pytest.raises(ChecksumError, match="notes.txt"):
        quiet(dataset, src, dest=tmp_path / "data")


def test_bad_arguments_are_refused_up_front(shared, tmp_path, capsys):
    src, dataset = shared
    with pytest.raises(ValueError, match="source.*does not exist"):
        quiet(dataset, tmp_path / "nowhere", dest=tmp_path / "data")
    with pytest.raises(ValueError, match="source.*not a folder"):
        quiet(dataset, src / "2006-Plastic" / "dmin.txt", dest=tmp_path / "data")
    with pytest.raises(ValueError, match="only"):
        quiet(dataset, src, dest=tmp_path / "data", only="nothing*")
    assert not (tmp_path / "data").exists()
    assert main(["fetch", "middlebury2006", "--from", str(tmp_path / "nowhere"), "--dest", str(tmp_path)]) == 1
    assert "does not exist" in capsys.readouterr().err
    assert main(["fetch", "middlebury2006", "--retries", "-1", "--dest", str(tmp_path)]) == 1
    assert "--retries" in capsys.readouterr().err
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["fetch", "depthcomp", "--from", str(empty), "--dest", str(tmp_path / "d")]) == 1
    assert "none of the selected" in capsys.readouterr().err


def test_cli_installs_the_registered_depthcomp_file_when_its_pixels_match(tmp_path, capsys):
    """The real pin: a file with other pixels is refused by the CLI, naming both hashes."""
    src = tmp_path / "src" / "depthcomp"
    src.mkdir(parents=True)
    cv2.imwrite(str(src / "plastic-disp-hole.png"), DISP)
    assert main(["fetch", "depthcomp", "--from", str(src.parent), "--dest", str(tmp_path / "d")]) == 1
    err = capsys.readouterr().err
    assert DATASETS["depthcomp"].files[0].pixel_sha256 in err and reference("png", DISP) in err
    assert not (tmp_path / "d" / "depthcomp" / "plastic-disp-hole.png").exists()


def test_layout_mapping_both_ways():
    assert shared_to_registry("2006-Plastic/view1.png") == ("middlebury2006", "HalfSize/Plastic/view1.png")
    assert shared_to_registry("2005-Art/dmin.txt") == ("middlebury2005", "HalfSize/Art/dmin.txt")
    assert shared_to_registry("2014-Piano-Q/im0.png") == ("middlebury2014q", "MiddEval3/trainingQ/Piano/im0.png")
    assert shared_to_registry("depthcomp/plastic-disp-hole.png") == ("depthcomp", "plastic-disp-hole.png")
    assert shared_to_registry("README.md") is None
    assert source_names("middlebury2006", "HalfSize/Plastic/view1.png") == [
        "HalfSize/Plastic/view1.png", "2006-Plastic/view1.png"]
    assert source_names("middlebury2006", "FullSize/Plastic/view1.png") == ["FullSize/Plastic/view1.png"]
    assert "2014-Piano-Q/disp0GT.pfm" in source_names("middlebury2014q", "MiddEval3/trainingQ/Piano/disp0GT.pfm")


def test_registry_middlebury_entries():
    from data_fetch.registry import MIDDLEBURY2005_SCENES, MIDDLEBURY2006_SCENES

    files10 = {f"view{k}.png" for k in range(7)} | {"disp1.png", "disp5.png", "dmin.txt"}
    for name, year, scenes, count in (("middlebury2005", 2005, MIDDLEBURY2005_SCENES, 6),
                                      ("middlebury2006", 2006, MIDDLEBURY2006_SCENES, 21)):
        d = DATASETS[name]
        assert len(scenes) == count and len(d.files) == count * 3 * 10 and not d.checked
        for size in ("FullSize", "HalfSize", "ThirdSize"):
            for scene in scenes:
                assert {f.name.split("/")[2] for f in d.files if f.name.startswith(f"{size}/{scene}/")} == files10
        for f in d.files:  # one URL layout
            assert f.url == f"https://vision.middlebury.edu/stereo/data/scenes{year}/{f.name}"
            assert f.sha256 is None
    assert not {"Computer", "Drumsticks", "Dwarves"} & set(MIDDLEBURY2005_SCENES)
    assert any("Computer" in n for n in DATASETS["middlebury2005"].notes)
    pinned = {(d.name, f.name) for d in DATASETS.values() for f in d.files if f.pixel_sha256}
    offline = {("middlebury2005", f"HalfSize/{s}/{f}") for s in MIDDLEBURY2005_SCENES for f in files10}
    offline |= {("middlebury2006", f"HalfSize/{s}/{f}") for s in ("Plastic", "Baby1", "Baby2", "Baby3", "Bowling1",
                                                                  "Bowling2") for f in files10}
    assert pinned == offline | {("depthcomp", "plastic-disp-hole.png")}
    q = DATASETS["middlebury2014q"]
    assert [f.url for f in q.files] == ["https://vision.middlebury.edu/stereo/submit3/zip/MiddEval3-data-Q.zip",
                                        "https://vision.middlebury.edu/stereo/submit3/zip/MiddEval3-GT0-Q.zip"]
    members = {m for f in q.files for m, _ in f.members}
    assert members == {f"MiddEval3/trainingQ/{s}/{f}" for s in ("Adirondack", "ArtL", "Jadeplant", "Piano", "Pipes",
                                                                 "Playroom", "Playtable")
                       for f in ("im0.png", "im1.png", "calib.txt", "disp0GT.pfm", "mask0nocc.png")}
    total = len(pinned) + len(members)
    assert total == 12 * 10 + 7 * 5 + 1
    every = [h for d in DATASETS.values() for f in d.files for h in [f.pixel_sha256, *[p for _, p in f.members]] if h]
    assert all(re.fullmatch(r"[0-9a-f]{64}", h) for h in every) and len(set(every)) > 100
    assert "middlebury2014" in DATASETS and len(DATASETS["middlebury2014"].files) == 46


def test_list_counts_pixel_pins_and_says_archives_are_trusted_on_first_use(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    block = out.split("middlebury2006  —")[1].split("\n\n")[0]
    assert "pixel hash" in block and "for 60, byte SHA-256 for 0, unverified for 570" in block
    q = out.split("middlebury2014q  —")[1].split("\n\n")[0]
    assert "trust-on-first-download" in q and "35 unpacked file(s) checked by pixel hash" in q


class _Server:
    def __init__(self, files):
        owner = self
        self.files = files

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def do_GET(self):
                data = owner.files.get(self.path)
                if data is None:
                    self.send_error(404)
                    return
                self.send_response(200)
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}"
        threading.Thread(target=self.httpd.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True).start()


def test_fetch_checks_pixel_pins_of_downloads_and_of_unpacked_members(tmp_path):
    good = cv2.imencode(".png", VIEW)[1].tobytes()
    changed = VIEW.copy()
    changed[1, 1, 1] ^= 1
    bad = cv2.imencode(".png", changed)[1].tobytes()
    buffer = tmp_path / "a.zip"
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("MiddEval3/trainingQ/S/im0.png", good)
        archive.writestr("MiddEval3/trainingQ/S/im1.png", bad)
    server = _Server({"/good.png": good, "/bad.png": bad, "/a.zip": buffer.read_bytes()})
    try:
        pin = reference("png", VIEW)

        def dataset(*files):
            return Dataset("toy", "toy", files, "cc0", "t", "tiny", "h")

        run = dict(dest=tmp_path / "d", progressbar=False, backoff=0.0, say=lambda *a: None)
        [path] = fetch(dataset(RemoteFile("good.png", f"{server.url}/good.png", pixel_sha256=pin)), **run)
        assert path.read_bytes() == good  # no --trust-first-download needed: verified by its pixels
        with pytest.raises(ChecksumError, match="bad.png.*" + pin):
            fetch(dataset(RemoteFile("bad.png", f"{server.url}/bad.png", pixel_sha256=pin)), **run)
        assert not (tmp_path / "d" / "toy" / "bad.png").exists()
        members = (("MiddEval3/trainingQ/S/im0.png", pin), ("MiddEval3/trainingQ/S/im1.png", pin))
        with pytest.raises(ChecksumError, match="im1.png"):
            fetch(dataset(RemoteFile("a.zip", f"{server.url}/a.zip", unpack=True, members=members)),
                  trust_first_download=True, **run)
        folder = tmp_path / "d" / "toy"
        assert not (folder / "MiddEval3/trainingQ/S/im1.png").exists() and not (folder / "a.zip").exists()
        assert "a.zip" not in json.loads((folder / "registry.json").read_text()) if (folder / "registry.json").exists() \
            else True
    finally:
        server.httpd.shutdown()
        server.httpd.server_close()
