"""Progress bars that stay readable in logs.

tqdm redraws its bar with carriage returns: fine on a terminal or as a notebook widget, but a log
file (CI, ``ddp-lite demo > log 2>&1``) gets every redraw on one ever-growing line (100 kB for one
fit). :func:`progress` returns tqdm's bar where it can be redrawn (a terminal, a Jupyter kernel)
and otherwise a :class:`LineProgress` that prints one short line every ``every`` percent.

The choice follows the stream the bar writes to (stderr, as tqdm does): a bar on a terminal stays
a bar even when stdout is redirected, and a redirected stderr gets lines.

A command that runs several fits (a demo, an ensemble) opens :func:`command_progress` with the
iterations it plans in all; every bar opened inside counts toward it and shows the whole
command's share and time left beside its own (``all 40%, 1:12 left``). The time left is the rate
of the iterations run so far (from the first one: set-up before it is not an iteration) times the
iterations still expected. A fit that may stop by itself expects to run ``expected_share`` of its
cap until it says better (:meth:`CommandClock.expect`, from its stopper's state); a fit that stops
early hands its unrun iterations back, so the share jumps ahead and the time left shrinks. Where
fits may stop by themselves, no single time is honest (one stops at half its cap, the next runs
to it), so the line gives the range too: every fit stopping at its earliest, every fit running to
its cap (``all 40%, 1:12 left (0:50–1:40)``).

A fit's loop reports through a hook its caller hands it, :class:`FitProgress`: the loop iterates over
it, and tells it each held-out error and where its stopper now expects the fit to stop. The kit's own
hook, :class:`FitBar`, is a bar over the iterations that passes those expectations on to the open
command's clock.
"""
from __future__ import annotations

import contextlib
import sys
import time
from typing import Iterator, Protocol

__all__ = ["progress", "LineProgress", "command_progress", "CommandClock", "FitProgress", "FitBar"]


