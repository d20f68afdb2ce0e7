"""Installs under concurrency and interruption, and text files as editors save them (no network: a local
folder, or a server on 127.0.0.1). Real processes: two installs at once, an install killed with SIGKILL."""
import hashlib
import json
import multiprocessing
import os
import shutil
import signal
import sys
import time

import numpy as np
import pytest

from data_fetch import ChecksumError, Dataset, FetchError, RemoteFile, fetch
from data_fetch.local import install_from

N_FILES = 200
posix_only = pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL and fork-free spawn timing are POSIX")


def sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def toy_dataset(n=N_FILES, url="http://127.0.0.1:9"):
    """Unpinned text files: each one trusted on first use and recorded."""
    return Dataset("toy", "toy", tuple(RemoteFile(f"part{k:02d}/notes{k:02d}.txt", f"{url}/notes{k:02d}.txt")
                                       for k in range(n)), "cc0", "tests", "tiny", "http://127.0.0.1/")


def toy_source(folder, n=N_FILES):
    for k in range(n):
        (folder / f"part{k:02d}").mkdir(parents=True, exist_ok=True)
        (folder / f"part{k:02d}" / f"notes{k:02d}.txt").write_text(f"file {k}\n" * 50)
    return folder


def every_path(root):
    return sorted(p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file())


def _install_at_once(barrier, source, dest, queue):
    barrier.wait()
    try:
        install_from(toy_dataset(), source, dest=dest, trust_first_download=True, say=lambda *a: None)
        queue.put("ok")
    except Exception as error:  # noqa: BLE001: the parent asserts on what each process ended with
        queue.put(f"{type(error).__name__}: {error}")


@posix_only
def test_two_installs_into_one_folder_at_once_record_every_file(tmp_path):
    source = toy_source(tmp_path / "src")
    context = multiprocessing.get_context("spawn")
    barrier, queue = context.Barrier(2), context.Queue()
    workers = [context.Process(target=_install_at_once, args=(barrier, source, tmp_path / "data", queue))
               for _ in range(2)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(120)
    outcomes = [queue.get(timeout=5) for _ in workers]
    assert outcomes == ["ok", "ok"]
    folder = tmp_path / "data" / "toy"
    records = json.loads((folder / "registry.json").read_text())
    for k in range(N_FILES):
        name = f"part{k:02d}/notes{k:02d}.txt"
        assert records[name]["sha256"] == sha((source / name).read_bytes()), name
    # nothing but the data and its registry: no lock file, no temporary
    assert every_path(tmp_path / "data") == sorted([f"toy/part{k:02d}/notes{k:02d}.txt" for k in range(N_FILES)]
                                                   + ["toy/registry.json"])


def _install_then_hang(source, dest, ready):
    """Install, but stop for ever after the third copy (the parent kills the process there)."""
    import data_fetch.local as local
    copy, copies = shutil.copyfile, []

    def copy_then_hang(origin, target):
        copy(origin, target)
        copies.append(target)
        if len(copies) == 3:
            open(ready, "w").close()
            time.sleep(600)
    local.shutil.copyfile = copy_then_hang
    install_from(toy_dataset(), source, dest=dest, trust_first_download=True, say=lambda *a: None)


def _wait_for(path, process, seconds=60):
    deadline = time.monotonic() + seconds
    while not os.path.exists(path):
        assert process.is_alive() and time.monotonic() < deadline, "the child did not reach the point to kill it at"
        time.sleep(0.05)


@posix_only
def test_an_install_killed_midway_leaves_nothing_behind_after_a_rerun(tmp_path):
    source, dest = toy_source(tmp_path / "src"), tmp_path / "data"
    context = multiprocessing.get_context("spawn")
    child = context.Process(target=_install_then_hang, args=(source, dest, tmp_path / "ready"))
    child.start()
    _wait_for(tmp_path / "ready", child)
    os.kill(child.pid, signal.SIGKILL)
    child.join(10)
    assert child.exitcode == -signal.SIGKILL
    left = [p for p in every_path(dest) if not p.endswith("registry.json")]
    assert left and not any(p.endswith(f"notes{k:02d}.txt") for p in left for k in range(N_FILES))  # only temporaries
    lines = []
    result = install_from(toy_dataset(), source, dest=dest, trust_first_download=True, say=lines.append)
    assert len(result.installed) == N_FILES
    assert any("removed 3 temporary file(s)" in line for line in lines)
    assert every_path(dest) == sorted([f"toy/part{k:02d}/notes{k:02d}.txt" for k in range(N_FILES)]
                                      + ["toy/registry.json"])
    records = json.loads((dest / "toy" / "registry.json").read_text())
    assert len(records) == N_FILES


def _fetch_then_hang(url, dest, ready):
    """Fetch, but stop for ever once pooch has made its temporary file (the parent kills the process there)."""
    from data_fetch.download import ResumableDownloader

    def hang(self, url, output_file, pooch=None, check_only=False):
        open(ready, "w").close()
        time.sleep(600)
    ResumableDownloader.__call__ = hang
    fetch(toy_dataset(1, url), dest=dest, trust_first_download=True, say=lambda *a: None, progressbar=False)


@posix_only
def test_a_fetch_killed_midway_leaves_nothing_behind_after_a_rerun(tmp_path):
    from test_data_fetch import Server
    server = Server()
    try:
        server.files["/notes00.txt"] = b"file 0\n" * 50
        context = multiprocessing.get_context("spawn")
        child = context.Process(target=_fetch_then_hang, args=(server.url, tmp_path / "data", tmp_path / "ready"))
        child.start()
        _wait_for(tmp_path / "ready", child)
        os.kill(child.pid, signal.SIGKILL)
        child.join(10)
        assert [p for p in every_path(tmp_path / "data")]  # pooch's temporary file is there
        lines = []
        fetch(toy_dataset(1, server.url), dest=tmp_path / "data", trust_first_download=True, say=lines.append,
              progressbar=False, backoff=0.0)
        assert any("removed 1 temporary file(s)" in line for line in lines)
        assert every_path(tmp_path / "data") == ["toy/part00/notes00.txt", "toy/registry.json"]
    finally:
        server.httpd.shutdown()
        server.httpd.server_close()


# --------------------------------------------------------------------------- text files as editors save them

EDITORS = {"bom": lambda text: ("\ufeff" + text).encode("utf-8"), "crlf": lambda text: (text + "\r\n").encode(),
           "bom+crlf": lambda text: ("\ufeff" + text + "\r\n").encode("utf-8"),
           "cr": lambda text: (text + "\r").encode(), "utf-16": lambda text: (text + "\r\n").encode("utf-16")}


@pytest.mark.parametrize("saved", sorted(EDITORS))
def test_a_pinned_dmin_saved_by_an_editor_installs(tmp_path, saved):
    """The pin of a text file is of its tokens; the same number saved with a BOM or CRLF is the same text."""
    tokens = np.frombuffer(b"200", np.uint8)
    header = f"ddp-lite-pixels-v1\nkind=text\ndtype=|u1\nshape={tokens.size}\n".encode()
    pin = hashlib.sha256(header + tokens.tobytes()).hexdigest()
    dataset = Dataset("middlebury2006", "toy", (RemoteFile("HalfSize/Plastic/dmin.txt", "http://127.0.0.1:9/d",
                                                           pixel_sha256=pin),), "c", "t", "s", "h")
    (tmp_path / "src" / "2006-Plastic").mkdir(parents=True)
    (tmp_path / "src" / "2006-Plastic" / "dmin.txt").write_bytes(EDITORS[saved]("200"))
    result = install_from(dataset, tmp_path / "src", dest=tmp_path / "data", say=lambda *a: None)
    assert [p.name for p in result.installed] == ["dmin.txt"]


@pytest.mark.parametrize("saved", sorted(EDITORS))
def test_the_rail_loader_reads_a_dmin_saved_by_an_editor(tmp_path, saved):
    from ddp_lite.data.middlebury_rail import load_rail_scene  # here: the spawned installs need not import torch
    from ddp_lite.data.samples import sample_scene
    folder = tmp_path / "Plastic"
    shutil.copytree(sample_scene("Plastic"), folder)
    reference = load_rail_scene(folder)
    dmin = (folder / "dmin.txt").read_bytes().decode("ascii").split()[0]
    (folder / "dmin.txt").write_bytes(EDITORS[saved](dmin))
    scene = load_rail_scene(folder)
    assert scene.meta["doffs"] == reference.meta["doffs"] == float(dmin) / 4
    np.testing.assert_array_equal(scene[0].depth, reference[0].depth)


def test_a_recorded_text_file_verifies_a_copy_saved_with_crlf(tmp_path):
    dataset = Dataset("toy", "toy", (RemoteFile("notes.txt", "http://127.0.0.1:9/n"),), "cc0", "t", "tiny", "h")
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "notes.txt").write_bytes(b"one\ntwo\n")
    install_from(dataset, tmp_path / "src", dest=tmp_path / "data", trust_first_download=True, say=None)
    (tmp_path / "data" / "toy" / "notes.txt").unlink()
    (tmp_path / "src" / "notes.txt").write_bytes(b"\xef\xbb\xbfone\r\ntwo\r\n")  # the same text, as Notepad saves it
    assert [p.name for p in install_from(dataset, tmp_path / "src", dest=tmp_path / "data", say=None).installed] \
        == ["notes.txt"]
    (tmp_path / "data" / "toy" / "notes.txt").unlink()
    (tmp_path / "src" / "notes.txt").write_bytes(b"one\r\nthree\r\n")  # other text: still refused
    with pytest.raises(ChecksumError, match="notes.txt"):
        install_from(dataset, tmp_path / "src", dest=tmp_path / "data", say=None)


