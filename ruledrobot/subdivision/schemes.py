"""Curve subdivision schemes, each written once from two-point geodesic averages.

A scheme refines one step of a sequence given *extended* data ``E``: the
sequence with ``ghosts`` extra elements on each side (periodic copies for
closed sequences, extrapolated phantoms for open ones; see
:mod:`ruledrobot.subdivision.engine`).  ``p_i = E[ghosts + i]``.  All work is
vectorised over the whole sequence.

In R^n every rule below is exactly the linear scheme it is named after; on a
manifold each affine average is replaced by a geodesic one (Wallner & Dyn
2005), which keeps the linear scheme's approximation order and smoothness for
dense data, and reproduces every geodesic — in SE(3) every uniform screw
motion sampled at equal steps (helical surfaces).

===================  =====  ==============  ============  =====================
name                 arity  interpolatory   smoothness    approximation order
===================  =====  ==============  ============  =====================
linear               2      yes             C^0           2
chaikin              2      no              C^1           2
bspline3             2      no              C^2           2
four_point (w)       2      yes             C^1 (w<.154)  4 at w = 1/16
six_point            2      yes             C^2           6
ternary_four_point   3      yes             C^2 (mu)      3
===================  =====  ==============  ============  =====================

The paper uses four_point (its DLG scheme, §2.5 Eq. 9, rewritten as two-point
averages in §2.7) and chaikin (§2.6 Eq. 10); the others are our additions.

References
----------
Odehnal, *Subdivision algorithms for ruled surfaces*, 2008 (the paper).
Wallner & Dyn, *Convergence and C^1 analysis of subdivision schemes on
manifolds by proximity*, CAGD 22, 2005.
Dyn, Levin & Gregory, *A 4-point interpolatory subdivision scheme for curve
design*, CAGD 4, 1987.
Chaikin, *An algorithm for high speed curve generation*, CGIP 3, 1974.
Lane & Riesenfeld, *A theoretical development for the computer generation and
display of piecewise polynomial surfaces*, IEEE PAMI 2, 1980.
Deslauriers & Dubuc, *Symmetric iterative interpolation processes*,
Constructive Approximation 5, 1989.
Hassan, Ivrissimtzis, Dodgson & Sabin, *An interpolating 4-point C^2 ternary
stationary subdivision scheme*, CAGD 19, 2002.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..geometry.checks import FloatArray
from .spaces import Space

__all__ = ["SCHEME_NAMES", "Scheme", "get_scheme"]


def interleave(*parts: FloatArray) -> FloatArray:
    """Interleave k arrays along axis 0: a0 b0 c0 a1 b1 c1 ...

    Parameters
    ----------
    *parts : ndarray, shape (n_j, ...)
        The arrays, with equal trailing shapes; the first may be one longer
        than the others (the kept old element after the last new one).

    Returns
    -------
    out : ndarray, shape (sum n_j, ...)
        ``out[j::k] = parts[j]``.
    """
    k = len(parts)
    total = sum(len(p) for p in parts)
    out = np.empty((total, *parts[0].shape[1:]))
    for j, p in enumerate(parts):
        out[j::k] = p
    return out


@dataclass(frozen=True)
class Scheme:
    """A subdivision scheme: its rule, arity and what its boundary handling needs.

    Made by :func:`get_scheme`; immutable.

    Attributes
    ----------
    name : str
        One of :data:`SCHEME_NAMES`.
    arity : int
        Refinement factor: 2 (binary) or 3 (ternary).
    interpolatory : bool
        Whether the old elements are kept.
    ghosts : int
        Extended elements the rule needs on each side.
    phantom_degree : int
        For open sequences, the degree of the geodesic (Neville–Aitken)
        extrapolation that makes the ghosts; 0 when the scheme has its own end
        rule and needs no ghosts for open data.
    min_points : int
        Fewest elements the scheme accepts.
    rule : callable
        ``rule(space, E, n, closed) -> refined``: one step on extended data
        ``E`` (n + 2 ghosts, ...) of n encoded elements.
    params : tuple of (str, float)
        The scheme's parameters, e.g. ``(("w", 0.0625),)``.
    """

    name: str
    arity: int
    interpolatory: bool
    ghosts: int
    phantom_degree: int
    min_points: int
    rule: Callable[[Space, FloatArray, int, bool], FloatArray] = field(repr=False)
    params: tuple[tuple[str, float], ...] = ()

    def refined_length(self, n: int, closed: bool) -> int:
        """Count the elements after one step on ``n`` elements.

        Parameters
        ----------
        n : int
            Number of elements before the step.
        closed : bool
            Whether the sequence is periodic.

        Returns
        -------
        count : int
            ``arity n`` when closed; otherwise ``arity (n - 1) + 1``
            (chaikin: ``2 n - 2``).
        """
        if closed:
            return self.arity * n
        if self.name == "chaikin":
            return 2 * n - 2
        return self.arity * (n - 1) + 1


# --------------------------------------------------------------------------
# the rules
# --------------------------------------------------------------------------


def _chaikin(space: Space, E: FloatArray, n: int, closed: bool) -> FloatArray:
    """Corner cutting at 1/4 and 3/4 of every edge (paper Eq. 10).

    Open sequences: the clamped quadratic B-spline rule — the first and last
    elements stay, the first and last edges contribute their midpoints instead
    of their 1/4, 3/4 points (the paper's end rule; exact knot insertion).
    """
    if closed:
        a, b = E[1 : n + 1], E[2 : n + 2]
        q, r = space.geodesic_many(a, b, [0.25, 0.75])
        return interleave(q, r)
    q, m, r = space.geodesic_many(E[:-1], E[1:], [0.25, 0.5, 0.75])
    inner = interleave(q[1:-1], r[1:-1])
    return np.concatenate([E[:1], m[:1], inner, m[-1:], E[-1:]])


def _bspline3(space: Space, E: FloatArray, n: int, closed: bool) -> FloatArray:
    """Cubic Lane–Riesenfeld: edge points = midpoints m_i, vertex points
    ``(p_{i-1} + 6 p_i + p_{i+1})/8 = mid(p_i, mid(m_{i-1}, m_i))``.

    Open sequences keep their end elements (the natural end condition).
    """
    if closed:
        P = E[0 : n + 2]  # p_{-1} .. p_n
        M = space.geodesic_many(P[:-1], P[1:], [0.5])[0]  # M[k] = mid(p_{k-1}, p_k)
        mm = space.geodesic_many(M[:-1], M[1:], [0.5])[0]  # between m_{i-1}, m_i
        v = space.geodesic(P[1:-1], mm, 0.5)
        return interleave(v, M[1:])
    M = space.geodesic_many(E[:-1], E[1:], [0.5])[0]  # M[k] = mid(p_k, p_{k+1})
    mm = space.geodesic_many(M[:-1], M[1:], [0.5])[0]
    v = space.geodesic(E[1:-1], mm, 0.5)
    v = np.concatenate([E[:1], v, E[-1:]])
    return interleave(v, M)


def _make_four_point(w: float) -> Callable[[Space, FloatArray, int, bool], FloatArray]:
    def rule(space: Space, E: FloatArray, n: int, closed: bool) -> FloatArray:
        """Dyn–Levin–Gregory (paper Eq. 9):
        new = (1/2 + w)(p_i + p_{i+1}) - w (p_{i-1} + p_{i+2}),
        as the paper's three two-point steps (§2.7): ``mid(g(p_{i-1}, p_i, 1+2w),
        g(p_{i+1}, p_{i+2}, -2w))`` — one logarithm per pair, used twice."""
        s = n if closed else n - 1  # segments
        P = E[1 : 1 + s + 3]  # p_{-1} .. p_{s+1}; pair k = (p_{k-1}, p_k)
        g1, g2 = space.geodesic_many(P[:-1], P[1:], [1.0 + 2.0 * w, -2.0 * w])
        new = space.geodesic_many(g1[:s], g2[2 : s + 2], [0.5])[0]
        return interleave(E[2 : 2 + n], new)

    return rule


def _linear(space: Space, E: FloatArray, n: int, closed: bool) -> FloatArray:
    """Geodesic midpoints: ``new = mid(p_i, p_{i+1})`` (four_point at ``w = 0``).

    The refined sequence lies on the geodesic polygon of the data: corners stay
    corners.  For data that already is a densely sampled path with intended
    corners (a foam cutter's moves), where a smoothing scheme would round or
    overshoot them."""
    if closed:  # E = p_{-1} .. p_n (one periodic ghost each side)
        old, nxt = E[1 : n + 1], E[2 : n + 2]
    else:  # open data come without ghosts (phantom degree 0)
        old, nxt = E[: n - 1], E[1:n]
    new = space.geodesic_many(old, nxt, [0.5])[0]
    return interleave(E[1 : n + 1] if closed else E, new)


_DD6 = np.array([3.0, -25.0, 150.0, 150.0, -25.0, 3.0]) / 256.0


def _six_point(space: Space, E: FloatArray, n: int, closed: bool) -> FloatArray:
    """Deslauriers–Dubuc 6-point (weights (3, -25, 150, 150, -25, 3)/256) as a
    log–exp average at the geodesic midpoint b of the two middle points:
    ``exp_b(sum_j w_j log_b(p_{i-2+j}))`` — keeps approximation order 6 on
    manifolds (nested two-point averages fall to order 4)."""
    s = n if closed else n - 1
    P = E[1 : 1 + s + 5]  # p_{-2} .. p_{s+2}
    base = space.geodesic_many(P[2 : s + 2], P[3 : s + 3], [0.5])[0]
    acc = None
    for j, wj in enumerate(_DD6):
        term = wj * space.log(base, P[j : j + s])
        acc = term if acc is None else acc + term
    new = space.exp(base, acc)
    return interleave(E[3 : 3 + n], new)


def _make_ternary(mu: float) -> Callable[[Space, FloatArray, int, bool], FloatArray]:
    a0 = -1.0 / 18.0 - mu / 6.0
    a1 = 13.0 / 18.0 + mu / 2.0
    a2 = 7.0 / 18.0 - mu / 2.0
    a3 = -1.0 / 18.0 + mu / 6.0
    left, right = a0 + a1, a2 + a3
    ts = [a1 / left, a2 / right, a3 / right, a0 / left]

    def rule(space: Space, E: FloatArray, n: int, closed: bool) -> FloatArray:
        """Hassan–Ivrissimtzis–Dodgson–Sabin ternary 4-point:
        ``p_{3i+1} = a0 p_{i-1} + a1 p_i + a2 p_{i+1} + a3 p_{i+2}``, ``p_{3i+2}``
        mirrored, each as ``g(g(p_{i-1}, p_i, .), g(p_{i+1}, p_{i+2}, .), .)``."""
        s = n if closed else n - 1
        P = E[1 : 1 + s + 3]  # p_{-1} .. p_{s+1}; pair k = (p_{k-1}, p_k)
        g = space.geodesic_many(P[:-1], P[1:], ts)
        n1 = space.geodesic(g[0][:s], g[2][2 : s + 2], right)
        n2 = space.geodesic(g[1][:s], g[3][2 : s + 2], left)
        old = E[2 : 2 + n]
        if closed:
            return interleave(old, n1, n2)
        out = np.empty((3 * s + 1, *E.shape[1:]))
        out[0::3] = old
        out[1::3] = n1
        out[2::3] = n2
        return out

    return rule


SCHEME_NAMES = ("linear", "chaikin", "bspline3", "four_point", "six_point", "ternary_four_point")

_DLG_C1_LIMIT = (np.sqrt(5.0) - 1.0) / 8.0


def get_scheme(name: str, **params: float) -> Scheme:
    """Make the scheme called ``name`` with its parameters.

    Parameters
    ----------
    name : str
        One of :data:`SCHEME_NAMES`.
    **params : float
        ``four_point`` takes ``w`` (dimensionless, default 1/16, allowed
        ``0 <= w < (sqrt 5 - 1)/8``, the C^1 range; paper Eq. 9);
        ``ternary_four_point`` takes ``mu`` (default 1/11, allowed
        ``0 <= mu <= 1/9``; C^2 for ``1/15 < mu < 1/9``).  The others take none.

    Returns
    -------
    scheme : Scheme
        The scheme with its rule, ghosts and phantom degree.

    Raises
    ------
    ValueError
        For an unknown name or parameter (the message lists what is valid) or
        a parameter out of its range.
    """
    allowed = {"four_point": {"w"}, "ternary_four_point": {"mu"}}
    if name not in SCHEME_NAMES:
        raise ValueError(
            f"scheme: unknown scheme {name!r}; expected one of {', '.join(SCHEME_NAMES)}"
        )
    extra = set(params) - allowed.get(name, set())
    if extra:
        ok = ", ".join(sorted(allowed.get(name, set()))) or "none"
        raise ValueError(f"scheme {name!r}: unknown parameter(s) {sorted(extra)}; accepted: {ok}")
    if name == "linear":
        return Scheme(name, 2, True, 1, 0, 2, _linear)
    if name == "chaikin":
        return Scheme(name, 2, False, 1, 0, 3, _chaikin)
    if name == "bspline3":
        return Scheme(name, 2, False, 1, 0, 3, _bspline3)
    if name == "four_point":
        w = float(params.get("w", 1.0 / 16.0))
        if not (0.0 <= w < _DLG_C1_LIMIT):
            raise ValueError(
                f"scheme four_point: w = {w!r}; expected 0 <= w < {_DLG_C1_LIMIT:.6f} "
                "(the range where the limit curve is C^1)"
            )
        return Scheme(name, 2, True, 2, 3, 4, _make_four_point(w), (("w", w),))
    if name == "six_point":
        return Scheme(name, 2, True, 3, 5, 6, _six_point)
    mu = float(params.get("mu", 1.0 / 11.0))
    if not (0.0 <= mu <= 1.0 / 9.0):
        raise ValueError(f"scheme ternary_four_point: mu = {mu!r}; expected 0 <= mu <= 1/9")
    return Scheme(name, 3, True, 2, 3, 4, _make_ternary(mu), (("mu", mu),))
