"""benchmarks/paper_scale.py end to end on a CPU at a tiny size: the classical fills' rows against each fill
scored on the real case directly, the fits' rows cut to the budget, and the schedule arithmetic by hand."""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from ddp_lite.classical.baselines import BASELINES
from ddp_lite.studies.real_cases import make_real_case

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import paper_scale  # noqa: E402


def test_milestones_scale_with_the_run_and_the_budget_covers_every_fit():
    assert paper_scale.scaled_schedule(16000, (12000, 15000), 160) == (160, (120, 150))
    assert paper_scale.scaled_schedule(16000, (12000, 15000), 5) == (5, (4,))  # 3.75 → 4; 4.69 → 5, the end: dropped
    assert paper_scale.scaled_schedule(16000, (12000, 15000), 16000) == (16000, (12000, 15000))
    # 4 fits of 2 s setup: (60 − 8) s over 4 × 0.5 s per iteration = 26 iterations
    assert paper_scale.iterations_for_budget(60.0, [(2.0, 0.5)] * 4, 16000) == 26
    assert paper_scale.iterations_for_budget(1.0, [(2.0, 0.5)] * 4, 16000) == 1  # never below one
    assert paper_scale.iterations_for_budget(1e9, [(2.0, 0.5)] * 4, 300) == 300  # never past the schedule


def test_paper_scale_runs_end_to_end_at_a_tiny_size(tmp_path, capsys):
    out = tmp_path / "rows.jsonl"
    # a budget smaller than the fits' setup: one iteration each
    paper_scale.main(["--size", "32", "48", "--holes", "blobs-2", "--budget-s", "0.001",
                      "--probe-iterations", "1", "--out", str(out)])
    printed = capsys.readouterr().out
    assert "ran 1 of 16000 iterations per fit" in printed and "ratio = DDP / best classical fill" in printed
    assert "s/it" in printed and "peak RSS MB" in printed and "DDP 0.46 px, 0.94× the best other method" in printed
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    fills = [r for r in rows if r["variant"] is None]
    fits = [r for r in rows if r["variant"] is not None]
    assert len(fills) == len(BASELINES)
    assert sorted((r["method"], r["variant"], r["case"]) for r in fits) == sorted(
        (recipe, variant, f"motorcycle-16/{holes}") for recipe in ("paper", "kit")
        for variant in ("rgbd", "rgbd+warp") for holes in ("blobs-2",))
    assert all(r["iterations"] == 1 and np.isfinite(r["px"]) and r["peak_mb"] > 0 for r in fits)
    case = make_real_case("blobs-2", factor=16)  # 31×46: the pair pooled to about twice 32×48's pixels
    disparity = case.fb / case.depth
    for name in ("linear", "colorization"):
        row = next(r for r in fills if r["case"] == "motorcycle-16/blobs-2" and r["method"] == name)
        assert row["size"] == "31x46"
        assert row["px"] == pytest.approx(case.rmse_px(case.fb / BASELINES[name](disparity, case.rgb)), rel=1e-6)


def test_paper_scale_refuses_a_bad_budget_before_any_work():
    with pytest.raises(SystemExit):
        paper_scale.main(["--budget-s", "-5"])


def test_paper_scale_runs_the_table6_scenes(tmp_path, capsys):
    out = tmp_path / "rows.jsonl"
    paper_scale.main(["--table6", "--size", "32", "48", "--iterations", "1", "--variants", "rgbd", "--recipes", "paper",
                      "--out", str(out)])
    assert "Table 6 scenes (shipped, quarter size)" in capsys.readouterr().out
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    assert {r["case"] for r in rows} == {"table6/Plastic", "table6/Baby1", "table6/Bowling1"}
    from ddp_lite.studies.table6 import table6_case
    case = table6_case("Plastic", paper_scale.profile_from_args(paper_scale.argparse.Namespace(
        threads=1, profile="paper", size=(32, 48))))
    linear = next(r for r in rows if r["case"] == "table6/Plastic" and r["method"] == "linear")
    disparity = case.fb / case.depth
    assert linear["px"] == pytest.approx(case.rmse_px(case.fb / BASELINES["linear"](disparity, case.rgb)), rel=1e-6)