class CommandClock:
    """Iterations done of a whole command's ``total``, and the time left at the rate so far.

    ``expected_share``: the share of its iterations a fit is expected to run (below 1 where fits stop
    by themselves), ``earliest_share`` the share it runs at least (default: ``expected_share``); the
    open bar's own expectation (:meth:`expect`) replaces them for that bar.
    """

    def __init__(self, total: int, expected_share: float = 1.0, earliest_share: float | None = None):
        if not (isinstance(total, int) and total >= 1):
            raise ValueError(f"total must be a positive number of iterations, got {total!r}")
        if not 0 < expected_share <= 1:
            raise ValueError(f"expected_share must be in (0, 1], got {expected_share!r}")
        earliest_share = expected_share if earliest_share is None else earliest_share
        if not 0 < earliest_share <= expected_share:
            raise ValueError(f"earliest_share must be in (0, expected_share={expected_share}], got {earliest_share!r}")
        self.total, self.expected_share, self.earliest_share = total, float(expected_share), float(earliest_share)
        self.ran = self.skipped = 0  # iterations run; iterations handed back unrun by fits that stopped early
        self.first = self.last = None  # when the first and the latest iteration started: the rate's span
        self.from_start = False  # True after begin(): ``first`` is when the first unit began, not ended
        self.at_once = 1  # after begin(): units that run side by side, started together
        self.bar_left = None  # (planned, expected, earliest) iterations left of the open bar, when it has said so

    @property
    def done(self) -> int:
        """Iterations run or handed back, of ``total``."""
        return min(self.total, self.ran + self.skipped)

    def begin(self, at_once: int = 1) -> None:
        """The first unit starts now. For units that report when they end, not when they begin (the views
        of a sequence): the rate is then the time since this call over the units done, the first included.
        ``at_once`` units run side by side: the first to end had ``at_once - 1`` others running beside it,
        so the time so far is counted over whole rounds of ``at_once`` units."""
        if not (isinstance(at_once, int) and at_once >= 1):
            raise ValueError(f"at_once must be a positive number of units, got {at_once!r}")
        self.first, self.from_start, self.at_once = time.perf_counter(), True, at_once

    def advance(self, n: int = 1) -> None:
        """``n`` iterations were run."""
        self.last = time.perf_counter()
        if self.first is None:
            self.first = self.last  # the rate is measured from here: set-up before it is no iteration
        self.ran += n

    def hand_back(self, n: int) -> None:
        """A fit stopped ``n`` iterations before its cap: they will not run."""
        self.skipped += n
        self.bar_left = None

    def expect(self, planned_left: int, expected_left: int, earliest_left: int | None = None) -> None:
        """The open bar has ``planned_left`` iterations to its cap, expects to run ``expected_left`` of
        them and runs at least ``earliest_left`` (default: ``expected_left``)."""
        expected_left = max(0, int(expected_left))
        earliest_left = expected_left if earliest_left is None else min(expected_left, max(0, int(earliest_left)))
        self.bar_left = (max(0, int(planned_left)), expected_left, earliest_left)

    def _rate(self) -> float | None:
        """Seconds per iteration since the first one started, or None before there is one."""
        if self.first is None:
            return None
        if self.from_start:
            rounds = -(-self.ran // self.at_once)  # rounds begun so far: the units done, and those beside them
            rate = (self.last - self.first) / (rounds * self.at_once) if self.ran else None
            return rate if rate else None
        if self.ran >= 2:
            rate = (self.last - self.first) / (self.ran - 1)
        else:
            rate = time.perf_counter() - self.first  # the first iteration, still running or just done
        return rate if rate > 0 else None

    def _iterations_left(self) -> tuple[float, float, float]:
        """(earliest, expected, planned) iterations still to run."""
        planned_left = self.total - self.done
        bar_planned, bar_expected, bar_earliest = self.bar_left if self.bar_left is not None else (0, 0, 0)
        rest = planned_left - min(bar_planned, planned_left)  # of the fits after the open bar
        return (bar_earliest + rest * self.earliest_share, bar_expected + rest * self.expected_share,
                float(planned_left))

    def seconds_left(self) -> float | None:
        """Seconds still expected, or None before a rate can be measured."""
        rate = self._rate()
        return None if rate is None else rate * self._iterations_left()[1]

    def seconds_left_range(self) -> tuple[float, float] | None:
        """(earliest, latest) seconds left: every fit stopping at its earliest, every fit running to its cap."""
        rate = self._rate()
        if rate is None:
            return None
        earliest, _, planned = self._iterations_left()
        return rate * earliest, rate * planned

    def summary(self) -> str:
        """``all 40%, 1:12 left``, with the range where fits may stop by themselves:
        ``all 40%, 1:12 left (0:50–1:40)`` (no time until a rate is measured)."""
        share = self.done / self.total
        rate = self._rate()
        if rate is None:
            return f"all {share:.0%}"
        low, left, high = (_minutes(rate * n) for n in self._iterations_left())
        return f"all {share:.0%}, {left} left" + (f" ({low}–{high})" if low != high else "")


def _minutes(seconds: float) -> str:
    """``1:05`` for 65 seconds."""
    minutes, seconds = divmod(int(round(seconds)), 60)
    return f"{minutes}:{seconds:02d}"


_COMMAND: list[CommandClock] = []  # the innermost open command_progress, if any


@contextlib.contextmanager
def command_progress(total: int, expected_share: float = 1.0, earliest_share: float | None = None):
    """Count every bar opened inside the block toward ``total`` iterations (a whole command's), of
    which fits that may stop by themselves are expected to run ``expected_share`` and run at least
    ``earliest_share``."""
    clock = CommandClock(total, expected_share, earliest_share)
    _COMMAND.append(clock)
    try:
        yield clock
    finally:
        _COMMAND.remove(clock)


class _Counted:
    """A bar (tqdm's or a LineProgress) whose items also advance the command's clock; the bar's own
    interface (``set_postfix``, ``close``, ...) passes through."""

    def __init__(self, bar, clock: CommandClock, desc: str, total: int | None):
        self.bar, self.clock, self.desc, self.total, self.n = bar, clock, desc, total, 0
        self._shown = 0.0

    def __iter__(self):
        for item in self.bar:
            self.n += 1
            self.clock.advance()
            now = time.perf_counter()
            if now - self._shown > 0.2 and hasattr(self.bar, "set_description"):
                self._shown = now
                self.bar.set_description(f"{self.desc} ({self.clock.summary()})" if self.desc else self.clock.summary(),
                                         refresh=False)
            yield item
        self._hand_back()

    def _hand_back(self) -> None:
        if self.total and self.n < self.total:  # stopped early: the rest will not run
            self.clock.hand_back(self.total - self.n)
            self.total = self.n
        self.clock.bar_left = None

    def expect(self, expected_total: int, earliest_total: int | None = None) -> None:
        """This bar now expects to run ``expected_total`` iterations in all and at least
        ``earliest_total`` (its stopper's estimates)."""
        if self.total:
            earliest = None if earliest_total is None else min(earliest_total, self.total) - self.n
            self.clock.expect(self.total - self.n, min(expected_total, self.total) - self.n, earliest)

    def close(self) -> None:
        self._hand_back()
        self.bar.close()

    def __getattr__(self, name):
        return getattr(self.bar, name)


def _in_kernel() -> bool:
    """True inside a Jupyter kernel, where tqdm.auto draws a widget that updates in place."""
    if "ipykernel" not in sys.modules:
        return False
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and hasattr(shell, "kernel")


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed file
        return False


class LineProgress:
    """Iterate over ``iterable``, printing ``desc: 30% (45/150) 2.1 s`` every ``every`` percent, and
    a last line when it closes (also after an early ``break``). Mirrors the part of tqdm's interface
    the kit uses: iteration, ``set_postfix`` and ``close``."""

    def __init__(self, iterable, desc: str = "", total: int | None = None, every: float = 10.0, stream=None):
        if not 0 < every <= 100:
            raise ValueError(f"every must be a percentage in (0, 100], got {every!r}")
        self.iterable = iterable
        self.total = total if total is not None else (len(iterable) if hasattr(iterable, "__len__") else None)
        self.desc, self.every, self.stream = desc, every, stream
        self.n, self.postfix, self.closed = 0, "", False
        self.start = time.perf_counter()
        self._next_percent = every

    def __iter__(self):
        for item in self.iterable:
            self.n += 1  # counted when handed out, so that a `break` in the loop body counts its item
            yield item
            if self.total and 100 * self.n / self.total >= self._next_percent - 1e-9 and self.n < self.total:
                self._line(f"{100 * self.n / self.total:.0f}% ({self.n}/{self.total})")
                while self._next_percent <= 100 * self.n / self.total + 1e-9:
                    self._next_percent += self.every
        self.close()

    def set_postfix(self, refresh: bool = True, **values) -> None:
        self.postfix = ", ".join(f"{key}={value}" for key, value in values.items())

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        if self.total and self.n < self.total:
            self._line(f"stopped at {self.n}/{self.total}")
        else:
            self._line(f"done ({self.n}{f'/{self.total}' if self.total else ''})")

    def _line(self, state: str) -> None:
        stream = self.stream if self.stream is not None else sys.stderr
        prefix = f"{self.desc}: " if self.desc else ""
        suffix = f" {self.postfix}" if self.postfix else ""
        if _COMMAND:
            suffix += f" ({_COMMAND[-1].summary()})"
        print(f"{prefix}{state} {time.perf_counter() - self.start:.1f} s{suffix}", file=stream, flush=True)


def progress(iterable, desc: str = "", disable: bool = False, leave: bool = True, total: int | None = None,
             every: float = 10.0, stream=None, **tqdm_options):
    """A progress bar over ``iterable``: tqdm's on a terminal or in Jupyter, short lines elsewhere.

    Args:
        desc: label of the bar or of each line.
        disable: no output at all (tqdm's bar, disabled).
        every: in line mode, print a line each time this many more percent are done.
        stream: where lines go (default: ``sys.stderr`` at the time of printing, like tqdm).
        leave, **tqdm_options: passed to tqdm in bar mode.
    """
    target = stream if stream is not None else sys.stderr
    if disable or _in_kernel() or _is_terminal(target):
        from tqdm.auto import tqdm
        bar = tqdm(iterable, desc=desc, disable=disable, leave=leave, total=total,
                   **({"file": stream} if stream is not None else {}), **tqdm_options)
    else:
        bar = LineProgress(iterable, desc=desc, total=total, every=every, stream=stream)
    if not _COMMAND:
        return bar
    total = total if total is not None else (len(iterable) if hasattr(iterable, "__len__") else None)
    return _Counted(bar, _COMMAND[-1], desc, total)


class FitProgress(Protocol):
    """What a fit's loop reports while it runs: the hook :func:`ddp_lite.method.loop.run` takes from its
    caller. The loop iterates over it for its iterations, may stop early, and closes it."""

    def __iter__(self) -> Iterator[int]:
        """The iteration numbers 0, 1, ..., ``iterations - 1``, each handed out as the loop takes it."""

    def held_out(self, error: float) -> None:
        """The latest held-out error (mean |Z_out − Z_in| over the held-out pixels, normalised disparity)."""

    def expect(self, expected_total: int, earliest_total: int) -> None:
        """The fit now expects to run ``expected_total`` iterations in all, and at least ``earliest_total``
        (its stopper's state, :mod:`ddp_lite.method.time_left`)."""

    def close(self) -> None:
        """The loop is done: after its last iteration, or an early stop."""


class FitBar:
    """The kit's :class:`FitProgress`: a bar over a fit's ``iterations`` (:func:`progress`, labelled
    ``description``, silent unless ``enabled``) showing the held-out error; inside a
    :func:`command_progress` block its expectations reach the command's clock (:meth:`CommandClock.expect`)."""

    def __init__(self, iterations: int, description: str = "fit", enabled: bool = True):
        self.bar = progress(range(iterations), desc=description, disable=not enabled, leave=False)
        # only a bar counted toward a command has a clock to tell; a plain bar shows the error alone
        self._clock_bar = self.bar if isinstance(self.bar, _Counted) else None

    def __iter__(self) -> Iterator[int]:
        return iter(self.bar)

    def held_out(self, error: float) -> None:
        self.bar.set_postfix(held_out=f"{error:.4f}", refresh=False)

    def expect(self, expected_total: int, earliest_total: int) -> None:
        if self._clock_bar is not None:
            self._clock_bar.expect(expected_total, earliest_total)

    def close(self) -> None:
        self.bar.close()
