"""Argument checks shared by the API, the loaders and the CLI: one message style, one place; and the
one check on what a fit returns (:func:`check_finite_output`).

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
import warnings

import numpy as np
import torch

__all__ = ["SkippedWarning", "report_skipped", "env_choice", "named_choice", "check_callback", "check_int", "check_real", "check_bool", "check_choice", "check_int_tuple", "check_image", "check_depth",
           "check_size", "unmask", "MIN_VALID_PIXELS", "check_finite_output", "check_same_units", "MIN_DEPTH_M"]

MIN_VALID_PIXELS = 16  # a fit, or a mask, with fewer known pixels is refused
MAX_DEPTH_RATIO = 1e6  # farthest / nearest valid depth: beyond it float32 disparity cannot resolve the far part
MIN_DEPTH_M = 1e-6  # a micrometre: no camera measures nearer; below it, float32 denormals or a wrong unit


def unmask(array, name: str, holes: bool):
    """A NumPy masked array → a plain one: masked entries become NaN holes (``holes``), or ``TypeError``
    for arrays with no holes (colour). Anything else is returned as it is."""
    if not np.ma.isMaskedArray(array):
        return array
    if not holes:
        raise TypeError(f"{name} must be a plain NumPy array, got a masked array (colour has no holes: "
                        f"fill it, e.g. {name}.filled(0))")
    if not np.issubdtype(array.dtype, np.floating):
        raise TypeError(f"{name} must be float metres with NaN holes, got a masked array of dtype {array.dtype}")
    return np.ma.filled(array, np.nan)  # masked = hole, the kit's NaN; a copy


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


def check_callback(callback, every) -> None:
    """A fit's ``callback``: None, or a function that ``every`` (options.callback_every) > 0 will call."""
    if callback is None:
        return
    if not callable(callback):
        raise TypeError(f"callback must be a function callback(iteration, outputs), got {type(callback).__name__}")
    if every == 0:
        raise ValueError("callback is given but options.callback_every is 0, so it would never be called; "
                         "set options.callback_every (RunOptions) to how often (iterations) to call it")


# --------------------------------------------------------------------------- arrays a fit takes

def check_image(image, name: str, shape=None) -> np.ndarray:
    """(H, W, 3) float32 in [0, 1] (uint8 is scaled by 1/255), a copy; ``shape`` (H, W) if given."""
    if isinstance(image, torch.Tensor):
        raise TypeError(f"{name} must be a NumPy array (H, W, 3), got a torch tensor")
    array = np.asarray(unmask(image, name, holes=False))
    if array.dtype == np.uint8:
        array = array.astype(np.float32) / 255.0
    if not np.issubdtype(array.dtype, np.floating):
        raise TypeError(f"{name} must be float in [0, 1] (or uint8), got dtype {array.dtype}")
    if array.ndim != 3 or array.shape[2] != 3:
        raise ValueError(f"{name} must have shape (H, W, 3), got {array.shape}")
    if shape is not None and array.shape[:2] != shape:
        raise ValueError(f"{name} must be (H, W, 3) = {(*shape, 3)} like depth, got {array.shape} "
                         f"({array.shape[0]}×{array.shape[1]} instead of {shape[0]}×{shape[1]})")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must contain only finite values")
    if array.min() < -1e-6 or array.max() > 1 + 1e-6:
        raise ValueError(f"{name} must lie in [0, 1], got range [{array.min():.3g}, {array.max():.3g}]")
    return np.clip(array, 0.0, 1.0).astype(np.float32)


