"""Running a scheme for several steps on open, closed and flip-closed sequences.

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
  end condition).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..geometry.checks import FloatArray
from .schemes import Scheme
from .spaces import Space

__all__ = ["extend", "neville", "refine_sequence"]


def neville(space: Space, points: list[FloatArray], taus: FloatArray) -> FloatArray:
    """Geodesic Neville–Aitken interpolation through ``points[i]`` at parameter i.

    ``points`` are d+1 arrays (each a single element with a leading axis of 1);
    returns the interpolant at each parameter of ``taus`` (k,), shape (k, ...).
    Level j combines ``P_{i..i+j}(tau) = geodesic(P_{i..i+j-1}, P_{i+1..i+j}, (tau - i)/j)``;
    in R^n it is Lagrange interpolation, on a geodesic it stays on the geodesic.
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
    """The sequence with ``ghosts`` extra elements on each side (see module doc)."""
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
    """Apply ``steps`` steps of ``scheme`` to encoded elements ``x`` (N, ...).

    ``after_step`` (optional) maps each step's result (the projection
    algorithm projects onto the line manifold there).
    """
    for _ in range(steps):
        n = x.shape[0]
        E = extend(space, x, scheme.ghosts, closed, flip, scheme.phantom_degree)
        x = scheme.rule(space, E, n, closed)
        if after_step is not None:
            x = after_step(x)
    return x
