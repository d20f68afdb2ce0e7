"""Where a command's CPU goes, by kind of process: `make test` (the default) and every process it starts.

    python benchmarks/suite_cpu.py
    python benchmarks/suite_cpu.py --interval 0.2 --command ".venv/bin/python -m pytest tests/core -n 2"

Every ``--interval`` seconds it reads, from /proc (Linux only), the CPU time (user + system) of each process
below the command and the machine's idle time. At the end it prints, per kind of process
(:func:`process_kind`: the pytest controller, its workers, the kernels they start (nbval's, the classroom's
runs; forked by tests/kernel_forkserver.py's server, or fresh), ``grade()``'s supervised children and their
kernels, ``ddp-lite`` commands, Dask and multiprocessing, Jupyter, the installer, the rest), how many ran and
their CPU seconds; then the wall time, the cores' idle seconds in each tenth of the run, and the command's exit
status. A process that ends between two reads loses its last
interval (at most ``--interval`` s each): the counts are a floor. It asserts nothing (a benchmark).
What it found on `make test`: docs/studies/benchmark_history.md.
"""
from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import parse_args  # noqa: E402

TICKS = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
XDIST_WORKER = "exec(eval(sys.stdin.readline()))"  # how execnet starts a pytest-xdist worker


def process_kind(command: str, parent_kind: str | None) -> str:
    """The kind of a process, from its command line (arguments joined by spaces) and its parent's kind.

    >>> process_kind("python -m ipykernel_launcher -f k.json", "pytest worker")
    "kernel (a worker's)"
    """
    program = Path(command.split(" ", 1)[0]).name
    if program in ("make", "sh", "bash", "env", "time"):  # before pytest: make's shell line holds the pytest command
        return "shell"
    if "ipykernel_launcher" in command:  # nbval and the classroom's runs start kernels themselves; grade() from a child
        return "kernel (a worker's)" if parent_kind == "pytest worker" else "kernel (a grader child's)"
    if "kernel_forkserver.py serve" in command:  # the tests' kernel server; the kernels it forks keep its command line
        return "kernel (a worker's, forked)" if parent_kind == "kernel server" else "kernel server"
    if "kernel_forkserver.py launch" in command:  # the stand-in for a forked kernel (a fresh one where it is refused)
        return "kernel (a worker's)"
    if XDIST_WORKER in command:  # a fork keeps its parent's command line: grade()'s supervised child per hand-in
        return "grader child" if parent_kind in ("pytest worker", "grader child") else "pytest worker"
    if " -m pytest" in command or program in ("pytest", "py.test"):  # not a path that holds "pytest-of-root"
        return "pytest controller" if parent_kind in (None, "shell") else "pytest (nested)"
    if "ddp-lite" in command or "ddp_lite.interface.cli" in command:
        return "ddp-lite command"
    if "distributed" in command or "dask" in command or "multiprocessing" in command:
        return "dask / multiprocessing"
    if "jupyter" in command:
        return "jupyter server"
    if " pip " in f" {command} " or "/uv " in command or command.startswith("uv "):
        return "installer (pip, uv)"
    return "other"


def _read_stat(pid: str):
    """(parent pid, CPU seconds) of ``pid`` from /proc, or None once it has gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as handle:
            fields = handle.read().rsplit(b")", 1)[1].split()
    except OSError:
        return None
    return fields[1].decode(), (int(fields[11]) + int(fields[12])) / TICKS


def _command_line(pid: str) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as handle:
            return handle.read().replace(b"\0", b" ").decode(errors="replace").strip()
    except OSError:
        return ""


def _idle_seconds() -> float:
    """The machine's idle + iowait time so far, summed over its cores (/proc/stat)."""
    with open("/proc/stat") as handle:
        fields = handle.readline().split()
    return (int(fields[4]) + int(fields[5])) / TICKS


def measure(command: list[str], interval: float = 0.25) -> dict:
    """Run ``command`` and sample its process tree every ``interval`` s. Returns {"processes": {pid:
    {"kind", "command", "cpu_s"}}, "wall_s", "idle_s" (core-seconds), "idle_by_tenth" (core-seconds),
    "returncode"}."""
    start, idle0 = time.monotonic(), _idle_seconds()
    child = subprocess.Popen(command)
    root = str(child.pid)
    seen: dict[str, dict] = {}
    idle_samples = [(0.0, idle0)]
    while True:
        done = child.poll() is not None
        stats = {pid: stat for pid in os.listdir("/proc") if pid.isdigit() and (stat := _read_stat(pid)) is not None}
        for pid, (ppid, cpu) in stats.items():
            if pid in seen:
                seen[pid]["cpu_s"] = cpu
            elif pid == root or ppid in seen:
                command = _command_line(pid)
                parent_kind = seen[ppid]["kind"] if ppid in seen else None
                seen[pid] = {"kind": process_kind(command, parent_kind), "command": command[:200], "cpu_s": cpu,
                             "parent": ppid}
        idle_samples.append((time.monotonic() - start, _idle_seconds()))
        if done:
            break
        time.sleep(interval)
    wall = time.monotonic() - start
    tenths = [0.0] * 10
    for (t0, i0), (t1, i1) in zip(idle_samples, idle_samples[1:]):
        tenths[min(9, int(10 * t0 / max(wall, 1e-9)))] += i1 - i0
    return {"processes": seen, "wall_s": wall, "idle_s": idle_samples[-1][1] - idle0, "idle_by_tenth": tenths,
            "returncode": child.returncode}


def report(result: dict) -> str:
    """The printout of :func:`measure`'s result: CPU seconds and counts per kind, then wall and idle time."""
    by_kind: dict[str, list] = defaultdict(lambda: [0, 0.0])
    for process in result["processes"].values():
        by_kind[process["kind"]][0] += 1
        by_kind[process["kind"]][1] += process["cpu_s"]
    total = sum(cpu for _, cpu in by_kind.values())
    lines = [f"{'kind of process':<28} {'processes':>9} {'CPU-s':>8} {'share':>6}"]
    for kind, (count, cpu) in sorted(by_kind.items(), key=lambda item: -item[1][1]):
        lines.append(f"{kind:<28} {count:>9} {cpu:>8.1f} {cpu / max(total, 1e-9):>6.1%}")
    cores = os.cpu_count() or 1
    lines += [f"{'all':<28} {sum(c for c, _ in by_kind.values()):>9} {total:>8.1f}",
              f"wall {result['wall_s']:.1f} s on {cores} cores ({cores * result['wall_s']:.0f} core-s): "
              f"idle {result['idle_s']:.1f} core-s; per tenth of the run: "
              + " ".join(f"{idle:.0f}" for idle in result["idle_by_tenth"]),
              f"exit status {result['returncode']}"]
    return "\n".join(lines)


def _check(args) -> None:
    if not args.interval > 0:
        raise ValueError(f"--interval must be a positive number of seconds, got {args.interval}")
    if not shlex.split(args.command):
        raise ValueError("--command: give the command to run, e.g. --command 'make test'")
    if not Path("/proc/stat").exists():
        raise ValueError("--interval: this script reads /proc (Linux); this machine has none")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--interval", type=float, default=0.25, help="seconds between two reads of /proc")
    parser.add_argument("--command", default="make test", help="the command to run, as a shell would split it")
    args = parse_args(parser, argv, check=_check)
    result = measure(shlex.split(args.command), args.interval)
    print(report(result))
    return result["returncode"]


if __name__ == "__main__":
    sys.exit(main())
