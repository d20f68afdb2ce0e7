"""The fit cache (ddp_lite.method.fit_cache): a hit returns what is stored, and every input that decides a fit misses."""
import errno
import io
import json
import os
import pickle
import subprocess
import sys
import warnings
import zipfile

import numpy as np
import pytest
import torch
from conftest import TINY, plane_with_hole, tilted_plane

from ddp_lite.method.complete import complete_depth
from ddp_lite.method.config import FitConfig
from ddp_lite.method.dip import fit_image
from ddp_lite.method import fit_cache
from ddp_lite.method.runtime.options import RunOptions

H, W = 24, 32


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("DDP_CACHE", str(tmp_path / "fits"))
    return tmp_path / "fits"


def _inputs():
    _, depth = plane_with_hole(H, W)
    rgb = np.random.default_rng(0).random((H, W, 3)).astype(np.float32)
    return rgb, depth


def _config(**changes):
    return FitConfig(**TINY, iterations=4).replace(**changes)


def _fit(rgb, depth, options=None, **config_changes):
    return complete_depth(rgb, depth, variant="d", config=_config(**config_changes), options=options)


def _members(path) -> dict:
    """The arrays of an entry, read as any .npz is (no pickles)."""
    with np.load(path, allow_pickle=False) as archive:
        return {name: archive[name] for name in archive.files}


def _rewrite(path, members: dict):
    buffer = io.BytesIO()
    np.savez(buffer, **members)
    path.write_bytes(buffer.getvalue())


def _meta(members: dict) -> dict:
    return json.loads(members["meta"].tobytes().decode())


def _array_named(members: dict, field: str) -> str:
    """The member name of the top-level result field ``field``."""
    return f"a{_meta(members)['result']['fields'][field]['array']}"


def test_a_hit_returns_the_stored_result_and_not_a_new_fit(folder):
    rgb, depth = _inputs()
    first = _fit(rgb, depth)
    [stored] = folder.iterdir()
    assert zipfile.is_zipfile(stored) and stored.suffix == ".npz"
    # a marked result in the file: the second call must return it, so it read the file
    members = _members(stored)
    members[_array_named(members, "depth")] = np.full_like(first.depth, 7.0)
    _rewrite(stored, members)
    again = _fit(rgb, depth)
    assert np.all(again.depth == 7.0)
    assert again.iterations == first.iterations and len(list(folder.iterdir())) == 1


def test_a_cached_fit_equals_the_computed_one_and_leaves_the_inputs_alone(folder, monkeypatch):
    rgb, depth = _inputs()
    rgb_before, depth_before = rgb.copy(), depth.copy()
    first = _fit(rgb, depth)
    second = _fit(rgb, depth)
    monkeypatch.delenv("DDP_CACHE")
    computed = _fit(rgb, depth)
    for result in (first, second):
        np.testing.assert_array_equal(result.depth, computed.depth)
        np.testing.assert_array_equal(result.history["loss"], computed.history["loss"])
    np.testing.assert_array_equal(rgb, rgb_before)
    np.testing.assert_array_equal(depth, depth_before)


def test_each_input_that_decides_a_fit_gets_its_own_entry(folder, monkeypatch):
    rgb, depth = _inputs()
    _fit(rgb, depth)
    one_pixel = depth.copy()
    one_pixel[0, 0] += 1e-3
    _fit(rgb, one_pixel)  # an array by value
    _fit(rgb, depth, seed=1)  # a config field
    _fit(rgb, depth, options=RunOptions(channels_last=True))  # a run option other than the progress bar
    complete_depth(rgb, depth, None, (), "d", _config(), tilted_plane(H, W))  # gt_depth, positionally
    monkeypatch.setattr(fit_cache, "_library_digest", lambda: "an edited ddp_lite")
    _fit(rgb, depth)  # the library's source
    assert len(list(folder.iterdir())) == 6


def test_the_profile_decides_a_call_without_a_config(monkeypatch):
    keys = []
    for profile in ("ci", "class", "ci"):
        monkeypatch.setenv("DDP_PROFILE", profile)
        keys.append(fit_cache._key(complete_depth, {"config": None}))
    assert keys[0] == keys[2] != keys[1]


def test_what_does_not_decide_a_fit_shares_the_entry(folder):
    rgb, depth = _inputs()
    _fit(rgb, depth)
    _fit(rgb.copy(), depth.copy(), options=RunOptions(progress=False))  # equal copies; no progress bar
    _fit(rgb, depth, options=RunOptions())  # the default options, given
    complete_depth(rgb, depth, None, (), "d", _config())  # positional, the defaults given or not
    complete_depth(rgb=rgb, depth=depth, variant="d", config=_config(), gt_depth=None)
    assert len(list(folder.iterdir())) == 1


def test_no_entry_without_the_variable_with_a_callback_or_for_bad_input(folder, monkeypatch):
    rgb, depth = _inputs()
    seen = []
    complete_depth(rgb, depth, variant="d", config=_config(), options=RunOptions(callback_every=2),
                   callback=lambda i, _: seen.append(i))
    assert seen == [2, 4] and not folder.exists()
    with pytest.raises(ValueError, match="depth"):
        _fit(rgb, depth[:, :-1])  # the fit's own check still speaks
    assert not folder.exists()
    monkeypatch.delenv("DDP_CACHE")
    _fit(rgb, depth)
    assert not folder.exists()


