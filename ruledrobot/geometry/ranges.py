"""Runs of a boolean mask: the one convention for index ranges in ruledrobot.

Every range of samples the product computes, stores or prints is **half-open**,
``(start, stop)`` with ``start <= k < stop``, as Python slices are (``mask[start:stop]``
is the run); messages print them inclusive through :func:`ruledrobot.io.words.index_ranges`.
``tests/architecture/test_one_home.py`` fails when a second spelling of a run finder
appears.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["checked_ranges", "ranges_mask", "run_indices", "runs_of", "runs_of_indices",
           "shifted_ranges"]


def runs_of(mask: ArrayLike) -> tuple[tuple[int, int], ...]:
    """Half-open ranges ``(start, stop)`` of the True runs of a boolean mask (M,)."""
    m = np.asarray(mask, dtype=bool).astype(np.int8)
    d = np.diff(np.r_[0, m, 0])
    return tuple(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(),
                     strict=True))  # fmt: skip


def runs_of_indices(idx: ArrayLike) -> tuple[tuple[int, int], ...]:
    """Return the runs of consecutive values of sorted indices as half-open ranges.

    Ranges ``(first, last + 1)`` of the runs of sorted integer indices ``idx`` (K,).
    """
    i = np.asarray(idx, dtype=np.int64).reshape(-1)
    if i.size == 0:
        return ()
    cut = np.flatnonzero(np.diff(i) != 1)
    starts = np.r_[0, cut + 1]
    ends = np.r_[cut, i.size - 1]
    return tuple((int(i[a]), int(i[b]) + 1) for a, b in zip(starts, ends, strict=True))


def run_indices(mask: ArrayLike, closed: bool = False) -> list[np.ndarray]:
    """Return the index arrays of the True runs of ``mask`` (M,).

    With ``closed`` a run through the end continues at the start (one array, wrapping).
    """
    m = np.asarray(mask, dtype=bool)
    runs = [np.arange(a, b) for a, b in runs_of(m)]
    if closed and len(runs) > 1 and m[0] and m[-1]:
        runs = [np.concatenate([runs[-1], runs[0]]), *runs[1:-1]]
    return runs


def checked_ranges(value: object, what: str) -> tuple[tuple[int, int], ...]:
    """Return ``value`` (pairs of integers) as half-open ranges.

    ValueError naming ``what[i]`` where a pair is not ``0 <= start < stop``.
    """
    out = []
    for i, r in enumerate(value or ()):  # type: ignore[attr-defined]
        a, b = (int(x) for x in r)
        if not 0 <= a < b:
            raise ValueError(f"{what}[{i}]: expected sample indices 0 <= start < stop, got {r!r}")
        out.append((a, b))
    return tuple(out)


def ranges_mask(ranges: tuple[tuple[int, int], ...], n: int) -> np.ndarray:
    """(n,) bool: sample k lies in one of the half-open ``ranges``."""
    m = np.zeros(n, dtype=bool)
    for a, b in ranges:
        m[a:b] = True
    return m


def shifted_ranges(
    ranges: tuple[tuple[int, int], ...], start: int, stop: int
) -> tuple[tuple[int, int], ...]:
    """The parts of ``ranges`` within samples ``start:stop``, renumbered from 0."""
    return tuple((max(a, start) - start, min(b, stop) - start) for a, b in ranges
                 if min(b, stop) > max(a, start))  # fmt: skip
