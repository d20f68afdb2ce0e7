"""What a user installs is the wheel, not this checkout: build it as pip does, check that it holds every
package and shipped file of the tree, install it into a folder of its own and run the front door and a tiny
fit from there, in a process that cannot see the checkout (an editable install hides a package left out)."""
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SHIPPED_SUFFIXES = (".png", ".txt")  # the shipped real scenes: images and dmin.txt


def _tree_packages() -> set[str]:
    """Every folder of ddp_lite/ and data_fetch/ holding an __init__.py, as a dotted name."""
    return {".".join(init.parent.relative_to(ROOT).parts)
            for top in ("ddp_lite", "data_fetch") for init in (ROOT / top).rglob("__init__.py")}


def _tree_data_files() -> set[str]:
    return {str(p.relative_to(ROOT)) for p in (ROOT / "ddp_lite").rglob("*")
            if p.is_file() and p.suffix in SHIPPED_SUFFIXES and "__pycache__" not in p.parts}


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """Built from a copy of the files git would give a fresh clone (tracked and new, not ignored): setuptools
    builds in the source folder, and a stale build/ there could lend the wheel files the tree no longer has."""
    source = tmp_path_factory.mktemp("source")
    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT,
                            check=True, capture_output=True).stdout.decode().split("\0")
    for name in filter(None, listed):
        if (ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, source / name)
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                    "--disable-pip-version-check", "-w", str(out), str(source)], check=True, capture_output=True)
    wheels = list(out.glob("ddp_lite-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


def test_wheel_holds_every_package_and_shipped_file(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    packages = {str(Path(n).parent).replace("/", ".") for n in names if n.endswith("/__init__.py")}
    assert _tree_packages() - packages == set(), "packages of the tree missing from the wheel"
    assert _tree_data_files() - names == set(), "shipped files of the tree missing from the wheel"
    assert not any(n.startswith(("tests/", "notebooks/", "benchmarks/")) for n in names)


def test_wheel_runs_the_front_door_and_a_fit_outside_the_checkout(wheel, tmp_path):
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-compile", "-q",
                    "--disable-pip-version-check", "--target", str(site), str(wheel)],
                   check=True, capture_output=True)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    # PYTHONPATH comes before site-packages, where the venv's editable install of this checkout lives: the
    # wheel's copy is the one imported (asserted below); the rest of the stack comes from the venv
    env = {k: v for k, v in os.environ.items() if k != "DDP_CACHE"}
    env.update(PYTHONPATH=str(site), DDP_PROFILE="ci", OMP_NUM_THREADS="1", MPLBACKEND="Agg")
    script = f"""
import sys
import ddp_lite, data_fetch
assert ddp_lite.__file__.startswith({str(site)!r}), ddp_lite.__file__
assert data_fetch.__file__.startswith({str(site)!r}), data_fetch.__file__
import numpy as np
from ddp_lite import complete_depth, FitConfig
from ddp_lite.method.runtime.options import RunOptions
from ddp_lite.data.samples import SAMPLES, sample_scene
assert all((sample_scene(n) / "view1.png").is_file() for n in SAMPLES)
depth = np.full((32, 32), 2.0, np.float32); depth[10:20, 10:20] = np.nan
cfg = FitConfig(channels=(8, 16), lr=1e-2, iterations=5)
out = complete_depth(np.zeros((32, 32, 3), np.float32), depth, variant="d", config=cfg, options=RunOptions(progress=False))
assert out.depth.shape == (32, 32) and np.isfinite(out.depth).all()
from ddp_lite.interface.cli import main
sys.argv = ["ddp-lite", "--version"]
try:
    main()
except SystemExit as stop:
    assert not stop.code, stop.code
print("wheel ok")
"""
    run = subprocess.run([sys.executable, "-c", script], cwd=elsewhere, env=env, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "wheel ok" in run.stdout
