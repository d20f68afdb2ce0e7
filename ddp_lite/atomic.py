"""Atomic file writes (temp file beside the target, then rename): see :mod:`data_fetch.atomic`.

The code lives in ``data_fetch`` because that package must not import torch; both use this one copy.
"""
from data_fetch.atomic import atomic_path, write_bytes_atomic

__all__ = ["atomic_path", "write_bytes_atomic"]
