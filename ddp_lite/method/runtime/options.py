"""RunOptions: how a fit runs, not what it computes: the device, precision, memory format, memory
limit, progress bar and callback rate. None of them changes a fit's numbers on one device, except
``bf16`` (the net under bfloat16: other rounding); the fit cache's key leaves ``progress`` out.
"""
from __future__ import annotations

from dataclasses import dataclass

from ...core.checks import check_bool, check_int, check_real
from ...core.settings import Settings
from .device import resolve_device

__all__ = ["RunOptions"]


@dataclass(frozen=True)
class RunOptions(Settings):
    """Where and how a fit runs (6 fields)."""

    device: str | None = None  # None → cuda or mps when available, else cpu (device.resolve_device)
    bf16: bool | None = False  # the network (not the losses) under bfloat16 autocast; None: where the hardware has it
    channels_last: bool = False  # memory format of the network's activations
    max_memory_gb: float | None = None  # refuse a fit whose estimated peak exceeds this; None → 75 % of RAM
    progress: bool = True  # a progress bar per fit
    callback_every: int = 0  # iterations between calls of a fit's callback (0: never)

    def validate(self) -> None:
        check_int(self.callback_every, "config.callback_every", minimum=0)
        for name in ("channels_last", "progress"):
            check_bool(getattr(self, name), f"config.{name}")
        if self.bf16 is not None:  # None: decided by the hardware (device.use_bf16)
            check_bool(self.bf16, "config.bf16")
        if self.max_memory_gb is not None:
            check_real(self.max_memory_gb, "config.max_memory_gb", 0.0, low_open=True)
        if self.device is not None:
            resolve_device(self)  # a name torch knows and a device this machine has
