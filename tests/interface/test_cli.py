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

from conftest import pinhole_plane as _plane, rgbd_files as _pair
from ddp_lite.interface import cli
from ddp_lite.interface.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]


def _subparsers():
    action = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices


def _tum_capture(tmp_path, n_views=3):
    """A tiny TUM RGB-D folder (desk, 24×32) written by the kit, named as TUM names fr3 captures."""
    from ddp_lite.data.tum import write_tum
    from ddp_lite.world.scenes import make_scene
    return write_tum(make_scene("desk", size=(24, 32), n_views=n_views), tmp_path / "rgbd_dataset_freiburg3_desk")


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
    code = ("import sys; from ddp_lite.interface.cli import main\n"
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
    # Ctrl-C as from a terminal: SIGINT neither blocked nor ignored in the command, whatever this test's
    # process passes on (a signal mask and an ignored SIGINT are inherited across exec)
    as_from_a_terminal = ("import signal, sys; signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT]); "
                          "signal.signal(signal.SIGINT, signal.default_int_handler); ")
    process = subprocess.Popen([sys.executable, "-u", "-c", as_from_a_terminal + "from ddp_lite.interface.cli import main; sys.exit(main())",
                                "demo", "--iterations", "100000", "--out", str(out)], cwd=tmp_path, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    for line in process.stdout:  # the scene is rendered and the fit starts after this line
        if "holes:" in line or time.monotonic() > deadline:
            break
    time.sleep(1.0)
    process.send_signal(signal.SIGINT)
    try:
        _, err = process.communicate(timeout=60)
    except subprocess.TimeoutExpired:  # a hang: end it, and show where the command was
        process.kill()
        out, err = process.communicate()
        pytest.fail(f"ddp-lite demo still running 60 s after Ctrl-C; its last output:\n{out[-1500:]}\n{err[-1500:]}")
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
    from ddp_lite.interface.cli_sequence import _workers
    cores = os.cpu_count()
    assert _workers(1000) == cores and f"{cores} CPU cores" in capsys.readouterr().err
    assert _workers(1) == 1


def test_sequence_tum_reads_a_millimetre_capture_with_depth_scale(tmp_path):
    from ddp_lite.interface.cli_sequence import _sequence_options
    from ddp_lite.data.formats import load_sequence
    from ddp_lite.data.tum import write_tum
    from ddp_lite.world.scenes import make_scene
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
    folder = _tum_capture(tmp_path)
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


# --- ddp-lite complete on a full-size image: a tilted plane with a known hole -------------------------

def test_complete_keeps_valid_pixels_exactly_fills_the_holes_and_writes_a_preview(tmp_path, capsys, monkeypatch):
    from ddp_lite.evaluation import viz
    figures, save = [], viz.save_figure
    monkeypatch.setattr(viz, "save_figure", lambda fig, path: (figures.append(fig), save(fig, path))[1])
    depth, gt = _pair(tmp_path)
    before = (tmp_path / "depth.npy").read_bytes()
    argv = ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
            "--out", str(tmp_path / "filled.npy"), "--profile", "ci", "--iterations", "15", "--max-side", "32"]
    assert main(argv + ["--gt", str(tmp_path / "gt.npy")]) == 0
    printed = capsys.readouterr().out
    assert "fitting at 21×32" in printed, printed  # 60×90 → longer side 32
    assert "then sharpened at 60×90" in printed and "sharpening at full size" in printed, printed
    filled = np.load(tmp_path / "filled.npy")
    valid = np.isfinite(depth)
    assert filled.shape == depth.shape and np.array_equal(filled[valid], depth[valid])  # bit for bit
    assert np.isfinite(filled).all() and 0.3 < np.nanmean(valid) < 0.95
    assert np.abs(filled[~valid] - gt[~valid]).max() < 1.0  # within the plane's 1.5–2.5 m, not a wild value
    assert (tmp_path / "depth.npy").read_bytes() == before
    preview = cv2.imread(str(tmp_path / "filled.preview.png"))
    assert preview is not None and preview.shape[1] > 2 * preview.shape[0]  # three panels side by side
    line = next(line for line in printed.splitlines() if line.startswith("hole RMSE at full size"))
    assert "DDP" in line and "linear" in line and "navier-stokes" in line
    rmse = dict((name, float(value)) for name, value in
                __import__("re").findall(r"(DDP|linear|navier-stokes) ([0-9.e-]+) m", line))
    holes = ~valid  # the printed DDP RMSE is the file's, recomputed independently here
    assert rmse["DDP"] == pytest.approx(float(np.sqrt(np.mean((filled[holes] - gt[holes]) ** 2))), rel=1e-3)
    # the preview's error panel names every method the line scores, with the value printed (m, same digits)
    printed_rmse = __import__("re").findall(r"([a-zA-Z-]+) ([0-9.e+-]+) m\b", line)
    assert [name for name, _ in printed_rmse] == ["DDP", "linear", "navier-stokes", "colorization", "guided-filter",
                                                  "bilateral-solver", "cross-bilateral"], line
    error_panel = [ax for ax in figures[0].axes if ax.get_title().startswith("hole RMSE (m)")]
    title = " ".join(error_panel[0].get_title().split()) + ","
    assert len(error_panel) == 1 and all(f"{name} {value}," in title for name, value in printed_rmse), (line, title)

    def with_out(name):  # the same command with another --out (a repeated option is refused)
        return [str(tmp_path / name) if a == str(tmp_path / "filled.npy") else a for a in argv]
    assert main(with_out("plain.npy") + ["--no-refine"]) == 0
    assert "sharpen" not in capsys.readouterr().out  # up-sampling alone
    plain = np.load(tmp_path / "plain.npy")
    assert np.array_equal(plain[valid], depth[valid]) and not np.array_equal(plain[~valid], filled[~valid])
    assert main(with_out("raw.npy") + ["--raw"]) == 0
    assert "differ by" in capsys.readouterr().out  # without --gt: the two fills' mean difference
    raw = np.load(tmp_path / "raw.npy")
    assert np.isfinite(raw).all() and not np.array_equal(raw[valid], depth[valid])  # the net's own output


def test_complete_with_a_stereo_depth_source_does_not_carry_a_wrong_rim_into_the_holes(tmp_path, capsys):
    # a matcher's rim: 3 px of valid depth around the hole hold a nearer surface's depth, as SGBM's foreground
    # fattening leaves them; at a working size a third of the photo's that is the 1 px rim the stereo source skips
    H, W = 48, 96
    gt = _plane(H, W)
    depth = gt.copy()
    depth[16:32, 36:60] = np.nan
    hole = np.isnan(depth)
    rim = __import__("scipy").ndimage.binary_dilation(hole, iterations=3) & ~hole
    depth[rim] = 1.2
    v, u = np.mgrid[0:H, 0:W]
    cv2.imwrite(str(tmp_path / "rgb.png"), (np.stack([u / W, v / H, 0.5 + 0 * u], -1)[..., ::-1] * 255).astype(np.uint8))
    np.save(tmp_path / "depth.npy", depth)
    argv = ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
            "--profile", "ci", "--iterations", "10", "--max-side", "32"]
    errors = {}
    for source in ("clean", "stereo"):
        assert main(argv + ["--depth-source", source, "--out", str(tmp_path / f"{source}.npy")]) == 0
        filled = np.load(tmp_path / f"{source}.npy")
        assert np.array_equal(filled[~hole], depth[~hole])  # the wrong rim too, as given
        errors[source] = np.abs(1 / filled[hole] - 1 / gt[hole]).mean()  # 1/m
    assert errors["stereo"] < 0.5 * errors["clean"], errors
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(argv + ["--depth-source", "kinect", "--out", str(tmp_path / "x.npy")])
    assert "--depth-source" in capsys.readouterr().err


