"""Settings: the base of a config's frozen sections, each a dataclass of plain values.

A section turns NumPy integers into Python ints on construction (``np.int64(3)`` → 3: torch's
seeding takes Python ints only) and checks its fields in its own ``validate()``, with messages
that name each field as users pass it (``config.lr``).

A field's flat name (how ``FitConfig`` takes it, ``FitConfig(warp_cost=...)``, and how its ``flat()``
and the fit cache's key name it) is the field's own name, except in a section whose field would
repeat the section's name (``config.warp.warp_cost``): there the field drops it (``config.warp.cost``)
and the section spells out each such field's flat name in ``flat_names``. A flat name given to the
section itself, or read from it, is refused with the field's name.
"""
from __future__ import annotations

import dataclasses
from typing import ClassVar

import numpy as np

__all__ = ["Settings"]


class Settings:
    """The base of a frozen dataclass of settings: NumPy integers become Python ints; a field's flat name
    given to the section (``WarpConfig(warp_cost=...)``) or read from it (``config.warp.warp_cost``) is
    refused, naming the field (``config.warp.cost``)."""

    section: ClassVar[str] = ""  # the section's name in FitConfig (config.warp), where flat_names has entries
    flat_names: ClassVar[dict] = {}  # field → its flat name, for the fields whose flat name is not their own

    def __new__(cls, *args, **kwargs):  # before the dataclass's __init__, which would say only "unexpected"
        for name in kwargs:
            field = cls.field_of_flat_name(name)
            if field != name:
                raise TypeError(f"{cls.__name__} has no field {name!r}: the field is {field!r} "
                                f"(config.{cls.section}.{field}); {name!r} is its name in FitConfig "
                                f"(FitConfig({name}=...), config.replace({name}=...))")
        return super().__new__(cls)

    def __post_init__(self):
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.integer):
                object.__setattr__(self, f.name, int(value))

    def __getattr__(self, name):  # only names that are no attribute come here
        field = type(self).field_of_flat_name(name)
        if field == name:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        raise AttributeError(f"{type(self).__name__} reads {name!r} as {field!r}: config.{self.section}.{field} "
                             f"({name!r} is its name in FitConfig: FitConfig({name}=...), config.flat()[{name!r}])")

    @classmethod
    def flat_name(cls, field: str) -> str:
        """The flat name of this section's ``field``: ``flat_names``' entry, else the field's own name."""
        return cls.flat_names.get(field, field)

    @classmethod
    def field_of_flat_name(cls, name: str) -> str:
        """The field of this section whose flat name is ``name``; ``name`` itself where none is."""
        return next((field for field, flat in cls.flat_names.items() if flat == name), name)

    @classmethod
    def from_flat(cls, settings: dict):
        """This section from ``settings`` given by flat names (a recipe's settings, ``FitConfig.flat()``):
        the fields of this section among them, the others at their defaults."""
        return cls(**{f.name: settings[cls.flat_name(f.name)] for f in dataclasses.fields(cls)
                      if cls.flat_name(f.name) in settings})

    def validate(self) -> None:
        """Raise ``TypeError``/``ValueError`` naming the first bad field (each section says which)."""
