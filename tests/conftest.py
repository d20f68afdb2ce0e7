import os

import matplotlib
import numpy as np
import torch

matplotlib.use("Agg")
os.environ.setdefault("DDP_PROFILE", "ci")
# under pytest-xdist (`make test`) each worker gets one thread: the workers share the cores
torch.set_num_threads(1 if os.environ.get("PYTEST_XDIST_WORKER") else max(1, min(2, os.cpu_count() or 1)))


def pytest_collection_modifyitems(config, items):
    """`make test` spreads whole files over its workers (``--dist loadfile``: a notebook's cells share
    one kernel; a module's fixtures are built once), in collection order. The slow files, the
    notebooks and the student copies (a few minutes), go first, so the short ones fill the tails."""
    items.sort(key=lambda item: not (item.path.suffix == ".ipynb" or item.path.name == "test_student_copies.py"))


# What several test files share; they import it with ``from conftest import ...`` (tests/ is on sys.path).
TINY = dict(channels=(8, 16, 32), lr=1e-2, progress=False)  # a small, fast FitConfig for short fits


def tilted_plane(height: int, width: int, slope: float = 0.04):
    """Ground-truth depth (H, W) float32 metres of a plane tilted in x: 2 m + ``slope`` m per pixel column."""
    u = np.arange(width, dtype=np.float32)
    return np.broadcast_to(2.0 + slope * u, (height, width)).astype(np.float32).copy()