def check_depth(depth, name: str = "depth", allow_holes: bool = True, min_valid: int = MIN_VALID_PIXELS,
                shape: tuple | None = None, dtype=np.float32) -> np.ndarray:
    """The depth contract: (H, W) float metres, positive where finite, NaN holes, at least
    ``min_valid`` valid pixels, (H, W) = ``shape`` if given → a copy as ``dtype`` (float32).

    One error type per fault: a torch tensor or a non-float dtype → ``TypeError``; a wrong shape,
    ``inf``, a value ≤ 0, too few valid pixels, holes where ``allow_holes=False``, values that
    ``dtype`` cannot hold, or a valid range wider than ``MAX_DEPTH_RATIO`` → ``ValueError``. A
    NumPy masked array is honoured: masked entries are holes.
    """
    if isinstance(depth, torch.Tensor):
        raise TypeError(f"{name} must be a NumPy array (H, W), got a torch tensor")
    array = np.asarray(unmask(depth, name, holes=True))
    if not np.issubdtype(array.dtype, np.floating):
        raise TypeError(f"{name} must be float metres with NaN holes, got dtype {array.dtype}")
    if array.ndim != 2:
        raise ValueError(f"{name} must be (H, W) metres with NaN holes, got shape {array.shape}")
    if shape is not None and array.shape != tuple(shape):
        raise ValueError(f"{name} is {array.shape[0]}×{array.shape[1]} but must be {shape[0]}×{shape[1]} (H×W)")
    finite = np.isfinite(array)
    if np.any(np.isinf(array)):
        raise ValueError(f"{name} contains inf; mark holes with NaN (loaders convert a dataset's own marker)")
    if np.any(array[finite] <= 0):
        raise ValueError(f"{name} must be positive metres where valid, got minimum {array[finite].min():.3g} "
                         f"({int((array[finite] <= 0).sum())} pixel(s) ≤ 0); mark unknown pixels with NaN, not 0")
    if finite.sum() < min_valid:
        raise ValueError(f"{name} has {int(finite.sum())} valid pixels; need at least {min_valid} valid (finite) pixel(s)")
    if not allow_holes and not finite.all():
        raise ValueError(f"{name} must have no holes")
    converted = array.astype(dtype)  # always a copy: astype copies by default
    lost = finite & ~(np.isfinite(converted) & (converted > 0))
    if lost.any():
        raise ValueError(f"{name} has {int(lost.sum())} valid value(s) that {np.dtype(dtype).name} cannot hold "
                         f"(they would become inf or 0, i.e. holes); range {array[finite].min():.3g}–"
                         f"{array[finite].max():.3g}: is the unit right (metres)?")
    if finite.any():
        near, far = float(converted[finite].min()), float(converted[finite].max())
        if near < MIN_DEPTH_M:  # float32 denormals pass "> 0" and then vanish in 1/Z: an all-zero result
            raise ValueError(f"{name} has valid depths down to {near:.3g} m ({int((converted[finite] < MIN_DEPTH_M).sum())} "
                             f"pixel(s) below {MIN_DEPTH_M:g} m, a micrometre): no camera measures that near. Are they "
                             f"invalid readings (make them NaN), or is the unit wrong (metres expected)?")
        if far > MAX_DEPTH_RATIO * near:
            raise ValueError(f"{name} spans {near:.3g}–{far:.3g} m, a ratio of {far / near:.3g} (at most "
                             f"{MAX_DEPTH_RATIO:g}): in float32 disparity the far part would be indistinguishable. "
                             f"Are the tiny values invalid readings (make them NaN), or is a unit wrong?")
    return converted


UNIT_FACTORS = ((1000.0, "millimetres"), (100.0, "centimetres"), (1 / 0.3048, "feet"), (1 / 0.0254, "inches"),
                (1 / 1000.0, "kilometres"))  # stored value per metre of each unit
SAME_UNIT_RATIO = 2.0  # the median ratio of two depths of one scene in one unit lies within [1/2, 2]


def check_same_units(depth, other, depth_name: str, other_name: str) -> None:
    """Refuse ``other`` (H, W) when it is not in ``depth``'s unit: the median of ``other / depth`` over the
    pixels valid (finite, > 0) in both lies outside [1/``SAME_UNIT_RATIO``, ``SAME_UNIT_RATIO``]. The message
    names ``other_name``, the ratio and the unit it likely is (``UNIT_FACTORS``). Too few pixels valid in both
    (< ``MIN_VALID_PIXELS``): the ratio of their medians, judged 4× more leniently (other pixels, other depths)."""
    depth, other = np.asarray(depth, np.float64), np.asarray(other, np.float64)
    with np.errstate(invalid="ignore"):
        valid_depth, valid_other = np.isfinite(depth) & (depth > 0), np.isfinite(other) & (other > 0)
    both = valid_depth & valid_other
    if both.sum() >= MIN_VALID_PIXELS:
        ratio, limit = float(np.median(other[both] / depth[both])), SAME_UNIT_RATIO
        basis = f"the median of {other_name} / {depth_name} over the {int(both.sum())} pixels valid in both"
    elif valid_depth.any() and valid_other.any():
        ratio, limit = float(np.median(other[valid_other]) / np.median(depth[valid_depth])), 4 * SAME_UNIT_RATIO
        basis = f"the ratio of their medians (too few pixels are valid in both to compare pixel by pixel)"
    else:
        return
    if 1 / limit <= ratio <= limit:
        return
    factor, unit = min(UNIT_FACTORS, key=lambda fu: abs(np.log(ratio / fu[0])))
    likely = (f"; {other_name} looks like {unit} against {depth_name} in metres (× {factor:.4g})"
              if abs(np.log(ratio / factor)) < np.log(1.25) else "")
    raise ValueError(f"{other_name} is {ratio:.4g} × {depth_name} ({basis}): they are not in the same unit, or not "
                     f"of the same view{likely}. Give both in metres (the same scale); nothing was fitted or scored")


