"""Input checking shared by the geometry layer.

Every public function that takes user data funnels it through these helpers so
that bad input raises one kind of error (:class:`ValueError`) with a message
that names the argument, the offending index and what was expected.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


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


def check_finite(arr: FloatArray, name: str, tail: tuple[int, ...] = ()) -> None:
    """Raise ValueError naming the first batch index of ``arr`` holding NaN or inf."""
    finite = np.isfinite(arr)
    if finite.all():
        return
    item_ok = finite.reshape(*arr.shape[: arr.ndim - len(tail)], -1).all(axis=-1)
    bad = np.argwhere(~item_ok)[0]
    where = f"[{', '.join(str(int(i)) for i in bad)}]" if bad.size else ""
    raise ValueError(f"{name}{where}: contains NaN or infinity; expected finite values")


def first_index(mask: NDArray[np.bool_]) -> str:
    """Format the first True index of a boolean array as ``[i, j]``."""
    idx = np.argwhere(mask)[0]
    return "[" + ", ".join(str(int(i)) for i in idx) + "]"


def norm(v: FloatArray) -> FloatArray:
    """Euclidean norm over the last axis (no division, no warnings)."""
    return np.sqrt(np.einsum("...i,...i->...", v, v))


def cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross product over the last axis (..., 3), broadcasting; faster than ``np.cross``."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def dot(a: FloatArray, b: FloatArray) -> FloatArray:
    """Dot product over the last axis (..., 3) -> (...), broadcasting."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def dot3(a: tuple, b: tuple) -> FloatArray:
    """Dot product of vectors given as component tuples ``(x, y, z)`` of arrays."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross3(a: tuple, b: tuple) -> tuple:
    """Cross product of vectors given as component tuples ``(x, y, z)`` of arrays."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
