"""The data model every loader and fit shares: ``View`` (one calibrated RGB-D image) and
``Scene`` (an ordered set of views of one static world), and their ``.npz`` file format.

Conventions: ``rgb`` (H, W, 3) float32 in [0, 1]; ``depth`` (H, W) float32 metres, NaN = unknown;
``camera`` a :class:`~ddp_lite.core.camera.Camera` (OpenCV convention) whose ``width × height`` match the
arrays. A stereo scene also holds one rectified right view per view (``Scene.right``). ``meta``
holds scene facts as floats (stereo ``baseline`` in metres, Middlebury ``doffs`` in pixels, DDP's
``d_min``/``d_max``). ``labels`` optionally holds one (H, W) uint8 texture-class map per view, with
the values below; the synthetic renderer (``scenes.py``) writes them, loaders of real data do not.

This module knows nothing of how a scene is made: loaders (``datasets``, ``formats``) and the
renderer (``scenes``, ``render``) both build these types.
"""
from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field

import numpy as np

from .files import atomic_path
from .camera import Camera, view_overlap, view_parallax
from .checks import check_depth, check_image

__all__ = ["View", "Scene", "image_and_camera", "check_neighbor_views", "MIN_PARALLAX_PX", "LABELS", "LABEL_SKY", "LABEL_TEXTURELESS", "LABEL_PLANKS", "LABEL_TEXTURED"]

# Scene.labels values: the texture class of the surface a pixel sees
LABEL_SKY, LABEL_TEXTURELESS, LABEL_PLANKS, LABEL_TEXTURED = 0, 1, 2, 3
LABELS = {LABEL_SKY: "sky", LABEL_TEXTURELESS: "textureless", LABEL_PLANKS: "planks", LABEL_TEXTURED: "textured"}


@dataclass(eq=False)
class View:
    """One calibrated view: ``rgb`` (H, W, 3) float32 in [0, 1], ``depth`` (H, W) float32 metres
    (NaN = unknown), ``camera`` (its ``width × height`` match the arrays)."""

    rgb: np.ndarray
    depth: np.ndarray
    camera: Camera
    name: str = ""

    def __post_init__(self):
        # the kit's contract, checked once here for every loader and renderer: colour (H, W, 3) in [0, 1]
        # (uint8 scaled by 1/255; 0–255 floats refused), depth (H, W) float metres, NaN = unknown (none needed)
        if not isinstance(self.camera, Camera):
            raise TypeError(f"camera must be a ddp_lite Camera, got {type(self.camera).__name__}")
        self.depth = check_depth(self.depth, "depth", min_valid=0)
        H, W = self.depth.shape
        if np.shape(self.rgb)[:2] != (H, W) or np.ndim(self.rgb) != 3 or np.shape(self.rgb)[2] != 3:
            raise ValueError(f"rgb must be (H, W, 3) = {(H, W, 3)} like depth, got {np.shape(self.rgb)}")
        self.rgb = check_image(self.rgb, "rgb", (H, W))
        if (self.camera.height, self.camera.width) != (H, W):
            raise ValueError(f"camera is {self.camera.height}×{self.camera.width} but the images are {H}×{W} (H×W)")

    @property
    def mask(self) -> np.ndarray:
        """Valid-depth mask (H, W) bool, True where depth is finite."""
        return np.isfinite(self.depth)

    def as_neighbor(self) -> tuple[np.ndarray, Camera]:
        """This view as a warp-loss neighbour: ``(rgb (H, W, 3), camera)``, the pair
        ``complete_depth(neighbors=...)`` takes (a ``View`` itself is accepted too)."""
        return self.rgb, self.camera

    @property
    def neighbor(self) -> tuple[np.ndarray, Camera]:
        """Old name of :meth:`as_neighbor` (kept so existing notebooks run)."""
        return self.as_neighbor()


