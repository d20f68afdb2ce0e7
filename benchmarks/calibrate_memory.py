"""Peak resident memory of one-iteration fits against ``ddp_lite.method.runtime.memory.estimate_peak_memory_gb``.

    OMP_NUM_THREADS=1 python benchmarks/calibrate_memory.py

Each fit runs in a fresh subprocess so that its ru_maxrss is its own. The constants in
``ddp_lite/method/loop.py`` (MEMORY_BASE_GB, FLOATS_PER_UNIT, BYTES_PER_PARAMETER) come from this table
(2-core CPU, torch eager, float32): measured 0.54 / 0.74 / 1.66 GiB for the 32–512 UNet at
96×128 / 192×256 / 384×512 (rgbd), 0.73 GiB at 192×256 (d), 1.00 GiB for the 16–128 net at 384×512.
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys

from _common import parse_args

CASES = [(96, 128, "rgbd", (32, 64, 128, 256, 512)), (192, 256, "rgbd", (32, 64, 128, 256, 512)),
         (384, 512, "rgbd", (32, 64, 128, 256, 512)), (192, 256, "d", (32, 64, 128, 256, 512)),
         (384, 512, "rgbd", (16, 32, 64, 128))]


def one(H: int, W: int, variant: str, channels) -> dict:
    import numpy as np

    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.complete import complete_depth
    from ddp_lite.method.runtime.options import RunOptions
    depth = np.full((H, W), 2.0, np.float32)
    depth[H // 4:H // 2, W // 4:W // 2] = np.nan
    rgb = np.random.default_rng(0).random((H, W, 3)).astype(np.float32)
    config = FitConfig(channels=tuple(channels), iterations=1)
    complete_depth(rgb, depth, variant=variant, config=config, options=RunOptions(device="cpu", progress=False))
    return {"peak_gib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20}


def main(argv=None) -> None:
    parse_args(argparse.ArgumentParser(description=__doc__.splitlines()[0]), argv)  # no options: --check-args, --help
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.runtime.memory import estimate_peak_memory_gb
    print(f"{'size':>9} {'variant':>7} {'net':>20} {'measured GiB':>12} {'estimate':>9}")
    for H, W, variant, channels in CASES:
        out = subprocess.run([sys.executable, __file__, "--one", json.dumps([H, W, variant, channels])], check=True,
                             capture_output=True, text=True).stdout
        measured = json.loads(out)["peak_gib"]
        estimate = estimate_peak_memory_gb(FitConfig(channels=channels), 1 if variant == "d" else 4, H, W)
        print(f"{H:>4}×{W:<4} {variant:>7} {'-'.join(map(str, channels)):>20} {measured:>12.2f} {estimate:>9.2f}")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--one":  # one fit, in the fresh process main starts for it
        print(json.dumps(one(*json.loads(sys.argv[2]))))
    else:
        main()
