"""Fits done once: with ``DDP_CACHE`` set to a folder, a fit whose inputs were all seen before is read back.

Re-running a notebook re-does every fit in it, minutes at ``class``. With the environment variable
``DDP_CACHE`` naming a folder (``DDP_CACHE=~/.cache/ddp-lite make lab``), :func:`complete_depth` and
:func:`fit_image` store each result there, under a hash of everything that decides it:

- every argument: arrays by value, cameras and views by their fields, the ``FitConfig`` (the net's
  precision, ``bf16``, included), the ``RunOptions`` (None as ``RunOptions()``; its ``progress`` flag aside:
  a progress bar changes no number), a warm start's weights;
- the source code of ``ddp_lite`` itself, and the torch and NumPy versions: an edited library
  never reads an old result;
- torch's thread count, the CPU's vector instructions and whether a GPU is there: CPU reductions
  may round differently with more threads or wider vectors, ``bf16=None`` means bfloat16 only where
  the CPU computes it natively, and ``device=None`` means the GPU when there is one;
- the profile ``DDP_PROFILE`` names: ``config=None`` means its config.

So a cached result is the result the same call would compute now (fits are deterministic on a
CPU: ``tests/method/test_fit.py::test_same_seed_same_numbers_and_inputs_untouched``), only without the
wait; ``seconds`` is the time the fit took when it ran. A fit with a ``callback`` is never cached
(the callback is what the caller wants to see), nor is a call whose arguments cannot be hashed,
nor one that raises. Hashing is ``joblib.hash`` (MD5 of a pickle, arrays by their bytes).

An entry cannot run code and cannot stand in for another call (:mod:`ddp_lite.method.runtime.cache_entry`):
it is one ``.npz`` file read with ``allow_pickle=False`` (the result's arrays, and its structure as
JSON naming only the kit's own result types), and it holds the key of the call that made it. On
read the key, the function and the result type must match the call, and the result's images must
have the shape of the call's input (``like``), hold floats and be finite; anything else (a foreign
or swapped entry, a pickle, a truncated file) is ignored with a warning and fitted again. What this
does not give: a person who can write the folder can still forge an entry for a call with the
right key and shapes but other numbers; share a ``DDP_CACHE`` only with people you trust. Entries
are written atomically, so notebooks run side by side can share one folder; a store that fails
(a full disk, a read-only folder) warns and returns the fitted result. Unset (the default): no cache.
"""
from __future__ import annotations

import dataclasses
import functools
import inspect
import os
import warnings

import numpy as np
import torch

from ..core.disk_cache import ENV_VAR, cache_folder, source_digest
from ..core.files import regular_file
from .runtime.cache_entry import BadEntry, Unstorable, read_entry, write_entry
from .runtime.options import RunOptions
from .config import FitConfig
from .profiles import current_profile_name
from .kit.recipes import current_recipe_name

__all__ = ["cached"]


def _library_digest() -> str:
    """SHA-256 over the package's own source files (every sub-package), in path order."""
    return source_digest()


def _plain(value):
    """``value`` with tensors as NumPy arrays and dataclasses as dicts, so that equal inputs hash
    equally in any process (a pickled tensor does not: its bytes differ from run to run)."""
    if isinstance(value, torch.Tensor):
        return value.detach().cpu().numpy()
    if isinstance(value, FitConfig):  # its fields by their flat names
        return (type(value).__qualname__, {name: _plain(item) for name, item in value.flat().items()})
    if isinstance(value, RunOptions):  # the progress bar changes no result
        fields = {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value) if f.name != "progress"}
        return (type(value).__qualname__, fields)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return (type(value).__qualname__, {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)})
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_plain(item) for item in value)
    return value


def _key(function, arguments: dict) -> str | None:
    import joblib  # only when the cache is on

    environment = (_library_digest(), torch.__version__, np.__version__, torch.get_num_threads(),
                   torch.backends.cpu.get_cpu_capability(), torch.cuda.is_available(),
                   current_profile_name(), current_recipe_name())  # config=None: the profile's config
    try:
        return joblib.hash((function.__module__, function.__qualname__, _plain(arguments), environment))
    except Exception:  # an argument that does not pickle (the fit itself will say what is wrong with it)
        return None


def cached(function=None, *, like: str | None = None, types=()):
    """Decorate a fit: when ``DDP_CACHE`` is set and no ``callback`` is given, return the stored result
    of an identical earlier call, or compute, store and return it.

    ``like`` names the argument whose (H, W) every image of a stored result must have
    (``@cached(like="depth")``); an entry that does not is ignored with a warning and fitted again.
    ``types``: the dataclasses a result holds (its own type, a transform...): an entry may name no other."""
    if function is None:
        return functools.partial(cached, like=like, types=types)
    signature = inspect.signature(function)
    name = f"{function.__module__}.{function.__qualname__}"
    result_type = signature.return_annotation if isinstance(signature.return_annotation, str) else None

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        folder = cache_folder()
        if folder is None:
            return function(*args, **kwargs)
        try:  # positional or keyword, given or default: the same call hashes the same
            bound = signature.bind(*args, **kwargs)
        except TypeError:
            return function(*args, **kwargs)  # let the call raise its own error
        bound.apply_defaults()
        if "options" in bound.arguments and bound.arguments["options"] is None:
            bound.arguments["options"] = RunOptions()  # the same run, the same key
        key = None if bound.arguments.get("callback") is not None else _key(function, bound.arguments)
        if key is None:
            return function(*args, **kwargs)
        path = folder / f"{function.__name__}-{key}.npz"
        if os.path.lexists(path):
            try:
                shape = None if like is None else np.shape(bound.arguments.get(like))[:2]
                return read_entry(regular_file(path, ENV_VAR), key, name, result_type, shape or None, types)
            except (BadEntry, OSError, ValueError) as error:  # never trusted, never fatal: fit again
                warnings.warn(f"{ENV_VAR}: ignoring the cache entry {path}: {error}; fitting again",
                              RuntimeWarning, stacklevel=2)
        result = function(*args, **kwargs)
        try:
            write_entry(path, result, key, name, types)
        except (Unstorable, OSError) as error:  # the fit is done: hand it back, say why it is not kept
            warnings.warn(f"{ENV_VAR}: could not store the result in {path} ({error}); it is returned "
                          f"but not cached", RuntimeWarning, stacklevel=2)
        return result

    return wrapper
