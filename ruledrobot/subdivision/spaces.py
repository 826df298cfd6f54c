"""The spaces subdivision runs in, each supplying the few operations schemes use.

Every scheme in :mod:`ruledrobot.subdivision.schemes` is written once against
this interface (Wallner–Dyn: rewrite affine averages as two-point geodesic
averages, or as a log–exp average at a base point):

* ``geodesic(a, b, t)`` — the point at parameter ``t`` (scalar or one per pair,
  any real value) of the geodesic from ``a`` to ``b``; in R^n ``a + t (b - a)``;
* ``geodesic_many(a, b, ts)`` — the same pairs at several parameters, computing
  each pair's logarithm once;
* ``log(base, x)`` / ``exp(base, v)`` — tangent vectors at a base point;
* ``flip(x)`` — the element's image under the orientation reversal used to
  close a sequence "with a flip" (Möbius band): a line's opposite orientation.

Elements are stored with the batch axis first in an internal form chosen by
the space (``encode``/``decode``): R^n and S^2 use the points themselves,
SE(3) uses unit quaternion + translation rows (n, 7).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import se3, sphere
from ..geometry.checks import FloatArray

__all__ = ["EuclideanSpace", "SE3Space", "Space", "SphereSpace"]


class Space(Protocol):
    """Operations a subdivision scheme needs from the space it runs in."""

    name: str

    def encode(self, x: FloatArray) -> FloatArray: ...
    def decode(self, x: FloatArray) -> FloatArray: ...
    def geodesic(self, a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray: ...
    def geodesic_many(
        self, a: FloatArray, b: FloatArray, ts: Sequence[float]
    ) -> list[FloatArray]: ...
    def log(self, base: FloatArray, x: FloatArray) -> FloatArray: ...
    def exp(self, base: FloatArray, v: FloatArray) -> FloatArray: ...
    def flip(self, x: FloatArray) -> FloatArray: ...


def _per_item(t: ArrayLike, like: FloatArray) -> FloatArray:
    """Reshape a scalar or per-item parameter to broadcast over an element array."""
    t = np.asarray(t, dtype=np.float64)
    return t.reshape(t.shape + (1,) * (like.ndim - t.ndim)) if t.ndim else t


@dataclass(frozen=True)
class EuclideanSpace:
    """R^n, elements (N, n).  ``flip`` negates when ``negate_on_flip`` (Plücker R^6)."""

    negate_on_flip: bool = False
    name: str = "euclidean"

    def encode(self, x: FloatArray) -> FloatArray:
        return np.asarray(x, dtype=np.float64)

    def decode(self, x: FloatArray) -> FloatArray:
        return x

    def geodesic(self, a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray:
        return a + _per_item(t, a) * (b - a)

    def geodesic_many(self, a: FloatArray, b: FloatArray, ts: Sequence[float]) -> list[FloatArray]:
        d = b - a
        return [a + t * d for t in ts]

    def log(self, base: FloatArray, x: FloatArray) -> FloatArray:
        return x - base

    def exp(self, base: FloatArray, v: FloatArray) -> FloatArray:
        return base + v

    def flip(self, x: FloatArray) -> FloatArray:
        return -x if self.negate_on_flip else x


@dataclass(frozen=True)
class SphereSpace:
    """The unit sphere S^2, elements (N, 3); geodesics are great circles, flip is ``-x``."""

    name: str = "sphere"

    def encode(self, x: FloatArray) -> FloatArray:
        return sphere.validate_unit(x, "unit vectors")

    def decode(self, x: FloatArray) -> FloatArray:
        return x

    def geodesic(self, a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray:
        return sphere.geodesic(a, b, np.asarray(t, dtype=np.float64))

    def geodesic_many(self, a: FloatArray, b: FloatArray, ts: Sequence[float]) -> list[FloatArray]:
        return sphere.geodesic_many(a, b, ts)

    def log(self, base: FloatArray, x: FloatArray) -> FloatArray:
        return sphere.log(base, x)

    def exp(self, base: FloatArray, v: FloatArray) -> FloatArray:
        return sphere.exp(base, v)

    def flip(self, x: FloatArray) -> FloatArray:
        return -x


@dataclass(frozen=True)
class SE3Space:
    """Rigid motions SE(3), elements (N, 4, 4); geodesics are screw motions.

    Internal form: rows ``[qw, qx, qy, qz, px, py, pz]``.  ``flip`` turns a frame
    by pi about its x axis (``T @ Rx(pi)``), which reverses its z axis: the DH
    frame of the same ruling with opposite orientation.  log/exp are the
    left-invariant ones, ``log(inv(base) x)`` and ``base exp(v)``.
    """

    name: str = "se3"

    def encode(self, x: FloatArray) -> FloatArray:
        return se3.qt_from_matrix(se3.validate_poses(x, "poses"))

    def decode(self, x: FloatArray) -> FloatArray:
        return se3.matrix_from_qt(x)

    def geodesic(self, a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray:
        return se3.qt_geodesic(a, b, t)

    def geodesic_many(self, a: FloatArray, b: FloatArray, ts: Sequence[float]) -> list[FloatArray]:
        return se3.qt_geodesic_many(a, b, ts)

    def log(self, base: FloatArray, x: FloatArray) -> FloatArray:
        return se3.qt_log_at(base, x)

    def exp(self, base: FloatArray, v: FloatArray) -> FloatArray:
        return se3.qt_exp_at(base, v)

    def flip(self, x: FloatArray) -> FloatArray:
        return se3.qt_flip(x)