def test_complete_refuses_a_gt_with_nothing_in_the_holes_before_the_fit(tmp_path, capsys, monkeypatch):
    depth, gt = _pair(tmp_path)
    np.save(tmp_path / "gt.npy", np.where(np.isfinite(depth), gt, np.nan))  # known only where the input is
    fits = []
    import ddp_lite.method.complete as complete
    monkeypatch.setattr(complete, "complete_depth", lambda *a, **k: fits.append(1))  # a fit would be the error
    argv = ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
            "--gt", str(tmp_path / "gt.npy"), "--out", str(tmp_path / "filled.npy"), "--profile", "ci"]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert "--gt has no valid value in the holes" in captured.err and not fits
    assert sorted(p.name for p in tmp_path.iterdir()) == ["depth.npy", "gt.npy", "rgb.png"]  # nothing written


def test_complete_raw_writes_the_nets_output_with_no_fill_mixed_in(tmp_path, monkeypatch):
    import ddp_lite.method.complete as complete
    _pair(tmp_path)
    shares, real_complete_depth = [], complete.complete_depth

    def recording(*args, **kwargs):  # the real fit, the fill share of the command's config noted
        shares.append((kwargs["config"] if "config" in kwargs else args[5]).combination.blend_fill)
        return real_complete_depth(*args, **kwargs)

    monkeypatch.setattr(complete, "complete_depth", recording)
    argv = ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
            "--profile", "class", "--recipe", "kit", "--variant", "rgbd", "--iterations", "3", "--max-side", "48"]
    assert main(argv + ["--out", str(tmp_path / "kit.npy")]) == 0
    assert shares[0] == 0.25  # class's kit mixes a quarter of the colour-guided fill into the fit's result
    shares.clear()
    assert main(argv + ["--raw", "--out", str(tmp_path / "raw.npy")]) == 0
    assert shares == [0.0]  # --raw: the net's output alone


