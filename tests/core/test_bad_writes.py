"""Writes that must not happen: an atomic write over a read-only file or onto a folder refused, the umask and a
replaced file's mode kept, and no writer writing through a link inside its output folder (one path guard,
``ddp_lite.core.files.path_inside``). The refusals use ``bad_input_harness``.
"""
from __future__ import annotations

import os
import stat

import pytest

from bad_input_harness import CaseList, refusal_test
from ddp_lite.core import files
from ddp_lite.core.files import write_bytes_atomic
from ddp_lite.core.outpaths import output_lock

CASES = CaseList()
case = CASES.case

def _readonly(tmp):
    (tmp / "ro.bin").write_bytes(b"old")
    os.chmod(tmp / "ro.bin", 0o444)
    return lambda: write_bytes_atomic(tmp / "ro.bin", b"new")


case("atomic write over a read-only file", PermissionError, "read-only")(_readonly)
case("atomic write onto a folder", IsADirectoryError, "folder")(lambda tmp: (lambda: write_bytes_atomic(tmp, b"x")))


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)


def test_umask_is_respected(tmp_path):
    old = os.umask(0o027)
    try:
        write_bytes_atomic(tmp_path / "a.bin", b"x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.bin").stat().st_mode) == 0o640
    os.chmod(tmp_path / "a.bin", 0o600)
    write_bytes_atomic(tmp_path / "a.bin", b"y")  # a replaced file keeps its mode
    assert stat.S_IMODE((tmp_path / "a.bin").stat().st_mode) == 0o600


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
