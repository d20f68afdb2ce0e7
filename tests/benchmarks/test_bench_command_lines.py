"""The benchmarks are a command line too: every bad argument a usage error naming the option (exit 2)
before any work, rows reused only at the same size, profile, recipe and overrides, a torn last line set
aside, and every command the docs give parsed (``--check-args``)."""
from __future__ import annotations

import json
import os
import re
import shlex
import stat
import sys
from pathlib import Path

import pytest

os.environ.setdefault("DDP_PROFILE", "ci")
ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))

import _common  # noqa: E402
import bench_quality  # noqa: E402
import bench_real  # noqa: E402

from ddp_lite.data.middlebury import make_middlebury_fixture  # noqa: E402

TINY = "tiny:iterations=2,channels=(8, 16),auto_stop=False,lr_milestones=()"


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """A folder of tiny Middlebury scenes with ground truth, named as the docs' commands name theirs."""
    root = tmp_path_factory.mktemp("scenes")
    for seed_, name in enumerate(("Art", "Plastic", "Baby1", "Bowling1", "Books", "Dolls")):
        make_middlebury_fixture(root / name, size=(48, 64), seed=seed_)
    import cv2
    import numpy as np
    cv2.imwrite(str(root / "plastic-disp-hole.png"), np.zeros((48, 64), np.uint8))  # DepthComp's holes, as named
    return root


def _usage_error(argv, capsys, option, main=bench_quality.main):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and "usage:" in err and option in err, err
    return err