def test_complete_refuses_an_implausible_scale_before_fitting_and_names_a_better_one(tmp_path, capsys):
    depth, _ = _pair(tmp_path)
    np.save(tmp_path / "mm.npy", depth * 1000)  # millimetres, read as metres
    assert main(["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "mm.npy"),
                 "--out", str(tmp_path / "f.npy"), "--profile", "ci"]) == 2
    printed = capsys.readouterr()
    assert "--depth-scale 0.001 would give 1.5" in printed.err and "fitting" not in printed.out, printed.err
    cv2.imwrite(str(tmp_path / "mm.png"), np.nan_to_num(depth * 1000).astype(np.uint16))
    assert main(["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "mm.png"),
                 "--depth-scale", "1", "--out", str(tmp_path / "f.npy"), "--profile", "ci"]) == 2
    assert "kilo" not in capsys.readouterr().err  # named in metres, with the scale to use
    assert not (tmp_path / "f.npy").exists() and not (tmp_path / "f.preview.png").exists()


def test_working_size_keeps_a_plane_a_plane_in_disparity():
    from ddp_lite.sequences.working_size import fill_holes_at_full_size, shrink, working_shape
    assert working_shape((500, 741), 128) == (86, 128) and working_shape((40, 30), 128) == (40, 30)
    gt = _plane(64, 96)
    depth = gt.copy()
    depth[10:40, 20:60] = np.nan
    _, small = shrink(np.zeros((64, 96, 3), np.float32), depth, (16, 24))
    v, u = np.mgrid[0:16, 0:24]
    centre_u, centre_v = (u + 0.5) * 4 - 0.5, (v + 0.5) * 4 - 0.5  # a block's centre in full-size pixels
    expected = 1.0 / (0.4 + 0.002 * centre_u + 0.001 * centre_v)
    rows = np.arange(16)[:, None] * 4  # each block's first full-size row: blocks wholly above or below the hole
    whole = np.isfinite(small) & ((rows + 4 <= 10) | (rows >= 40)) & np.ones((1, 24), bool)
    assert np.allclose(small[whole], expected[whole], rtol=1e-5)  # the average of an affine disparity
    full = fill_holes_at_full_size(depth, expected)  # the plane's own small depth, brought back
    inner = np.zeros(depth.shape, bool)
    inner[2:-2, 2:-2] = True  # OpenCV clamps at the outer half-block
    assert np.allclose(full[inner], gt[inner], rtol=1e-5) and np.array_equal(full[np.isfinite(depth)],
                                                                              depth[np.isfinite(depth)])


# --- progress of a whole command ------------------------------------------------------------------

class _Terminal(__import__("io").StringIO):
    def isatty(self):
        return True


def test_a_terminal_bar_shows_the_whole_commands_share_and_time_left(monkeypatch):
    from ddp_lite.core import progress as progress_module
    from ddp_lite.core.progress import command_progress, progress
    clock_now = [0.0]
    monkeypatch.setattr(progress_module.time, "perf_counter", lambda: clock_now[0])
    screen = _Terminal()
    with command_progress(200) as clock:  # two fits of 100 iterations
        first = progress(range(100), desc="fit 1", stream=screen)
        for i in first:
            clock_now[0] += 1.0  # one second per iteration
            if i == 49:
                break  # the first fit stops early: its 50 unrun iterations are handed back
        first.close()
        # 50 s for the 50 iterations run, 100 to go: the 50 handed back count as done, not as time spent
        assert clock.done == 100 and clock.summary() == "all 50%, 1:40 left"
        second = progress(range(100), desc="fit 2", stream=screen)
        for _ in second:
            clock_now[0] += 1.0
        second.close()
    assert clock.done == 200 and "fit 2 (all " in screen.getvalue() and " left)" in screen.getvalue()
    log = __import__("io").StringIO()  # a log's lines carry the command's share too
    with command_progress(10):
        for _ in progress(range(10), desc="fit", stream=log):
            clock_now[0] += 1.0
    assert log.getvalue().splitlines()[0].endswith("(all 10%, 0:09 left)")