def check_size(size) -> tuple[int, int]:
    """An image ``size`` as (H, W) ints, each ≥ 8; ``ValueError`` naming ``size`` otherwise."""
    try:
        H, W = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ValueError(f"size must be (H, W), got {size!r}") from None
    if H < 8 or W < 8 or tuple(size) != (H, W):
        raise ValueError(f"size must be two integers >= 8, got {size!r}")
    return H, W


def env_choice(variable: str, default: str, choices) -> str:
    """The value of the environment ``variable`` (stripped, lower case; ``default`` when unset or blank),
    which must be one of ``choices``: a ``ValueError`` naming the variable otherwise."""
    import os

    value = os.environ.get(variable, default).strip().lower() or default
    if value not in choices:
        raise ValueError(f"{variable} must be one of {sorted(choices)}, got {value!r}")
    return value


def named_choice(name, table: dict, what: str, current):
    """``table[name]``, or ``table[current()]`` for None; a ``ValueError`` saying ``what`` must be one of
    the table's keys otherwise."""
    name = current() if name is None else name
    if name not in table:
        raise ValueError(f"{what} must be one of {sorted(table)}, got {name!r}")
    return table[name]


# --------------------------------------------------------------------------- nothing dropped without a word

class SkippedWarning(UserWarning):
    """A reader or command left out frames, views or files: how many, which, and why."""


SKIPPED_NAMES_SHOWN = 8  # a long list is cut after this many names, with the count of the rest


def report_skipped(where, names, what: str, reason: str, strict: bool = False, total: int | None = None) -> None:
    """The one rule for everything a reader or command leaves out: say it, or refuse it.

    ``names`` (the files, frames or views left out, each as the user would recognise it) are counted
    and named in a :class:`SkippedWarning` (``where``: the folder or argument they came from; ``what``:
    their kind, plural, e.g. "colour frame(s)"; ``reason``: why; ``total``: out of how many). With
    ``strict`` (CLI: ``--strict``) the same message is a ``ValueError`` instead, raised before any work.
    Nothing happens for an empty ``names``."""
    names = [str(n) for n in names]
    if not names:
        return
    shown = ", ".join(names[:SKIPPED_NAMES_SHOWN]) + (f", … ({len(names) - SKIPPED_NAMES_SHOWN} more)"
                                                     if len(names) > SKIPPED_NAMES_SHOWN else "")
    count = f"{len(names)} of {total}" if total is not None else f"{len(names)}"
    message = f"{where}: {count} {what} {reason} and were left out: {shown}"
    if strict:
        raise ValueError(message + " (strict: nothing may be left out; fix the input, or run without strict "
                                   "(CLI: without --strict) to go on without them)")
    warnings.warn(message + " (strict=True, CLI --strict, makes this an error)", SkippedWarning, stacklevel=3)


def check_finite_output(name: str, array) -> None:
    """A fit must never return NaN or inf: raise instead (the optimisation diverged)."""
    if array is not None and not np.all(np.isfinite(array)):
        bad = int(np.size(array) - np.isfinite(array).sum())
        raise FloatingPointError(f"the fit's {name} has {bad} non-finite value(s) of {np.size(array)}: the "
                                 f"optimisation diverged. Lower config.lr, or check the inputs and init.")
