"""What the fit cache (``DDP_CACHE``, ``ddp_lite/method/fit_cache.py``) saves: each notebook run twice at a profile,
in a fresh kernel each time, first with an empty cache folder, then with the folder the first run
filled. Prints the wall seconds of both runs, the cache entries, and whether the second run printed
the same text (lines that report a time are left out of that comparison, temporary folders' names
masked).

    OMP_NUM_THREADS=1 python benchmarks/bench_cache.py                 # every notebook at ci
    OMP_NUM_THREADS=1 python benchmarks/bench_cache.py --only 03 05 --profile class
"""
from __future__ import annotations

import argparse
import re
import tempfile
import time
from pathlib import Path

import nbformat

from ddp_lite.interface import classroom
from ddp_lite.interface.classroom import _environment
from _common import parse_args

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"
TIMING = re.compile(r"\d\s*(s|min|seconds?)\b|s/it|it/s")
TEMPORARY = re.compile(r"tmp[\w-]{6,}")  # tempfile's folder names differ from run to run


def _printed(nb) -> list[str]:
    lines = []
    for cell in nb.cells:
        for output in cell.get("outputs", []):
            lines += [TEMPORARY.sub("tmp…", line) for line in output.get("text", "").splitlines()
                      if not TIMING.search(line)]
    return lines


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="ci", choices=("ci", "class"))
    parser.add_argument("--only", nargs="*", default=[], help="notebook number prefixes, e.g. 03 05")
    args = parse_args(parser, argv)
    paths = sorted(p for p in NOTEBOOKS.glob("*.ipynb") if not args.only or p.stem[:2] in args.only)
    print(f"profile {args.profile}; each notebook in a fresh kernel, cold cache then warm")
    print(f"{'notebook':<26} {'cold s':>7} {'warm s':>7} {'saved':>6} {'entries':>7}  same text")
    totals = [0.0, 0.0]
    for path in paths:
        with tempfile.TemporaryDirectory(prefix="ddp-cache-bench-") as folder, _environment(DDP_CACHE=folder):
            runs = []
            for _ in range(2):
                nb = nbformat.read(path, as_version=4)
                start = time.perf_counter()
                error = classroom.execute(nb, profile=args.profile, workdir=path.parent, allow_errors=False)
                runs.append((time.perf_counter() - start, nb, error))
            entries = len(list(Path(folder).glob("*.npz")))
        (cold, nb_cold, _), (warm, nb_warm, _) = runs
        totals[0] += cold
        totals[1] += warm
        same = "yes" if _printed(nb_cold) == _printed(nb_warm) else "NO"
        print(f"{path.stem:<26} {cold:7.1f} {warm:7.1f} {1 - warm / cold:6.0%} {entries:7d}  {same}", flush=True)
    print(f"{'total':<26} {totals[0]:7.1f} {totals[1]:7.1f} {1 - totals[1] / totals[0]:6.0%}")


if __name__ == "__main__":
    main()
