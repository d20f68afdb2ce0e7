"""A Middlebury scene as the input of a completion: the photo, a depth with holes, the truth, the neighbours.

What ``ddp-lite complete --scene`` fills. The scene is a folder in either layout (``middlebury_rail``:
2005/2006 view1 with ``disp1.png`` and ``dmin.txt``; ``middlebury``: 2014 ``im0``/``im1``, ``calib.txt``,
``disp0GT.pfm`` or ``disp0.pfm``), read at its own size. The input depth (``holes``):

* ``"sgbm"``: OpenCV SGBM on the scene's own stereo pair (view1–view5, im0–im1; dense parameters,
  left-right checked), its depth Z = f·B / (d + doffs) where it answered: what a user with a stereo rig has;
* ``"blobs"``: DepthComp-style smooth blobs (20 % of the pixels, the real suite's pattern, seed 1) cut into
  the truth;
* a hole file: an image with 0 = hole (DepthComp's ``plastic-disp-hole.png`` for Plastic), any size,
  brought to the scene's (``samples.read_depthcomp_holes``), cut into the truth.

Holes cut into the truth leave its unknown pixels holes too; only holes where the truth is known are scored. The warp
term's neighbours are the rail's view0 and view2 (the paper's N = 2 calibrated views) or a 2014 pair's im1.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..classical.holes import random_holes
from ..classical.stereo import sgm_depth
from ..core.views import Scene, View
from .middlebury_rail import load_middlebury_scene
from .samples import read_depthcomp_holes

__all__ = ["HOLE_KINDS", "SceneInput", "scene_input"]

HOLE_KINDS = ("sgbm", "blobs")
BLOB_FRACTION, BLOB_SEED = 0.2, 1  # the real suite's blobs (real_suite.SUITE_HOLES "blobs")


@dataclass(frozen=True, eq=False)
class SceneInput:
    """``scene`` (full size: ``scene[0]`` the reference with its truth, then the neighbours; ``right`` its
    stereo partner; ``meta`` baseline m, doffs px), ``depth`` (H, W) float32 metres with NaN holes (the input),
    ``holes`` (what made them, in words), ``depth_source`` (``"stereo"`` for SGBM's depth, else ``"clean"``)."""

    scene: Scene
    depth: np.ndarray
    holes: str
    depth_source: str

    @property
    def truth(self) -> np.ndarray:
        """(H, W) float32 metres, NaN where the truth is unknown."""
        return self.scene[0].depth

    @property
    def neighbors(self) -> list[View]:
        """The warp term's calibrated neighbours: the rail's other views, else the stereo partner."""
        return list(self.scene.views[1:]) or list(self.scene.right[:1])

    @property
    def fb(self) -> float:
        """f·B (px · m) at the scene's size: disparity (px) = fb / depth − doffs."""
        return float(self.scene[0].camera.focal * self.scene.meta["baseline"])


def scene_input(folder, holes: str = "sgbm", name: str | None = None, what: str = "--holes") -> SceneInput:
    """A Middlebury scene ``folder`` and a hole kind (``HOLE_KINDS``) or a hole file → :class:`SceneInput`.
    ValueError naming ``what`` for an unknown kind, a missing or unreadable hole file, or holes that leave
    nothing to score (no hole where the truth is known) or nothing to keep."""
    if not isinstance(holes, (str, Path)) or not str(holes).strip():
        raise ValueError(f"{what} must be one of {', '.join(HOLE_KINDS)} or a hole file (0 = hole), got {holes!r}")
    hole_file = None if str(holes) in HOLE_KINDS else Path(str(holes)).expanduser()
    if hole_file is not None and not hole_file.is_file():
        raise ValueError(f"{what} must be one of {', '.join(HOLE_KINDS)} or a hole file (an image, 0 = hole), "
                         f"got {str(holes)!r}: no such file")
    scene = load_middlebury_scene(folder, name=name)
    truth = scene[0].depth
    if hole_file is not None:
        try:
            mask = read_depthcomp_holes(hole_file, truth.shape)
        except ValueError as error:
            raise ValueError(f"{what}: {error}") from None
        depth = np.where(mask, np.nan, truth).astype(np.float32)
        described, source = f"the holes of {hole_file} (0 = hole) cut into the truth", "clean"
    elif holes == "blobs":
        H, W = truth.shape
        depth, _ = random_holes(truth, fraction=BLOB_FRACTION, seed=BLOB_SEED, blob_size=min(H, W) / 10)
        described, source = f"blobs on {BLOB_FRACTION:.0%} of the pixels (seed {BLOB_SEED}) cut into the truth", "clean"
    else:
        pair = Scene(scene.name, scene.views[:1], scene.right[:1], dict(scene.meta))
        depth, _ = sgm_depth(pair, 0, "dense")
        partner = scene.right[0].name if scene.right else "the right view"
        described, source = f"OpenCV SGBM on {scene[0].name}–{partner} (its depth where it answered)", "stereo"
    depth = np.asarray(depth, np.float32)
    holes_mask = ~np.isfinite(depth)
    if not (holes_mask & np.isfinite(truth)).any():
        raise ValueError(f"{what}: {described} leaves no hole where the scene's truth is known; nothing to score")
    if holes_mask.all():
        raise ValueError(f"{what}: {described} leaves no valid depth to complete from")
    return SceneInput(scene, depth, described, source)
