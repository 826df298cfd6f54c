"""The discretised path problem: the chordal parameter, the grid, the constraint rows."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .tolerances import _MERGE_TOL, _SD_CAP_FACTOR, MIN_STAGES, FloatArray

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
    gap_sf: FloatArray  # (n-1,) largest speed factor per unit σ over each kept gap
    feed_speed: float
    spline: Any  # scipy CubicSpline q(σ)
    grid: FloatArray = field(default_factory=lambda: np.zeros(0))  # (G,) solver grid in σ
    d1: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))  # (G, J) q'(σ)
    d2: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))  # (G, J) q''(σ)
    x_feed: FloatArray = field(default_factory=lambda: np.zeros(0))  # (G,) (feed/sf_σ)²
    feed_scale: float = 1.0  # < 1 after a verification round found the feed too high

    @property
    def deltas(self) -> FloatArray:
        return np.diff(self.grid)

    def s_at(self, sigma: ArrayLike) -> FloatArray:
        """Caller's parameter at σ (piecewise linear between kept samples)."""
        return np.interp(sigma, self.sigma, self.s_w)

    def set_grid(self, grid: FloatArray) -> None:
        """Use ``grid`` (G,) as the solver grid: path derivatives and feed bound there.

        The speed factor at a node is the largest over the gaps the node touches, so
        that the bound holds between nodes too (x and the speed factor are both
        piecewise linear there).
        """
        n = self.sigma.shape[0]
        g = np.clip(np.searchsorted(self.sigma, grid, side="right") - 1, 0, n - 2)
        node_sf = self.gap_sf[g]
        on = (grid == self.sigma[g]) & (g > 0)  # a node on an interior kept sample
        node_sf[on] = np.maximum(node_sf[on], self.gap_sf[g[on] - 1])
        with np.errstate(divide="ignore"):
            self.x_feed = np.where(
                node_sf > 0, (self.feed_scale * self.feed_speed / node_sf) ** 2, np.inf
            )
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


def _prepare(s: FloatArray, q: FloatArray, sf: FloatArray, feed_speed: float) -> _Problem:
    """Chordal parameter, merged repeats, spline, solver grid and feed bound."""
    from scipy.interpolate import CubicSpline

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
    # largest speed factor of the caller's samples spanned by each kept gap, per unit σ
    run_max = np.maximum.reduceat(sf, idx)  # max of sf[idx_i : idx_{i+1}]
    gap_sf = np.maximum(run_max[:-1], sf[idx[1:]]) * np.diff(s_w) / np.diff(sigma)
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
        s=s, q=q, sf=sf, s_w=s_w, sigma=sigma, q_w=q_w, gap_sf=gap_sf, feed_speed=feed_speed,
        spline=CubicSpline(sigma, q_w, bc_type="not-a-knot"),
    )  # fmt: skip
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
