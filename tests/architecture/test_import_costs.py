"""What the kit's processes import, and what they do not need to, read from fresh interpreters after each
step of work (one interpreter for the kit's steps, in the order below, and one that only reads a notebook).

- A fit: torch.optim's first optimizer imports torch._dynamo (1.9 s of CPU); the loop's Adam does not.
- Reading a notebook (nbformat, which validates with jsonschema), in every process that grades, builds
  student copies or runs the tests: from jsonschema 4.24 on, its format checkers pull in rfc3987-syntax,
  which builds a Lark grammar at import (2.2 s of CPU here); environment.txt pins 4.23.0, which checks the
  same formats without it.
- Open3D (evaluation.open3d_loader): Open3D-ML's datasets import scikit-learn, 2.5 s of the 3.5 s of
  `import open3d`, and its visualization package Plotly and Dash, 0.9 s more; both load on first use
  instead, and still work then. Open3D's web visualizer, which it enables (and announces) in a Jupyter
  kernel, stays off, and the environment is left as it was.
- The exercises' checks: scikit-image's metrics import scipy.stats (~1 s); only the checks that compare
  with them import them, when they run. The classical fills import SciPy's interpolation and sparse
  solvers (~0.5 s) on the first fill that uses them."""
import json
import subprocess
import sys

import pytest

# The kit's steps in one fresh interpreter (each interpreter imports torch: 3-4 s), in an order where each
# observation is made before a later step could have imported what it looks for.
KIT_STEPS = """
import json, os, sys
import numpy as np
seen = {}
loaded = lambda *names: [name in sys.modules for name in names]
HEAVY = ("scipy.stats", "scipy.interpolate", "scipy.sparse.linalg")

from ddp_lite.interface import exercises
from ddp_lite.classical import baselines
from ddp_lite.method.complete import complete_depth
from ddp_lite.method.config import FitConfig
from ddp_lite.evaluation.open3d_loader import import_open3d
seen["scipy after the imports"] = loaded(*HEAVY)

depth = np.full((16, 20), 2.0, np.float32); depth[5:9, 6:12] = np.nan
complete_depth(np.zeros((16, 20, 3), np.float32), depth, variant="d", config=FitConfig(iterations=2, channels=(4, 8)))
seen["dynamo after a fit"] = any(m.startswith("torch._dynamo") for m in sys.modules)

exercises.check_psnr(lambda a, b: 10 * np.log10(1 / np.mean((a - b) ** 2)))
depth = np.tile(np.arange(8, dtype=np.float32) + 1, (6, 1)); depth[2:4, 3:5] = np.nan
rgb = np.random.default_rng(0).random((6, 8, 3)).astype(np.float32)
seen["linear fill right"] = bool(np.allclose(baselines.fill_linear(depth), np.tile(np.arange(8) + 1, (6, 1))))
baselines.fill_colorization(depth, rgb)
seen["scipy after a check and two fills"] = loaded(*HEAVY)

o3d = import_open3d()
seen["open3d imported"] = [*loaded("sklearn", "dash"), "OPEN3D_DISABLE_WEB_VISUALIZER" in os.environ,
                           o3d.geometry.PointCloud().is_empty(), import_open3d() is o3d]
import open3d.ml.datasets
seen["open3d.ml used"] = [*loaded("sklearn"), hasattr(open3d.ml.datasets, "SemanticKITTI")]
seen["open3d.visualization used"] = [callable(o3d.visualization.draw_plotly), *loaded("dash"),
                                     o3d.visualization.rendering.OffscreenRenderer.__name__]
print(json.dumps(seen))
"""


def _printed(code: str) -> str:
    """What ``code`` prints in a fresh interpreter."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


@pytest.fixture(scope="module")
def seen():
    return json.loads(_printed(KIT_STEPS).splitlines()[-1])


def test_a_fit_never_imports_torchs_compiler(seen):
    assert seen["dynamo after a fit"] is False


def test_reading_a_notebook_builds_no_grammar():
    assert _printed("import sys, nbformat, jsonschema\n"
                    "nbformat.validate(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell('x = 1')]))\n"
                    "print(any(m.split('.')[0] in ('lark', 'rfc3987_syntax') for m in sys.modules))\n").split() == ["False"]


def test_open3d_comes_without_open3d_ml_or_dash_until_they_are_used_and_without_the_web_visualizer(seen):
    assert seen["open3d imported"] == [False, False, False, True, True]
    assert seen["open3d.ml used"] == [True, True]
    assert seen["open3d.visualization used"] == [True, True, "OffscreenRenderer"]


def test_the_checks_and_the_fills_import_scipys_heavy_parts_only_when_they_use_them(seen):
    assert seen["scipy after the imports"] == [False, False, False]
    assert seen["linear fill right"] and seen["scipy after a check and two fills"] == [True, True, True]
