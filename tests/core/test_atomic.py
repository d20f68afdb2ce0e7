"""Atomic writes: the target is whole or untouched, and no temporary file is left behind."""
import os

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ddp_lite.core.files import atomic_path, write_bytes_atomic  # noqa: E402
from ddp_lite.evaluation.viz import save_figure  # noqa: E402


def test_replaces_the_target_and_leaves_nothing_else(tmp_path):
    target = tmp_path / "sub" / "data.bin"  # the folder does not exist yet
    write_bytes_atomic(target, b"old")
    write_bytes_atomic(target, b"new contents")
    assert target.read_bytes() == b"new contents"
    assert os.listdir(tmp_path / "sub") == ["data.bin"]


def test_a_failing_write_keeps_the_old_file(tmp_path):
    target = tmp_path / "depth.npy"
    np.save(target, np.arange(3))
    with pytest.raises(RuntimeError, match="disk full"):
        with atomic_path(target) as tmp, open(tmp, "wb") as handle:
            handle.write(b"half a file")
            raise RuntimeError("disk full")
    np.testing.assert_array_equal(np.load(target), [0, 1, 2])
    assert os.listdir(tmp_path) == ["depth.npy"]


@pytest.mark.parametrize("name, magic", [("fig.png", b"\x89PNG"), ("fig.pdf", b"%PDF")])
def test_format_follows_the_target_suffix(tmp_path, name, magic):
    fig, ax = plt.subplots(figsize=(1, 1))
    ax.plot([0, 1])
    save_figure(fig, tmp_path / name)
    plt.close(fig)
    assert (tmp_path / name).read_bytes()[:len(magic)] == magic
    assert os.listdir(tmp_path) == [name]
