"""Settings: the base of a config's frozen sections, each a dataclass of plain values.

A section turns NumPy integers into Python ints on construction (``np.int64(3)`` → 3: torch's
seeding takes Python ints only) and checks its fields in its own ``validate()``, with messages
that name each field as users pass it (``config.lr``).
"""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["Settings"]


class Settings:
    """The base of a frozen dataclass of settings: NumPy integers become Python ints."""

    def __post_init__(self):
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.integer):
                object.__setattr__(self, f.name, int(value))

    def validate(self) -> None:
        """Raise ``TypeError``/``ValueError`` naming the first bad field (each section says which)."""