def test_a_trusted_text_file_is_said_to_be_unverified_and_must_be_text(tmp_path):
    dataset = Dataset("toy", "toy", (RemoteFile("notes.txt", "http://127.0.0.1:9/n"),), "cc0", "t", "tiny", "h")
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "notes.txt").write_bytes(b"\x00\x01\x02binary")
    with pytest.raises(FetchError, match="notes.txt.*NUL bytes"):
        install_from(dataset, tmp_path / "src", dest=tmp_path / "data", trust_first_download=True, say=None)
    assert not (tmp_path / "data" / "toy" / "notes.txt").exists()
    (tmp_path / "src" / "notes.txt").write_text("hello\n")
    lines = []
    install_from(dataset, tmp_path / "src", dest=tmp_path / "data", trust_first_download=True, say=lines.append)
    assert any("notes.txt" in line and "unverified" in line for line in lines)


def test_say_none_is_silent_and_a_bad_say_is_refused_before_any_work(tmp_path, capsys):
    source = toy_source(tmp_path / "src", 3)
    with pytest.raises(TypeError, match="say"):
        install_from(toy_dataset(3), source, dest=tmp_path / "data", trust_first_download=True, say="loud")
    with pytest.raises(TypeError, match="say"):
        fetch(toy_dataset(3), dest=tmp_path / "data", trust_first_download=True, say=42)
    assert not (tmp_path / "data").exists()
    result = install_from(toy_dataset(3), source, dest=tmp_path / "data", trust_first_download=True, say=None)
    assert len(result.installed) == 3 and capsys.readouterr().out == ""
    records = json.loads((tmp_path / "data" / "toy" / "registry.json").read_text())
    assert len(records) == 3
