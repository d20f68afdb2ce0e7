"""How long ``ddp-lite --help`` and each ``ddp-lite COMMAND --help`` take, as a user meets them: a
fresh process each time (the console script's own start, imports included), median of ``--repeat``.
Also the time to a refused argument, which must answer as fast, and the modules a ``--help`` imported.

    OMP_NUM_THREADS=1 python benchmarks/bench_cli.py
    OMP_NUM_THREADS=1 python benchmarks/bench_cli.py --repeat 9
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path
from _common import parse_args

ROOT = Path(__file__).resolve().parent.parent
COMMANDS = ("demo", "scenes", "complete", "sequence", "student", "solutions", "grade")
HEAVY = ("torch", "open3d", "cv2", "matplotlib", "nbformat", "scipy", "dask")


def _seconds(argv, repeat: int) -> float:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    runs = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "ddp_lite.interface.cli", *argv], env=env, capture_output=True)
        runs.append(time.perf_counter() - start)
    return statistics.median(runs)


def _imported(argv) -> list[str]:
    code = (f"import sys; from ddp_lite.interface.cli import main\ntry: main({list(argv)!r})\nexcept SystemExit: pass\n"
            f"print('HEAVY:' + ','.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], env={**os.environ, "PYTHONPATH": str(ROOT)},
                         capture_output=True, text=True).stdout
    line = out[out.rindex("HEAVY:") + len("HEAVY:"):].strip()
    return line.split(",") if line else []


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per command (median; default 5)")
    args = parse_args(parser, argv)
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")),
               platform.processor()) if os.path.exists("/proc/cpuinfo") else platform.processor()
    print(f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}; median of {args.repeat} fresh processes")
    print(f"{'python -c pass':<34} {_seconds_python(args.repeat):6.3f} s   (the interpreter alone)")
    cases = [["--help"], ["--version"]] + [[c, "--help"] for c in COMMANDS] + [["demo", "--profile", "nope"]]
    for argv in cases:
        heavy = _imported(argv)
        print(f"{'ddp-lite ' + ' '.join(argv):<34} {_seconds(argv, args.repeat):6.3f} s   "
              f"heavy modules imported: {', '.join(heavy) or 'none'}")


def _seconds_python(repeat: int) -> float:
    runs = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"])
        runs.append(time.perf_counter() - start)
    return statistics.median(runs)


if __name__ == "__main__":
    main()
