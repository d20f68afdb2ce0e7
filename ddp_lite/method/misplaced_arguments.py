"""A keyword given to the wrong place of a fit's entry point, named with where it goes: a run option to
``options=RunOptions(...)``, a config field to ``config=FitConfig...``, else the nearest parameter, instead of
Python's bare "unexpected keyword argument"."""
from __future__ import annotations

import difflib
import functools
import inspect

from .config import FIELDS, RENAMED_FIELDS
from .runtime.options import RUN_OPTIONS

__all__ = ["names_misplaced_arguments"]


def names_misplaced_arguments(function):
    """Decorate an entry point that runs a fit: a keyword it does not take is refused with a ``TypeError``
    that says where it goes, a run option to ``options=RunOptions(...)``, a config field to
    ``config=FitConfig...``, else the nearest parameter, instead of Python's bare "unexpected keyword"."""
    parameters = inspect.signature(function).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()):
        return function  # it takes any keyword itself

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        for name in kwargs:
            if name not in parameters:
                raise TypeError(_misplaced(function.__name__, name, parameters))
        return function(*args, **kwargs)
    return wrapper


def _misplaced(function: str, name: str, parameters) -> str:
    if name in RUN_OPTIONS:
        return (f"{function}() got {name!r}: it is a run option (how a fit runs, not what it computes); pass "
                f"options=RunOptions({name}=...) (ddp_lite.RunOptions)")
    if name in FIELDS:
        return (f"{function}() got {name!r}: it is a FitConfig field (what a fit computes); pass "
                f"config=FitConfig.for_profile({name}=...)")
    if name in RENAMED_FIELDS:
        return (f"{function}() got {name!r}: it is now the FitConfig field {RENAMED_FIELDS[name]!r}; pass "
                f"config=FitConfig.for_profile({RENAMED_FIELDS[name]}=...)")
    close = difflib.get_close_matches(name, list(parameters), n=1)
    return (f"{function}() got an unexpected keyword argument {name!r}"
            + (f"; did you mean {close[0]!r}?" if close else f"; it takes {', '.join(parameters)}"))
