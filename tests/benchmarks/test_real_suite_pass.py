"""benchmarks/real_suite_pass.py: which cases a half's pass holds, and the expected time it prints first
(``bench_real.expected_time``), computed by hand from hand-made rows."""
import re
import shutil
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import bench_real  # noqa: E402
import real_suite_pass  # noqa: E402
from ddp_lite.data.samples import sample_scene  # noqa: E402


def test_a_half_holds_its_scenes_on_every_kind_and_the_one_case_kind(tmp_path):
    for name in ("Art", "Plastic"):  # Art is in half A, Plastic (and Motorcycle) in half B
        shutil.copytree(sample_scene(name), tmp_path / f"2006-{name}")
    kinds = ("blobs", "dropouts", "sgbm", "occlusion")
    assert sorted(real_suite_pass.pass_cases(tmp_path, "A")) == sorted(
        ["Plastic/depthcomp"] + [f"Art/{k}" for k in kinds])
    assert sorted(real_suite_pass.pass_cases(tmp_path, "B")) == sorted(
        ["Plastic/depthcomp"] + [f"{s}/{k}" for s in ("Plastic", "Motorcycle") for k in kinds])
    assert real_suite_pass.pass_cases(tmp_path, "all", ("dropouts",)) == [
        "Art/dropouts", "Plastic/dropouts", "Motorcycle/dropouts"]
    assert real_suite_pass.default_out("quarter").name == "real_suite_quarter.jsonl"
    assert real_suite_pass.default_out("eighth").name != "real_suite_eighth.jsonl"  # the earlier recipes' rows


def test_the_expected_time_counts_the_fits_left_two_at_a_time_at_the_measured_seconds():
    names = ["Art/blobs", "Art/sgbm", "Dolls/blobs"]
    fit = dict(case="Art/blobs", variant="rgbd", seed=0, size="quarter", profile="class", px=1.0, seconds=100.0)
    rows = [dict(case="Art/blobs", method="linear", variant=None, seed=None, size="quarter", profile=None, px=1.0,
                 seconds=30.0), dict(fit, method="DDP kit"), dict(fit, method="DDP photo"),
            dict(fit, method="DDP kit", seed=1, profile="ci", seconds=5.0)]  # another profile's fit: not reused
    line = bench_real.expected_time(names, "quarter", ["kit", "photo"], ["rgbd"], [0, 1], rows, "class")
    # by hand: 6 case-seeds less the one done = 5 runs of 2 plain fits (photo fits on its own), side by side at
    # 100 s a fit (this pass's own median) = 1000 s; fills of the 2 cases not filled at 30 s = 60 s; 1060 s
    assert "5 case-variant-seed runs (10 fits)" in line
    assert re.search(r"about 0\.3 h", line) and "100 s a fit" in line and "1 min of fills" in line