def test_time_left_skips_set_up_and_expects_an_auto_stop(monkeypatch):
    """Set-up before the first iteration is no iteration; a fit that may stop by itself expects to run
    its expected share, until its stopper says more, and the line gives the range from every fit
    stopping at its earliest to every fit running to its cap (hand-computed, one second per iteration)."""
    from ddp_lite.core import progress as progress_module
    from ddp_lite.core.progress import command_progress, progress
    now = [0.0]
    monkeypatch.setattr(progress_module.time, "perf_counter", lambda: now[0])
    # two fits of ≤ 200, expected to run half, at least a quarter
    with command_progress(400, expected_share=0.5, earliest_share=0.25) as clock:
        now[0] += 100.0  # set-up: 100 s before the first iteration
        bar = progress(range(200), desc="fit", stream=_Terminal())
        for i in bar:
            now[0] += 1.0
            if i == 19:
                break
        # 20 run at 1 s each; 380 to the caps: expected at half (190), at least a quarter (95)
        assert clock.summary() == "all 5%, 3:10 left (1:35–6:20)"
        # its stopper: 150 in all expected (130 more), 60 at least (40 more); the next fit 100 and 50
        bar.expect(150, 60)
        assert clock.summary() == "all 5%, 3:50 left (1:30–6:20)"
        bar.close()  # it stopped at 20: 180 handed back, the next fit expected at 100, at least 50
        assert clock.summary() == "all 50%, 1:40 left (0:50–3:20)"
    with command_progress(100) as clock:  # fits that run to their cap: one time, no range
        for _ in progress(range(100), desc="fit", stream=_Terminal()):
            now[0] += 1.0
            if clock.ran == 40:
                assert clock.summary() == "all 40%, 1:00 left"


def test_time_left_over_units_that_report_their_end_counts_the_first_from_the_start(monkeypatch):
    """A sequence's views report when they end: after the first of six (60 s) five are left, 5:00, not
    the 0:00 a rate measured from the first report would give (hand-computed)."""
    from ddp_lite.core import progress as progress_module
    from ddp_lite.core.progress import CommandClock
    now = [0.0]
    monkeypatch.setattr(progress_module.time, "perf_counter", lambda: now[0])
    clock = CommandClock(6)
    clock.begin()
    assert clock.summary() == "all 0%"  # no view done: no rate yet
    now[0] += 60.0
    clock.advance()
    assert clock.summary() == "all 17%, 5:00 left"
    now[0] += 30.0  # the second view took 30 s: 45 s a view so far
    clock.advance()
    assert clock.summary() == "all 33%, 3:00 left"
    # two views side by side: the first ends after 60 s with the second nearly done beside it
    clock = CommandClock(6)
    clock.begin(at_once=2)
    now[0] += 60.0
    clock.advance()
    assert clock.summary() == "all 17%, 2:30 left"  # 60 s for a round of two: 30 s a view, five left
    now[0] += 6.0
    clock.advance()
    assert clock.summary() == "all 33%, 2:12 left"  # 66 s for two views, four left


