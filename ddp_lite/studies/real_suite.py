"""The real suite: every Middlebury scene with ground truth in a folder, plus Motorcycle, with real holes.

A folder of scenes is what ``data_fetch`` installs (``middlebury2005``, ``middlebury2006`` HalfSize,
``middlebury2014q``) or any folder holding scene folders (``view1.png``/``disp1.png``/``dmin.txt``, or
``im0.png``/``calib.txt``/``disp0GT.pfm``) at any depth; DepthComp's ``plastic-disp-hole.png`` anywhere
in it adds the paper's own holes on Plastic. Hole kinds (``SUITE_HOLES``):

- ``depthcomp``: DepthComp's own Table 6 holes (Plastic only);
- ``blobs``: DepthComp-style smooth blobs, 20 % of the pixels, one fixed pattern (seed 1);
- ``dropouts``: a depth sensor's dropouts, many small blobs (:func:`dropout_holes`): 2–5 % of the pixels (the
  share drawn per scene, seeded by its name), each blob blurred over 1 % of the short side, cut at the scene's
  own size and pooled like every mask, so each size sees the same holes, as large a share of the image;
- ``sgbm``: the input is OpenCV SGBM's own depth on the scene's stereo pair (view1–view5, im0–im1), holes
  where it gives no answer: the real stereo holes;
- ``occlusion``: the ground truth with holes where the stereo partner does not see the reference
  (``middlebury_rail.ground_truth_occlusion``; Motorcycle: where SGBM's left-right check fails).

Each scene is pooled by the integer factor that brings it nearest a size's pixel count (``SUITE_SIZES``:
``eighth`` ≈ 140×160 of a 2005/2006 scene, to iterate on; ``quarter`` ≈ 280×320, to confirm). The warp
loss's neighbours are view0 and view2 of the rail (the paper's N = 2), or the right view of a 2014 pair.
Studies choose on one half of the scenes and confirm on the other (``SUITE_HALF_A``, :func:`suite_half`).
"""
from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np

from ..data.installed import DEPTHCOMP_FILE, scene_folders
from ..data.middlebury_rail import ground_truth_occlusion, load_middlebury_scene
from ..classical.holes import random_holes
from ..data.samples import read_depthcomp_holes
from .real_cases import RealCase, make_real_case

__all__ = ["SUITE_HOLES", "SUITE_SIZES", "SUITE_HALF_A", "MOTORCYCLE", "DROPOUT_SHARES", "DROPOUT_BLOB",
           "find_scenes", "suite_case_names", "suite_half", "make_suite_case", "pooling_factor", "dropout_holes"]

SUITE_HOLES = ("depthcomp", "blobs", "dropouts", "sgbm", "occlusion")
# the scenes studies choose on; the rest (Books, Laundry, Reindeer, Baby2, Bowling1, Plastic, ArtL, Piano, Playroom,
# Motorcycle) confirm: each half holds 2005, 2006 and 2014 scenes
SUITE_HALF_A = ("Art", "Dolls", "Moebius", "Baby1", "Baby3", "Bowling2", "Adirondack", "Jadeplant", "Pipes",
                "Playtable")
DROPOUT_SHARES = (0.02, 0.05)  # the share of the pixels a sensor's dropouts cover: drawn in this range per scene
DROPOUT_BLOB = 0.01  # their blobs' blur scale, a fraction of the short side (a few px across at the eighth size)
SUITE_SIZES = {"eighth": 160 * 140, "quarter": 320 * 280}  # target pixels of a pooled scene
MOTORCYCLE = "Motorcycle"  # scikit-image's pair, always in the suite


def find_scenes(root) -> dict[str, Path]:
    """{scene name: folder} of every Middlebury scene with ground truth under ``root`` (any depth; a data root
    as ``data_fetch`` fills it, or the offline copies' folder), named by the folder (``2006-Plastic``,
    ``HalfSize/Plastic`` → ``Plastic``; ``2014-Piano-Q``, ``trainingQ/Piano`` → ``Piano``), one copy of each:
    ``data.installed.scene_folders``."""
    return scene_folders(root)


def _depthcomp_file(root) -> Path | None:
    hits = sorted(Path(root).rglob(DEPTHCOMP_FILE))
    return hits[0] if hits else None


