"""Input checks of the time law: numbers, arrays, per-joint limits, increasing parameters."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .limits import FloatArray

# --------------------------------------------------------------------------- checks


def _float(value: Any, name: str, *, positive: bool = True, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name}: expected a finite number, got {v}")
    if positive and (v < 0 or (v == 0 and not allow_zero)):
        raise ValueError(f"{name}: expected a number {'>=' if allow_zero else '>'} 0, got {v}")
    return v


def _array(value: ArrayLike, name: str, shape: tuple[int | None, ...]) -> FloatArray:
    try:
        arr = np.array(value, dtype=np.float64)  # a copy: results are frozen in place
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected numbers ({exc})") from None
    if arr.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(arr.shape, shape, strict=True)
    ):
        want_s = "(" + ", ".join("n" if w is None else str(w) for w in shape)
        want_s += ",)" if len(shape) == 1 else ")"
        raise ValueError(f"{name}: expected shape {want_s}, got {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        where = idx[0] if len(idx) == 1 else list(idx)
        raise ValueError(f"{name}[{where}]: expected a finite number, got {arr[idx]}")
    return arr


def _limits(value: ArrayLike, name: str, J: int) -> FloatArray:
    arr = _array(value, name, (J,))
    bad = np.flatnonzero(arr <= 0)
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{name}[{i}]: expected a limit > 0, got {arr[i]}")
    return arr


def _increasing(arr: FloatArray, name: str) -> None:
    bad = np.flatnonzero(np.diff(arr) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise ValueError(
            f"{name}[{i}]: expected strictly increasing values, got {arr[i]!r} after "
            f"{name}[{i - 1}] = {arr[i - 1]!r}"
        )
