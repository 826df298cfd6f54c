"""Run a scheme for several steps on open, closed and flip-closed sequences.

Boundary rules (also in ``docs/subdivision.md``):

* **closed**: the sequence is periodic, ``p_{n+k} = p_k``.
* **closed with a flip** (Möbius band): ``p_{n+k} = flip(p_k)``, where ``flip``
  is the space's orientation reversal (a line with opposite orientation, its
  unit direction negated, its DH frame turned by pi about x).  The refined
  sequence is again closed with a flip.
* **open**: the first and last elements are kept.  Interpolatory schemes
  (four_point, six_point, ternary_four_point) see *phantom* elements beyond
  each end, extrapolated by geodesic Neville–Aitken interpolation of degree 3
  (5 for six_point) through the nearest end elements, so that near the ends
  they reproduce what they reproduce inside (cubics in R^n; any uniformly
  sampled geodesic — screw motion, great circle — exactly).  chaikin uses the
  clamped quadratic B-spline rule and bspline3 keeps its end points (natural
  end condition); linear needs no ghosts for open data.

The paper keeps the end elements of open curves (§2.6, after Eq. 10) and only
says that higher-order schemes need care at the ends; the phantoms are our
decision.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..geometry.checks import FloatArray
from .schemes import Scheme
from .spaces import Space

__all__ = ["extend", "neville", "refine_sequence"]


def neville(space: Space, points: list[FloatArray], taus: FloatArray) -> FloatArray:
    """Evaluate the geodesic Neville–Aitken interpolant through ``points[i]`` at i.

    Level j combines
    ``P_{i..i+j}(tau) = geodesic(P_{i..i+j-1}, P_{i+1..i+j}, (tau - i)/j)``;
    in R^n it is Lagrange interpolation of degree d, on a geodesic it stays on
    the geodesic (uniform samples of a screw motion or great circle are
    reproduced exactly).

    Parameters
    ----------
    space : Space
        The space the elements live in.
    points : list of ndarray, each shape (1, ...)
        The d + 1 encoded elements (a leading axis of 1 each), at parameters
        0, 1, ..., d.
    taus : ndarray, shape (k,)
        Parameters to evaluate at (any real value; negative ones extrapolate).

    Returns
    -------
    values : ndarray, shape (k, ...)
        The interpolant at each parameter, encoded like ``points``.
    """
    k = taus.shape[0]
    level = [np.repeat(p, k, axis=0) for p in points]
    for j in range(1, len(points)):
        level = [
            space.geodesic(level[i], level[i + 1], (taus - i) / j) for i in range(len(level) - 1)
        ]
    return level[0]


def extend(
    space: Space, x: FloatArray, ghosts: int, closed: bool, flip: bool, degree: int
) -> FloatArray:
    """Pad a sequence with ``ghosts`` extra elements on each side (see module doc).

    Parameters
    ----------
    space : Space
        The space of the elements (its ``flip`` and ``geodesic``).
    x : ndarray, shape (N, ...)
        Encoded elements.
    ghosts : int
        Number of extra elements on each side (:attr:`Scheme.ghosts`).
    closed : bool
        Periodic copies (True) or extrapolated phantoms (False).
    flip : bool
        For closed sequences, flip the copied elements (Möbius band).
    degree : int
        For open sequences, degree of the phantom extrapolation
        (:attr:`Scheme.phantom_degree`; at most N - 1 is used); 0 returns
        ``x`` unpadded.

    Returns
    -------
    extended : ndarray, shape (N + 2 ghosts, ...)
        ``x`` with its ghosts, or ``x`` itself when nothing is added.
    """
    if ghosts == 0 or (not closed and degree == 0):
        return x
    n = x.shape[0]
    if closed:
        idx_left = np.arange(n - ghosts, n) % n
        idx_right = np.arange(ghosts) % n
        left, right = x[idx_left], x[idx_right]
        if flip:
            left, right = space.flip(left), space.flip(right)
        return np.concatenate([left, x, right])
    d = min(degree, n - 1)
    taus = -np.arange(ghosts, 0, -1, dtype=np.float64)  # -g .. -1
    left = neville(space, [x[i : i + 1] for i in range(d + 1)], taus)
    # right ghosts p_n, p_{n+1}, ... sit at -1, -2, ... of the reversed sequence
    right = neville(space, [x[n - 1 - i : n - i] for i in range(d + 1)], taus[::-1])
    return np.concatenate([left, x, right])


def refine_sequence(
    space: Space,
    x: FloatArray,
    scheme: Scheme,
    steps: int,
    closed: bool,
    flip: bool = False,
    after_step: Callable[[FloatArray], FloatArray] | None = None,
) -> FloatArray:
    """Apply ``steps`` steps of ``scheme`` to encoded elements.

    Each step extends the sequence (:func:`extend`), applies the scheme's rule
    and then ``after_step``.

    Parameters
    ----------
    space : Space
        The space of the elements.
    x : ndarray, shape (N, ...)
        Encoded elements (:meth:`Space.encode`).
    scheme : Scheme
        The subdivision scheme.
    steps : int
        Number of refinement steps.
    closed : bool
        Whether the sequence is periodic.
    flip : bool, default False
        Close with an orientation flip (Möbius band); only with ``closed``.
    after_step : callable or None, default None
        Maps each step's result (N', ...) to an array of the same shape; the
        projection algorithm projects onto the line manifold there (Eq. 4).

    Returns
    -------
    refined : ndarray, shape (M, ...)
        Encoded refined elements (:meth:`Space.decode` gives the elements).
    """
    for _ in range(steps):
        n = x.shape[0]
        E = extend(space, x, scheme.ghosts, closed, flip, scheme.phantom_degree)
        x = scheme.rule(space, E, n, closed)
        if after_step is not None:
            x = after_step(x)
    return x
