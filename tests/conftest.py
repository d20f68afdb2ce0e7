import os
import shutil
import sys
import tempfile

import numpy as np
import pytest

import kernel_forkserver

os.environ.setdefault("DDP_PROFILE", "ci")


def pytest_configure(config):
    """One fresh fit cache (``ddp_lite.method.fit_cache``) per test session, shared by its xdist workers (they start
    after this hook and inherit the environment) and the notebook kernels they start. The notebooks
    run first and fill it; the student copies and graded solutions run the same notebooks again and
    read their fits back (they test the notebooks' flow and checks, not the fits). Python tests run
    without it (``_fit_cache_only_where_marked``): a test of a fit must compute it."""
    config.addinivalue_line("markers", "fit_cache: run with the session's DDP_CACHE (notebook re-runs)")
    runs_tests = hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None)
    if runs_tests:
        # a process that runs tests: under pytest-xdist (`make test`) each worker gets one thread, as the workers
        # share the cores. torch and Matplotlib are imported here, not above: the controller of a `make test` run
        # runs no test, and its workers start sooner when it does not import them first
        import matplotlib
        import torch

        matplotlib.use("Agg")

        torch.set_num_threads(1 if os.environ.get("PYTEST_XDIST_WORKER") else max(1, min(2, os.cpu_count() or 1)))
    if not hasattr(config, "workerinput"):  # the controller, or a run without xdist
        config._ddp_cache_saved = os.environ.get("DDP_CACHE")
        config._ddp_cache = tempfile.mkdtemp(prefix="ddp-lite-test-cache-")
        os.environ["DDP_CACHE"] = config._ddp_cache
        if getattr(config.option, "nbval_lax", False) or getattr(config.option, "nbval", False):
            # a run of the notebooks (`make test`): their kernels are forked from one that has imported their
            # stack (see kernel_forkserver.py); the workers, started after this hook, inherit its address
            config._kernel_server = kernel_forkserver.start_server(config.rootpath / "notebooks")
    if runs_tests:
        kernel_forkserver.redirect_kernel_launches()  # where a server was started (the address is in os.environ)


@pytest.hookimpl(trylast=True)  # after pytest's own (its last garbage collection, whose warnings still go out)
def pytest_unconfigure(config):
    server = getattr(config, "_kernel_server", None)
    if server is not None:
        server.stop()
    folder = getattr(config, "_ddp_cache", None)
    if folder is not None:
        shutil.rmtree(folder, ignore_errors=True)
        if config._ddp_cache_saved is None:
            os.environ.pop("DDP_CACHE", None)
        else:
            os.environ["DDP_CACHE"] = config._ddp_cache_saved
    if hasattr(config, "workerinput"):
        # an xdist worker has sent every report and warning (the run's outcome is the controller's), and the
        # controller waits for it to end: tearing down an interpreter that holds torch, Open3D, Dask and two
        # thousand modules took 3-4 s at the end of every `make test`, which this skips
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)


@pytest.fixture(scope="session")
def _empty_data_root(tmp_path_factory):
    return tmp_path_factory.mktemp("empty-data-root")


@pytest.fixture(autouse=True)
def _no_installed_data(_empty_data_root, monkeypatch):
    # the tests read the data a fresh clone has: nothing the user installed in their data root (a test that
    # installs something sets DDP_DATA to its own folder)
    monkeypatch.setenv("DDP_DATA", str(_empty_data_root))


@pytest.fixture(autouse=True)
def _fit_cache_only_where_marked(request, monkeypatch):
    if request.node.get_closest_marker("fit_cache") is None:
        monkeypatch.delenv("DDP_CACHE", raising=False)


# The notebooks that take longest at `ci`, longest first: started first, they do not end the run alone.
SLOW_NOTEBOOKS = ("10_", "12_", "05_", "06_", "11_", "07_")
# The test files that take longest (10-30 s each held to AVX2), longest first: they start right after the
# student copies, so that the run ends on files of a second or less (test_sequence.py, started last in
# collection order, kept one worker busy 18 s after the other had finished).
SLOW_TESTS = ("test_classroom.py", "test_grader_supervisor.py", "test_sequence.py", "test_cli.py", "test_fit.py", "test_real_cases.py",
              "test_grader_trust.py", "test_recipe_levers.py")


