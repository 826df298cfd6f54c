"""The discretised path problem: the chordal parameter, the grid, the constraint rows."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .tolerances import _MERGE_TOL, _SD_CAP_FACTOR, FEED_SMOOTH, FEED_SPLIT, MIN_STAGES, FloatArray

# --------------------------------------------------------------------------- problem


@dataclass
class _Problem:
    """A path prepared for timing, in the internal (chordal) parameter σ."""

    s: FloatArray  # (N,) caller's parameter
    q: FloatArray  # (N, J) caller's samples
    sf: FloatArray  # (N,) speed factor per unit s
    s_w: FloatArray  # (n,) caller's parameter of the kept samples
    sigma: FloatArray  # (n,) σ of the kept samples
    q_w: FloatArray  # (n, J) kept samples
    feed_speed: float
    spline: Any  # scipy CubicSpline q(σ)
    s_map: Any  # scipy PchipInterpolator s(σ): monotone, C¹ (:func:`_feed_per_sigma`)
    grid: FloatArray = field(default_factory=lambda: np.zeros(0))  # (G,) solver grid in σ
    d1: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))  # (G, J) q'(σ)
    d2: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))  # (G, J) q''(σ)
    x_feed: FloatArray = field(default_factory=lambda: np.zeros(0))  # (G,) (feed/sf_σ)²
    feed_scale: float = 1.0  # < 1 after a verification round found the feed too high

    @property
    def deltas(self) -> FloatArray:
        return np.diff(self.grid)

    def s_at(self, sigma: ArrayLike) -> FloatArray:
        """Caller's parameter at σ: the monotone C¹ interpolation of the kept samples."""
        sig = np.clip(np.asarray(sigma, dtype=np.float64), self.sigma[0], self.sigma[-1])
        return np.clip(self.s_map(sig), self.s_w[0], self.s_w[-1])

    def set_grid(self, grid: FloatArray) -> None:
        """Use ``grid`` (G,) as the solver grid: path derivatives and feed bound there.

        The feed bound of a node is the largest wire speed per unit σ over the stages the
        node touches (:func:`_feed_per_sigma`), so that it holds between nodes too (x is
        linear between nodes).
        """
        hi, _ = _feed_per_sigma(self, grid)
        node = np.maximum(np.r_[hi[:1], hi], np.r_[hi, hi[-1:]])
        self.x_feed = np.full(node.shape, np.inf)
        pos = node > 0
        self.x_feed[pos] = (self.feed_scale * self.feed_speed / node[pos]) ** 2
        self.grid = grid
        self.d1 = self.spline(grid, 1)
        self.d2 = self.spline(grid, 2)

    def refine(self, lo: FloatArray, hi: FloatArray, parts: int = 4) -> None:
        """Split every stage that overlaps some ``[lo_k, hi_k]`` (and its neighbours)."""
        grid = self.grid
        G = grid.shape[0]
        first = np.clip(np.searchsorted(grid, lo, side="right") - 2, 0, G - 2)
        last = np.clip(np.searchsorted(grid, hi, side="left"), 0, G - 2)
        mark = np.zeros(G, dtype=np.int64)
        np.add.at(mark, first, 1)
        np.add.at(mark, last + 1, -1)
        stages = np.flatnonzero(np.cumsum(mark)[: G - 1] > 0)
        frac = np.arange(1, parts) / parts
        D = np.diff(grid)[stages]
        extra = (grid[stages, None] + D[:, None] * frac).ravel()
        self.set_grid(np.unique(np.concatenate([grid, extra])))


