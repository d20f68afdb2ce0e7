"""The fit cache (ddp_lite.method.cache): a hit returns what is stored, and every input that decides a fit misses."""
import pickle
import subprocess
import sys

import numpy as np
import pytest
import torch
from conftest import TINY, plane_with_hole, tilted_plane

import ddp_lite as ddp
from ddp_lite import cache

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
    return ddp.FitConfig(**TINY, iterations=4).replace(**changes)


def _fit(rgb, depth, **config_changes):
    return ddp.complete_depth(rgb, depth, variant="d", config=_config(**config_changes))


def test_a_hit_returns_the_stored_result_and_not_a_new_fit(folder):
    rgb, depth = _inputs()
    first = _fit(rgb, depth)
    [stored] = folder.iterdir()
    # a marked result in the file: the second call must return it, so it read the file
    marked = pickle.loads(stored.read_bytes())
    marked.depth = np.full_like(marked.depth, 7.0)
    stored.write_bytes(pickle.dumps(marked))
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
    ddp.complete_depth(rgb, depth, None, (), "d", _config(), tilted_plane(H, W))  # gt_depth, positionally
    monkeypatch.setattr(cache, "_library_digest", lambda: "an edited ddp_lite")
    _fit(rgb, depth)  # the library's source
    assert len(list(folder.iterdir())) == 5


def test_the_profile_decides_a_call_without_a_config(monkeypatch):
    keys = []
    for profile in ("ci", "class", "ci"):
        monkeypatch.setenv("DDP_PROFILE", profile)
        keys.append(cache._key(ddp.complete_depth, {"config": None}))
    assert keys[0] == keys[2] != keys[1]


def test_what_does_not_decide_a_fit_shares_the_entry(folder):
    rgb, depth = _inputs()
    _fit(rgb, depth)
    _fit(rgb.copy(), depth.copy(), progress=True)  # equal copies; a progress bar
    ddp.complete_depth(rgb, depth, None, (), "d", _config())  # positional, the defaults given or not
    ddp.complete_depth(rgb=rgb, depth=depth, variant="d", config=_config(), gt_depth=None)
    assert len(list(folder.iterdir())) == 1


def test_no_entry_without_the_variable_with_a_callback_or_for_bad_input(folder, monkeypatch):
    rgb, depth = _inputs()
    seen = []
    ddp.complete_depth(rgb, depth, variant="d", config=_config(callback_every=2), callback=lambda i, _: seen.append(i))
    assert seen == [2, 4] and not folder.exists()
    with pytest.raises(ValueError, match="depth"):
        _fit(rgb, depth[:, :-1])  # the fit's own check still speaks
    assert not folder.exists()
    monkeypatch.delenv("DDP_CACHE")
    _fit(rgb, depth)
    assert not folder.exists()


def test_an_unreadable_entry_is_fitted_again_and_replaced(folder):
    rgb, depth = _inputs()
    first = _fit(rgb, depth)
    [stored] = folder.iterdir()
    stored.write_bytes(b"not a pickle")
    again = _fit(rgb, depth)
    np.testing.assert_array_equal(again.depth, first.depth)
    np.testing.assert_array_equal(pickle.loads(stored.read_bytes()).depth, first.depth)


def test_deep_image_prior_fits_are_cached_too(folder):
    image = np.random.default_rng(1).random((H, W, 3)).astype(np.float32)
    first = ddp.fit_image(image, config=_config())
    second = ddp.fit_image(image, config=_config())
    assert len(list(folder.iterdir())) == 1
    np.testing.assert_array_equal(first.image, second.image)


def test_a_warm_start_hashes_the_same_in_another_process():
    # pickled tensors differ from process to process; the key hashes their values
    state = {"w": torch.arange(6.0).reshape(2, 3)}
    here = cache._key(ddp.complete_depth, {"init": state})
    code = (f"import torch, ddp_lite as ddp; from ddp_lite import cache; torch.set_num_threads({torch.get_num_threads()}); "
            "print(cache._key(ddp.complete_depth, {'init': {'w': torch.arange(6.0).reshape(2, 3)}}))")
    there = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert here == there and here is not None
    assert cache._key(ddp.complete_depth, {"init": {"w": torch.arange(6.0).reshape(3, 2)}}) != here
