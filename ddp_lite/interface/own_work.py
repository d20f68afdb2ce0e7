"""The exercises' one rule about whose work an answer is: while a check runs the student's function, the
function may not call the kit's or a library's implementation of that very exercise.

Each check in :mod:`ddp_lite.interface.exercises` names the callables it forbids (dotted names, beside
the check). :func:`call_watched` calls the student's function with a profile hook (``sys.setprofile``)
that records every call of one of them, however it is reached: directly, through a lambda, a dict
(``BASELINES["nearest"]``), ``functools.partial``, ``getattr`` or an import inside the function.
A forbidden call found makes the check FAIL, whatever the numbers. Watching imports nothing: a callable
exists only once its module is loaded, so each name is looked up among the loaded modules, and again
whenever the function loads more. In grading the function runs in the student's kernel: the kernel
imports this module (the standard library only) and reports what it saw with the answer
(:mod:`ddp_lite.interface.grading_kernel`), without loading the libraries the check forbids. This stops
the one-line answer, not a determined cheat: a function that switches the hook off is reported as such,
but the kernel is the student's.
"""
from __future__ import annotations

import functools
import inspect
import sys
import types

__all__ = ["resolve", "call_watched"]

_WATCHES: dict[tuple, "_Watch"] = {}
_LOADING = object()  # what _loaded gives while a module on the way is still executing its body


def _loaded(name: str):
    """The object a dotted name ``package.module.attr[.attr]`` names, found among the modules loaded now, or
    None while it is not (yet): nothing is imported for it, except what a lazily loading package
    (``skimage.metrics``: a module ``__getattr__``) loads when one of its names is asked for, once that
    package itself is loaded. ``_LOADING`` while a module on the way is still executing its body."""
    parts = name.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        obj = sys.modules.get(".".join(parts[:cut]))
        if obj is not None:
            break
    else:
        return None
    try:
        for attr in parts[cut:]:
            if isinstance(obj, types.ModuleType):
                if getattr(getattr(obj, "__spec__", None), "_initializing", False):
                    return _LOADING
                if attr not in vars(obj) and "__getattr__" not in vars(obj):
                    return None  # a submodule not imported yet, or a name its module has not defined yet
            obj = getattr(obj, attr)
    except Exception:  # noqa: BLE001 - not there (yet): looked up again when more modules are loaded
        return None
    return obj


class _Watch:
    """The forbidden callables ``names`` as keys a profile hook looks up: a Python function's key is its code
    object (and a wrapped one's, ``functools.wraps``), a C function's its ``id``. A callable can only be called
    once the module that defines it is loaded, so a name is looked up among the loaded modules only
    (:func:`_loaded`) and, while it is not found, again whenever more modules are loaded (:meth:`refresh`):
    watching imports nothing, and a function that imports the forbidden module itself is still caught. A name
    that never loads (an optional library not installed) is never found."""

    def __init__(self, names: tuple):
        self.keys: dict = {}
        self.pending = list(names)
        self.modules = -1  # len(sys.modules) when last refreshed
        self.refresh()

    def refresh(self) -> None:
        if len(sys.modules) == self.modules or not self.pending:
            return
        self.modules = len(sys.modules)
        for name in list(self.pending):
            obj = _loaded(name)
            if obj is _LOADING:  # its module may define it without loading any other: looked up at the next event
                self.modules = -1
                continue
            if obj is None:
                continue
            self.pending.remove(name)
            for candidate in (obj, inspect.unwrap(obj)) if callable(obj) else (obj,):
                function = getattr(candidate, "__func__", candidate)
                code = getattr(function, "__code__", None)
                if code is not None:
                    self.keys[code] = name
                else:
                    self.keys[("id", id(function))] = name
                    self.keys.setdefault(("keep", name), function)  # keeps the object, and so its id, alive


def _watch(names) -> _Watch:
    names = tuple(names)
    if names not in _WATCHES:
        _WATCHES[names] = _Watch(names)
    watch = _WATCHES[names]
    watch.refresh()
    return watch


def resolve(names) -> dict:
    """``{key: dotted name}`` for the forbidden callables ``names`` that the modules loaded now define (see
    :class:`_Watch`): a Python function's key is its code object, a C function's its ``id``."""
    return {key: name for key, name in _watch(names).keys.items() if not (isinstance(key, tuple) and key[0] == "keep")}


def _c_key(function):
    while isinstance(function, functools.partial):
        function = function.func
    return ("id", id(getattr(function, "__func__", function)))


def call_watched(fn, args, kwargs, names, seen: set):
    """``fn(*args, **kwargs)`` with every call of a forbidden callable (dotted ``names``) added to ``seen``
    (also when ``fn`` raises); returns what ``fn`` returns."""
    if not names:
        return fn(*args, **kwargs)
    watch = _watch(names)
    keys = watch.keys
    direct = keys.get(getattr(fn, "__code__", None)) or keys.get(_c_key(fn))
    if direct:
        seen.add(direct)

    def hook(frame, event, arg):
        if watch.pending and len(sys.modules) != watch.modules:  # the function imported something
            watch.refresh()
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
