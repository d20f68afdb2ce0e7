"""What reading a notebook imports: every process that grades, builds student copies or runs the tests reads
notebooks (nbformat, which validates with jsonschema). From jsonschema 4.24 on, its format checkers pull in
rfc3987-syntax, which builds a Lark grammar at import (2.2 s of CPU here, per process); environment.txt pins
4.23.0, which checks the same formats without it."""
import subprocess
import sys


def test_reading_a_notebook_builds_no_grammar():
    code = ("import sys, nbformat, jsonschema\n"
            "nbformat.validate(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell('x = 1')]))\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('lark', 'rfc3987_syntax')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout


def test_open3d_comes_without_open3d_ml_until_it_is_used_and_without_the_web_visualizer():
    """The kit's Open3D (evaluation.open3d_loader): Open3D-ML's datasets import scikit-learn, 2.5 s of the 3.5 s of
    `import open3d`; they load on first use instead, and still work then. Open3D's web visualizer, which it
    enables (and announces) in a Jupyter kernel, stays off, and the environment is left as it was."""
    code = ("import os, sys\n"
            "from ddp_lite.evaluation.fusion import fuse_depths\n"
            "from ddp_lite.evaluation.open3d_loader import import_open3d\n"
            "o3d = import_open3d()\n"
            "print('sklearn' in sys.modules, 'OPEN3D_DISABLE_WEB_VISUALIZER' in os.environ,\n"
            "      o3d.geometry.PointCloud().is_empty(), import_open3d() is o3d)\n"
            "import open3d.ml.datasets\n"
            "print('sklearn' in sys.modules, hasattr(open3d.ml.datasets, 'SemanticKITTI'))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["False", "False", "True", "True", "True", "True"], out.stdout
