"""Writing outputs: a set of files lands whole or not at all, one command at a time, whatever stops it
(an error, a full disk, SIGTERM); a lock left by a process that is gone does not block."""
import errno
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from ddp_lite.core.files import write_bytes_atomic
from ddp_lite.core.outpaths import lock_path, output_lock, output_set
from ddp_lite.interface.cli import main

HOLDER = """
import sys, time
from ddp_lite.core.files import write_bytes_atomic
from ddp_lite.core.outpaths import output_set
a, b = sys.argv[1:3]
with output_set([a, b], "--out") as staged:
    write_bytes_atomic(staged(a), b"new a")
    print("ready", flush=True)
    time.sleep(60)  # a long write of b: SIGTERM comes here
    write_bytes_atomic(staged(b), b"new b")
"""


def _old_pair(tmp_path):
    a, b = tmp_path / "depth.npy", tmp_path / "depth.preview.png"
    a.write_bytes(b"old a")
    b.write_bytes(b"old b")
    return a, b


def test_sigterm_mid_set_leaves_the_old_files_and_a_concurrent_writer_is_refused(tmp_path):
    a, b = _old_pair(tmp_path)
    child = subprocess.Popen([sys.executable, "-c", HOLDER, str(a), str(b)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "ready"
        with pytest.raises(ValueError, match=rf"--out .*another ddp-lite command \(process {child.pid}"):
            with output_set([b], "--out"):  # the other command's preview is this one's output
                pass
        child.terminate()  # SIGTERM
        child.wait(timeout=30)
    finally:
        child.kill()
    assert child.returncode != 0
    assert (a.read_bytes(), b.read_bytes()) == (b"old a", b"old b")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["depth.npy", "depth.preview.png"]  # no temp, no lock


def test_a_full_disk_midway_keeps_every_old_file(tmp_path, monkeypatch):
    a, b = _old_pair(tmp_path)
    real_write, calls = os.write, []

    def second_write_fails(fd, data):
        calls.append(fd)
        if len(calls) > 1:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(fd, data)

    with pytest.raises(OSError, match="No space"):
        with output_set([a, b], "--out") as staged:
            monkeypatch.setattr(os, "write", second_write_fails)
            write_bytes_atomic(staged(a), b"new a")
            write_bytes_atomic(staged(b), b"new b")
    monkeypatch.undo()
    assert (a.read_bytes(), b.read_bytes()) == (b"old a", b"old b")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["depth.npy", "depth.preview.png"]
    with output_set([a, b], "--out") as staged:  # and the lock is free again
        write_bytes_atomic(staged(a), b"new a")
        write_bytes_atomic(staged(b), b"new b")
    assert (a.read_bytes(), b.read_bytes()) == (b"new a", b"new b")


def test_a_lock_whose_process_is_gone_is_taken_over(tmp_path):
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    target = tmp_path / "out"
    with open(lock_path(target), "w") as handle:
        handle.write('{"pid": %d, "host": "%s", "started": "earlier"}' % (int(gone.stdout), os.uname().nodename))
    with output_lock([target], "--out"):
        assert os.path.exists(lock_path(target))
    assert not os.path.exists(lock_path(target))


def _inputs(tmp_path, H=24, W=32):
    v, u = np.mgrid[0:H, 0:W]
    depth = (1.5 + u / W).astype(np.float32)
    depth[8:14, 10:20] = np.nan
    cv2.imwrite(str(tmp_path / "rgb.png"), np.stack([u * 8, v * 8, 0 * u + 128], -1).astype(np.uint8))
    np.save(tmp_path / "depth.npy", depth)
    return ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
            "--out", str(tmp_path / "filled.npy"), "--profile", "ci", "--iterations", "4", "--max-side", "16"]


def test_complete_is_refused_while_another_command_writes_its_preview(tmp_path, capsys):
    argv = _inputs(tmp_path)
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        with open(lock_path(tmp_path / "filled.preview.png"), "w") as handle:
            handle.write('{"pid": %d, "host": "%s", "started": "now"}' % (other.pid, os.uname().nodename))
        assert main(argv) == 2
    finally:
        other.kill()
        other.wait()
    assert f"another ddp-lite command (process {other.pid}" in capsys.readouterr().err
    assert not (tmp_path / "filled.npy").exists()


def test_complete_that_fails_on_its_preview_keeps_the_old_depth_and_preview(tmp_path, monkeypatch, capsys):
    from matplotlib.figure import Figure
    argv = _inputs(tmp_path)
    (tmp_path / "filled.npy").write_bytes(b"old depth")
    (tmp_path / "filled.preview.png").write_bytes(b"old preview")

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(Figure, "savefig", full)
    assert main(argv) == 1
    assert "No space left" in capsys.readouterr().err
    assert (tmp_path / "filled.npy").read_bytes() == b"old depth"  # not the new depth beside the old preview
    assert (tmp_path / "filled.preview.png").read_bytes() == b"old preview"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["depth.npy", "filled.npy", "filled.preview.png", "rgb.png"]


def test_grade_is_refused_while_another_grading_writes_the_same_csv(tmp_path, capsys):
    (tmp_path / "hand-in" / "ada").mkdir(parents=True)
    (tmp_path / "source").mkdir()
    (tmp_path / "source" / "01_x.ipynb").write_text("{}")
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        with open(lock_path(tmp_path / "grades.csv"), "w") as handle:
            handle.write('{"pid": %d, "host": "%s", "started": "now"}' % (other.pid, os.uname().nodename))
        assert main(["grade", str(tmp_path / "hand-in"), "--source", str(tmp_path / "source"),
                     "--csv", str(tmp_path / "grades.csv")]) == 2
    finally:
        other.kill()
        other.wait()
    assert f"another ddp-lite command (process {other.pid}" in capsys.readouterr().err
    assert not (tmp_path / "grades.csv").exists()


def test_sequence_is_refused_while_another_run_writes_the_same_folder(tmp_path, capsys):
    from ddp_lite.data.tum import write_tum
    from ddp_lite.world.scenes import make_scene
    folder = write_tum(make_scene("desk", size=(16, 16), n_views=2), tmp_path / "capture")
    out = tmp_path / "o"
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        with open(lock_path(out), "w") as handle:
            handle.write('{"pid": %d, "host": "%s", "started": "now"}' % (other.pid, os.uname().nodename))
        assert main(["sequence", str(folder), "--format", "tum", "--out", str(out), "--profile", "ci",
                     "--iterations", "2"]) == 2
    finally:
        other.kill()
        other.wait()
    assert f"another ddp-lite command (process {other.pid}" in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())  # nothing of this run written


def test_complete_stopped_by_sigterm_mid_fit_says_so_and_leaves_the_old_outputs(tmp_path):
    argv = _inputs(tmp_path)
    argv[argv.index("--iterations") + 1] = "100000"  # still fitting when the signal comes
    (tmp_path / "filled.npy").write_bytes(b"old depth")
    (tmp_path / "filled.preview.png").write_bytes(b"old preview")
    child = subprocess.Popen([sys.executable, "-m", "ddp_lite.interface.cli", *argv], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
    try:
        assert "fitting at" in child.stdout.readline()
        child.terminate()
        _, err = child.communicate(timeout=60)
    finally:
        child.kill()
    assert child.returncode == 130 and "interrupted" in err and "Traceback" not in err, err
    assert (tmp_path / "filled.npy").read_bytes() == b"old depth"
    assert (tmp_path / "filled.preview.png").read_bytes() == b"old preview"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["depth.npy", "filled.npy", "filled.preview.png", "rgb.png"]
