"""Time on a student's laptop, in one run: the fit loop against its FLOP bound, one `class` fit,
`ddp-lite complete` on a full-size photo (with how good its time-left estimate was), and with
``--notebooks`` every notebook at `class`; on this CPU and held to AVX2, as most laptops are.

    python benchmarks/bench_laptop.py                        # native and AVX2 rows, no notebooks
    python benchmarks/bench_laptop.py --isa avx2 --notebooks --skip loop fit complete              # README, class
    python benchmarks/bench_laptop.py --isa avx2 --notebooks --skip loop fit complete --profile ci # README, ci

With ``--notebooks`` each notebook's time is appended to ``results/notebook_times.jsonl`` and the README's
notebook table is rendered from that file (``notebook_table.py``; ``--no-readme`` leaves the README alone).

Each part runs in a fresh process with the ISA's environment (``benchmarks/isa.py``) and the
thread count of a student's machine (2 by default). Run it alone: two processes sharing the 2
cores slow each other several times. Prints figures; asserts nothing.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from _common import parse_args, positive_int, check_output_folder

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from isa import ISA_ENV  # noqa: E402
import notebook_table  # noqa: E402

NOTEBOOKS = HERE.parent / "notebooks"


def _child(isa: str, threads: int, code: str) -> dict:
    """Run ``code`` (which prints one JSON line last) in a fresh Python with the ISA's environment."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), **ISA_ENV[isa])
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=HERE)
    if out.returncode:
        raise SystemExit(f"a benchmark part failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def summary(isa: str) -> str:
    return _child(isa, 1, "import json, isa; print(json.dumps({'line': isa.isa_summary()}))")["line"]


def loop_ratio(isa: str, threads: int, channels: str, variant: str = "rgbd+warp") -> dict:
    """s/it of the fit loop at 96×128 and its FLOP bound (bench_fit.run_one)."""
    code = (f"import json, torch, bench_fit; torch.set_num_threads({threads}); "
            f"print(json.dumps(bench_fit.run_one({variant!r}, 96, 128, {[int(c) for c in channels.split('-')]}, 20)))")
    return _child(isa, threads, code)


CLASS_FIT = """
import json, time, torch
from ddp_lite import FitConfig, RunOptions, complete_depth
from ddp_lite.studies.real_cases import make_real_case, factor_for_profile
torch.set_num_threads({threads})
case = make_real_case("sgbm", factor_for_profile("class"))
config = FitConfig.for_profile("class", variant="rgbd", recipe="kit")
start = time.perf_counter()
result = complete_depth(case.rgb, case.depth, variant="rgbd", config=config, transform=case.transform,
                        options=RunOptions(progress=False))
seconds = time.perf_counter() - start
print(json.dumps(dict(seconds=seconds, iterations=int(result.iterations), shape=list(case.depth.shape),
                      px=case.rmse_px(result.depth))))
"""


def class_fit(isa: str, threads: int) -> dict:
    """One `class` kit fit (rgbd) on the real Motorcycle pair's SGBM holes, at the size the notebooks use."""
    return _child(isa, threads, CLASS_FIT.format(threads=threads))


WRITE_PHOTO = """
import json, sys, cv2, numpy as np
from ddp_lite.data.middlebury import load_motorcycle
from ddp_lite.classical.stereo import sgm_depth
scene = load_motorcycle()
depth, _ = sgm_depth(scene, 0)
folder = sys.argv[1]
cv2.imwrite(folder + "/rgb.png", (scene[0].rgb[:, :, ::-1] * 255).round().astype(np.uint8))
np.save(folder + "/depth.npy", depth.astype(np.float32))
np.save(folder + "/gt.npy", scene[0].depth.astype(np.float32))
print(json.dumps(dict(shape=list(depth.shape), holes=float(np.isnan(depth).mean()))))
"""


def complete_full_size(isa: str, threads: int) -> dict:
    """`ddp-lite complete` on the full-size Motorcycle photo with SGBM holes, at `class`: wall time,
    and every progress line's time-left estimate against the time that was actually left."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), DDP_PROFILE="class", **ISA_ENV[isa])
    env.pop("DDP_CACHE", None)
    with tempfile.TemporaryDirectory() as folder:
        made = subprocess.run([sys.executable, "-c", WRITE_PHOTO, folder], capture_output=True, text=True, env=env)
        if made.returncode:
            raise SystemExit(made.stderr[-3000:])
        command = [sys.executable, "-m", "ddp_lite.interface.cli", "complete", "--rgb", f"{folder}/rgb.png",
                   "--depth", f"{folder}/depth.npy", "--gt", f"{folder}/gt.npy", "--out", f"{folder}/filled.npy"]
        start = time.perf_counter()
        process = subprocess.Popen(command, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
        estimates = []  # (seconds since start, share done, seconds left as estimated)
        for line in process.stderr:
            found = re.search(r"all (\d+)%, (\d+):(\d+) left", line)
            if found:
                estimates.append((time.perf_counter() - start, int(found[1]) / 100,
                                  60 * int(found[2]) + int(found[3])))
        out = process.stdout.read()
        if process.wait():
            raise SystemExit(f"complete failed: {out[-2000:]}")
        total = time.perf_counter() - start
    errors = [(share, (left - (total - at)) / max(total - at, 1e-9)) for at, share, left in estimates]
    late = [abs(error) for share, error in errors if share >= 0.2 and share < 1.0]
    return dict(seconds=total, estimates=len(estimates), worst_error_from_20=max(late) if late else float("nan"),
                errors=[(share, round(error, 2)) for share, error in errors], summary=out.strip().splitlines()[-1])


def notebook_seconds(isa: str, threads: int, path: Path, profile: str = "class", keep: Path | None = None) -> float:
    """Wall time of one notebook executed at ``profile`` in a fresh kernel (nbconvert, kernel start included);
    with ``keep`` the executed notebook (its printed figures) is written there as ``<name>.<profile>.<isa>.ipynb``."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), DDP_PROFILE=profile, MPLBACKEND="Agg", **ISA_ENV[isa])
    env.pop("DDP_CACHE", None)
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        run = subprocess.run([sys.executable, "-m", "jupyter", "nbconvert", "--to", "notebook", "--execute",
                              "--ExecutePreprocessor.timeout=3600", "--output-dir", folder, str(path)],
                             capture_output=True, text=True, env=env, cwd=path.parent)
        seconds = time.perf_counter() - start
        if keep is not None and not run.returncode:
            keep.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(Path(folder) / path.name, keep / f"{path.stem}.{profile}.{isa}.ipynb")
    if run.returncode:
        raise SystemExit(f"{path.name} failed:\n{run.stderr[-3000:]}")
    return seconds


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--isa", nargs="+", default=["native", "avx2"], choices=sorted(ISA_ENV))
    parser.add_argument("--threads", type=positive_int, default=2, help="torch threads (a laptop: 2)")
    parser.add_argument("--notebooks", action="store_true", help="also time every notebook (at --profile)")
    parser.add_argument("--profile", default="class", choices=("ci", "class", "paper"), help="the notebooks' profile (class; ci as in make test)")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="notebooks whose name contains NAME")
    parser.add_argument("--keep", type=Path, metavar="DIR", help="write the executed notebooks (outputs included) here")
    parser.add_argument("--skip", nargs="+", default=[], choices=["loop", "fit", "complete"], help="parts to skip")
    parser.add_argument("--note", default="", help="with --notebooks: a note the README prints beside each figure")
    parser.add_argument("--no-readme", action="store_true",
                        help="with --notebooks: record the times, leave README.md's table as it is")
    args = parse_args(parser, argv, lambda a: check_output_folder(a.keep, "--keep") if a.keep else None)
    for isa in args.isa:
        line = summary(isa)
        print(f"\n== {isa}: {line}; {args.threads} threads", flush=True)
        if "loop" not in args.skip:
            for channels in ("32-64-128-256-512", "16-32-64-128-256"):
                r = loop_ratio(isa, args.threads, channels)
                print(f"fit loop rgbd+warp 96×128 UNet {channels}: {r['s_per_it']:.3f} s/it, bound {r['bound']:.3f} s "
                      f"({r['mm_gflops']:.0f} GFLOP/s matmul), ratio {r['s_per_it'] / r['bound']:.2f}; its convolutions "
                      f"alone {r['conv_s']:.3f} s, ratio {r['conv_s'] / r['bound']:.2f}", flush=True)
        if "fit" not in args.skip:
            r = class_fit(isa, args.threads)
            print(f"one class kit fit (rgbd, real SGBM holes, {r['shape'][0]}×{r['shape'][1]}): {r['seconds']:.1f} s, "
                  f"{r['iterations']} iterations, hole RMSE {r['px']:.2f} px", flush=True)
        if "complete" not in args.skip:
            r = complete_full_size(isa, args.threads)
            print(f"complete, full-size Motorcycle (SGBM holes) at class: {r['seconds']:.1f} s; time-left estimate "
                  f"worst error from 20 % on {r['worst_error_from_20']:+.0%} ({r['estimates']} lines)\n  {r['summary']}",
                  flush=True)
        if args.notebooks:
            for path in sorted(NOTEBOOKS.glob("[0-9][0-9]_*.ipynb")):
                if args.only and not any(name in path.name for name in args.only):
                    continue
                seconds = notebook_seconds(isa, args.threads, path, args.profile, args.keep)
                print(f"notebook {path.stem} at {args.profile}: {seconds:.0f} s ({seconds / 60:.1f} min)", flush=True)
                row = dict(notebook=path.stem, profile=args.profile, isa=isa, seconds=round(seconds, 1),
                           threads=args.threads, cpu=line, when=time.strftime("%Y-%m-%d"), note=args.note)
                with open(notebook_table.RESULTS, "a") as out:  # one line per notebook: a run stopped keeps the rest
                    out.write(json.dumps(row, ensure_ascii=False) + "\n")
    if args.notebooks and not args.no_readme:
        for change in notebook_table.write_readme():
            print("README.md:", change)


if __name__ == "__main__":
    main()
