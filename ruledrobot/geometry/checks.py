"""Input checks for the whole package: one place that turns user data into arrays.

Every public function funnels user data through these helpers, so that bad input
raises one kind of error (:class:`ValueError`) whose message names the argument,
the first offending index and what was expected (the project's error contract,
``docs/conventions.md``).  Pure numpy; every layer may import it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

__all__ = [
    "FloatArray",
    "as_float_array",
    "as_limits",
    "as_number",
    "as_per_joint",
    "as_point",
    "as_shaped",
    "check_finite",
    "check_increasing",
    "first_index",
    "readonly",
]


def as_float_array(value: ArrayLike, name: str, tail: tuple[int, ...] = ()) -> FloatArray:
    """Return ``value`` as a float64 array whose trailing axes equal ``tail``.

    Raises ValueError naming ``name`` when the shape is wrong or an entry is
    not finite (the message gives the index of the first bad entry).
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected numbers, got {type(value).__name__} ({exc})") from None
    if tail and (arr.ndim < len(tail) or arr.shape[arr.ndim - len(tail) :] != tail):
        want = "(..., " + ", ".join(str(n) for n in tail) + ")"
        raise ValueError(f"{name}: expected an array of shape {want}, got shape {arr.shape}")
    check_finite(arr, name, tail)
    return arr


def as_shaped(value: ArrayLike, name: str, shape: tuple[int | None, ...]) -> FloatArray:
    """A float64 *copy* of ``value`` of exactly ``shape`` (``None``: any length), finite.

    The message names the first non-finite entry, e.g. ``q[3, 1]: expected a finite
    number, got nan``.
    """
    try:
        arr = np.array(value, dtype=np.float64)  # a copy: callers freeze results in place
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


def as_number(value: Any, name: str, *, positive: bool = True, allow_zero: bool = False) -> float:
    """Return ``value`` as a finite float; with ``positive`` (the default) also ``> 0``.

    ``>= 0`` with ``allow_zero``.
    """
    if isinstance(value, bool):
        raise ValueError(f"{name}: expected a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name}: expected a finite number, got {v}")
    if positive and (v < 0 or (v == 0 and not allow_zero)):
        raise ValueError(f"{name}: expected a number {'>=' if allow_zero else '>'} 0, got {v}")
    return v


def as_per_joint(
    value: ArrayLike,
    name: str,
    n: int,
    *,
    allow_inf: bool = False,
    minimum: float | None = None,
    strict: bool = False,
) -> FloatArray:
    """A per-joint parameter (n,): a scalar (broadcast) or a length-``n`` vector.

    With ``allow_inf`` the entries may be +-inf (an unlimited joint), never NaN.
    ``minimum``: every entry ``>= minimum`` (``> minimum`` with ``strict``).
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected numbers, got {type(value).__name__} ({exc})") from None
    if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != n):
        raise ValueError(f"{name}: expected a scalar or shape ({n},), got shape {arr.shape}")
    arr = np.broadcast_to(arr, (n,)).astype(np.float64)
    bad = np.isnan(arr) if allow_inf else ~np.isfinite(arr)
    if bad.any():
        what = "NaN" if allow_inf else "NaN or infinity"
        raise ValueError(f"{name}{first_index(bad)}: contains {what}")
    if minimum is not None:
        low = arr <= minimum if strict else arr < minimum
        if low.any():
            k = int(np.flatnonzero(low)[0])
            rel = ">" if strict else ">="
            raise ValueError(f"{name}[{k}]: expected a value {rel} {minimum:g}, "
                             f"got {float(arr[k])!r}")  # fmt: skip
    return arr


def as_limits(value: ArrayLike, name: str, n: int) -> FloatArray:
    """Per-joint limits (n,) [rad/s, rad/s^2, ...]: exactly ``n`` finite values, each > 0."""
    arr = as_shaped(value, name, (n,))
    bad = np.flatnonzero(arr <= 0)
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{name}[{i}]: expected a limit > 0, got {arr[i]}")
    return arr


def as_point(value: ArrayLike, name: str, *, what: str = "m") -> FloatArray:
    """A read-only point or vector (3,), finite; ValueError naming ``name`` otherwise.

    ``what`` says in the message what the three numbers are: ``"m"`` (a point or an
    offset in metres, the default) or ``"x, y, z"`` (any vector).
    """
    v = as_float_array(value, name)
    if v.shape != (3,):
        raise ValueError(f"{name}: expected 3 numbers ({what}), got shape {v.shape}")
    return readonly(v)


def check_finite(arr: FloatArray, name: str, tail: tuple[int, ...] = ()) -> None:
    """Raise ValueError naming the first batch index of ``arr`` holding NaN or inf."""
    finite = np.isfinite(arr)
    if finite.all():
        return
    item_ok = finite.reshape(*arr.shape[: arr.ndim - len(tail)], -1).all(axis=-1)
    bad = np.argwhere(~item_ok)[0]
    where = f"[{', '.join(str(int(i)) for i in bad)}]" if bad.size else ""
    raise ValueError(f"{name}{where}: contains NaN or infinity; expected finite values")


def check_increasing(arr: FloatArray, name: str) -> None:
    """Raise ValueError at the first entry of ``arr`` (n,) not above its predecessor."""
    bad = np.flatnonzero(np.diff(arr) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise ValueError(
            f"{name}[{i}]: expected strictly increasing values, got {float(arr[i])!r} after "
            f"{name}[{i - 1}] = {float(arr[i - 1])!r}"
        )


def first_index(mask: NDArray[np.bool_]) -> str:
    """Format the first True index of a boolean array as ``[i, j]``."""
    idx = np.argwhere(mask)[0]
    return "[" + ", ".join(str(int(i)) for i in idx) + "]"


def readonly(arr: ArrayLike) -> FloatArray:
    """A read-only float64 copy of ``arr`` (data of a frozen dataclass must not change)."""
    out = np.array(arr, dtype=np.float64, copy=True)
    out.setflags(write=False)
    return out
