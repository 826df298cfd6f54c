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

The sphere's geodesic is the paper's slerp (§2.7, Eq. 12, extended to every
real t); SE(3)'s is the shortest screw motion between two frames (§2.8).

References
----------
Wallner & Dyn, *Convergence and C^1 analysis of subdivision schemes on
manifolds by proximity*, CAGD 22, 2005.
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
    """Operations a subdivision scheme needs from the space it runs in.

    Arrays below are *encoded* elements, shape (N, k) with the batch axis
    first (k = n for R^n, 3 for S^2, 7 for SE(3)); tangent vectors have shape
    (N, t) (t = n, 3, 6).  Pairs ``a[i]``, ``b[i]`` are taken row by row.

    Attributes
    ----------
    name : str
        ``"euclidean"``, ``"sphere"`` or ``"se3"``.
    """

    name: str

    def encode(self, x: FloatArray) -> FloatArray:
        """Convert elements to the internal form the operations work on.

        Parameters
        ----------
        x : array-like, shape (N, ...)
            Elements as the user gives them: points (N, n), unit vectors
            (N, 3) or poses (N, 4, 4).

        Returns
        -------
        encoded : ndarray, shape (N, k)
            The internal form.

        Raises
        ------
        ValueError
            When an element is not in the space (a non-unit vector, a
            non-rigid pose).
        """
        ...

    def decode(self, x: FloatArray) -> FloatArray:
        """Convert encoded elements back to the user's form.

        Parameters
        ----------
        x : ndarray, shape (N, k)
            Encoded elements.

        Returns
        -------
        elements : ndarray, shape (N, ...)
            Points, unit vectors or poses, as :meth:`encode` takes them.
        """
        ...

    def geodesic(self, a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray:
        """Evaluate the geodesic from ``a`` to ``b`` at parameter ``t``.

        Parameters
        ----------
        a, b : ndarray, shape (N, k)
            Encoded end elements (``t = 0`` gives ``a``, ``t = 1`` gives ``b``).
        t : float or array-like, shape (N,)
            Parameter, one for all pairs or one per pair; any real value
            (outside [0, 1] the geodesic is extrapolated).

        Returns
        -------
        points : ndarray, shape (N, k)
            The encoded elements at ``t``.
        """
        ...

    def geodesic_many(
        self, a: FloatArray, b: FloatArray, ts: Sequence[float]
    ) -> list[FloatArray]:
        """Evaluate the geodesics of the same pairs at several parameters.

        Each pair's logarithm is computed once.

        Parameters
        ----------
        a, b : ndarray, shape (N, k)
            Encoded end elements.
        ts : sequence of float
            Parameters (any real values).

        Returns
        -------
        points : list of ndarray, each shape (N, k)
            ``[geodesic(a, b, t) for t in ts]``.
        """
        ...

    def log(self, base: FloatArray, x: FloatArray) -> FloatArray:
        """Map elements to tangent vectors at a base point (the inverse of :meth:`exp`).

        Parameters
        ----------
        base : ndarray, shape (N, k)
            Encoded base points.
        x : ndarray, shape (N, k)
            Encoded elements.

        Returns
        -------
        v : ndarray, shape (N, t)
            Tangent vectors at ``base`` with ``exp(base, v) = x``.
        """
        ...

    def exp(self, base: FloatArray, v: FloatArray) -> FloatArray:
        """Map tangent vectors at a base point to elements.

        Parameters
        ----------
        base : ndarray, shape (N, k)
            Encoded base points.
        v : ndarray, shape (N, t)
            Tangent vectors at ``base``.

        Returns
        -------
        x : ndarray, shape (N, k)
            Encoded elements, the end of the geodesic from ``base`` along ``v``.
        """
        ...

    def flip(self, x: FloatArray) -> FloatArray:
        """Reverse the orientation of elements (to close a sequence with a flip).

        Parameters
        ----------
        x : ndarray, shape (N, k)
            Encoded elements.

        Returns
        -------
        flipped : ndarray, shape (N, k)
            The elements' images under the orientation reversal: a line of
            opposite orientation, a negated unit vector, a DH frame turned by
            pi about x; points of R^n stay unless ``negate_on_flip``.
        """
        ...


def _per_item(t: ArrayLike, like: FloatArray) -> FloatArray:
    """Reshape a scalar or per-item parameter to broadcast over an element array."""
    t = np.asarray(t, dtype=np.float64)
    return t.reshape(t.shape + (1,) * (like.ndim - t.ndim)) if t.ndim else t


@dataclass(frozen=True)
class EuclideanSpace:
    """R^n with its straight lines as geodesics; elements (N, n).

    Used for points (a striction curve, [m]) and for Plücker rows in R^6 (the
    projection algorithm, paper §3.1).

    Attributes
    ----------
    negate_on_flip : bool, default False
        ``flip`` negates the elements (a Plücker row ``[l, m]`` reversed is
        ``[-l, -m]``); False leaves them unchanged (points).
    name : str
        ``"euclidean"``.
    """

    negate_on_flip: bool = False
    name: str = "euclidean"

    def encode(self, x: FloatArray) -> FloatArray:
        """Return the points (N, n) as float64; no check."""
        return np.asarray(x, dtype=np.float64)

    def decode(self, x: FloatArray) -> FloatArray:
        """Return the points (N, n) unchanged."""
        return x

    def geodesic(self, a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray:
        """Return ``a + t (b - a)`` (N, n), ``t`` scalar or per pair (N,)."""
        return a + _per_item(t, a) * (b - a)

    def geodesic_many(self, a: FloatArray, b: FloatArray, ts: Sequence[float]) -> list[FloatArray]:
        """Return ``[a + t (b - a) for t in ts]``, each (N, n)."""
        d = b - a
        return [a + t * d for t in ts]

    def log(self, base: FloatArray, x: FloatArray) -> FloatArray:
        """Return ``x - base`` (N, n)."""
        return x - base

    def exp(self, base: FloatArray, v: FloatArray) -> FloatArray:
        """Return ``base + v`` (N, n)."""
        return base + v

    def flip(self, x: FloatArray) -> FloatArray:
        """Return ``-x`` when ``negate_on_flip``, else ``x`` itself."""
        return -x if self.negate_on_flip else x


@dataclass(frozen=True)
class SphereSpace:
    """The unit sphere S^2; elements (N, 3) unit vectors, geodesics great circles.

    Used for the spherical image of the rulings (their unit directions) in the
    combined algorithm (paper §2.7, §3.2).  Antipodal pairs have no unique
    geodesic and raise ValueError.

    Attributes
    ----------
    name : str
        ``"sphere"``.
    """

    name: str = "sphere"

    def encode(self, x: FloatArray) -> FloatArray:
        """Return the unit vectors (N, 3), re-normalised after checking ``| |x| - 1 | <= 1e-9``."""
        return sphere.validate_unit(x, "unit vectors")

    def decode(self, x: FloatArray) -> FloatArray:
        """Return the unit vectors (N, 3) unchanged."""
        return x

    def geodesic(self, a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray:
        """Return the great-circle points (N, 3) at ``t``: slerp, Eq. 12, for any real t."""
        return sphere.geodesic(a, b, np.asarray(t, dtype=np.float64))

    def geodesic_many(self, a: FloatArray, b: FloatArray, ts: Sequence[float]) -> list[FloatArray]:
        """Return the great-circle points at each t of ``ts``, one angle per pair."""
        return sphere.geodesic_many(a, b, ts)

    def log(self, base: FloatArray, x: FloatArray) -> FloatArray:
        """Return tangent vectors (N, 3) at ``base`` towards ``x``, length the angle [rad]."""
        return sphere.log(base, x)

    def exp(self, base: FloatArray, v: FloatArray) -> FloatArray:
        """Return ``cos|v| base + sin|v| v/|v|`` (N, 3) for tangent vectors ``v`` [rad]."""
        return sphere.exp(base, v)

    def flip(self, x: FloatArray) -> FloatArray:
        """Return ``-x``: the direction of the reversed ruling."""
        return -x


@dataclass(frozen=True)
class SE3Space:
    """Rigid motions SE(3); elements (N, 4, 4) poses, geodesics screw motions.

    The geodesic from frame ``A`` to frame ``B`` is the shortest uniform
    Euclidean motion (helical motion, rotation or translation) taking one to
    the other (paper §2.8): ``A exp(t log(inv(A) B))``, rotation angle <= pi.
    Used for the DH frames of the rulings (§3.3); poses are in one common frame
    (translations [m]).

    Internal form: rows ``[qw, qx, qy, qz, px, py, pz]`` (N, 7), unit
    quaternion (scalar first, ``qw >= 0``) and translation [m].  ``flip`` turns
    a frame by pi about its x axis (``T @ Rx(pi)``), which reverses its z axis:
    the DH frame of the same ruling with opposite orientation.  log/exp are the
    left-invariant ones, ``log(inv(base) x)`` and ``base exp(v)``, with twists
    ``[omega, v]`` (N, 6) in the base frame ([rad], [m]).

    Attributes
    ----------
    name : str
        ``"se3"``.
    """

    name: str = "se3"

    def encode(self, x: FloatArray) -> FloatArray:
        """Return qt rows (N, 7) of poses (N, 4, 4), checked to be rigid motions (tol 1e-6)."""
        return se3.qt_from_matrix(se3.validate_poses(x, "poses"))

    def decode(self, x: FloatArray) -> FloatArray:
        """Return poses (N, 4, 4) of qt rows (N, 7), quaternions normalised."""
        return se3.matrix_from_qt(x)

    def geodesic(self, a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray:
        """Return the screw-motion frames (N, 7) at ``t`` (scalar or per pair (N,))."""
        return se3.qt_geodesic(a, b, t)

    def geodesic_many(self, a: FloatArray, b: FloatArray, ts: Sequence[float]) -> list[FloatArray]:
        """Return the screw-motion frames (N, 7) at each t of ``ts``, one screw per pair."""
        return se3.qt_geodesic_many(a, b, ts)

    def log(self, base: FloatArray, x: FloatArray) -> FloatArray:
        """Return twists ``log(inv(base) x)`` (N, 6), ``[omega, v]``, ``|omega| <= pi``."""
        return se3.qt_log_at(base, x)

    def exp(self, base: FloatArray, v: FloatArray) -> FloatArray:
        """Return frames ``base @ exp(v)`` (N, 7) for twists ``v`` (N, 6) in the base frame."""
        return se3.qt_exp_at(base, v)

    def flip(self, x: FloatArray) -> FloatArray:
        """Return the frames turned by pi about their own x axis, ``T @ Rx(pi)``."""
        return se3.qt_flip(x)
