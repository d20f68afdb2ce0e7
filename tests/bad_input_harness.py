"""The bad-input harness the ``test_bad_*.py`` files share: a case is a refusal, checked the same way everywhere.

Each case builds its inputs in a fresh folder, then acts; the test asserts the exception type, that the message
names the argument, that no file in the folder was created or changed, and that no array the caller gave was
modified. The cases live by the class of input they check, beside the tests of the sub-package whose rule
refuses them (``tests/method/test_bad_config.py``, ``tests/data/test_bad_readers.py``, ...); each file keeps its
own ``CASES`` (a ``CaseList``) and takes its test from ``refusal_test``.

``python tests/bad_input_harness.py`` prints every case's verdict against whatever ``ddp_lite`` is on the path
(clear / unclear / silent): how the lists were counted before and after a fix. ``SKIP_CASES="id|id"`` leaves out
cases too heavy to run unguarded.
"""
from __future__ import annotations

import contextlib
import io
import os
import stat
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

os.environ.setdefault("DDP_PROFILE", "ci")

H, W = 24, 32
BAD = (TypeError, ValueError)

# the files that hold cases, by folder (the verdict count imports them all)
CASE_FILES = ("core/test_bad_cameras.py", "core/test_bad_writes.py", "core/test_masked_arrays.py",
              "method/test_bad_config.py", "method/test_bad_fit_inputs.py", "interface/test_bad_cli.py",
              "data/test_bad_readers.py", "data_fetch/test_bad_installs.py", "sequences/test_bad_sequences.py")


class Refused(Exception):
    """A command line that exited non-zero; the message is what it printed on stderr."""


@dataclass
class Case:
    id: str
    setup: Callable  # setup(tmp: Path) -> act(), a callable that must raise
    exc: type | tuple
    name: str  # what the message must contain (the argument's name)


ALL_IDS: set[str] = set()  # every case of every file: an id names one case
_WATCHED: list = []


class CaseList(list):
    """One file's cases; ``case(id, exc, name)`` is the decorator that adds one (ids unique across files)."""

    def case(self, id, exc, name):
        def register(setup):
            assert id not in ALL_IDS, f"two bad-input cases named {id!r}"
            ALL_IDS.add(id)
            self.append(Case(id, setup, exc, name))
            return setup
        return register


def watch(array):
    """Remember ``array`` and a copy: the test checks that it was not modified."""
    _WATCHED.append((array, np.array(array, copy=True)))
    return array


