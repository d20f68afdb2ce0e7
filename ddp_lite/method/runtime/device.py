"""Where and in what precision a fit runs: the device (CPU by default; CUDA or MPS when asked for or
available; ``RunOptions.device``) and bfloat16 for the net (the config's :class:`Precision`; not in the paper).

    bf16 = config.precision.bf16, or for None: the device computes bfloat16 natively (AVX-512 BF16 / AMX, CUDA)

Only the net runs under bfloat16 autocast (:func:`ddp_lite.method.loop.run`); the losses stay in float32.
The precision changes a fit's numbers, so it is a section of the method's config, which a recipe sets
(``kit`` at ``class``: where the CPU has it natively); the device is a run option.
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass

import torch

from ...core.checks import check_bool
from ...core.settings import Settings

__all__ = ["Precision", "use_bf16", "resolve_device"]


@dataclass(frozen=True)
class Precision(Settings):
    """The arithmetic the net runs in (1 field; the paper's: float32)."""

    bf16: bool | None = False  # the network (not the losses) under bfloat16 autocast; None: where the hardware has it

    def validate(self) -> None:
        if self.bf16 is not None:  # None: decided by the hardware (use_bf16)
            check_bool(self.bf16, "config.bf16")


def use_bf16(bf16: bool | None, device: torch.device) -> bool:
    """Whether a fit runs its net in bfloat16: ``bf16`` itself, or for ``None`` whether ``device``
    computes bfloat16 natively (a CPU with AVX-512 BF16 or AMX, a CUDA GPU with bf16). Where it
    is emulated it is slower than float32, where it is native faster with no worse hole error over
    seeds (``docs/studies/benchmark_history.md``, "What to keep (the speed study)")."""
    if bf16 is not None:
        return bool(bf16)
    if device.type == "cuda":
        return torch.cuda.is_bf16_supported()
    return device.type == "cpu" and _cpu_has_native_bf16()


@functools.lru_cache(maxsize=1)
def _cpu_has_native_bf16() -> bool:
    # oneDNN reports bf16 "supported" on any AVX-512 CPU, emulated or not: ask the CPU itself, and
    # whether torch may use it (ATEN_CPU_CAPABILITY / ONEDNN_MAX_CPU_ISA cap the kernels at AVX2, as on
    # most laptops: there bfloat16 would be emulated, several times slower than float32)
    try:
        with open("/proc/cpuinfo") as handle:
            flags = next((line.split(":", 1)[1].split() for line in handle if line.startswith("flags")), [])
    except OSError:
        return False
    return ("avx512_bf16" in flags or "amx_bf16" in flags) and not _isa_capped_below_avx512()


def _isa_capped_below_avx512() -> bool:
    """Whether torch's or oneDNN's kernels are held below AVX-512 (by the environment variables above)."""
    if torch.backends.cpu.get_cpu_capability() not in ("AVX512", "AVX512_BF16", "AMX"):
        return True
    isa = os.environ.get("ONEDNN_MAX_CPU_ISA", os.environ.get("DNNL_MAX_CPU_ISA", "ALL")).upper()
    return isa != "ALL" and not isa.startswith(("AVX512", "AVX10", "AMX"))


def resolve_device(options) -> torch.device:
    """The ``torch.device`` a fit with these :class:`~ddp_lite.method.runtime.options.RunOptions` runs on:
    ``options.device``, checked against this machine, or for None CUDA, then MPS, then the CPU."""
    if options.device is not None:
        if not isinstance(options.device, (str, torch.device)):
            raise TypeError(f"options.device must be None or a name like 'cpu', 'cuda', 'cuda:0', 'mps', "
                            f"got {type(options.device).__name__}")
        try:
            device = torch.device(options.device)
        except RuntimeError:
            raise ValueError(f"options.device must be None, 'cpu', 'cuda[:N]' or 'mps', got {options.device!r}") from None
        mps = getattr(torch.backends, "mps", None)
        available = {"cpu": True, "cuda": torch.cuda.is_available(),
                     "mps": mps is not None and mps.is_available()}
        if not available.get(device.type, False):
            raise ValueError(f"options.device={options.device!r}: this machine has no usable {device.type} device; "
                             f"use 'cpu' or None (picks cuda/mps when present)")
        if device.type == "cuda" and device.index is not None and device.index >= torch.cuda.device_count():
            raise ValueError(f"options.device={options.device!r}: only {torch.cuda.device_count()} CUDA device(s)")
        return device
    if torch.cuda.is_available():
        return torch.device("cuda")
    if getattr(torch.backends, "mps", None) is not None and torch.backends.mps.is_available():
        return torch.device("mps")
    return torch.device("cpu")