@pytest.mark.parametrize("argv, option", [
    (["--lane", "0/0"], "--lane"),
    (["--lane", "2/2"], "--lane"),
    (["--lane", "x"], "--lane"),
    (["--recipes", "kit:lr"], "--recipes"),
    (["--recipes", "kit:lr=abc"], "--recipes"),
    (["--recipes", "kitt"], "--recipes"),
    (["--recipes", "default:seed=1"], "--recipes"),
    (["--recipes", "default:lrr=0.1"], "did you mean 'lr'"),
    (["--recipes", ":lr=0.1"], "--recipes"),
    (["--seeds", "-1"], "--seeds"),
    (["--cases", "desk/nosuch"], "--cases"),
    (["--cases", "nosuch/blobs"], "--cases"),
    (["--cases", "desk"], "--cases"),
    (["--cases", "motorcycle-x/sgbm"], "--cases"),
    (["--size", "0", "64"], "--size"),
    (["--threads", "0"], "--threads"),
    (["--profile", "nosuch"], "--profile"),
    (["--variants", "rgb"], "--variants"),
    (["--ensembles", "0"], "--ensembles"),
    (["--ensembles", "2"], "--ensembles"),
    (["--refill"], "--refill"),
    (["--report"], "--report"),
])
def test_bench_quality_refuses_a_bad_argument_before_any_work(argv, option, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _usage_error(argv + ["--out", "rows.jsonl"] if argv != ["--report"] else argv, capsys, option)
    assert not (tmp_path / "rows.jsonl").exists()


def test_bench_quality_refuses_an_out_it_cannot_write(capsys, tmp_path):
    (tmp_path / "a-file").write_text("")
    _usage_error(["--out", str(tmp_path / "a-file" / "rows.jsonl")], capsys, "--out")
    _usage_error(["--out", str(tmp_path)], capsys, "--out")  # a folder
    _usage_error(["--save-fits", str(tmp_path / "a-file")], capsys, "--save-fits")
    _usage_error(["--report", str(tmp_path / "none.jsonl")], capsys, "--report")


def test_bench_quality_refuses_a_read_only_out_or_save_fits(capsys, tmp_path):
    out = tmp_path / "rows.jsonl"
    out.write_text("")
    out.chmod(stat.S_IRUSR)
    if os.access(out, os.W_OK):
        pytest.skip("running as a user who may write anything")
    _usage_error(["--out", str(out)], capsys, "--out")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(stat.S_IRUSR | stat.S_IXUSR)
    _usage_error(["--out", str(locked / "rows.jsonl")], capsys, "--out")
    _usage_error(["--save-fits", str(locked / "fits")], capsys, "--save-fits")
    _usage_error(["--report", str(tmp_path / "none.jsonl")], capsys, "--report")


def test_the_real_suite_refuses_bad_data_cases_recipes_and_seeds_before_any_row(data, capsys, tmp_path):
    out = tmp_path / "real.jsonl"
    base = ["--suite", "middlebury", "--out", str(out)]
    empty = tmp_path / "empty"
    empty.mkdir()
    for argv, option in [(["--data", str(tmp_path / "nowhere")], "--data"), (["--data", str(empty)], "--data"),
                         (["--data", str(data), "--recipes", "kitt"], "--recipes"),
                         (["--data", str(data), "--recipes", "kit:seed=1"], "--recipes"),
                         (["--data", str(data), "--recipes", "kit:warp_combine=maximum"], "warp_combine"),
                         (["--data", str(data), "--seeds", "-1"], "--seeds"),
                         (["--data", str(data), "--cases", "Art/nosuch"], "--cases"),
                         (["--data", str(data), "--size", "48", "64"], "--size")]:
        _usage_error(base + argv, capsys, option)
    assert not out.exists()


def test_the_real_suite_without_data_reads_the_data_root_and_a_scene_twice_once(capsys, tmp_path):
    """No ``--data``: the data root (empty under the tests: the shipped samples, said on the first line); a root
    holding one scene at two sizes: one copy of it, not an error (``data.installed.scene_folders``)."""
    out = tmp_path / "real.jsonl"
    twice = tmp_path / "twice"
    for size in ("HalfSize", "ThirdSize"):
        make_middlebury_fixture(twice / size / "Desk", size=(48, 64) if size == "ThirdSize" else (96, 128), seed=0)
    for argv in ([], ["--data", str(twice)]):
        with pytest.raises(SystemExit) as stop:
            bench_quality.main(["--suite", "middlebury", "--out", str(out), *argv, "--check-args"])
        printed = capsys.readouterr()
        assert stop.value.code == 0 and "arguments OK" in printed.out, printed.err
    assert not out.exists()
    import bench_real
    folder, line, samples = bench_real.suite_data(None)
    assert samples and "shipped" in line and "data_fetch fetch" in line, line
    folder, line, samples = bench_real.suite_data(twice)
    assert not samples and "1 scenes" in line and "Desk" in line, line


def test_the_documented_real_suite_commands_parse(data, capsys, tmp_path):
    rows = tmp_path / "real.jsonl"
    rows.write_text(json.dumps(dict(case="Art/blobs", method="linear", variant=None, seed=None, size="eighth",
                                    profile=None, px=1.0)) + "\n")
    for argv in (["--real-size", "quarter", "--seeds", "0", "1", "2"], ["--report"],
                 ["--variants", "rgbd+warp", "--recipes", "kit", "kit:warp_combine=min,gammas=(0.96,0.02)",
                  "--cases", "Art/sgbm", "Art/occlusion"]):
        with pytest.raises(SystemExit) as stop:
            bench_quality.main(["--suite", "middlebury", "--data", str(data), "--out", str(rows), *argv, "--check-args"])
        assert stop.value.code == 0, capsys.readouterr().err
        assert "arguments OK" in capsys.readouterr().out


# ------------------------------------------------------------------ rows: keyed, torn lines set aside

def test_a_resumed_run_at_another_profile_fits_again_and_reports_apart(tmp_path, capsys):
    out = tmp_path / "rows.jsonl"
    common = ["--cases", "desk/blobs", "--variants", "rgbd", "--seeds", "0", "--recipes", TINY, "--size", "32", "48",
              "--out", str(out)]
    bench_quality.main(["--profile", "ci", *common])
    bench_quality.main(["--profile", "class", *common])
    fits = [json.loads(line) for line in out.read_text().splitlines() if '"rgbd"' in line]
    assert sorted(r["profile"] for r in fits) == ["ci", "class"]  # not class reported from ci's row
    printed = capsys.readouterr().out
    assert "=== 32x48, profile ci:" in printed and "=== 32x48, profile class:" in printed


def test_a_resumed_run_with_other_overrides_fits_again(tmp_path):
    out = tmp_path / "rows.jsonl"
    common = ["--profile", "ci", "--cases", "desk/blobs", "--variants", "rgbd", "--seeds", "0", "--size", "32", "48",
              "--out", str(out)]
    bench_quality.main([*common, "--recipes", TINY])
    bench_quality.main([*common, "--recipes", TINY + ",lr=0.002"])
    bench_quality.main([*common, "--recipes", TINY])  # both there now: nothing fitted
    fits = [json.loads(line) for line in out.read_text().splitlines() if '"rgbd"' in line]
    assert len(fits) == 2 and len({r["overrides"] for r in fits}) == 2


def test_the_real_suite_at_another_size_computes_its_own_rows(data, tmp_path, capsys):
    out = tmp_path / "real.jsonl"
    bench_real.run(data, "eighth", [], [], [], out, cases=["Art/blobs"])
    eighth = out.read_text().count("\n")
    bench_real.run(data, "quarter", [], [], [], out, cases=["Art/blobs"])
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    assert eighth > 0 and len(rows) == 2 * eighth
    assert sorted({r["size"] for r in rows}) == ["eighth", "quarter"]


def test_a_torn_last_line_is_set_aside_with_a_word_and_the_rest_resumed(tmp_path, capsys):
    out = tmp_path / "rows.jsonl"
    good = [dict(case="a/b", method="linear", variant=None, seed=None, size="8x8", profile="ci", overrides=None,
                 px=1.0)]
    out.write_text(json.dumps(good[0]) + "\n" + '{"case": "a/b", "method": "nea')
    rows = _common.RowsFile(out, bench_quality.ROW_FIELDS)
    said = capsys.readouterr().out
    assert "cut short" in said and str(out) + ".torn" in said
    assert rows.rows == good and rows.done(good[0])
    assert (tmp_path / "rows.jsonl.torn").read_text() == '{"case": "a/b", "method": "nea\n'
    assert out.read_text() == json.dumps(good[0]) + "\n"
    rows.record(dict(good[0], method="nearest"))
    rows.close()
    assert [json.loads(line)["method"] for line in out.read_text().splitlines()] == ["linear", "nearest"]
    out.write_text("not json\n" + json.dumps(good[0]) + "\n")  # a bad line inside is no torn write: said, not moved
    with pytest.raises(ValueError, match="line 1 is not a JSON row"):
        _common.read_rows(out)


def test_rows_that_do_not_record_what_changes_their_numbers_are_not_reused(tmp_path, capsys):
    out = tmp_path / "rows.jsonl"
    old = dict(case="a/b", method="linear", variant=None, seed=None, size="8x8", px=1.0)  # no profile recorded
    out.write_text(json.dumps(old) + "\n")
    rows = _common.RowsFile(out, bench_quality.ROW_FIELDS)
    assert not rows.done(dict(old, profile="ci", overrides=None))
    assert "do not record overrides, profile: not reused" in capsys.readouterr().out


# ------------------------------------------------------------------ every benchmark, every documented command

SCRIPTS = sorted(p.stem for p in (ROOT / "benchmarks").glob("*.py")
                 if p.stem not in ("_common", "isa", "study_recipes", "bench_real"))  # modules, not commands


@pytest.mark.parametrize("script", SCRIPTS)
def test_every_benchmark_checks_its_arguments_and_refuses_an_unknown_one(script, capsys, monkeypatch):
    module = _load(script, monkeypatch)
    with pytest.raises(SystemExit) as stop:
        module.main(["--help"])
    assert stop.value.code == 0 and "--check-args" in capsys.readouterr().out  # _common's parsing, not its own
    with pytest.raises(SystemExit) as stop:
        module.main(["--no-such-option"])
    assert stop.value.code == 2 and "usage:" in capsys.readouterr().err


def _load(script: str, monkeypatch):
    import importlib
    monkeypatch.setattr(sys, "argv", [script + ".py"])
    return importlib.import_module(script)


COMMAND = re.compile(r"(?:\.venv/bin/)?python (benchmarks/(\w+)\.py(?:\\\n|[^`\n|])*)")


def documented_commands() -> list[tuple[str, str]]:
    """(where, command line) of every benchmark command in README.md, benchmarks/README.md, docs/**/*.md and the
    benchmarks' docstrings, continuation lines joined, comments cut."""
    sources = [ROOT / "README.md", ROOT / "benchmarks" / "README.md", *sorted((ROOT / "docs").rglob("*.md")),
               *sorted((ROOT / "benchmarks").glob("*.py"))]
    found = []
    for path in sources:
        text = path.read_text()
        if path.suffix == ".py":
            text = text.split('"""')[1] if text.count('"""') >= 2 else ""
        for match in COMMAND.finditer(text.replace("\\\\\n", "\\\n")):
            line = re.sub(r"\\\n\s*", " ", match.group(1)).split("#")[0].split(" > ")[0].strip().rstrip("&").strip()
            line = re.sub(r"\[(--[^\]]*)\]", r"\1", line).replace(" ...", "")  # [--option value]: optional, given
            found.append((f"{path.relative_to(ROOT)}", line))
    return found


def _argv(line: str, data: Path, tmp: Path) -> tuple[str, list[str]]:
    line = re.sub(r'"\$\(.*?\)"', str(data), line)  # the data root a shell would find
    words = shlex.split(line)
    script = Path(words[0]).stem
    placeholders = {"DIR": str(data), "DATA": str(data), "FILE": str(tmp / "rows.jsonl"), "q.jsonl": str(tmp / "q.jsonl")}
    argv = []
    for word in words[1:]:
        if word in placeholders:
            word = placeholders[word]
        elif re.fullmatch(r"DIR\d+", word):  # another folder of the same page's commands
            (tmp / word).mkdir(exist_ok=True)
            word = str(tmp / word)
        elif re.fullmatch(r"[A-Z][A-Z0-9]*(_[a-z0-9]+)?", word) and not word.startswith("DIR"):  # rows made before
            (tmp / word).write_text("")
            word = str(tmp / word)
        elif word.startswith("DATA/"):
            word = str(data / "Art")
        elif word.startswith("benchmarks/results/") and not (ROOT / word).exists():
            word = str(tmp / Path(word).name)
        elif word.startswith("benchmarks/"):
            word = str(ROOT / word)
        argv.append(word)
    return script, argv


def test_the_docs_give_benchmark_commands():
    scripts = {Path(line.split()[0]).stem for _, line in documented_commands()}
    assert {"bench_quality", "bench_laptop", "paper_scale", "study_warp_costs"} <= scripts


@pytest.mark.parametrize("where, line", documented_commands())
def test_every_documented_benchmark_command_parses(where, line, data, tmp_path, capsys, monkeypatch):
    script, argv = _argv(line, data, tmp_path)
    monkeypatch.chdir(tmp_path)  # what an earlier command of the same page made: a folder, a rows file
    for word in argv:
        if not word.startswith(("-", "/")) and word.endswith("/"):
            (tmp_path / word).mkdir(parents=True, exist_ok=True)
        elif not word.startswith(("-", "/")) and word.endswith(".jsonl"):
            (tmp_path / word).write_text("")
    (tmp_path / "q.jsonl").write_text("")
    if "--report" in argv and not any(Path(a).is_file() for a in argv if a.endswith(".jsonl")):
        for path in [a for a in argv if a.endswith(".jsonl")]:
            Path(path).write_text("")
    module = _load(script, monkeypatch)
    with pytest.raises(SystemExit) as stop:
        module.main(argv + ["--check-args"])
    captured = capsys.readouterr()
    assert stop.value.code == 0, f"{where}: {line}\n{captured.err}"
    assert "arguments OK" in captured.out
