"""Rebuild the shipped Middlebury samples from a folder of the real scenes (maintainers only).

    python -m ddp_lite.data.samples.make_samples DIR

``DIR`` is laid out as ``data_fetch`` installs the HalfSize 2005/2006 scenes from a local copy
(``<year>-<Scene>/view0.png`` …, ``depthcomp/plastic-disp-hole.png``). Each sample is the HalfSize scene
pooled 2× to a quarter of full size (colour by 2×2 block means; disparity PNG intensities, which are
≈ full-size disparities at every size, by the mean of the block's known values, unknown where fewer
than 3 of 4 are known): views 0, 1, 2 and 5, ``disp1.png``, ``disp5.png``, ``dmin.txt``. Plastic also
gets DepthComp's own holes, from full size by 4×4 blocks (a hole where at least half the block is),
in DepthComp's format: the disparity with 0 = hole. Nothing here runs at import or test time.
"""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

import cv2
import numpy as np

SCENES = {"Plastic": "2006-Plastic", "Baby1": "2006-Baby1", "Bowling1": "2006-Bowling1", "Art": "2005-Art"}
VIEWS = (0, 1, 2, 5)
HERE = Path(__file__).resolve().parent


def _pool_colour(image: np.ndarray) -> np.ndarray:
    H, W = image.shape[0] // 2, image.shape[1] // 2
    blocks = image[:2 * H, :2 * W].astype(np.float64).reshape(H, 2, W, 2, -1)
    return np.rint(blocks.mean(axis=(1, 3))).astype(np.uint8)


def _pool_disparity(raw: np.ndarray) -> np.ndarray:
    H, W = raw.shape[0] // 2, raw.shape[1] // 2
    blocks = raw[:2 * H, :2 * W].astype(np.float64).reshape(H, 2, W, 2)
    known = blocks > 0
    count = known.sum(axis=(1, 3))
    mean = np.where(known, blocks, 0.0).sum(axis=(1, 3)) / np.maximum(count, 1)
    return np.where(count >= 3, np.clip(np.rint(mean), 1, 255), 0).astype(np.uint8)


def _holes_quarter(full: np.ndarray, shape) -> np.ndarray:
    H, W = shape
    blocks = (full[:4 * H, :4 * W] == 0).reshape(H, 4, W, 4)
    return blocks.mean(axis=(1, 3)) >= 0.5


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1 or not Path(argv[0]).is_dir():
        print(__doc__)
        return 2
    source = Path(argv[0])
    for name, folder in SCENES.items():
        out = HERE / name
        out.mkdir(exist_ok=True)
        for k in VIEWS:
            image = cv2.imread(str(source / folder / f"view{k}.png"), cv2.IMREAD_COLOR)
            cv2.imwrite(str(out / f"view{k}.png"), _pool_colour(image), [cv2.IMWRITE_PNG_COMPRESSION, 9])
        for file in ("disp1.png", "disp5.png"):
            raw = cv2.imread(str(source / folder / file), cv2.IMREAD_UNCHANGED)
            cv2.imwrite(str(out / file), _pool_disparity(raw), [cv2.IMWRITE_PNG_COMPRESSION, 9])
        shutil.copyfile(source / folder / "dmin.txt", out / "dmin.txt")
        if name == "Plastic":
            disparity = cv2.imread(str(out / "disp1.png"), cv2.IMREAD_UNCHANGED)
            full = cv2.imread(str(source / "depthcomp" / "plastic-disp-hole.png"), cv2.IMREAD_UNCHANGED)
            holes = _holes_quarter(full, disparity.shape)
            cv2.imwrite(str(out / "plastic-disp-hole.png"), np.where(holes, 0, disparity).astype(np.uint8),
                        [cv2.IMWRITE_PNG_COMPRESSION, 9])
        print(f"{name}: written to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
