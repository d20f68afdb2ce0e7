"""What the kit's processes import, and what they do not need to: each a fresh interpreter, whose modules are
read after the work.

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
import subprocess
import sys


def _printed(code: str) -> list[str]:
    """The words ``code`` prints in a fresh interpreter."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout.split()


def test_a_fit_never_imports_torchs_compiler():
    assert _printed("import sys, numpy as np\n"
                    "from ddp_lite.method.complete import complete_depth\n"
                    "from ddp_lite.method.config import FitConfig\n"
                    "depth = np.full((16, 20), 2.0, np.float32); depth[5:9, 6:12] = np.nan\n"
                    "config = FitConfig(iterations=2, channels=(4, 8))\n"
                    "complete_depth(np.zeros((16, 20, 3), np.float32), depth, variant='d', config=config)\n"
                    "print(any(m.startswith('torch._dynamo') for m in sys.modules))\n")[-1:] == ["False"]


def test_reading_a_notebook_builds_no_grammar():
    assert _printed("import sys, nbformat, jsonschema\n"
                    "nbformat.validate(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell('x = 1')]))\n"
                    "print(any(m.split('.')[0] in ('lark', 'rfc3987_syntax') for m in sys.modules))\n") == ["False"]


def test_open3d_comes_without_open3d_ml_or_dash_until_they_are_used_and_without_the_web_visualizer():
    assert _printed("import os, sys\n"
                    "from ddp_lite.evaluation.open3d_loader import import_open3d\n"
                    "o3d = import_open3d()\n"
                    "print('sklearn' in sys.modules, 'dash' in sys.modules, 'OPEN3D_DISABLE_WEB_VISUALIZER' in os.environ,\n"
                    "      o3d.geometry.PointCloud().is_empty(), import_open3d() is o3d)\n"
                    "import open3d.ml.datasets\n"
                    "print('sklearn' in sys.modules, hasattr(open3d.ml.datasets, 'SemanticKITTI'))\n"
                    "print(callable(o3d.visualization.draw_plotly), 'dash' in sys.modules,\n"
                    "      o3d.visualization.rendering.OffscreenRenderer.__name__)\n") \
        == ["False", "False", "False", "True", "True", "True", "True", "True", "True", "OffscreenRenderer"]


def test_the_checks_and_the_fills_import_scipys_heavy_parts_only_when_they_use_them():
    printed = _printed(
        "import sys, numpy as np\n"
        "from ddp_lite.interface import exercises\n"
        "from ddp_lite.classical import baselines\n"
        "heavy = ('scipy.stats', 'scipy.interpolate', 'scipy.sparse.linalg')\n"
        "print(''.join('1' if m in sys.modules else '0' for m in heavy))\n"
        "exercises.check_psnr(lambda a, b: 10 * np.log10(1 / np.mean((a - b) ** 2)))\n"
        "depth = np.tile(np.arange(8, dtype=np.float32) + 1, (6, 1)); depth[2:4, 3:5] = np.nan\n"
        "rgb = np.random.default_rng(0).random((6, 8, 3)).astype(np.float32)\n"
        "assert np.allclose(baselines.fill_linear(depth), np.tile(np.arange(8) + 1, (6, 1)))\n"
        "baselines.fill_colorization(depth, rgb)\n"
        "print(''.join('1' if m in sys.modules else '0' for m in heavy))\n")
    assert (printed[0], printed[-1]) == ("000", "111"), printed  # none on import; each once used