def _quadratic_range(
    coef: FloatArray, xa: FloatArray, xb: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Largest and smallest value (K,) of ``c0 x² + c1 x + c2`` (coef (3, K)) on
    ``[xa, xb]`` (K,): the ends and, where it lies between them, the vertex."""
    c0, c1, c2 = coef
    fa = (c0 * xa + c1) * xa + c2
    fb = (c0 * xb + c1) * xb + c2
    with np.errstate(divide="ignore", invalid="ignore"):
        xv = np.where(c0 != 0.0, -c1 / (2.0 * c0), xa)
    inner = (xv > xa) & (xv < xb)
    fv = (c0 * xv + c1) * xv + c2
    hi = np.maximum(fa, fb)
    lo = np.minimum(fa, fb)
    hi = np.where(inner & (c0 < 0.0), np.maximum(hi, fv), hi)
    lo = np.where(inner & (c0 > 0.0), np.minimum(lo, fv), lo)
    return hi, lo


def _feed_per_sigma(prob: _Problem, grid: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Largest and smallest wire speed per unit σ (G−1,) [m/rad] over each stage of
    ``grid`` (G,): bounds of ``sf(s(σ))·s'(σ)`` from the bounds of both factors.

    ``s(σ)`` is the monotone C¹ (PCHIP) interpolation of the kept samples, so the wire's
    speed per unit σ is continuous along the path: where the joint path kinks (a loop's
    exit slit meeting the loop: its direction turns 6° at one ruling while the wire
    travels 23 % farther per joint distance after it) or the chord's end changes faces
    of the block, it changes over the stages around the node instead of jumping there.
    With the piecewise linear ``s(σ)`` of before, ``ds/dσ`` jumped at such nodes and the
    node's bound — the larger side's — held the wire below its feed by the jump (to
    10.7 of 12 mm/s at a loop's exit slit; 1-2 % every other ruling of a refined loop).
    ``sf`` is linear in ``s`` between the caller's samples (their model, kept: a speed
    factor that steps from 0 as the wire enters the stock stays a step): its range over
    a stage is its values at the stage's ends and at the caller's samples inside (merged
    repeats).  ``s'`` is a quadratic per kept interval: its range is exact
    (:func:`_quadratic_range`).
    """
    a, b = grid[:-1], grid[1:]
    n = prob.sigma.shape[0]
    k = np.clip(np.searchsorted(prob.sigma, a, side="right") - 1, 0, n - 2)
    coef = np.asarray(prob.s_map.derivative().c, dtype=np.float64)[:, k]
    x0 = prob.sigma[k]
    d_hi, d_lo = _quadratic_range(coef, a - x0, b - x0)
    d_hi, d_lo = np.maximum(d_hi, 0.0), np.maximum(d_lo, 0.0)
    s_a, s_b = prob.s_at(a), prob.s_at(b)
    f_a, f_b = np.interp(s_a, prob.s, prob.sf), np.interp(s_b, prob.s, prob.sf)
    f_hi, f_lo = np.maximum(f_a, f_b), np.minimum(f_a, f_b)
    # caller's samples strictly inside a stage (merged repeats, a sample between kept ones)
    i0 = np.searchsorted(prob.s, s_a, side="right")
    i1 = np.searchsorted(prob.s, s_b, side="left")
    has = np.flatnonzero(i1 > i0)
    if has.size:
        sf_ext = np.r_[prob.sf, 0.0]
        bounds = np.ravel(np.c_[i0[has], i1[has]])
        f_hi[has] = np.maximum(f_hi[has], np.maximum.reduceat(sf_ext, bounds)[::2])
        f_lo[has] = np.minimum(f_lo[has], np.minimum.reduceat(sf_ext, bounds)[::2])
    return f_hi * d_hi, f_lo * d_lo


def _smooth_grid(prob: _Problem, grid: FloatArray) -> FloatArray:
    """``grid`` with the stages split where the wire's speed per unit σ changes by more
    than ``FEED_SMOOTH`` within a stage (into at most ``FEED_SPLIT`` parts), so that the
    feed bounds of neighbouring nodes differ by about that much at most: the time law
    follows a bound that changes quickly but continuously instead of holding a whole
    stage to its largest value."""
    hi, lo = _feed_per_sigma(prob, grid)
    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.where(hi > 0, (hi - lo) / hi, 0.0)
    parts = np.minimum(np.ceil(var / FEED_SMOOTH), FEED_SPLIT).astype(np.int64)
    stages = np.flatnonzero(parts > 1)
    if not stages.size:
        return grid
    k = parts[stages]
    D = np.diff(grid)[stages]
    local = np.arange(int(k.sum())) - np.repeat(np.cumsum(k) - k, k)
    extra = np.repeat(grid[stages], k) + np.repeat(D / k, k) * local
    return np.unique(np.concatenate([grid, extra]))


def _prepare(s: FloatArray, q: FloatArray, sf: FloatArray, feed_speed: float) -> _Problem:
    """Chordal parameter, merged repeats, spline, solver grid and feed bound."""
    from scipy.interpolate import CubicSpline, PchipInterpolator

    N = s.shape[0]
    chord = np.linalg.norm(np.diff(q, axis=0), axis=1)
    keep = np.concatenate([[True], chord > _MERGE_TOL])
    if keep.sum() >= 2:
        if not keep[-1]:  # the end sample stays exact: it replaces the last kept one
            keep[int(np.flatnonzero(keep)[-1])] = False
            keep[-1] = True
        idx = np.flatnonzero(keep)
        sigma = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q[idx], axis=0), axis=1))])
    else:  # the robot does not move: σ proportional to s over [0, 1]
        idx = np.arange(N)
        sigma = (s - s[0]) / (s[-1] - s[0])
    n = idx.shape[0]
    s_w, q_w = s[idx], q[idx]
    # each gap split evenly into stages no longer than twice the mean gap and 1/MIN_STAGES
    # of the path: the law has constant σ̈ per stage, so one long gap (a sparse lead-in, a
    # jump of the IK branch) would otherwise be crossed without accelerating
    gaps = np.diff(sigma)
    h = sigma[-1] * min(1.0 / MIN_STAGES, 2.0 / (n - 1))
    k = np.maximum(1, np.ceil(gaps / h * (1.0 - 1e-9))).astype(np.int64)
    start = np.repeat(sigma[:-1], k)
    step = np.repeat(gaps / k, k)
    local = np.arange(int(k.sum())) - np.repeat(np.cumsum(k) - k, k)
    grid = np.concatenate([start + step * local, sigma[-1:]])
    prob = _Problem(
        s=s, q=q, sf=sf, s_w=s_w, sigma=sigma, q_w=q_w, feed_speed=feed_speed,
        spline=CubicSpline(sigma, q_w, bc_type="not-a-knot"),
        s_map=PchipInterpolator(sigma, s_w, extrapolate=False),
    )  # fmt: skip
    if np.any(sf > 0):
        grid = _smooth_grid(prob, grid)
    prob.set_grid(grid)
    return prob