def depth(h=H, w=W):
    d = np.full((h, w), 2.0, np.float32)
    d[h // 4:h // 2, w // 4:w // 2] = np.nan
    return watch(d)


def rgb(h=H, w=W):
    return watch(np.random.default_rng(0).random((h, w, 3)).astype(np.float32))


def camera(pose=None, h=H, w=W):
    from ddp_lite.core.camera import Camera
    return Camera.from_fov(w, h, 60.0, pose)


def tiny(**fields):
    from ddp_lite.method.config import FitConfig
    return FitConfig(**{"channels": (8, 16), "iterations": 2, **fields})


def desk_scene(n_views=3):
    """The ``desk`` scene at H × W, seeded."""
    from ddp_lite.world.scenes import make_scene
    return make_scene("desk", size=(H, W), n_views=n_views, seed=0)


def tum_capture(tmp):
    """``desk_scene()`` written as a TUM RGB-D capture under ``tmp/capture``; returns its folder."""
    from ddp_lite.data.tum import write_tum
    return write_tum(desk_scene(), tmp / "capture")


def colmap_workspace(tmp, depth_format="png"):
    """``desk_scene()`` written as a COLMAP workspace under ``tmp/workspace``; returns its folder."""
    from ddp_lite.data.colmap import write_colmap
    return write_colmap(desk_scene(), tmp / "workspace", depth_format=depth_format)


def fifo(path):
    """A named pipe at ``path`` (a reader that opens it would wait for ever)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    os.mkfifo(path)
    return path


def with_env(name, value, act):
    """``act`` run with the environment variable ``name`` set to ``value``, then restored."""
    def run():
        saved = os.environ.get(name)
        os.environ[name] = value
        try:
            act()
        finally:
            os.environ.pop(name) if saved is None else os.environ.__setitem__(name, saved)
    return run


def run_cli(main, argv):
    """``main(argv)`` with its output swallowed; a non-zero exit raises ``Refused`` with what it printed on stderr."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            rc = main(argv)
        except SystemExit as exit_:
            rc = exit_.code
            if isinstance(rc, str):
                err.write(rc)
    if rc != 0:
        raise Refused(err.getvalue())


def snapshot(folder: Path) -> dict:
    """Every path under ``folder`` with its size, mtime and mode (a folder's mtime, which a temporary
    file made and removed inside it changes, is left out)."""
    return {str(p.relative_to(folder)): (p.is_dir(), p.stat().st_size if p.is_file() else 0,
                                         0 if p.is_dir() else p.stat().st_mtime_ns, stat.S_IMODE(p.stat().st_mode))
            for p in folder.rglob("*")}


def refusal_test(cases: CaseList):
    """The test of a file's ``cases``: each refused with its exception, the message naming the argument, no file
    created or changed, no array the caller gave modified. A warning on the way is fine; the refusal is what counts."""
    @pytest.mark.parametrize("c", cases, ids=[c.id for c in cases])
    def test_bad_input_is_refused_clearly_and_changes_nothing(c, tmp_path):
        _WATCHED.clear()
        act = c.setup(tmp_path)
        before = snapshot(tmp_path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with pytest.raises(c.exc) as info:
                act()
        assert c.name in str(info.value), f"the message does not name {c.name!r}: {info.value}"
        assert snapshot(tmp_path) == before, "a file was created or changed"
        for array, copy in _WATCHED:
            np.testing.assert_array_equal(np.asarray(array), copy)  # the caller's arrays are untouched
    return test_bad_input_is_refused_clearly_and_changes_nothing


# --------------------------------------------------------------------------- counting verdicts

def judge(c) -> tuple[str, str]:
    """One case against the ddp_lite on the path → (verdict, note): 'clear' (the expected exception,
    naming the argument, no file changed), 'unclear' (another exception, or a message not naming the
    argument, or files changed) or 'silent' (accepted)."""
    import tempfile
    _WATCHED.clear()
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            act = c.setup(Path(tmp))
            before = snapshot(Path(tmp))
            act()
            return "silent", "accepted"
        except c.exc as error:
            changed = snapshot(Path(tmp)) != before
            verdict = "clear" if c.name in str(error) and not changed else "unclear"
            return verdict, ("changed files; " if changed else "") + (str(error).splitlines()[0][:100] if str(error) else "")
        except BaseException as error:  # noqa: BLE001 - a count, not a test
            return "unclear", f"{type(error).__name__}: {str(error).splitlines()[0][:100] if str(error) else ''}"


def verdicts(cases, skip=()) -> tuple[dict, list]:
    """Every case's verdict (``judge``): the counts and one (verdict, id, note) row per case. A case in
    ``skip`` (too heavy to run unguarded) counts as silent, as the measurement that listed it found."""
    counts, rows = {"clear": 0, "unclear": 0, "silent": 0}, []
    for c in cases:
        if c.id in skip:
            verdict, note = "silent", "not run here (SKIP_CASES): accepted, as measured"
        else:
            verdict, note = judge(c)
        counts[verdict] += 1
        rows.append((verdict, c.id, note))
    return counts, rows


def all_cases() -> list[Case]:
    """Every file's cases, in ``CASE_FILES`` order (each file imported by its path, as pytest does)."""
    import importlib.util
    import sys
    here = Path(__file__).resolve().parent
    cases = []
    for relative in CASE_FILES:
        path = here / relative
        if str(path.parent) not in sys.path:
            sys.path.insert(0, str(path.parent))  # a case file may import a helper beside it
        module = sys.modules.get(path.stem)
        if module is None:
            spec = importlib.util.spec_from_file_location(path.stem, path)
            module = importlib.util.module_from_spec(spec)
            sys.modules[path.stem] = module
            spec.loader.exec_module(module)
        cases += module.CASES
    return cases


if __name__ == "__main__":
    counts, rows = verdicts(all_cases(), skip=set(os.environ.get("SKIP_CASES", "").split("|")) - {""})
    for verdict, id_, note in rows:
        print(f"{verdict:8} {id_:55} {note}")
    print(counts, "of", sum(counts.values()))
