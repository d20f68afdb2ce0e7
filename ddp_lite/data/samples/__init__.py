"""Four real Middlebury scenes shipped with the kit, at a quarter of full size (≈ 277×317 px, 2 MB).

``Plastic``, ``Baby1`` and ``Bowling1`` (2006; the scenes of the paper's Table 6) and ``Art`` (2005): views
0, 1, 2 and 5 of the seven-view rail, the ground truth ``disp1.png`` / ``disp5.png`` and ``dmin.txt``, in
the dataset's own format (``middlebury_rail`` reads them: intensity = 4 × the disparity at this size).
Plastic also holds DepthComp's own Table 6 holes (``plastic-disp-hole.png``: the disparity, 0 = hole).
Made from the HalfSize scenes by ``make_samples.py``; every other scene and size comes through
``python -m data_fetch fetch middlebury2006`` (or ``middlebury2005``, ``middlebury2014q``).

Middlebury grants permission to use and publish these images and disparity maps; cite D. Scharstein and
C. Pal, *Learning conditional random fields for stereo*, CVPR 2007, and H. Hirschmüller and D. Scharstein,
*Evaluation of cost functions for stereo matching*, CVPR 2007. The holes are from the examples of
A. Atapour-Abarghouei and T. Breckon, *DepthComp: real-time depth image completion based on prior
semantic scene segmentation*, BMVC 2017.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["SAMPLES", "SAMPLE_DATASETS", "sample_scene", "depthcomp_holes", "read_depthcomp_holes"]

SAMPLES = ("Plastic", "Baby1", "Bowling1", "Art")
SAMPLE_DATASETS = {"Plastic": "middlebury2006", "Baby1": "middlebury2006", "Bowling1": "middlebury2006",
                   "Art": "middlebury2005"}  # the data_fetch dataset each was made from (its HalfSize files)
_HERE = Path(__file__).resolve().parent


def sample_scene(name: str = "Plastic") -> Path:
    """The folder of a shipped scene (one of ``SAMPLES``), for ``middlebury_rail.load_rail_scene``."""
    if name not in SAMPLES:
        raise ValueError(f"name must be one of {SAMPLES}, got {name!r}")
    return _HERE / name


def read_depthcomp_holes(path, shape=None) -> np.ndarray:
    """DepthComp's hole file (a disparity PNG, 0 = hole or unknown) → (H, W) bool, True = hole, at the
    file's size, or brought to ``shape`` (H, W): by blocks (a hole where at least half the block is) when
    the file is an integer multiple of ``shape`` (after dropping the last row/column as the dataset's
    sizes do), else by the nearest pixel centre."""
    from ..fileio import read_image_file  # the file readers load cv2; kept local so the list above is cheap

    raw = read_image_file(path, "path", truth=True)  # a JPEG's ringing would make and fill holes of its own
    if raw.ndim != 2:
        raise ValueError(f"path: {path} must be a 1-channel disparity PNG with 0 = hole, got shape {raw.shape}")
    holes = raw == 0
    if shape is None or tuple(shape) == holes.shape:
        return holes
    H, W = (int(n) for n in shape)
    factor = holes.shape[0] // H
    if factor >= 1 and holes.shape[1] // W == factor and holes.shape[0] - factor * H < factor \
            and holes.shape[1] - factor * W < factor:
        return holes[:factor * H, :factor * W].reshape(H, factor, W, factor).mean(axis=(1, 3)) >= 0.5
    rows = np.minimum(((np.arange(H) + 0.5) * holes.shape[0] / H).astype(int), holes.shape[0] - 1)
    columns = np.minimum(((np.arange(W) + 0.5) * holes.shape[1] / W).astype(int), holes.shape[1] - 1)
    return holes[np.ix_(rows, columns)]


def depthcomp_holes(shape=None) -> np.ndarray:
    """DepthComp's own Table 6 holes on Plastic, shipped at a quarter of full size → (H, W) bool, True =
    hole (see ``read_depthcomp_holes`` for ``shape``)."""
    return read_depthcomp_holes(sample_scene("Plastic") / "plastic-disp-hole.png", shape)
