"""Scenes: calibrated RGB-D views, and the kit's synthetic multi-view scenes.

A ``View`` is one calibrated image with its depth; a ``Scene`` is an ordered list of views of
one static world (plus, for stereo scenes, a rectified right image per view).
"""
from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field

import numpy as np

from .camera import Camera

__all__ = ["View", "Scene"]


@dataclass(eq=False)
class View:
    """One calibrated view: ``rgb`` (H, W, 3) float32 in [0, 1], ``depth`` (H, W) float32 metres
    (NaN = unknown), ``camera`` (its ``width × height`` match the arrays)."""

    rgb: np.ndarray
    depth: np.ndarray
    camera: Camera
    name: str = ""

    def __post_init__(self):
        self.rgb = np.asarray(self.rgb, dtype=np.float32)
        self.depth = np.asarray(self.depth, dtype=np.float32)
        H, W = self.depth.shape[:2] if self.depth.ndim == 2 else (None, None)
        if self.depth.ndim != 2:
            raise ValueError(f"depth must be (H, W), got shape {self.depth.shape}")
        if self.rgb.shape != (H, W, 3):
            raise ValueError(f"rgb must be (H, W, 3) = {(H, W, 3)}, got {self.rgb.shape}")
        if (self.camera.height, self.camera.width) != (H, W):
            raise ValueError(f"camera is {self.camera.width}×{self.camera.height} but the images are {W}×{H}")

    @property
    def mask(self) -> np.ndarray:
        """Valid-depth mask (H, W) bool, True where depth is finite."""
        return np.isfinite(self.depth)

    @property
    def neighbor(self) -> tuple[np.ndarray, Camera]:
        """``(rgb, camera)``: the form ``complete_depth(neighbors=...)`` takes."""
        return self.rgb, self.camera


@dataclass(eq=False)
class Scene:
    """A named, ordered set of views of one static world.

    ``right`` optionally holds a rectified right view per view (stereo rigs); ``meta`` holds
    scene facts such as the stereo baseline (metres) or the DDP disparity range.
    """

    name: str
    views: list[View]
    right: list[View] = field(default_factory=list)
    meta: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.views)

    def __getitem__(self, index: int) -> View:
        return self.views[index]

    @property
    def size(self) -> tuple[int, int]:
        """``(H, W)`` of the views."""
        return self.views[0].depth.shape

    def __repr__(self) -> str:
        depths = np.concatenate([v.depth[np.isfinite(v.depth)] for v in self.views]) if self.views else np.zeros(1)
        H, W = self.size if self.views else (0, 0)
        stereo = f", stereo pairs={len(self.right)}" if self.right else ""
        return (f"Scene('{self.name}', {len(self.views)} views of {H}×{W}{stereo}, "
                f"depth {depths.min():.2f}–{depths.max():.2f} m)")

    def save(self, path) -> None:
        """Write the scene to an ``.npz`` file atomically (temporary file, then rename)."""
        arrays = {"name": np.array(self.name), "n_views": np.array(len(self.views)),
                  "n_right": np.array(len(self.right)),
                  "meta_keys": np.array(list(self.meta.keys()), dtype=str),
                  "meta_values": np.array([float(v) for v in self.meta.values()], dtype=np.float64)}
        for prefix, views in (("view", self.views), ("right", self.right)):
            for i, view in enumerate(views):
                arrays[f"{prefix}{i}_rgb"] = view.rgb
                arrays[f"{prefix}{i}_depth"] = view.depth
                arrays[f"{prefix}{i}_K"] = view.camera.K
                arrays[f"{prefix}{i}_pose"] = view.camera.cam_from_world
                arrays[f"{prefix}{i}_name"] = np.array(view.name)
        path = os.fspath(path)
        directory = os.path.dirname(os.path.abspath(path))
        fd, tmp = tempfile.mkstemp(dir=directory, suffix=".npz.tmp")
        try:
            with os.fdopen(fd, "wb") as handle:
                np.savez_compressed(handle, **arrays)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.remove(tmp)
            raise

    @classmethod
    def load(cls, path) -> "Scene":
        """Read a scene written by :meth:`save`."""
        with np.load(os.fspath(path), allow_pickle=False) as data:
            def read(prefix, count):
                views = []
                for i in range(count):
                    depth = data[f"{prefix}{i}_depth"]
                    camera = Camera(data[f"{prefix}{i}_K"], data[f"{prefix}{i}_pose"], depth.shape[1], depth.shape[0])
                    views.append(View(data[f"{prefix}{i}_rgb"], depth, camera, str(data[f"{prefix}{i}_name"])))
                return views
            meta = {str(k): float(v) for k, v in zip(data["meta_keys"], data["meta_values"])}
            return cls(str(data["name"]), read("view", int(data["n_views"])), read("right", int(data["n_right"])), meta)