def test_an_unreadable_entry_is_fitted_again_with_a_warning_and_replaced(folder):
    rgb, depth = _inputs()
    first = _fit(rgb, depth)
    [stored] = folder.iterdir()
    for junk in (b"not an entry", stored.read_bytes()[:200]):  # garbage; a truncated entry
        stored.write_bytes(junk)
        with pytest.warns(RuntimeWarning, match="ignoring the cache entry"):
            again = _fit(rgb, depth)
        np.testing.assert_array_equal(again.depth, first.depth)
        np.testing.assert_array_equal(_members(stored)[_array_named(_members(stored), "depth")], first.depth)


class _Planted:
    """Unpickling this runs code: it creates ``marker``."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


def test_an_entry_never_runs_code(folder, tmp_path):
    rgb, depth = _inputs()
    first = _fit(rgb, depth)
    [stored] = folder.iterdir()
    marker = tmp_path / "ran"
    members = _members(stored)
    planted = [  # a pickle as the whole entry; an object array (a pickle inside the .npz) as the depth
        pickle.dumps(_Planted(marker)),
        None,
    ]
    for payload in planted:
        if payload is None:
            buffer = io.BytesIO()
            np.savez(buffer, **{**members, _array_named(members, "depth"): np.array([_Planted(marker)], object)})
            payload = buffer.getvalue()
        stored.write_bytes(payload)
        with pytest.warns(RuntimeWarning, match="ignoring the cache entry"):
            again = _fit(rgb, depth)
        assert not marker.exists()
        np.testing.assert_array_equal(again.depth, first.depth)


def test_an_entry_of_another_call_is_not_returned(folder):
    rgb, depth = _inputs()
    first = _fit(rgb, depth)
    small_rgb, small_depth = rgb[:16, :24].copy(), depth[:16, :24].copy()
    _fit(small_rgb, small_depth)
    [mine] = [p for p in folder.iterdir() if _members(p)[_array_named(_members(p), "depth")].shape == (H, W)]
    [other] = [p for p in folder.iterdir() if p != mine]
    mine.write_bytes(other.read_bytes())  # swapped: another image's result under this call's name
    with pytest.warns(RuntimeWarning, match="another call"):
        again = _fit(rgb, depth)
    assert again.depth.shape == (H, W)
    np.testing.assert_array_equal(again.depth, first.depth)
    # the other call's entry with this call's key written in: its shapes give it away
    members = _members(other)
    meta = _meta(_members(mine))
    forged = {**members, "meta": np.frombuffer(json.dumps({**_meta(members), "key": meta["key"]}).encode(), np.uint8)}
    _rewrite(mine, forged)
    with pytest.warns(RuntimeWarning, match=r"\(16, 24"):
        again = _fit(rgb, depth)
    np.testing.assert_array_equal(again.depth, first.depth)
    # non-finite depth under the right key and shape
    members = _members(mine)
    members[_array_named(members, "depth")] = np.full((H, W), np.nan, np.float32)
    _rewrite(mine, members)
    with pytest.warns(RuntimeWarning, match="finite"):
        again = _fit(rgb, depth)
    np.testing.assert_array_equal(again.depth, first.depth)


def test_a_full_disk_returns_the_fit_and_leaves_no_partial_entry(folder, monkeypatch):
    rgb, depth = _inputs()

    def full(fd, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    with monkeypatch.context() as patch:
        patch.setattr(os, "write", full)
        with pytest.warns(RuntimeWarning, match="not cached"):
            result = _fit(rgb, depth)
    assert result.depth.shape == (H, W) and np.isfinite(result.depth).all()
    assert list(folder.iterdir()) == []


def test_a_cached_result_keeps_every_field(folder, monkeypatch):
    rgb, depth = _inputs()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a clean store and read say nothing
        _fit(rgb, depth)
        stored = _fit(rgb, depth)
    monkeypatch.delenv("DDP_CACHE")
    computed = _fit(rgb, depth)
    assert stored.rgb is None and stored.transform == computed.transform
    assert stored.history.keys() == computed.history.keys()
    for name, value in computed.history.items():
        np.testing.assert_array_equal(stored.history[name], value)
    assert stored.state.keys() == computed.state.keys()
    for name, value in computed.state.items():
        assert isinstance(stored.state[name], torch.Tensor) and torch.equal(stored.state[name], value)
    assert (stored.iterations, stored.best_iteration, stored.fits) == (computed.iterations, computed.best_iteration, 1)


def test_deep_image_prior_fits_are_cached_too(folder):
    image = np.random.default_rng(1).random((H, W, 3)).astype(np.float32)
    first = fit_image(image, config=_config())
    second = fit_image(image, config=_config())
    assert len(list(folder.iterdir())) == 1
    np.testing.assert_array_equal(first.image, second.image)


def test_a_warm_start_hashes_the_same_in_another_process():
    # pickled tensors differ from process to process; the key hashes their values
    state = {"w": torch.arange(6.0).reshape(2, 3)}
    here = fit_cache._key(complete_depth, {"init": state})
    code = ("import torch; from ddp_lite.method import fit_cache; from ddp_lite.method.complete import complete_depth; "
            f"torch.set_num_threads({torch.get_num_threads()}); "
            "print(fit_cache._key(complete_depth, {'init': {'w': torch.arange(6.0).reshape(2, 3)}}))")
    there = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert here == there and here is not None
    assert fit_cache._key(complete_depth, {"init": {"w": torch.arange(6.0).reshape(3, 2)}}) != here
