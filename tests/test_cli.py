"""The ``ddp-lite`` command line as its users meet it: help, exit codes, Ctrl-C, and every output
path refused before the work starts."""
import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from ddp_lite import cli
from ddp_lite.cli import build_parser, main

ROOT = Path(__file__).resolve().parent.parent


def _subparsers():
    action = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices


def test_demo_honours_the_profile(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("DDP_PROFILE", "ci")
    out = tmp_path / "demo.png"
    assert main(["demo", "--iterations", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "of 48×64" in printed and out.stat().st_size > 0  # ci's size, not class's 96×128
    assert main(["demo", "--iterations", "2", "--size", "40", "56", "--out", str(out)]) == 0
    assert "of 40×56" in capsys.readouterr().out


def test_every_option_has_help_every_command_examples_and_profile_is_one_list(capsys):
    for name, parser in _subparsers().items():
        for action in parser._actions:
            assert action.help, f"{name} {action.option_strings or action.dest} has no help text"
            if "--profile" in action.option_strings:
                assert tuple(action.choices) == ("ci", "class", "paper"), name
        text = parser.format_help()
        assert f"ddp-lite {name}" in text.split("examples:", 1)[1], name  # an example of the command itself
        assert "2 usage error" in text and "1 failed at run time" in text and "130 interrupted" in text
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.startswith("ddp-lite 0.")


def test_help_imports_nothing_heavy():
    code = ("import sys; from ddp_lite.cli import main\n"
            "try: main(['complete', '--help'])\nexcept SystemExit: pass\n"
            "print(sorted(m for m in ('torch', 'open3d', 'cv2', 'matplotlib', 'nbformat', 'scipy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONPATH": str(ROOT)}).stdout
    assert out.strip().splitlines()[-1] == "[]"


def test_usage_errors_exit_2_and_failures_at_run_time_exit_1(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "f.txt")]) == 2
    source = tmp_path / "source"
    source.mkdir()
    import nbformat
    nbformat.write(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1 / 0")]), source / "01_broken.ipynb")
    capsys.readouterr()
    assert main(["solutions", "--source", str(source), "--out", str(tmp_path / "solutions"), "--profile", "ci"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "01_broken.ipynb" in err[0] and "ZeroDivisionError" in err[0], err
    assert not (tmp_path / "solutions" / "01_broken.ipynb").exists()


def test_ctrl_c_prints_one_line_exits_130_and_leaves_no_file(tmp_path):
    out = tmp_path / "demo.png"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "DDP_PROFILE": "ci", "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    process = subprocess.Popen([sys.executable, "-u", "-c", "import sys; from ddp_lite.cli import main; sys.exit(main())",
                                "demo", "--iterations", "100000", "--out", str(out)], cwd=tmp_path, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    for line in process.stdout:  # the scene is rendered and the fit starts after this line
        if "holes:" in line or time.monotonic() > deadline:
            break
    time.sleep(1.0)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    assert [line for line in err.splitlines() if line.startswith("ddp-lite")] == [
        "ddp-lite demo: interrupted; " + cli.INTERRUPTED["demo"] + "."]
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no figure, no temporary file


@pytest.mark.parametrize("argv, message", [
    (["--out", "{tmp}/f.txt"], "--out must end in"),
    (["--out", "{tmp}"], "is a folder"),
    (["--out", "{tmp}/a_file/f.png"], "is a file, not a folder"),
    (["--size", "3000", "4000", "--out", "{tmp}/f.png"], "GB at its peak"),
    (["--scene", "nope", "--out", "{tmp}/f.png"], "--scene must be one of"),
])
def test_demo_refuses_before_rendering(tmp_path, capsys, argv, message):
    (tmp_path / "a_file").write_text("x")
    assert main(["demo", *[a.format(tmp=tmp_path) for a in argv]]) == 2
    printed = capsys.readouterr()
    assert message in printed.err and "holes:" not in printed.out  # no scene was rendered


def test_scenes_keeps_its_columns(capsys):
    assert main(["scenes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    starts = {len(line) - len(line.split(None, 1)[1]) for line in lines}
    assert len(lines) >= 7 and len(starts) == 1, lines


def test_sequence_workers_capped_at_the_cpu_count(capsys):
    from ddp_lite.cli_sequence import _workers
    cores = os.cpu_count()
    assert _workers(1000) == cores and f"{cores} CPU cores" in capsys.readouterr().err
    assert _workers(1) == 1


def test_sequence_tum_reads_a_millimetre_capture_with_depth_scale(tmp_path):
    from ddp_lite.cli_sequence import _sequence_options
    from ddp_lite.formats import load_sequence, write_tum
    from ddp_lite.scenes import make_scene
    scene = make_scene("desk", size=(24, 32), n_views=2)
    folder = write_tum(scene, tmp_path / "rgbd_dataset_freiburg3_desk")
    for png in (folder / "depth").glob("*.png"):  # TUM's 1/5000 m → millimetres, as a RealSense stores them
        stored = cv2.imread(str(png), cv2.IMREAD_UNCHANGED).astype(np.float64)
        cv2.imwrite(str(png), np.round(stored / 5).astype(np.uint16))
    args = build_parser().parse_args(["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "o"),
                                      "--depth-scale", "0.001"])
    read = load_sequence(folder, "tum", **_sequence_options(args))
    for view, original in zip(read.views, scene.views):
        valid = np.isfinite(view.depth) & np.isfinite(original.depth)
        assert valid.mean() > 0.5 and np.abs(view.depth[valid] - original.depth[valid]).max() <= 0.0006


def test_sequence_refuses_a_view_index_out_of_range(tmp_path, capsys):
    from ddp_lite.formats import write_tum
    from ddp_lite.scenes import make_scene
    folder = write_tum(make_scene("desk", size=(24, 32), n_views=3), tmp_path / "rgbd_dataset_freiburg3_desk")
    assert main(["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "o"), "--views", "0", "99",
                 "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert "--views: 99 is out of range" in err and "3 views" in err


def test_grade_refuses_bad_output_paths_before_any_notebook_runs(tmp_path, capsys):
    import nbformat
    (tmp_path / "source").mkdir()
    nbformat.write(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("import time; time.sleep(30)")]),
                   tmp_path / "source" / "01_slow.ipynb")
    (tmp_path / "submissions" / "ada").mkdir(parents=True)
    nbformat.write(nbformat.v4.new_notebook(), tmp_path / "submissions" / "ada" / "01_slow.ipynb")
    (tmp_path / "taken").write_text("x")
    (tmp_path / "folder.csv").mkdir()
    base = ["grade", str(tmp_path / "submissions"), "--source", str(tmp_path / "source")]
    for extra, message in ((["--executed", str(tmp_path / "taken")], "--executed"),
                           (["--csv", str(tmp_path / "folder.csv")], "--csv"),
                           (["--feedback", str(tmp_path / "submissions" / "fb")], "--feedback")):
        assert main(base + extra) == 2
        printed = capsys.readouterr()
        assert message in printed.err and "ada" not in printed.out, printed  # no student was graded


def test_student_refuses_an_out_that_is_inside_or_contains_the_source(tmp_path, capsys):
    import shutil
    source = tmp_path / "notebooks"
    shutil.copytree(ROOT / "notebooks", source, ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    before = {p.name: p.read_bytes() for p in source.glob("*.ipynb")}
    for out in (source, source / "student", tmp_path, source / ".." / "notebooks"):
        assert main(["student", "--source", str(source), "--out", str(out)]) == 2
        assert "--out" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in source.glob("*.ipynb")} == before
    assert main(["student", "--source", str(source), "--out", str(tmp_path / "build")]) == 0