def suite_case_names(root) -> list[str]:
    """The suite's case names ``scene/holes``, hole kind by hole kind: Plastic with ``depthcomp`` when the
    hole file is under ``root``, then every scene of ``root`` and Motorcycle with ``blobs``, ``dropouts``, ``sgbm``,
    ``occlusion``."""
    scenes = [name for name in find_scenes(root) if name != MOTORCYCLE] + [MOTORCYCLE]  # scikit-image's pair stands for it
    names = []
    for holes in SUITE_HOLES:  # hole kind by hole kind: a run stopped part-way has covered every scene once
        for scene in scenes:
            if holes == "depthcomp" and (scene != "Plastic" or _depthcomp_file(root) is None):
                continue
            names.append(f"{scene}/{holes}")
    return names


def suite_half(name: str) -> str:
    """"A" or "B": the half of the suite a case ``scene/holes`` (or a scene's name) is in (``SUITE_HALF_A``)."""
    return "A" if name.split("/")[0] in SUITE_HALF_A else "B"


def dropout_holes(shape, scene_name: str) -> np.ndarray:
    """(H, W) bool, True = hole: a depth sensor's dropouts on a scene of full size ``shape`` (H, W): small smooth
    blobs (``classical.holes.random_holes``, blur ``DROPOUT_BLOB`` of the short side) covering a share in
    ``DROPOUT_SHARES`` drawn for ``scene_name``, seeded by the name (the same holes on every run and machine).

    Example:
        >>> holes = dropout_holes((555, 695), "Art")
        >>> 0.02 <= float(holes.mean()) <= 0.05, dropout_holes((555, 695), "Art").tolist() == holes.tolist()
        (True, True)
    """
    H, W = (int(n) for n in shape)
    seed = zlib.crc32(scene_name.encode())
    low, high = DROPOUT_SHARES
    share = low + (high - low) * float(np.random.default_rng(seed).random())
    cut, _ = random_holes(np.ones((H, W), np.float32), fraction=share, seed=seed, blob_size=DROPOUT_BLOB * min(H, W))
    return np.isnan(cut)


def pooling_factor(shape, size: str = "eighth") -> int:
    """The integer factor that pools an image of ``shape`` (H, W) nearest ``SUITE_SIZES[size]`` pixels."""
    if size not in SUITE_SIZES:
        raise ValueError(f"size must be one of {sorted(SUITE_SIZES)}, got {size!r}")
    pixels = shape[0] * shape[1]
    return min(range(1, 17), key=lambda f: abs(np.log(pixels / f ** 2 / SUITE_SIZES[size])))


def make_suite_case(root, name: str, size: str = "eighth") -> RealCase:
    """The case ``scene/holes`` of the suite under ``root`` at ``size`` → :class:`RealCase` (neighbours:
    view0 and view2 of a rail scene, the right view of a pair). Deterministic."""
    scene_name, holes = name.rsplit("/", 1)
    if holes not in SUITE_HOLES:
        raise ValueError(f"name: the holes must be one of {SUITE_HOLES}, got {name!r}")
    if scene_name == MOTORCYCLE:
        from ..data.middlebury import load_motorcycle

        factor = pooling_factor((500, 740), size)
        kind = {"blobs": "blobs-1"}.get(holes, holes)
        if holes == "depthcomp":
            raise ValueError("name: DepthComp's holes exist for Plastic only")
        motorcycle = load_motorcycle()
        if holes == "dropouts":
            case = make_real_case(holes, factor, motorcycle,
                                  hole_mask=dropout_holes(motorcycle[0].depth.shape, scene_name))
        else:
            case = make_real_case(kind, factor=factor, scene=motorcycle)
    else:
        folders = find_scenes(root)
        if scene_name not in folders:
            raise ValueError(f"name: no scene {scene_name!r} under {root}; found {sorted(folders)}")
        folder = folders[scene_name]
        scene = load_middlebury_scene(folder, name=scene_name)
        factor = pooling_factor(scene[0].depth.shape, size)
        if holes == "depthcomp":
            hole_file = _depthcomp_file(root)
            if scene_name != "Plastic" or hole_file is None:
                raise ValueError(f"name: DepthComp's holes exist for Plastic only, and {DEPTHCOMP_FILE} must be "
                                 f"under {root}")
            case = make_real_case(holes, factor, scene, hole_mask=read_depthcomp_holes(hole_file, scene.size))
        elif holes == "occlusion":
            case = make_real_case(holes, factor, scene, hole_mask=ground_truth_occlusion(folder))
        elif holes == "dropouts":
            case = make_real_case(holes, factor, scene, hole_mask=dropout_holes(scene[0].depth.shape, scene_name))
        else:
            case = make_real_case({"blobs": "blobs-1"}.get(holes, holes), factor, scene)
    case.name = name
    return case
