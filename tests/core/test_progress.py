"""Progress output: a bar on a terminal or in Jupyter, short lines in logs."""
import io

import pytest
from tqdm import tqdm as tqdm_class

from ddp_lite.core.progress import LineProgress, progress


class FakeTerminal(io.StringIO):
    def isatty(self):
        return True


def test_a_log_gets_one_short_line_every_ten_percent():
    log = io.StringIO()
    bar = progress(range(150), desc="DDP rgbd", stream=log)
    assert isinstance(bar, LineProgress)
    for i in bar:
        if i == 100:
            bar.set_postfix(held_out="0.0123", refresh=False)
    bar.close()  # the fit loop (method/loop.py) closes after the loop too: no second last line
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue()
    assert [line.split()[2] for line in lines[:-1]] == [f"{p}%" for p in range(10, 100, 10)]
    assert lines[0].startswith("DDP rgbd: 10% (15/150)")
    assert lines[-1].startswith("DDP rgbd: done (150/150)") and lines[-1].endswith("held_out=0.0123")
    assert max(len(line) for line in lines) < 80


def test_an_early_stop_says_where_it_stopped():
    log = io.StringIO()
    bar = progress(range(200), desc="fit", stream=log, every=25)
    for i in bar:
        if i == 119:
            break
    bar.close()
    lines = log.getvalue().splitlines()
    assert [line.split()[1] for line in lines] == ["25%", "50%", "stopped"]
    assert "stopped at 120/200" in lines[-1]


def test_a_terminal_gets_tqdm_and_disable_prints_nothing():
    assert isinstance(progress(range(3), stream=FakeTerminal()), tqdm_class)
    log = io.StringIO()
    assert list(progress(range(3), disable=True, stream=log)) == [0, 1, 2]
    assert log.getvalue() == ""


def test_small_totals_and_unknown_lengths():
    log = io.StringIO()
    assert list(progress(range(3), stream=log, every=10)) == [0, 1, 2]
    assert [line.split()[0] for line in log.getvalue().splitlines()] == ["33%", "67%", "done"]
    log = io.StringIO()
    assert list(progress(iter("abc"), stream=log)) == ["a", "b", "c"]
    assert log.getvalue().splitlines()[-1].startswith("done (3)")


@pytest.mark.parametrize("every", [0, -5, 150])
def test_every_must_be_a_percentage(every):
    with pytest.raises(ValueError, match="every"):
        progress(range(3), stream=io.StringIO(), every=every)


def test_the_loop_reports_through_the_hook_its_caller_passes():
    """The fit's loop iterates over its caller's hook and tells it each held-out error and where its
    stopper expects the fit to stop; the kit's own hook hands those expectations to a command's clock."""
    import numpy as np
    import torch

    from ddp_lite.core.progress import FitBar, command_progress
    from ddp_lite.method import loop
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.runtime.options import RunOptions

    class Recorder:
        def __init__(self, iterations):
            self.iterations, self.calls = iterations, []

        def __iter__(self):
            return iter(range(self.iterations))

        def held_out(self, error):
            self.calls.append(("held_out", error))

        def expect(self, expected_total, earliest_total):
            self.calls.append(("expect", expected_total, earliest_total))

        def close(self):
            self.calls.append(("close",))

    config = FitConfig(channels=(4, 8), iterations=20, eval_every=5, patience=100, auto_stop=True)
    net, noise = loop.build(config, 1, 8, 8, torch.device("cpu"))
    target = torch.zeros(1, 1, 8, 8)

    def loss_fn(output):
        loss = (output - target).abs().mean()
        return loss, {"l1": loss}

    recorder = Recorder(20)
    _, history, ran, _ = loop.run(net, noise, loss_fn, config, 20, lambda out: float(out.abs().mean()),
                                  progress=recorder, options=RunOptions())
    kinds = [call[0] for call in recorder.calls]
    assert ran == 20 and kinds == ["held_out", "expect"] * 4 + ["close"]
    assert np.allclose([c[1] for c in recorder.calls if c[0] == "held_out"], history["held_out"])
    assert all(0 < c[2] <= c[1] <= 20 for c in recorder.calls if c[0] == "expect")
    with command_progress(20, expected_share=0.5) as clock:
        bar = FitBar(20, "fit", enabled=False)
        bar.expect(15, 10)  # 15 expected in all, 10 at least: what the clock now counts on
        assert clock.bar_left == (20, 15, 10)
        bar.close()
    FitBar(20, enabled=False).expect(15, 10)  # with no command open, nobody to tell: no error