def pytest_xdist_make_scheduler(config, log):
    """`make test` spreads whole files over its workers (a notebook's cells share one kernel; a module's
    fixtures are built once), except the student copies, one notebook each, so both workers share them.
    (pytest-xdist's own ``loadgroup`` cannot express this with pytest 9, whose test ids it no longer sets.)"""
    from xdist.scheduler import LoadScopeScheduling

    class FilesAndStudentCopies(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path, _, rest = nodeid.partition("::")
            return nodeid if path.endswith("test_student_copies.py") and "[" in rest else path

    return FilesAndStudentCopies(config, log)


def pytest_collection_modifyitems(config, items):
    """The workers take the files in collection order (``--no-loadscope-reorder``). The slow files go
    first, so the short ones fill the tails: the notebooks, slowest first, then the student copies in
    the same order (they read the notebooks' fits from the session's cache, so they come after
    them: a copy started before its notebook has ended would fit again), then the slow test files,
    slowest first, then the rest."""
    def notebook_rank(name: str) -> int:
        return next((i for i, prefix in enumerate(SLOW_NOTEBOOKS) if name.startswith(prefix)), len(SLOW_NOTEBOOKS))

    def rank(item):
        if item.path.suffix == ".ipynb":
            return 0, notebook_rank(item.path.name)
        if item.path.name == "test_student_copies.py":
            source = getattr(item, "callspec", None) and item.callspec.params.get("source")
            return 1, notebook_rank(source.name) if source is not None else -1
        if item.path.name in SLOW_TESTS:
            return 2, SLOW_TESTS.index(item.path.name)
        return 3, 0

    items.sort(key=rank)  # stable: a file's tests and a notebook's cells keep their order


# The tests are laid out like the package (tests/core, tests/method/kit, ...; tests/benchmarks, tests/notebooks and
# tests/architecture for the rest), with no __init__.py: pytest's default import mode puts tests/ (this file's
# folder) and each test file's own folder on sys.path, so a test imports a file beside it by its name (``from
# test_classroom import ...``) and the helpers kept here in tests/ from anywhere (``conftest``,
# ``bad_input_harness``, ``fill_references``). A test file's name is therefore unique across the folders.
#
# What several test files share; they import it with ``from conftest import ...``.
TINY = dict(channels=(8, 16, 32), lr=1e-2)  # a small, fast FitConfig for short fits


def tilted_plane(height: int, width: int, slope: float = 0.04):
    """Ground-truth depth (H, W) float32 metres of a plane tilted in x: 2 m + ``slope`` m per pixel column."""
    u = np.arange(width, dtype=np.float32)
    return np.broadcast_to(2.0 + slope * u, (height, width)).astype(np.float32).copy()


def plane_with_hole(height: int = 24, width: int = 32):
    """(ground truth, input) depth (H, W) metres: ``tilted_plane`` with slope 0.05 and an enclosed
    8 × 10 hole (NaN) at rows 8–15, columns 10–19."""
    gt = tilted_plane(height, width, slope=0.05)
    depth = gt.copy()
    depth[8:16, 10:20] = np.nan
    return gt, depth


def process_has_ended(pid: int) -> bool:
    """True once ``pid`` is gone or a zombie (killed, not yet reaped by its parent): Linux's /proc."""
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


def pinhole_plane(height: int = 60, width: int = 90):
    """Ground-truth depth (H, W) float32 metres of a tilted plane seen by a pinhole camera: disparity 1/Z is
    affine in the pixel coordinates (0.4–0.65 1/m: 1.5–2.5 m)."""
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    return (1.0 / (0.4 + 0.002 * u + 0.001 * v)).astype(np.float32)


def rgbd_files(folder, height: int = 60, width: int = 90):
    """``rgb.png``, ``depth.npy`` (``pinhole_plane`` with 10 % random holes and one known hole at rows 20–34,
    columns 30–49) and ``gt.npy`` written into ``folder``, the inputs of ``ddp-lite complete``; returns (depth, gt)."""
    import cv2
    from ddp_lite.classical.holes import random_holes
    gt = pinhole_plane(height, width)
    depth, _ = random_holes(gt, fraction=0.1, seed=3)
    depth[20:35, 30:50] = np.nan
    v, u = np.mgrid[0:height, 0:width]
    rgb = np.stack([u / width, v / height, 0.5 + 0 * u], axis=-1)
    cv2.imwrite(str(folder / "rgb.png"), (rgb[..., ::-1] * 255).astype(np.uint8))
    np.save(folder / "depth.npy", depth)
    np.save(folder / "gt.npy", gt)
    return depth, gt


def rectified_pair(width: int, height: int, focal: float = 60.0, baseline: float = 0.1):
    """(left, right) Cameras of ``width`` × ``height`` px: the left at the origin, the right ``baseline`` m to
    its right, the same K (``focal`` px, principal point at the image centre): disparity d = f·B/Z px."""
    from ddp_lite.core.camera import Camera
    K = np.array([[focal, 0.0, width / 2], [0.0, focal, height / 2], [0.0, 0.0, 1.0]])
    right = np.eye(4)
    right[0, 3] = -baseline
    return Camera(K, np.eye(4), width, height), Camera(K, right, width, height)
