"""Run a benchmark as on a laptop: ``--isa avx2`` holds torch, oneDNN and MKL to AVX2 kernels.

Most student laptops have AVX2 and no AVX-512 or AMX; a machine that has them runs other kernels
(and, at ``class``, the net in bfloat16). Three switches, read once when each library starts, so
they must be in the environment before ``import torch``: :func:`reexec_with_isa` puts them there
and starts the script again.

    ATEN_CPU_CAPABILITY=avx2       torch's own vectorised kernels (torch.backends.cpu.get_cpu_capability())
    ONEDNN_MAX_CPU_ISA=AVX2        oneDNN's convolutions (its verbose line names the kernel: jit:avx2)
    MKL_ENABLE_INSTRUCTIONS=AVX2   MKL's matrix multiply, which gives the FLOP bound

``ddp_lite.method.runtime.device`` sees the cap and runs the net in float32, as a laptop without
AVX-512 BF16 would. :func:`isa_summary` says what took effect, to print beside every figure.

    python benchmarks/bench_fit.py --isa avx2
"""
from __future__ import annotations

import os
import subprocess
import sys

ISA_ENV = {
    "native": {},
    "avx2": {"ATEN_CPU_CAPABILITY": "avx2", "ONEDNN_MAX_CPU_ISA": "AVX2", "MKL_ENABLE_INSTRUCTIONS": "AVX2"},
}
CPU_FLAGS = ("avx2", "avx512f", "avx512_bf16", "amx_bf16")


def reexec_with_isa(argv=None) -> str:
    """Read ``--isa NAME`` from ``argv`` (default ``sys.argv``); when its variables are not yet in the
    environment, set them and re-execute this process (before torch is imported). Returns the name."""
    argv = list(sys.argv if argv is None else argv)
    name = "native"
    for i, item in enumerate(argv):
        if item == "--isa" and i + 1 < len(argv):
            name = argv[i + 1]
        elif item.startswith("--isa="):
            name = item.split("=", 1)[1]
    if name not in ISA_ENV:
        raise SystemExit(f"--isa must be one of {', '.join(ISA_ENV)}, got {name!r}")
    wanted = ISA_ENV[name]
    if any(os.environ.get(key) != value for key, value in wanted.items()):
        if "torch" in sys.modules:
            raise RuntimeError("reexec_with_isa must run before torch is imported")
        os.environ.update(wanted)
        os.execv(sys.executable, [sys.executable, *argv])
    return name


def cpu_flags() -> tuple[str, set]:
    """(model name, flags) from /proc/cpuinfo (empty on other systems)."""
    model, flags = "unknown CPU", set()
    try:
        with open("/proc/cpuinfo") as handle:
            for line in handle:
                key, _, value = line.partition(":")
                if key.strip() == "model name":
                    model = value.strip()
                elif key.strip() == "flags":
                    flags = set(value.split())
                    break
    except OSError:
        pass
    return model, flags


def onednn_kernel() -> str:
    """The oneDNN kernel a 3×3 float32 convolution runs with here (e.g. ``jit:avx2``), read from its
    verbose line in a child process with this environment."""
    code = ("import torch; torch.nn.functional.conv2d(torch.rand(1, 32, 96, 128), torch.rand(32, 32, 3, 3), "
            "padding=1)")  # large enough for torch to hand it to oneDNN
    env = dict(os.environ, ONEDNN_VERBOSE="1", OMP_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env).stdout
    for line in out.splitlines():
        if ",exec,cpu,convolution," in line:
            return line.split(",")[6]
    return "unknown (no oneDNN verbose line)"


def isa_summary() -> str:
    """One line: the CPU, its vector flags, and the kernels torch and oneDNN actually run."""
    import torch
    from ddp_lite.method.runtime.device import use_bf16
    model, flags = cpu_flags()
    marks = " ".join(f"{flag}{'+' if flag in flags else '-'}" for flag in CPU_FLAGS)
    capped = {key: os.environ[key] for key in ISA_ENV["avx2"] if key in os.environ}
    return (f"CPU: {model} [{marks}]; torch kernels {torch.backends.cpu.get_cpu_capability()}, oneDNN "
            f"{onednn_kernel()}, class's bf16=None → {'bfloat16' if use_bf16(None, torch.device('cpu')) else 'float32'}"
            + (f"; capped by {' '.join(f'{k}={v}' for k, v in capped.items())}" if capped else ""))
