"""benchmarks/bench_quality.py --report: the paired comparison the quality study's notes quote."""
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
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


def test_other_middlebury_pairs_join_the_suite_as_real_cases(tmp_path):
    import numpy as np

    from ddp_lite.data.middlebury import make_middlebury_fixture
    from ddp_lite.studies.real_cases import REAL_HOLES, make_real_case
    from ddp_lite.method.profiles import get_profile

    folder = make_middlebury_fixture(tmp_path / "Desk", size=(96, 128), seed=2)
    names = bench_quality.middlebury_cases([str(folder)], get_profile("ci"))
    # 96×128 holds 12288 pixels; ci's 48×64 doubled is 6144, so the pair is pooled by 2
    assert names == [f"middlebury:{folder}-2/{holes}" for holes in REAL_HOLES]
    assert all(bench_quality.is_real(n) for n in names) and not bench_quality.is_real("hills/blobs")
    case, fb = bench_quality.build_case(names[0], get_profile("ci"))
    expected = make_real_case("blobs-1", factor=2, scene=folder)
    assert case.depth.shape == (48, 64) and fb == expected.fb
    assert np.array_equal(case.depth, expected.depth, equal_nan=True)
    assert bench_quality.suite(kind="none") == []
