"""The ``ddp-lite demo`` command follows DDP_PROFILE (or --profile), like ``complete`` does."""
from ddp_lite.cli import main


def test_demo_honours_the_profile(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("DDP_PROFILE", "ci")
    out = tmp_path / "demo.png"
    assert main(["demo", "--iterations", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "of 48×64" in printed and out.stat().st_size > 0  # ci's size, not class's 96×128
    assert main(["demo", "--iterations", "2", "--size", "40", "56", "--out", str(out)]) == 0
    assert "of 40×56" in capsys.readouterr().out