def _x_upper(prob: _Problem, vlim: FloatArray) -> FloatArray:
    """(G,) upper bound of x = σ̇² from joint velocity, feed and the cap."""
    with np.errstate(divide="ignore"):
        x_vel = np.min((vlim / np.abs(prob.d1)) ** 2, axis=1)
    cap = (_SD_CAP_FACTOR * float(vlim.max())) ** 2
    return np.minimum(np.minimum(x_vel, prob.x_feed), cap)


def _stage_rows(prob: _Problem, alim: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Acceleration rows of every stage as σ̈ intervals ``[c·x − w, c·x + w]``.

    Stage i holds the rows of grid point i (``q'_i u + q''_i x_i``) and of grid point
    i+1 reached with constant u (``(q'_{i+1} + 2Δ q''_{i+1}) u + q''_{i+1} x_i``),
    each bounded by ±alim. Returns ``c``, ``w`` (G−1, 2J) and ``x_only`` (G−1,), the
    bound on x from rows whose u coefficient vanishes.
    """
    D = prob.deltas[:, None]
    alpha = np.concatenate([prob.d1[:-1], prob.d1[1:] + 2.0 * D * prob.d2[1:]], axis=1)
    beta = np.concatenate([prob.d2[:-1], prob.d2[1:]], axis=1)
    A = np.concatenate([alim, alim])[None, :]
    scale = np.abs(alpha).max() if alpha.size else 1.0
    zero = np.abs(alpha) <= 1e-13 * max(scale, 1e-300)
    safe = np.where(zero, 1.0, alpha)
    c = np.where(zero, 0.0, -beta / safe)
    w = np.where(zero, np.inf, A / np.abs(safe))
    with np.errstate(divide="ignore"):
        x_only = np.where(zero, A / np.abs(beta), np.inf).min(axis=1)
    return c, w, x_only


def _static_bound(c: FloatArray, w: FloatArray, deltas: FloatArray) -> FloatArray:
    """(G−1,) largest x at which the σ̈ interval of a stage is not empty and still
    allows x_{i+1} ≥ 0."""
    dc = c[:, :, None] - c[:, None, :]  # lower row r vs upper row r'
    ww = w[:, :, None] + w[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        pair = np.where(dc > 0, ww / dc, np.inf).min(axis=(1, 2))
        k = -1.0 / (2.0 * deltas)[:, None] - c
        stop = np.where(k > 0, w / k, np.inf).min(axis=1)
    return np.minimum(pair, stop)
