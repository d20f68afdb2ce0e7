"""benchmarks/bench_quality.py --report: the paired comparison the quality study's notes quote."""
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import bench_quality  # noqa: E402


def test_report_pairs_each_recipe_with_the_default_on_the_same_fits(tmp_path, capsys):
    rows = [dict(case="hills/blobs", method="linear", variant=None, seed=None, size="8x8", px=2.0, seconds=None),
            dict(case="hills/blobs", method="nearest", variant=None, seed=None, size="8x8", px=4.0, seconds=None)]
    # ratios to the best fill (linear, 2.0): default 1.0 and 0.5, recipe x 0.5 and 0.5; x has a third
    # seed that default lacks, which must not enter the pairs
    for method, pxs in (("default", (2.0, 1.0)), ("x", (1.0, 1.0, 9.0))):
        for seed, px in enumerate(pxs):
            rows.append(dict(case="hills/blobs", method=method, variant="rgbd", seed=seed, size="8x8", px=px, seconds=1.0))
    path = tmp_path / "rows.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    bench_quality.report(str(path))
    line = next(l for l in capsys.readouterr().out.splitlines() if l.startswith("x ") and "±" in l)
    # differences -0.5 and 0: mean -0.25, standard error 0.25; log ratios ln 0.5 and 0: -0.347 ± 0.347
    assert line.split() == ["x", "rgbd", "2", "-0.250", "±", "0.250", "-0.347", "±", "0.347", "1/2"]
