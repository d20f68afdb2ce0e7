"""Every exercise check FAILs an answer that only calls the kit's or a library's implementation of that
very exercise, and PASSes the notebooks' own solutions (their solution cells, run as a student would)."""
import re
import statistics
from pathlib import Path

import nbformat
import numpy as np
import pytest
import torch
from skimage.metrics import mean_squared_error, peak_signal_noise_ratio, structural_similarity

from ddp_lite.interface import exercises
from ddp_lite.classical import baselines, stereo
from ddp_lite.classical.kinect import quantise_depth
from ddp_lite.core import camera
from ddp_lite.core.camera import Camera
from ddp_lite.evaluation import metrics
from ddp_lite.interface.classroom import nbgrader_meta
from ddp_lite.interface.own_work import call_watched
from ddp_lite.method.paper.disparity import DisparityTransform
from ddp_lite.method.paper.losses import ssim
from ddp_lite.method.paper.warp import warp_to_reference
from ddp_lite.studies.additions import paired_change

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"


def _rays(d, K):
    v, u = np.mgrid[0:d.shape[0], 0:d.shape[1]]
    return (camera.pixel_rays(u.ravel(), v.ravel(), K) * d.reshape(-1, 1)).reshape(*d.shape, 3)


# check → the one-line answer that hands the exercise to the kit or a library
ONE_LINERS = {
    "check_psnr": lambda a, b: peak_signal_noise_ratio(a, b, data_range=1.0),
    "check_masked_mse": lambda o, t, m: mean_squared_error(o[m], t[m]) if m.any() else 0.0,
    "check_disparity_transform": lambda d, a, b, c: DisparityTransform(a, b, c).to_disparity(d),
    "check_hole_rmse": lambda p, g, i: metrics.hole_rmse(p, g, np.isnan(i)),
    "check_ssim": lambda x, y: structural_similarity(x, y, gaussian_weights=True, sigma=1.5,
                                                     use_sample_covariance=False, data_range=1.0),
    "check_masked_l1": lambda x, y, m: metrics.mae(x, y, m),
    "check_backproject": _rays,
    "check_warp": lambda *a: warp_to_reference(*a)[0],
    "check_fscore": lambda p, r: statistics.harmonic_mean([p, r]),
    "check_nearest_fill": lambda d: baselines.BASELINES["nearest"](d, None),
    "check_d1": lambda p, g: 100 * metrics.d1_error(p, g)["d1_all"],
    "check_depth_from_disparity": lambda d, f, b, o: stereo.disparity_to_depth(d, f, b, o).astype(np.float64),
    "check_resize_calibration": lambda K, o, sx, sy: (Camera(K, np.eye(4), 741, 500).resized(741, 500).K, o * sx),
    "check_kinect_quantisation": lambda z, f, b, s: quantise_depth(z, f, b, s).astype(np.float64),
    "check_paired_change": paired_change,
}
# the ones that are right answers by the numbers: without the rule their check would PASS them
RIGHT_BY_THE_NUMBERS = {"check_psnr", "check_masked_mse", "check_disparity_transform", "check_hole_rmse", "check_ssim",
                        "check_masked_l1", "check_backproject", "check_warp", "check_fscore", "check_nearest_fill",
                        "check_d1", "check_paired_change"}


def test_every_check_has_a_one_liner_and_names_what_it_forbids():
    assert set(ONE_LINERS) == set(exercises.__all__)
    for name in exercises.__all__:
        assert getattr(exercises, name).forbidden, name


@pytest.mark.parametrize("name", sorted(ONE_LINERS))
def test_a_one_liner_that_calls_an_implementation_fails(name, capsys):
    check = getattr(exercises, name)
    with np.errstate(all="ignore"):
        if name in RIGHT_BY_THE_NUMBERS:  # the numbers alone would pass it: only the rule fails it
            assert check.__wrapped__(ONE_LINERS[name]) is True
            capsys.readouterr()
        assert check(ONE_LINERS[name]) is False
    out = capsys.readouterr().out
    assert out.startswith("FAIL") and " calls " in out and "write it yourself" in out, out


def test_passing_the_library_function_itself_fails(capsys):
    assert exercises.check_psnr(peak_signal_noise_ratio) is False
    assert "skimage.metrics.peak_signal_noise_ratio" in capsys.readouterr().out


def test_the_kit_function_through_a_partial_or_a_torch_call_fails(capsys):
    import functools
    fill = functools.partial(baselines.BASELINES["nearest"], rgb=None)
    assert exercises.check_nearest_fill(lambda d: fill(d)) is False
    assert exercises.check_ssim(lambda x, y: float(ssim(torch.as_tensor(x)[None, None],
                                                                  torch.as_tensor(y)[None, None]))) is False
    assert "ddp_lite.method.paper.losses.ssim" in capsys.readouterr().out


def test_a_function_that_switches_off_the_watch_is_caught():
    import sys
    seen = set()
    call_watched(lambda: sys.setprofile(None), (), {}, ("ddp_lite.evaluation.metrics.psnr",), seen)
    assert any("setprofile" in s for s in seen) and sys.getprofile() is None


