"""The scene cache (ddp_lite.world.scene_cache): with DDP_CACHE set, a scene rendered once is read back, equal
array by array to a fresh render; another call, an edited renderer or a bad entry renders again."""
import os
import shutil
import warnings

import numpy as np
import pytest

from ddp_lite.world import scene_cache, scenes
from ddp_lite.world.scenes import make_scene

SMALL = dict(size=(12, 16), n_views=2)


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("DDP_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.fixture
def renders(monkeypatch):
    """How many scenes were rendered (not read back) since the test began."""
    count = []
    real = scenes._render_scene

    def counted(*args, **kwargs):
        count.append(args[0])
        return real(*args, **kwargs)
    monkeypatch.setattr(scenes, "_render_scene", counted)
    return count


def _fresh(name, **kwargs):
    """The scene rendered with no cache at all: the reference."""
    saved = os.environ.pop("DDP_CACHE", None)
    try:
        return make_scene(name, **kwargs)
    finally:
        if saved is not None:
            os.environ["DDP_CACHE"] = saved


def _assert_same(a, b):
    assert (a.name, a.meta, len(a.views), len(a.right)) == (b.name, b.meta, len(b.views), len(b.right))
    for x, y in zip(a.views + a.right, b.views + b.right):
        assert x.name == y.name and x.rgb.dtype == y.rgb.dtype == np.float32
        np.testing.assert_array_equal(x.rgb, y.rgb)
        np.testing.assert_array_equal(x.depth, y.depth)
        np.testing.assert_array_equal(x.camera.K, y.camera.K)
        np.testing.assert_array_equal(x.camera.cam_from_world, y.camera.cam_from_world)
    for x, y in zip(a.labels, b.labels, strict=True):
        np.testing.assert_array_equal(x, y)


def test_a_scene_rendered_once_is_read_back_equal_to_a_fresh_render(folder, renders):
    first = make_scene("house", **SMALL)
    assert renders == ["house"] and len(list(folder.glob("make_scene-*.npz"))) == 1
    again = make_scene("house", size=[12, 16], n_views=2, seed=0, supersample=3)  # the same call, spelt otherwise
    assert renders == ["house"]  # read back, not rendered
    _assert_same(again, _fresh("house", **SMALL))
    _assert_same(first, again)


def test_every_argument_that_changes_the_scene_renders_it_again(folder, renders):
    make_scene("house", **SMALL)
    changes = (dict(seed=1), dict(size=(12, 20)), dict(n_views=3), dict(fov_x_deg=50.0), dict(supersample=1))
    got = [make_scene("house", **{**SMALL, **changed}) for changed in changes]
    make_scene("desk", **SMALL)
    assert len(renders) == 7 and len(list(folder.glob("make_scene-*.npz"))) == 7
    for scene, changed in zip(got, changes):
        _assert_same(scene, _fresh("house", **{**SMALL, **changed}))


def test_an_edited_renderer_never_reads_an_old_scene(folder, renders, monkeypatch):
    make_scene("house", **SMALL)
    monkeypatch.setattr(scene_cache, "source_digest", lambda *packages: "an edited ddp_lite/world")
    make_scene("house", **SMALL)
    assert len(renders) == 2


@pytest.mark.parametrize("spoil", ["swapped", "truncated", "not a zip", "a folder"])
def test_a_bad_entry_is_ignored_with_a_warning_and_the_scene_rendered_again(folder, renders, spoil):
    make_scene("desk", **SMALL)
    make_scene("house", **SMALL)
    desk, house = sorted(folder.glob("make_scene-*.npz"), key=os.path.getmtime)
    if spoil == "swapped":  # another call's entry under this call's name
        shutil.copy(desk, house)
    elif spoil == "truncated":
        house.write_bytes(house.read_bytes()[:500])
    elif spoil == "not a zip":
        house.write_bytes(b"not an npz")
    else:
        house.unlink()
        house.mkdir()
    with pytest.warns(RuntimeWarning, match="ignoring the cached scene"):
        scene = make_scene("house", **SMALL)
    assert renders == ["desk", "house", "house"]
    _assert_same(scene, _fresh("house", **SMALL))


def test_a_folder_that_cannot_be_written_warns_and_returns_the_scene(tmp_path, monkeypatch, renders):
    blocked = tmp_path / "blocked"
    blocked.write_text("a file where the cache's folder would go")
    monkeypatch.setenv("DDP_CACHE", str(blocked / "cache"))
    with pytest.warns(RuntimeWarning, match="could not store the scene"):
        scene = make_scene("house", **SMALL)
    _assert_same(scene, _fresh("house", **SMALL))


def test_without_ddp_cache_nothing_is_stored(tmp_path, monkeypatch, renders):
    monkeypatch.delenv("DDP_CACHE", raising=False)
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        make_scene("house", **SMALL)
        make_scene("house", **SMALL)
    assert renders == ["house", "house"] and not list(tmp_path.iterdir())


def test_bad_arguments_are_refused_before_the_cache_is_read(folder):
    with pytest.raises(ValueError, match="supersample must be an odd positive integer"):
        make_scene("house", **SMALL, supersample=2)
    with pytest.raises(ValueError, match="name must be one of"):
        make_scene("nowhere", **SMALL)
    assert not folder.exists()
