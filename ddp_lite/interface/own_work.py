"""The exercises' one rule about whose work an answer is: while a check runs the student's function, the
function may not call the kit's or a library's implementation of that very exercise.

Each check in :mod:`ddp_lite.interface.exercises` names the callables it forbids (dotted names, beside
the check). :func:`call_watched` calls the student's function with a profile hook (``sys.setprofile``)
that records every call of one of them, however it is reached: directly, through a lambda, a dict
(``BASELINES["nearest"]``), ``functools.partial``, ``getattr`` or an import inside the function.
A forbidden call found makes the check FAIL, whatever the numbers. In grading the function runs in
the student's kernel: the kernel imports this module (the standard library only) and reports what it
saw with the answer (:mod:`ddp_lite.interface.grading_kernel`). This stops the one-line answer, not
a determined cheat: a function that switches the hook off is reported as such, but the kernel is the
student's.
"""
from __future__ import annotations

import functools
import importlib
import inspect
import sys

__all__ = ["resolve", "call_watched"]

_RESOLVED: dict[tuple, dict] = {}


def _lookup(name: str):
    """The object a dotted name ``package.module.attr[.attr]`` names, or None if it cannot be imported."""
    parts = name.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except Exception:  # not installed, or not a module at this cut
            continue
        try:
            for attr in parts[cut:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def resolve(names) -> dict:
    """``{key: dotted name}`` for the forbidden callables ``names``: a Python function's key is its code
    object (and a wrapped one's, ``functools.wraps``), a C function's its ``id``; names that do not
    import (an optional library not installed) are left out."""
    names = tuple(names)
    if names not in _RESOLVED:
        keys: dict = {}
        for name in names:
            obj = _lookup(name)
            if obj is None:
                continue
            for candidate in (obj, inspect.unwrap(obj)) if callable(obj) else (obj,):
                function = getattr(candidate, "__func__", candidate)
                code = getattr(function, "__code__", None)
                if code is not None:
                    keys[code] = name
                else:
                    keys[("id", id(function))] = name
                    keys.setdefault(("keep", name), function)  # keeps the object, and so its id, alive
        _RESOLVED[names] = keys
    return _RESOLVED[names]


def _c_key(function):
    while isinstance(function, functools.partial):
        function = function.func
    return ("id", id(getattr(function, "__func__", function)))


def call_watched(fn, args, kwargs, names, seen: set):
    """``fn(*args, **kwargs)`` with every call of a forbidden callable (dotted ``names``) added to ``seen``
    (also when ``fn`` raises); returns what ``fn`` returns."""
    keys = resolve(names)
    if not keys:
        return fn(*args, **kwargs)
    direct = keys.get(getattr(fn, "__code__", None)) or keys.get(_c_key(fn))
    if direct:
        seen.add(direct)

    def hook(frame, event, arg):
        if event == "call":
            name = keys.get(frame.f_code)
        elif event == "c_call":
            name = keys.get(_c_key(arg))
        else:
            return
        if name:
            seen.add(name)

    previous = sys.getprofile()
    sys.setprofile(hook)
    try:
        return fn(*args, **kwargs)
    finally:
        if sys.getprofile() is not hook:
            seen.add("sys.setprofile (the function switched off the check's watch on what it calls)")
        sys.setprofile(previous)
