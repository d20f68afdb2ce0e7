"""RunOptions: how a fit runs, not what it computes: the device, memory format, memory limit, progress
bar and callback rate. None of them changes a fit's numbers on one device; what does is the method's
:class:`~ddp_lite.method.config.FitConfig` (the net's precision, ``bf16``, included).

Every entry point that runs a fit takes them as ``options``:
``complete_depth(rgb, depth, config=config, options=RunOptions(progress=False))``; None is ``RunOptions()``.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ...core.checks import check_bool, check_int, check_real
from ...core.settings import Settings
from .device import resolve_device

__all__ = ["RunOptions", "RUN_OPTIONS", "run_options"]


@dataclass(frozen=True)
class RunOptions(Settings):
    """Where and how a fit runs (5 fields)."""

    device: str | None = None  # None → cuda or mps when available, else cpu (device.resolve_device)
    channels_last: bool = False  # memory format of the network's activations
    max_memory_gb: float | None = None  # refuse a fit whose estimated peak exceeds this; None → 75 % of RAM
    progress: bool = True  # a progress bar per fit
    callback_every: int = 0  # iterations between calls of a fit's callback (0: never)

    def validate(self) -> None:
        check_int(self.callback_every, "options.callback_every", minimum=0)
        for name in ("channels_last", "progress"):
            check_bool(getattr(self, name), f"options.{name}")
        if self.max_memory_gb is not None:
            check_real(self.max_memory_gb, "options.max_memory_gb", 0.0, low_open=True)
        if self.device is not None:
            resolve_device(self)  # a name torch knows and a device this machine has

    def replace(self, **changes) -> "RunOptions":
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)


RUN_OPTIONS = tuple(f.name for f in dataclasses.fields(RunOptions))


def run_options(options) -> RunOptions:
    """``options`` checked: a :class:`RunOptions` (None → ``RunOptions()``), else ``TypeError``; its fields
    validated."""
    options = RunOptions() if options is None else options
    if not isinstance(options, RunOptions):
        raise TypeError(f"options must be a RunOptions (ddp_lite.RunOptions(progress=False, ...)), "
                        f"got {type(options).__name__}")
    options.validate()
    return options