def test_complete_with_intrinsics_writes_the_frame_as_a_point_cloud(tmp_path, capsys):
    import open3d as o3d
    depth, _ = _pair(tmp_path)
    H, W = depth.shape
    fx, fy, cx, cy = 80.0, 82.0, 45.0, 30.0
    argv = ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
            "--out", str(tmp_path / "filled.npy"), "--profile", "ci", "--iterations", "5", "--max-side", "32"]
    assert main(argv + ["--ply", str(tmp_path / "c.ply")]) == 2  # a cloud needs a camera
    assert "--ply needs --intrinsics" in capsys.readouterr().err
    assert main(argv + ["--intrinsics", "525,525,319.5,239.5"]) == 2  # K of a 640×480 camera on this 90×60 image
    assert "--intrinsics: the principal point (319.5, 239.5) px lies outside" in capsys.readouterr().err
    assert not (tmp_path / "filled.npy").exists()  # refused before the fit
    assert main(argv + ["--intrinsics", f"{fx},{fy},{cx},{cy}"]) == 0
    filled = np.load(tmp_path / "filled.npy")
    points = np.asarray(o3d.io.read_point_cloud(str(tmp_path / "filled.ply")).points)
    assert points.shape == (H * W, 3)
    v, u = np.mgrid[0:H, 0:W]
    z = filled.astype(np.float64)
    expected = np.stack([(u - cx) / fx * z, (v - cy) / fy * z, z], axis=-1).reshape(-1, 3)  # the pinhole model
    order = np.lexsort((points[:, 0], points[:, 1], points[:, 2]))
    reference = np.lexsort((expected[:, 0], expected[:, 1], expected[:, 2]))
    assert np.allclose(points[order], expected[reference], atol=1e-5)


def test_complete_reads_a_jpeg_with_exif_orientation_as_stored_like_its_depth(tmp_path):
    """A phone JPEG tagged 'rotate 90°': OpenCV's default reader would turn the colour and not the depth,
    misregistering them; complete's reader takes the pixels as stored (and warns)."""
    import warnings

    import cv2
    from PIL import Image

    from ddp_lite.interface.cli_complete import _read_rgb
    rgb = np.zeros((8, 12, 3), np.uint8)
    rgb[:, :6] = 200  # left half bright: a rotation would put it on top
    image = Image.fromarray(rgb)
    exif = image.getexif()
    exif[0x0112] = 6  # Orientation: rotate 90° clockwise to display
    path = tmp_path / "phone.jpg"
    image.save(path, exif=exif, quality=95)
    assert cv2.imread(str(path), cv2.IMREAD_COLOR).shape[:2] == (12, 8)  # what the old reader did
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        read = _read_rgb(str(path))
    assert read.shape == (8, 12, 3) and read[:, :6].mean() > read[:, 6:].mean() + 0.5


def test_complete_says_what_an_input_that_is_no_file_is(tmp_path, capsys):
    """A FIFO or a folder given as --rgb, --depth or --gt is named as such (not "no such file"), exit 2."""
    _pair(tmp_path)
    os.mkfifo(tmp_path / "pipe.png")
    (tmp_path / "folder.npy").mkdir()
    base = {"--rgb": tmp_path / "rgb.png", "--depth": tmp_path / "depth.npy"}
    for flag, path, kind in (("--rgb", tmp_path / "pipe.png", "FIFO"), ("--depth", tmp_path / "folder.npy", "folder"),
                             ("--gt", tmp_path / "pipe.png", "FIFO"), ("--depth", tmp_path / "none.npy", "no such file")):
        argv = {**base, flag: path}
        assert main(["complete", *[str(a) for item in argv.items() for a in item],
                     "--out", str(tmp_path / "f.npy"), "--profile", "ci"]) == 2
        err = capsys.readouterr().err
        assert flag in err and kind in err, err
    assert not (tmp_path / "f.npy").exists()


