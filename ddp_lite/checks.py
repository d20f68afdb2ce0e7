"""Argument checks shared by the API, the loaders and the CLI: one message style, one place.

Each check returns the value in its plain Python type or raises ``TypeError`` (wrong kind of
value) or ``ValueError`` (right kind, out of range), with a message that names the argument
and says what was expected. ``bool`` is never accepted as a number (``True == 1`` in Python,
so ``iterations=True`` would otherwise run one iteration).

Example:
    >>> check_int(3, "iterations", minimum=1)
    3
    >>> check_real(float("inf"), "lr", low=0.0, low_open=True)
    Traceback (most recent call last):
    ...
    ValueError: lr must be a finite number > 0, got inf
"""
from __future__ import annotations

import math
import numbers

__all__ = ["check_int", "check_real", "check_bool", "check_choice", "check_int_tuple"]


def check_bool(value, name: str) -> bool:
    """``value`` if it is a bool (or a NumPy bool), else ``TypeError``."""
    if not isinstance(value, bool) and type(value).__name__ != "bool_":
        raise TypeError(f"{name} must be True or False, got {type(value).__name__} {value!r}")
    return bool(value)


def check_int(value, name: str, minimum: int | None = None, maximum: int | None = None) -> int:
    """``value`` as an ``int`` if it is a whole-number integer type (not bool, not float) within bounds."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__} {value!r}")
    value = int(value)
    if (minimum is not None and value < minimum) or (maximum is not None and value > maximum):
        bounds = (f"≥ {minimum}" if maximum is None else f"≤ {maximum}" if minimum is None
                  else f"in [{minimum}, {maximum}]")
        raise ValueError(f"{name} must be an integer {bounds}, got {value}")
    return value


def check_real(value, name: str, low: float | None = None, high: float | None = None,
               low_open: bool = False, high_open: bool = False) -> float:
    """``value`` as a finite ``float`` within [low, high] (``*_open``: the bound itself excluded)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    value = float(value)
    ok = math.isfinite(value)
    ok = ok and (low is None or (value > low if low_open else value >= low))
    ok = ok and (high is None or (value < high if high_open else value <= high))
    if not ok:
        parts = [f"{'>' if low_open else '≥'} {low:g}" if low is not None else "",
                 f"{'<' if high_open else '≤'} {high:g}" if high is not None else ""]
        bounds = " and ".join(p for p in parts if p)
        raise ValueError(f"{name} must be a finite number{' ' + bounds if bounds else ''}, got {value!r}")
    return value


def check_choice(value, name: str, choices) -> str:
    """``value`` if it is one of ``choices`` (strings), else a ``TypeError``/``ValueError`` listing them."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be one of {tuple(choices)}, got {type(value).__name__} {value!r}")
    if value not in choices:
        raise ValueError(f"{name} must be one of {tuple(choices)}, got {value!r}")
    return value


def check_int_tuple(value, name: str, minimum: int, min_length: int = 0) -> tuple[int, ...]:
    """A tuple or list of integers ≥ ``minimum`` with at least ``min_length`` entries → ``tuple``."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (tuple, list)):
        raise TypeError(f"{name} must be a tuple of integers, got {type(value).__name__} {value!r}")
    if len(value) < min_length:
        raise ValueError(f"{name} must list at least {min_length} integer(s), got {tuple(value)!r}")
    return tuple(check_int(v, f"{name}[{i}]", minimum=minimum) for i, v in enumerate(value))
