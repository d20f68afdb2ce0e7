"""benchmarks/bench_real.py's table from hand-made rows: each DDP row over the best of all fills and over the
best of the paper's Table 6 methods, averaged over seeds, computed by hand."""
import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import bench_real  # noqa: E402


def test_ratios_against_the_best_fill_and_the_best_table6_fill(tmp_path, capsys):
    rows = [dict(case="Art/blobs", method="linear", variant=None, seed=None, px=2.0),
            dict(case="Art/blobs", method="colorization", variant=None, seed=None, px=1.0),  # best of all, not Table 6
            dict(case="Art/blobs", method="telea", variant=None, seed=None, px=4.0),
            dict(case="Art/blobs", method="DDP kit", variant="rgbd", seed=0, px=1.5),
            dict(case="Art/blobs", method="DDP kit", variant="rgbd", seed=1, px=0.5)]
    table = bench_real.ratios(rows)
    best_of_all, best_table6, px, seeds = table[("Art/blobs", "DDP kit", "rgbd")]
    assert (px, seeds) == (1.0, 2) and best_of_all == pytest.approx(1.0 / 1.0) and best_table6 == pytest.approx(1.0 / 2.0)
    path = tmp_path / "rows.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    bench_real.report(path)
    printed = capsys.readouterr().out
    assert "colorization 1.000" in printed and "linear 2.000" in printed and "1.00 (0.50)" in printed
    assert "blobs      kit/rgbd 1.000; 0.500 (n=1)" in printed