def _notebook_imports(path) -> str:
    """The notebook's own import statements, from every code cell that is no solution: the names its
    solutions may use as the notebook gives them."""
    import ast
    nb = nbformat.read(path, as_version=4)
    found = []
    for cell in nb.cells:
        if cell.cell_type == "code" and not nbgrader_meta(cell).get("solution"):
            source = "\n".join(l for l in cell.source.splitlines() if not l.lstrip().startswith(("%", "!")))
            found += [ast.get_source_segment(source, node) for node in ast.parse(source).body
                      if isinstance(node, (ast.Import, ast.ImportFrom))]
    return "\n".join(found)


def _solutions_and_checks(path):
    """The notebook's solution cells' code (in order) and its check cells' code, as the source holds them."""
    nb = nbformat.read(path, as_version=4)
    solutions, checks = [], []
    for cell in nb.cells:
        meta = nbgrader_meta(cell)
        if cell.cell_type != "code":
            continue
        if meta.get("solution"):
            solutions.append(cell.source)
        elif meta.get("grade"):
            checks.append(cell.source)
    return solutions, checks


NOTEBOOKS_WITH_CHECKS = [p for p in sorted(NOTEBOOKS.glob("[0-9][0-9]_*.ipynb")) if _solutions_and_checks(p)[1]]


@pytest.mark.parametrize("path", NOTEBOOKS_WITH_CHECKS, ids=lambda p: p.stem[:2])
def test_the_notebooks_solutions_pass(path, capsys):
    solutions, checks = _solutions_and_checks(path)
    namespace = {"__name__": "__main__"}
    exec(compile(_notebook_imports(path), f"<{path.stem} imports>", "exec"), namespace)
    for source in solutions:  # defined as a notebook cell defines them
        exec(compile(source, f"<{path.stem} solution>", "exec"), namespace)
    for source in checks:
        assert re.search(r"assert check_\w+\(", source)
        exec(compile(source, f"<{path.stem} check>", "exec"), namespace)
        out = capsys.readouterr().out
        assert out.startswith("PASS"), out


def test_in_grading_the_kernel_watches_and_reports_what_it_saw(tmp_path, capsys):
    """The grader's path without a kernel: RemoteFunction → answer_call in a namespace standing for the kernel."""
    from ddp_lite.interface.grading_kernel import RemoteFunction
    kernel = {"np": np, "peak_signal_noise_ratio": peak_signal_noise_ratio}
    exec("psnr = lambda a, b: peak_signal_noise_ratio(a, b, data_range=1.0)\n"
         "mine = lambda a, b: 10 * np.log10(1 / np.mean((a - b) ** 2))", kernel)

    def run(code):
        exec(code, kernel)

    assert exercises.check_psnr(RemoteFunction("psnr", run, tmp_path)) is False
    out = capsys.readouterr().out
    assert out.startswith("FAIL psnr: psnr calls skimage.metrics.peak_signal_noise_ratio"), out
    assert exercises.check_psnr(RemoteFunction("mine", run, tmp_path)) is True


def test_watching_imports_nothing_and_still_catches_an_import_inside_the_function():
    """A grading kernel watches the student's function for the check's forbidden callables without importing
    them (torch, SciPy: seconds per kernel): a callable exists only once its module is loaded. A function that
    imports the forbidden module itself, or reaches it through a lazily loading package, is still caught."""
    import subprocess
    import sys
    script = (
        "import sys\n"
        "from ddp_lite.interface.own_work import call_watched\n"
        "heavy = ('statistics', 'scipy', 'skimage', 'torch', 'ddp_lite.evaluation')\n"
        "loaded = lambda: sorted(m for m in sys.modules if m.split('.')[0] in heavy or m.startswith(heavy))\n"
        "assert not loaded(), loaded()\n"
        "names = ('statistics.harmonic_mean', 'scipy.stats.hmean', 'ddp_lite.evaluation.metrics.point_cloud_prf',\n"
        "         'skimage.exposure.rescale_intensity')\n"
        "seen = set()\n"
        "assert call_watched(lambda p, r: 2 * p * r / (p + r), (0.5, 0.5), {}, names, seen) == 0.5\n"
        "assert not seen and not loaded(), (seen, loaded())\n"
        "def imports_it(p, r):\n"
        "    import statistics\n"
        "    return statistics.harmonic_mean([p, r])\n"
        "assert call_watched(imports_it, (0.5, 0.5), {}, names, seen) == 0.5\n"
        "assert seen == {'statistics.harmonic_mean'}, seen\n"
        "def lazily(image):\n"
        "    import skimage.exposure  # a lazily loading package: the name is loaded on first use\n"
        "    return skimage.exposure.rescale_intensity(image)\n"
        "import numpy as np\n"
        "call_watched(lazily, (np.arange(16.0).reshape(4, 4),), {}, names, seen)\n"
        "assert 'skimage.exposure.rescale_intensity' in seen, seen\n"
        "print('ok')\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300,
                          env={**__import__("os").environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])})
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-3000:]
