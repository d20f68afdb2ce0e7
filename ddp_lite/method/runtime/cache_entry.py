"""One fit-cache entry on disk: a result as an ``.npz`` that cannot run code, and the checks made on reading it.

A result (a :class:`~ddp_lite.method.result.DepthResult`, an :class:`~ddp_lite.method.dip.ImageResult`,
the arrays, tensors, histories and transform inside them) is split into its arrays, stored as the
``.npz`` members ``a0``, ``a1``, ..., and its structure, stored as JSON in the member ``meta`` next to
the key of the call that made it. Reading uses ``np.load(allow_pickle=False)``: an object array or a
pickle is refused by NumPy itself, and the JSON can name only the dataclasses the cached function
declares (``types``), which are built from their fields (their own checks run). :func:`read_entry` then refuses an entry
whose key, function or result type differs from the call's, or whose images do not have the input's
height and width or hold non-finite values: :class:`BadEntry` says which.
"""
from __future__ import annotations

import dataclasses
import json
import zipfile

import numpy as np
import torch

from ...core.array_archive import array_node, write_archive

__all__ = ["BadEntry", "Unstorable", "write_entry", "read_entry"]

FORMAT = 1


class BadEntry(ValueError):
    """An entry that must not be returned (foreign, swapped, tampered with or unreadable); the message says why."""


class Unstorable(TypeError):
    """A result holding something an entry cannot hold without pickling it."""


def _type_name(cls) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def _encode(value, arrays: list, types: dict):
    """``value`` as JSON-able structure, its arrays appended to ``arrays``."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, float)) and type(value) in (int, float):
        return {"float": repr(value)} if isinstance(value, float) else value
    if isinstance(value, torch.Tensor):
        array = value.detach().cpu()
        if array.dtype == torch.bfloat16:
            raise Unstorable("a bfloat16 tensor")
        arrays.append(array.numpy())
        return {"tensor": len(arrays) - 1}
    if isinstance(value, (np.ndarray, np.generic)):
        return array_node(value, arrays, Unstorable)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        if types.get(_type_name(type(value))) is not type(value):
            raise Unstorable(f"a {_type_name(type(value))}")
        return {"dataclass": _type_name(type(value)),
                "fields": {f.name: _encode(getattr(value, f.name), arrays, types) for f in dataclasses.fields(value)}}
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            raise Unstorable("a dict with keys that are not strings")
        return {"dict": [[k, _encode(v, arrays, types)] for k, v in value.items()]}
    if isinstance(value, (list, tuple)):
        return {type(value).__name__: [_encode(v, arrays, types) for v in value]}
    raise Unstorable(f"a {type(value).__qualname__}")


def write_entry(path, result, key: str, function: str, types=()) -> None:
    """Store ``result`` made by ``function`` (its qualified name) for ``key`` at ``path``, atomically, as an
    ``.npz`` (:func:`ddp_lite.core.array_archive.write_archive`); ``types``: the dataclasses it may hold.

    Raises :class:`Unstorable` for a value that only a pickle could hold, before anything is written."""
    arrays: list = []
    types = {_type_name(cls): cls for cls in types}
    meta = {"format": FORMAT, "key": key, "function": function, "result": _encode(result, arrays, types)}
    write_archive(path, "meta", meta, arrays)


def _decode(node, arrays, types: dict):
    if node is None or isinstance(node, (bool, str, int)):
        return node
    if not isinstance(node, dict) or len(node) not in (1, 2):
        raise BadEntry(f"unexpected {type(node).__name__} in its structure")
    (tag, body), = list(node.items())[:1]
    if tag == "float" and isinstance(body, str):
        return float(body)
    if tag in ("array", "scalar", "tensor"):
        array = arrays(body)
        if tag == "scalar":
            return array[()]
        return torch.from_numpy(array.copy()) if tag == "tensor" else array
    if tag == "dict" and isinstance(body, list):
        if not all(isinstance(item, list) and len(item) == 2 and isinstance(item[0], str) for item in body):
            raise BadEntry("a malformed dict in its structure")
        return {k: _decode(v, arrays, types) for k, v in body}
    if tag in ("list", "tuple") and isinstance(body, list):
        items = [_decode(v, arrays, types) for v in body]
        return items if tag == "list" else tuple(items)
    if tag == "dataclass" and isinstance(body, str) and body in types and isinstance(node.get("fields"), dict):
        cls = types[body]
        name = cls.__qualname__
        names = {f.name for f in dataclasses.fields(cls)}
        if set(node["fields"]) != names:
            raise BadEntry(f"its {name} has fields {sorted(node['fields'])}, expected {sorted(names)}")
        try:
            return cls(**{k: _decode(v, arrays, types) for k, v in node["fields"].items()})
        except (TypeError, ValueError) as error:
            raise BadEntry(f"its {name} is invalid ({error})") from None
    raise BadEntry(f"unexpected {tag!r} in its structure")


def read_entry(path, key: str, function: str, result_type: str | None, like: tuple | None, types=()):
    """The result stored at ``path``, if it was made for ``key`` by ``function``; else :class:`BadEntry`.

    Args:
        result_type: the result's class name (the function's return annotation), or None: any.
        types: the dataclasses the entry may hold (any other is refused).
        like: (H, W) of the call's input: every top-level image of the result must be (H, W) or
            (H, W, C), floating point and finite. None: not checked.
    """
    try:
        archive = np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        raise BadEntry(f"it is not an .npz entry ({type(error).__name__}: {error})") from None
    if not isinstance(archive, np.lib.npyio.NpzFile):
        raise BadEntry("it is a single array, not an .npz entry")
    with archive:
        try:
            meta = json.loads(archive["meta"].tobytes().decode())
        except (KeyError, ValueError, UnicodeDecodeError, zipfile.BadZipFile) as error:
            raise BadEntry(f"its metadata is unreadable ({type(error).__name__})") from None
        if not isinstance(meta, dict) or meta.get("format") != FORMAT:
            raise BadEntry("it has no metadata of a known format")
        if meta.get("key") != key or meta.get("function") != function:
            raise BadEntry(f"it was made by another call ({meta.get('function')} with key {meta.get('key')!r})")

        def arrays(index):
            if not isinstance(index, int) or isinstance(index, bool):
                raise BadEntry("an array reference that is not a number")
            try:
                return archive[f"a{index}"]
            except (KeyError, ValueError, OSError, zipfile.BadZipFile) as error:
                raise BadEntry(f"its array a{index} is missing or unreadable ({type(error).__name__})") from None

        result = _decode(meta.get("result"), arrays, {_type_name(cls): cls for cls in types})
    if result_type is not None and type(result).__qualname__ != result_type:
        raise BadEntry(f"it holds a {type(result).__qualname__}, expected a {result_type}")
    if like is not None and dataclasses.is_dataclass(result):
        for field in dataclasses.fields(result):
            image = getattr(result, field.name)
            if not isinstance(image, np.ndarray) or image.ndim < 2:
                continue
            if image.shape[:2] != tuple(like) or image.ndim > 3:
                raise BadEntry(f"its {field.name} is {image.shape}, the call's input is {tuple(like)}")
            if image.dtype.kind != "f" or not np.isfinite(image).all():
                raise BadEntry(f"its {field.name} is not finite floating point ({image.dtype})")
    return result
