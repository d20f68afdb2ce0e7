"""Progress bars that stay readable in logs.

tqdm redraws its bar with carriage returns: fine on a terminal or as a notebook widget, but a log
file (CI, ``ddp-lite demo > log 2>&1``) gets every redraw on one ever-growing line (100 kB for one
fit). :func:`progress` returns tqdm's bar where it can be redrawn (a terminal, a Jupyter kernel)
and otherwise a :class:`LineProgress` that prints one short line every ``every`` percent.

The choice follows the stream the bar writes to (stderr, as tqdm does): a bar on a terminal stays
a bar even when stdout is redirected, and a redirected stderr gets lines.

A command that runs several fits (a demo, an ensemble) opens :func:`command_progress` with the
iterations it expects in all; every bar opened inside counts toward it and shows the whole
command's share and time left beside its own (``all 40%, 1:12 left``). A fit that stops early
hands its unrun iterations back, so the estimate shrinks instead of stalling.
"""
from __future__ import annotations

import contextlib
import sys
import time

__all__ = ["progress", "LineProgress", "command_progress", "CommandClock"]


class CommandClock:
    """Iterations done of a whole command's ``total``, and the time left at the rate so far."""

    def __init__(self, total: int):
        if not (isinstance(total, int) and total >= 1):
            raise ValueError(f"total must be a positive number of iterations, got {total!r}")
        self.total, self.done, self.start = total, 0, time.perf_counter()

    def advance(self, n: int = 1) -> None:
        self.done = min(self.total, self.done + n)

    def summary(self) -> str:
        """``all 40%, 1:12 left`` (no time until something is done)."""
        share = self.done / self.total
        if not self.done:
            return f"all {share:.0%}"
        left = (time.perf_counter() - self.start) * (self.total - self.done) / self.done
        minutes, seconds = divmod(int(round(left)), 60)
        return f"all {share:.0%}, {minutes}:{seconds:02d} left"


_COMMAND: list[CommandClock] = []  # the innermost open command_progress, if any


@contextlib.contextmanager
def command_progress(total: int):
    """Count every bar opened inside the block toward ``total`` iterations (a whole command's)."""
    clock = CommandClock(total)
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
            self.clock.advance(self.total - self.n)
            self.total = self.n

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
