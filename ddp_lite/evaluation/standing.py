"""Where one method stands among others, as a sentence a notebook prints under its table.

A notebook's conclusion that quotes a rank or a figure in its prose drifts from what the run
prints; these helpers say it from the run's own numbers instead (lower error = better).
"""
from __future__ import annotations

import numpy as np

__all__ = ["ordinal", "standing", "leads_and_trails"]


def ordinal(n: int) -> str:
    """1 → "1st", 2 → "2nd", 11 → "11th", 23 → "23rd"."""
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def standing(errors: dict[str, float], name: str, unit: str = "", digits: int = 3) -> str:
    """Where ``name`` ranks in ``errors`` ({method: error}, lower is better), with its error and the
    nearest rival: the one just ahead of it, or (when it is first) the one just behind it.

    Example:
        >>> standing({"linear": 1.0, "DDP": 1.2, "nearest": 1.5}, "DDP", " px", digits=1)
        'DDP ranks 2nd of 3 (1.2 px), behind linear (1.0 px)'
        >>> standing({"linear": 1.0, "DDP": 0.9}, "DDP", digits=2)
        'DDP ranks 1st of 2 (0.90), ahead of linear (1.00)'
    """
    if name not in errors:
        raise ValueError(f"name {name!r} is not among the methods {list(errors)}")
    if len(errors) < 2:
        raise ValueError(f"errors must hold at least two methods to rank, got {list(errors)}")
    ranked = sorted(errors, key=errors.get)
    rank = ranked.index(name)
    rival = ranked[rank - 1] if rank else ranked[1]
    shown = lambda method: f"{errors[method]:.{digits}f}{unit}"  # noqa: E731
    return (f"{name} ranks {ordinal(rank + 1)} of {len(ranked)} ({shown(name)}), "
            f"{'behind' if rank else 'ahead of'} {rival} ({shown(rival)})")


def leads_and_trails(table: dict[str, dict[str, float]], name: str) -> tuple[list[str], list[str]]:
    """``table`` {case: {method: error}} → (the cases where ``name`` has a lower error than every other
    method, the cases where some other method is lower). A tie counts as trailing."""
    leads, trails = [], []
    for case, errors in table.items():
        others = [e for method, e in errors.items() if method != name]
        (leads if errors[name] < float(np.min(others)) else trails).append(case)
    return leads, trails