@dataclass(eq=False)
class Scene:
    """A named, ordered set of views of one static world.

    ``right`` optionally holds a rectified right view per view (stereo rigs); ``meta`` holds
    scene facts (floats) such as the stereo baseline (metres) or the DDP disparity range;
    ``labels`` optionally holds a (H, W) uint8 texture-class map per view (see ``LABELS``);
    ``sources`` the files and folders a reader took it from (not saved: a writer of results
    refuses to write over, into or beside them, ``sequence.run_sequence``).
    """

    name: str
    views: list[View]
    right: list[View] = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    labels: list = field(default_factory=list)
    sources: list = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.views)

    def __getitem__(self, index: int) -> View:
        return self.views[index]

    @property
    def size(self) -> tuple[int, int]:
        """``(H, W)`` of the views."""
        return self.views[0].depth.shape

    def __repr__(self) -> str:
        finite = [v.depth[np.isfinite(v.depth)] for v in self.views]
        depths = np.concatenate(finite) if self.views else np.zeros(1)
        depths = depths if depths.size else np.full(1, np.nan)
        H, W = self.size if self.views else (0, 0)
        stereo = f", stereo pairs={len(self.right)}" if self.right else ""
        return (f"Scene('{self.name}', {len(self.views)} views of {H}×{W}{stereo}, "
                f"depth {np.min(depths):.2f}–{np.max(depths):.2f} m)")

    def save(self, path, tag: str = "") -> None:
        """Write the scene to an ``.npz`` file atomically (temporary file, then rename); ``tag``, a string
        kept with it, is what :meth:`load` can ask for (the scene cache stores its key there)."""
        arrays = {"name": np.array(self.name), "tag": np.array(str(tag)), "n_views": np.array(len(self.views)),
                  "n_right": np.array(len(self.right)), "n_labels": np.array(len(self.labels)),
                  "meta_keys": np.array(list(self.meta.keys()), dtype=str),
                  "meta_values": np.array([float(v) for v in self.meta.values()], dtype=np.float64)}
        for prefix, views in (("view", self.views), ("right", self.right)):
            for i, view in enumerate(views):
                arrays[f"{prefix}{i}_rgb"] = view.rgb
                arrays[f"{prefix}{i}_depth"] = view.depth
                arrays[f"{prefix}{i}_K"] = view.camera.K
                arrays[f"{prefix}{i}_pose"] = view.camera.cam_from_world
                arrays[f"{prefix}{i}_name"] = np.array(view.name)
        for i, label in enumerate(self.labels):
            arrays[f"labels{i}"] = np.asarray(label)
        with atomic_path(path) as tmp, open(tmp, "wb") as handle:
            np.savez_compressed(handle, **arrays)

    @classmethod
    def load(cls, path, tag: str | None = None) -> "Scene":
        """Read a scene written by :meth:`save`; with ``tag``, a file saved with another tag is refused
        (``ValueError``) before anything else is read."""
        with np.load(os.fspath(path), allow_pickle=False) as data:
            if tag is not None and (str(data["tag"]) if "tag" in data.files else "") != tag:
                raise ValueError(f"{os.fspath(path)} was saved with another tag than {tag!r}")
            def read(prefix, count):
                views = []
                for i in range(count):
                    depth = data[f"{prefix}{i}_depth"]
                    camera = Camera(data[f"{prefix}{i}_K"], data[f"{prefix}{i}_pose"], depth.shape[1], depth.shape[0])
                    views.append(View(data[f"{prefix}{i}_rgb"], depth, camera, str(data[f"{prefix}{i}_name"])))
                return views
            meta = {str(k): float(v) for k, v in zip(data["meta_keys"], data["meta_values"])}
            n_labels = int(data["n_labels"]) if "n_labels" in data.files else 0
            labels = [data[f"labels{i}"] for i in range(n_labels)]
            return cls(str(data["name"]), read("view", int(data["n_views"])), read("right", int(data["n_right"])),
                       meta, labels)


def image_and_camera(item, name: str) -> tuple[np.ndarray, Camera]:
    """A :class:`View` or an ``(rgb, Camera)`` pair → (rgb (H, W, 3) float32 in [0, 1], Camera), checked;
    a ``TypeError`` naming ``name`` for anything else. How every function taking neighbours reads one."""
    if hasattr(item, "camera") and hasattr(item, "rgb"):
        rgb, camera = item.rgb, item.camera
    elif isinstance(item, (tuple, list)) and len(item) == 2:
        rgb, camera = item
    else:
        raise TypeError(f"{name} must be an (rgb, Camera) pair or a View, got {type(item).__name__}")
    if not isinstance(camera, Camera):
        raise TypeError(f"{name} must be an (rgb, Camera) pair or a View, got camera {type(camera).__name__}")
    return check_image(rgb, f"{name} rgb", (camera.height, camera.width)), camera


MIN_PARALLAX_PX = 0.5  # below this a neighbour's warp cannot tell one depth from another


def check_neighbor_views(camera: Camera, depth: np.ndarray, neighbors) -> None:
    """Check that the ``neighbors`` ((rgb, Camera) pairs) of a reference view (``camera``, its valid depth
    ``depth`` (H, W) metres, NaN holes) can tell its depths apart, as a warp term needs: ``ValueError`` if none
    sees any valid pixel, or one repeats another or sits at the reference's own pose (it adds nothing but
    weight); a warning for one that sees none of them, or whose parallax over the valid depth is below
    ``MIN_PARALLAX_PX``."""
    blind = [i for i, (_, cam) in enumerate(neighbors) if view_overlap(camera, depth, cam) == 0.0]
    if len(blind) == len(neighbors):
        raise ValueError(f"neighbors: none of the {len(neighbors)} neighbour camera(s) sees any valid reference "
                         f"pixel (check their poses: cam_from_world, metres), so the warp term would be 0")
    for i in blind:
        warnings.warn(f"neighbors[{i}] sees none of the reference's valid pixels; its warp term is 0", stacklevel=3)
    for i, (image, cam) in enumerate(neighbors):
        if np.allclose(cam.cam_from_world, camera.cam_from_world, rtol=0.0, atol=1e-12):
            raise ValueError(f"neighbors[{i}] has the reference's own pose (zero baseline): its warp compares the "
                             f"reference with itself and adds nothing; use another view")
        for j in range(i):
            other_image, other = neighbors[j]
            if (np.array_equal(other.cam_from_world, cam.cam_from_world) and np.array_equal(other.K, cam.K)
                    and np.array_equal(other_image, image)):
                raise ValueError(f"neighbors[{i}] repeats neighbors[{j}] (same image and camera): it only doubles "
                                 f"that view's weight; list each neighbour once")
        parallax = view_parallax(camera, depth, cam)
        if parallax < MIN_PARALLAX_PX:
            baseline = float(np.linalg.norm(cam.center - camera.center))
            warnings.warn(f"neighbors[{i}]: a baseline of {baseline:.3g} (pose units) gives at most {parallax:.2g} px "
                          f"of parallax over the valid depth ({np.nanmin(depth):.3g}–{np.nanmax(depth):.3g} m), so its "
                          f"warp cannot tell depths apart; are depth and poses in the same unit (metres)?", stacklevel=3)
