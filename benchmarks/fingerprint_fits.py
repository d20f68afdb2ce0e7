"""Fingerprints of small fits: a SHA-256 of each fit's outputs, to check a refactor changes no number.

    OMP_NUM_THREADS=1 python benchmarks/fingerprint_fits.py > before.txt
    ... change the code ...
    OMP_NUM_THREADS=1 python benchmarks/fingerprint_fits.py | diff before.txt -

Covers the profiles ``ci`` and ``class`` (their configs, at 32×32 and 20 iterations), the three
variants, the recipes ``kit`` and ``paper``, and a few configs with the kit's other levers on (hole
terms with a reach and RGB edges, bf16, fill input, affinity, input jitter, output averaging, an
ensemble, coarse-to-fine) and its combinations (a blend with the paper recipe's fit whose weight a held-out
ring chooses, a fill's share chosen on held-out blobs, the refining solve). Each row hashes the depth, disparity, colour output and loss history;
the table is identical before and after a behaviour-preserving change on the same machine.
"""
from __future__ import annotations

import argparse
import hashlib
import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from ddp_lite.classical.holes import random_holes  # noqa: E402
from ddp_lite.method.coarse_to_fine import complete_depth_coarse_to_fine  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.world.scenes import make_scene  # noqa: E402
from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402
from _common import parse_args  # noqa: E402

SIZE = (32, 32)
ITERATIONS = 20
# history keys hashed under the names the recorded fingerprints were taken with: a renamed key alone
# leaves every fingerprint as it was
HASHED_AS = {"held_out": "heldout"}


def digest(result) -> str:
    """SHA-256 (first 16 hex digits) of a result's arrays and loss history (timings aside)."""
    h = hashlib.sha256()
    for array in (result.depth, result.disparity, result.rgb):
        if array is not None:
            h.update(np.ascontiguousarray(array).tobytes())
    for hashed, key in sorted((HASHED_AS.get(key, key), key) for key in result.history):
        if "seconds" in key:  # wall-clock time (coarse-to-fine's stage_seconds) is no output
            continue
        h.update(hashed.encode())
        h.update(repr(result.history[key]).encode())
    return h.hexdigest()[:16]


def configs():
    """(name, variant, FitConfig, coarse_to_fine) rows."""
    small = dict(iterations=ITERATIONS, eval_every=5)
    for profile in ("ci", "class"):
        for recipe in ("kit", "paper"):
            for variant in ("d", "rgbd", "rgbd+warp"):
                config = FitConfig.for_profile(profile, variant=variant, recipe=recipe, **small)
                # 32×32 takes at most 3 levels here
                config = config.replace(channels=config.paper.channels[:3], lr_milestones=(12, 16))
                yield f"{profile}/{recipe}/{variant}", variant, config, False
    base = FitConfig.for_profile("class", variant="rgbd+warp", recipe="kit", **small).replace(channels=(8, 16, 32))
    yield "levers: reach+rgb edges+bf16", "rgbd+warp", base.replace(flatness_reach=4.0, edge_guide="rgb", bf16=True), False
    yield "levers: fill+affinity", "rgbd", base.replace(fill_input=1.0, affinity=0.5, bf16=False), False
    yield "levers: jitter+averaging+cosine", "rgbd+warp", base.replace(reg_noise_std=0.03, average_outputs=0.9,
                                                                      schedule="cosine", bf16=False), False
    yield "levers: auto-stop blobs", "rgbd", base.replace(held_out_shape="blobs", patience=5, plateau_decays=1,
                                                          bf16=False), False
    yield "ensemble 2", "rgbd", base.replace(ensemble=2, bf16=False), False
    yield "skip net", "rgbd", base.replace(net="skip", channels=(8, 8), bf16=False), False
    yield "coarse-to-fine", "rgbd+warp", base.replace(bf16=False), True
    yield "blend, ring-chosen weight and fill", "rgbd", base.replace(blend_paper=True, blend_weight=None,
                                                                   blend_fill=None, bf16=False), False
    yield "ensemble 3, chosen fill, refined", "rgbd", base.replace(ensemble=3, blend_fill=None, refine=True,
                                                                  bf16=False), False
    yield "coarse-to-fine, chosen fill, refined", "rgbd+warp", base.replace(blend_fill=None, refine=True,
                                                                           bf16=False), True


def main(argv=None) -> None:
    parse_args(argparse.ArgumentParser(description=__doc__.splitlines()[0]), argv)  # no options: --check-args, --help
    torch.set_num_threads(1)
    scene = make_scene("desk", size=SIZE, n_views=3, seed=0)
    ref = scene[0]
    depth, _ = random_holes(ref.depth, seed=0)
    neighbors = [scene[1].as_neighbor(), scene[2].as_neighbor()]
    quiet = RunOptions(progress=False)
    start = time.perf_counter()
    print(f"{'config':36s} {'sha256[:16]':16s}")
    for name, variant, config, c2f in configs():
        nbrs = neighbors if variant == "rgbd+warp" else ()
        if c2f:
            result = complete_depth_coarse_to_fine(ref.rgb, depth, ref.camera, nbrs, variant=variant,
                                                       config=config, gt_depth=ref.depth, scale=2, options=quiet)
        else:
            result = complete_depth(ref.rgb, depth, ref.camera, nbrs, variant=variant, config=config,
                                        gt_depth=ref.depth, options=quiet)
        print(f"{name:36s} {digest(result)}", flush=True)
    print(f"({time.perf_counter() - start:.0f} s)", file=sys.stderr)


if __name__ == "__main__":
    main()