def test_sequence_views_by_index_or_name_and_no_other(tmp_path, capsys):
    """--views takes indices 0..N-1 or names; a negative index (-1 is no view: "all" is --views left out),
    one past the end, or a view listed twice is refused before anything is estimated or fitted."""
    from ddp_lite.interface.cli_sequence import _view_indices
    from ddp_lite.data.tum import write_tum
    from ddp_lite.world.scenes import make_scene
    scene = make_scene("desk", size=(24, 32), n_views=3)
    assert _view_indices(scene, ["2", "0"]) == [2, 0] and _view_indices(scene, [scene[1].name]) == [1]
    folder = write_tum(scene, tmp_path / "rgbd_dataset_freiburg3_desk")
    base = ["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "o"), "--dry-run", "--views"]
    assert main(base + ["2"]) == 0 and "1 jobs" in capsys.readouterr().out
    for views, says in ((["-1"], "-1 is out of range"), (["3"], "3 is out of range"),
                        (["0", "0"], "listed twice")):
        assert main(base + views) == 2
        err = capsys.readouterr().err
        assert "--views" in err and says in err, err


def test_demo_and_sequence_name_size_when_the_net_cannot_take_it(tmp_path, capsys):
    assert main(["demo", "--size", "8", "8", "--profile", "ci", "--out", str(tmp_path / "f.png")]) == 2
    printed = capsys.readouterr()
    assert "--size is 8×8 px" in printed.err and "holes:" not in printed.out, printed.err
    folder = _tum_capture(tmp_path)
    assert main(["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "o"), "--size", "8", "8",
                 "--profile", "ci", "--dry-run"]) == 2
    assert "--size is 8×8 px" in capsys.readouterr().err


@pytest.mark.parametrize("with_gt", [False, True])
@pytest.mark.parametrize("shape", [(60, 90), (480, 640), (300, 1200), (600, 300), (12, 200)])
def test_complete_preview_titles_overlap_nothing(shape, with_gt, monkeypatch):
    """No panel title, colour bar (with its labels), the hole panel's legend or the summary line overlaps
    another, at any aspect; the hole panel has a two-entry legend and no colour bar; the input and the fill,
    on one scale, share one bar and keep equal widths."""
    import itertools

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from ddp_lite.interface import cli_complete
    from ddp_lite.evaluation import viz
    figures = []
    monkeypatch.setattr(viz, "save_figure", lambda fig, path: figures.append(fig))
    H, W = shape
    depth = np.full(shape, 2.0, np.float32)
    depth[: H // 3, : W // 3] = np.nan
    scores = (np.full(shape, 2.4, np.float32), {"DDP": 0.1, "linear": 0.2, "navier-stokes": 0.25,
                                                "bilateral-solver": 0.15}) if with_gt else None
    cli_complete._write_preview("unused.png", depth, np.nan_to_num(depth, nan=2.5),
                                "hole RMSE at full size (1234 pixels with ground truth): DDP 0.1 m, linear 0.2 m",
                                scores)
    fig = figures[0]
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert len(panels) == (4 if with_gt else 3)
    legend = panels[2].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == ["valid", "hole"]
    boxes = [(f"title {ax.get_title()!r}", ax.title.get_window_extent(renderer)) for ax in fig.axes if ax.get_title()]
    every = list(fig.axes) + [child for ax in fig.axes for child in ax.child_axes]  # a shared bar is a panel's inset
    boxes += [("colour bar", ax.get_tightbbox(renderer)) for ax in every if ax.get_label() == "<colorbar>"]
    boxes += [("legend", legend.get_window_extent(renderer)), ("summary", fig._suptitle.get_window_extent(renderer))]
    assert len(boxes) == (4 + 2 + 2 if with_gt else 3 + 1 + 2)  # input and fill share one bar; the error map has its own
    assert panels[0].get_position().width == pytest.approx(panels[1].get_position().width)  # no bar takes a panel's width
    assert [(a, b) for (a, box_a), (b, box_b) in itertools.combinations(boxes, 2) if box_a.overlaps(box_b)] == []
    assert len(panels[1].collections) >= 1  # the holes' outline on the filled panel
    if with_gt:
        assert "DDP 0.1" in panels[3].get_title() and "bilateral-solver 0.15" in panels[3].get_title()


@pytest.mark.parametrize("shape", [(250, 370), (600, 300), (12, 200)])
def test_complete_preview_has_no_blank_band_under_its_title(shape, tmp_path):
    """Measured on the written PNG: the longest run of blank rows between the first and the last inked row
    (the band a summary line at the figure's top left above fixed-aspect panels) is a small part of the
    image at every aspect."""
    from ddp_lite.interface import cli_complete
    H, W = shape
    depth = np.full(shape, 2.0, np.float32)
    depth[: H // 3, : W // 3] = np.nan
    rmse = {"DDP": 0.1, "linear": 0.2, "navier-stokes": 0.25, "colorization": 0.12, "guided-filter": 0.3,
            "bilateral-solver": 0.15, "cross-bilateral": 0.18}
    for scores in (None, (np.full(shape, 2.4, np.float32), rmse)):
        path = tmp_path / "preview.png"
        cli_complete._write_preview(str(path), depth, np.nan_to_num(depth, nan=2.5), "a summary line", scores)
        image = cv2.imread(str(path))
        blank = (image > 250).all(axis=(1, 2))
        inked = np.flatnonzero(~blank)
        inner = blank[inked[0]:inked[-1] + 1]
        longest = max((len(run) for run in "".join("b" if b else "." for b in inner).split(".")), default=0)
        assert longest < 0.06 * image.shape[0], (shape, scores is not None, longest, image.shape)


def test_sequence_dry_run_refuses_an_out_inside_the_capture_as_the_run_would(tmp_path, capsys):
    folder = _tum_capture(tmp_path)
    for out in (folder / "rgb", folder / "results", tmp_path):
        assert main(["sequence", str(folder), "--format", "tum", "--out", str(out), "--dry-run"]) == 2
        err = capsys.readouterr().err
        assert "out:" in err and str(folder) in err, err


def test_sequence_input_that_is_not_there_is_a_usage_error(tmp_path, capsys):
    """A capture path that does not exist, or one of its listed files missing, exits 2 (usage) like every
    other command's missing input, not 1 (a failure at run time)."""
    out = str(tmp_path / "o")
    for argv in (["sequence", str(tmp_path / "none"), "--format", "tum"],
                 ["sequence", str(tmp_path / "none.npz"), "--format", "scene"]):
        assert main(argv + ["--out", out, "--dry-run"]) == 2
        assert "PATH" in capsys.readouterr().err
    folder = _tum_capture(tmp_path)
    next((folder / "depth").iterdir()).unlink()  # depth.txt lists a file that is gone
    assert main(["sequence", str(folder), "--format", "tum", "--out", out, "--dry-run"]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_sequence_log_gives_the_whole_runs_share_and_time_left(tmp_path):
    """Each view's line says how far the whole run is (views done of all to fit) and the time left."""
    import re

    from ddp_lite.method.config import FitConfig
    from ddp_lite.world.scenes import make_scene
    from ddp_lite.sequences.sequence import run_sequence
    lines = []
    config = FitConfig.for_profile("ci", variant="rgbd+warp", iterations=1)
    run_sequence(make_scene("desk", size=(24, 32), n_views=3), tmp_path / "o", config, fuse=False, log=lines.append)
    views = [line for line in lines if line.strip().startswith("view ")]
    assert len(views) == 3, lines
    shares = [re.search(r"\((\d)/3 views; all (\d+)%(, \d+:\d\d left)?\)$", line) for line in views]
    assert all(shares), views
    assert [(m.group(1), m.group(2)) for m in shares] == [("1", "33"), ("2", "67"), ("3", "100")]
    assert views[-1].endswith("0:00 left)")


def test_sequence_dry_run_says_h_by_w_on_both_lines(tmp_path, capsys):
    """The scene line and the estimate both give H×W (40×56 for --size 40 56), as the rest of the kit."""
    folder = _tum_capture(tmp_path)
    assert main(["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "o"), "--dry-run",
                 "--size", "40", "56"]) == 0
    printed = capsys.readouterr().out
    assert "3 views of 40×56" in printed and "40×56 px (H×W)" in printed and "56×40" not in printed


def test_recipe_flag_runs_the_named_method_as_ddp_recipe_does(tmp_path, monkeypatch, capsys):
    """``--recipe paper`` gives the fit DDP_RECIPE=paper gives, and not the kit's."""
    _pair(tmp_path)
    argv = ["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"), "--raw",
            "--profile", "ci", "--iterations", "5", "--max-side", "32"]
    monkeypatch.setenv("DDP_RECIPE", "kit")
    assert main(argv + ["--recipe", "paper", "--out", str(tmp_path / "flag.npy")]) == 0
    assert main(argv + ["--out", str(tmp_path / "kit.npy")]) == 0
    monkeypatch.setenv("DDP_RECIPE", "paper")
    assert main(argv + ["--out", str(tmp_path / "env.npy")]) == 0
    flag, kit, env = (np.load(tmp_path / f"{name}.npy") for name in ("flag", "kit", "env"))
    np.testing.assert_array_equal(flag, env)
    assert not np.allclose(flag, kit)
    said = [line for line in capsys.readouterr().out.splitlines() if "fitting at" in line]
    assert [line.split("recipe ")[-1] for line in said] == ["'paper'", "'kit'", "'paper'"], said  # the one it ran
    with pytest.raises(SystemExit):
        main(argv + ["--recipe", "papper", "--out", str(tmp_path / "bad.npy")])
    assert "--recipe" in capsys.readouterr().err


def test_sequence_dry_run_names_the_recipe_and_passes_it_on(tmp_path, capsys):
    folder = _tum_capture(tmp_path)
    assert main(["sequence", str(folder), "--format", "tum", "--out", str(tmp_path / "o"), "--dry-run",
                 "--recipe", "paper"]) == 0
    printed = capsys.readouterr().out
    assert "recipe 'paper'" in printed and "--recipe paper" in printed
