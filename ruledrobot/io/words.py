"""How messages write numbers: one home for every consumer (issue 23).

* :func:`index_ranges` — indices as compact ranges, ``"3-17, 40"``;
* :func:`mm` — metres as whole millimetres, ``"212"`` (never ``"-0"``);
* :func:`counted` — a count and its noun, ``"1 setup"``, ``"2 setups"``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["counted", "index_ranges", "mm"]


def index_ranges(mask: ArrayLike, labels: ArrayLike | None = None) -> str:
    """The True entries of a boolean ``mask`` (N,) as compact ranges of their indices.

    ``"3-17, 40"`` — or of ``labels[i]`` (N,) (e.g. the ruling numbers of sampled rulings: runs
    of consecutive samples joined); ``""`` when none."""
    k = np.flatnonzero(np.asarray(mask, dtype=bool))
    if k.size == 0:
        return ""
    names = k if labels is None else np.asarray(labels)[k]
    breaks = np.flatnonzero(np.diff(k) > 1)
    starts, ends = np.r_[0, breaks + 1], np.r_[breaks, k.size - 1]
    return ", ".join(f"{names[a]}" if a == b else f"{names[a]}-{names[b]}"
                     for a, b in zip(starts, ends, strict=True))  # fmt: skip


def mm(v: float) -> str:
    """Metres as whole millimetres, for messages (never "-0")."""
    return str(round(float(v) * 1e3) + 0)


def counted(n: int, noun: str) -> str:
    """``n`` and ``noun``, the noun in the plural (an ``s`` added) unless ``n`` is 1."""
    return f"{n} {noun}{'' if n == 1 else 's'}"
