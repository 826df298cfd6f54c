"""The time law of a hot-wire cut: time-optimal timing of a joint path under joint
velocity, joint acceleration and wire-feed limits, sampled at the controller rate.

The planner hands over a *geometric* path — joint positions ``q`` (N, J) at strictly
increasing parameter values ``s`` (N,) — and ``speed_factor`` (N,): metres moved by
the fastest wire point inside the stock per unit of ``s`` (0 where the wire is out of
the stock). Any parameter works (sample index, arc length, cumulative joint
distance); only ``speed_factor`` must be expressed per unit of that same ``s``.

Method of :func:`time_path` (details and measurements in ``docs/timing.md``):

1. **Internal parameter.** The spline and the solver use the chordal parameter σ,
   the cumulative joint distance ``Σ|Δq|`` of the samples (samples closer than
   ``_MERGE_TOL`` rad to their predecessor merged). ``|dq/dσ| ≈ 1`` everywhere, so
   ``x = σ̇²`` is of the order of a joint speed squared whatever unit and spacing
   the caller's ``s`` has; ``s`` maps to σ piecewise linearly. (With a spline in the
   caller's ``s``, repeated samples gave ``dq/ds ≈ 0``, path speeds at the cap and
   2.8× the acceleration limit between grid points.)
2. **Path.** A not-a-knot cubic spline q(σ) through the samples
   (``toppra.SplineInterpolator``; scipy ``CubicSpline`` for our own evaluation —
   the same spline). The solver grid is the samples, each gap split evenly into
   stages no longer than twice the mean gap and ``1/MIN_STAGES`` of the path.
3. **Constraints** on ``x = σ̇²`` and ``u = σ̈`` at the grid points:

   - joint velocity ``|q'_j| σ̇ ≤ safety·v_j`` and the feed
     ``sf_σ σ̇ ≤ feed_speed`` are both *path-velocity* bounds, folded into one upper
     bound ``x ≤ x_hi`` handed to toppra as the ``xbound`` of a canonical linear
     constraint (the mechanism ``JointVelocityConstraint`` itself uses), where
     ``sf_σ = speed_factor·ds/dσ``. The speed factor at a grid point is the largest
     sample value of the gaps it touches, so the bound also holds between grid
     points (x and the speed factor are both piecewise linear there);
   - joint acceleration ``|q'_j u + q''_j x| ≤ safety·a_j``: toppra's
     ``JointAccelerationConstraint`` with *interpolation* discretisation (the
     constraint of stage i is imposed at both ends of the stage; collocation alone
     overshot the limits by 5–8 % on the sampled output).
4. **Solve.** toppra (seidel LP) computes the controllable sets K_i (backward pass).
   The forward pass is done here in closed form with the same constraint rows: the
   largest σ̈ that keeps ``x_{i+1}`` in ``K_{i+1}``, so the accelerations of the
   sampled law are exactly those that were checked.
   **Fallback** when toppra fails (exception, NaN or empty controllable set —
   toppra issues #14, #17, #226 — or a profile that stalls): the same reachability
   recursion done here in closed form (per stage a 1-D problem: the acceleration
   rows give a σ̈ interval whose ends are affine in x); ``method`` says which ran.
5. **Time law and sampling.** Constant σ̈ on every stage, duration rounded *up* to a
   whole number of controller periods by uniform time scaling (slower by less than
   one period over the whole path), samples at ``t = k·dt``, the last one exactly at
   the end, endpoints copied from the input.
6. **Verification.** Joint speed, joint acceleration and feed are measured by finite
   differences of the *sampled* output (:func:`trajectory_limits_report`; the feed
   as the difference of the wire distance ``∫ speed_factor ds`` over each period).
   Where a true limit is broken — between grid points, where the constraints are
   not imposed — the stages around those samples are split in four and the path is
   solved again (``REFINE_ROUNDS`` times), then the limits are tightened everywhere,
   and after ``MAX_TRIES`` rounds :class:`ValueError` is raised.

``safety`` scales the joint limits only. The feed bound is not scaled: a constant
feed equal to ``feed_speed`` is the goal of the cut.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..robot.rates import finite_difference_rates

__all__ = [
    "CONTINUITY_TOL",
    "FEED_HOLD_TOL",
    "FEED_TOL",
    "MAX_SAMPLES",
    "RATIO_TOL",
    "TimedPath",
    "concatenate",
    "joint_move",
    "time_path",
    "trajectory_limits_report",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]

#: Ratios (sampled value / limit) up to ``1 + RATIO_TOL`` count as within the limit:
#: finite differences of positions of size ~1 rad divided by dt² = 4e-6 s² carry a
#: rounding error of ~1e-16/4e-6 ≈ 3e-11 rad/s²; 1e-9 covers it with margin.
RATIO_TOL = 1e-9
#: Allowed relative excess of the sampled feed over ``feed_speed`` (round-off of the
#: controllable sets; the bound itself holds between grid points, see step 3).
FEED_TOL = 1e-6
#: A sample inside the stock whose feed is below ``(1 - FEED_HOLD_TOL)·feed_speed``
#: is reported as feed-limited (the joints, not the feed bound, set the speed there).
FEED_HOLD_TOL = 0.01
#: Largest position mismatch (rad) between the end of a part and the start of the
#: next in :func:`concatenate`.
CONTINUITY_TOL = 1e-9
#: Most samples a timed path may have (1 h 6 min at 500 Hz; ~300 MB of q, qd, qdd).
MAX_SAMPLES = 2_000_000
#: Fewest solver stages; sparse inputs have their gaps split evenly up to this.
MIN_STAGES = 200
#: Verification rounds of :func:`time_path`: the first ``REFINE_ROUNDS`` split the
#: solver stages around the samples that break a limit, the later ones tighten the
#: limits everywhere.
MAX_TRIES = 6
REFINE_ROUNDS = 3
#: Consecutive samples closer than this (rad, Euclidean over the joints) are merged.
_MERGE_TOL = 1e-10
#: Cap on σ̇ (σ in rad of joint distance) as a multiple of the fastest joint limit:
#: bounds the speed on stretches where neither the joints nor the wire move.
_SD_CAP_FACTOR = 1e3


# --------------------------------------------------------------------------- result


@dataclass(frozen=True, eq=False)
class TimedPath:
    """A joint trajectory sampled every controller period.

    Arrays are read-only. ``M`` samples, ``J`` joints.

    Attributes:
        t: (M,) time from the start [s], ``t[k] = k·dt``; the last sample is the end.
        q: (M, J) joint positions [rad].
        qd: (M, J) joint velocities [rad/s] of the time law (analytic, not differenced).
        qdd: (M, J) joint accelerations [rad/s²] of the time law.
        s_of_t: (M,) path parameter at each sample, in the caller's units of ``s``
            (:func:`joint_move`: the fraction of the move, 0…1; :func:`concatenate`:
            each part's parameter offset so that the whole is continuous).
        feed: (M,) wire feed [m/s]: central differences of the wire distance
            ``∫ speed_factor ds`` at the sampled ``s_of_t`` (0 out of the stock).
        feed_limited: (M,) True inside the stock where ``feed`` is below
            ``(1 − FEED_HOLD_TOL)·feed_speed``: joint speed/acceleration (including
            the start and stop ramps) and not the feed bound set the pace there.
            "Inside" = the sample and its two neighbours lie in gaps of the caller's
            samples whose both ends have a speed factor > 0 (so the partial gaps at
            stock entry and exit, where the speed factor is interpolated, are not
            reported).
        segment: (M,) index of the part a sample comes from (0 unless concatenated).
        dt: controller period [s].
        vel_limits: (J,) joint velocity limits [rad/s] the ratios refer to.
        acc_limits: (J,) joint acceleration limits [rad/s²] the ratios refer to.
        feed_speed: feed bound [m/s], or None for a motion without a cut.
        max_speed_ratio: max over samples and joints of |Δq/Δt| / vel_limits.
        max_acc_ratio: max of |second difference / Δt²| / acc_limits.
        max_feed_ratio: max over sample intervals of the wire distance travelled in
            the interval / (interval · feed_speed) (0 when there is no feed).
        method: how the time law was computed (``"toppra"``, ``"reachability"``
            fallback with the reason, ``"joint_move"``, ``"concatenate"``).
    """

    t: FloatArray = field(repr=False)
    q: FloatArray = field(repr=False)
    qd: FloatArray = field(repr=False)
    qdd: FloatArray = field(repr=False)
    s_of_t: FloatArray = field(repr=False)
    feed: FloatArray = field(repr=False)
    feed_limited: BoolArray = field(repr=False)
    segment: IntArray = field(repr=False)
    dt: float
    vel_limits: FloatArray = field(repr=False)
    acc_limits: FloatArray = field(repr=False)
    feed_speed: float | None
    max_speed_ratio: float
    max_acc_ratio: float
    max_feed_ratio: float
    method: str

    def __post_init__(self) -> None:
        for name in ("t", "q", "qd", "qdd", "s_of_t", "feed", "feed_limited", "segment",
                     "vel_limits", "acc_limits"):  # fmt: skip
            arr = getattr(self, name)
            if isinstance(arr, np.ndarray):
                arr.flags.writeable = False

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self.t[-1])

    @property
    def n_samples(self) -> int:
        """Number of samples M."""
        return int(self.t.shape[0])

    @property
    def within_limits(self) -> bool:
        """Whether the sampled joint speeds and accelerations are within the limits."""
        return self.max_speed_ratio <= 1.0 + RATIO_TOL and self.max_acc_ratio <= 1.0 + RATIO_TOL

    @property
    def feed_limited_intervals(self) -> FloatArray:
        """(K, 2) ``[t_start, t_end]`` [s] of the runs of feed-limited samples."""
        return _runs(self.feed_limited, self.t)

    def feed_limited_s_intervals(self) -> FloatArray:
        """(K, 2) ``[s_start, s_end]`` of the runs of feed-limited samples."""
        return _runs(self.feed_limited, self.s_of_t)


def _runs(mask: BoolArray, values: FloatArray) -> FloatArray:
    if not mask.any():
        return np.zeros((0, 2))
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    start = np.flatnonzero(d == 1)
    stop = np.flatnonzero(d == -1) - 1
    return np.stack([values[start], values[stop]], axis=1)


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


# --------------------------------------------------------------------------- report


def trajectory_limits_report(
    t: ArrayLike, q: ArrayLike, vel_limits: ArrayLike, acc_limits: ArrayLike
) -> dict[str, Any]:
    """Joint speed and acceleration of a sampled trajectory by finite differences.

    Independent of how the trajectory was made: velocity ``v_k = (q_{k+1} − q_k) /
    (t_{k+1} − t_k)`` per interval, acceleration ``(v_k − v_{k−1}) / ((t_{k+1} −
    t_{k−1})/2)`` per interior sample (the usual second difference when the
    sampling is uniform).

    Args:
        t: (M,) strictly increasing sample times [s].
        q: (M, J) joint positions [rad].
        vel_limits: (J,) joint velocity limits [rad/s], > 0.
        acc_limits: (J,) joint acceleration limits [rad/s²], > 0.

    Returns:
        dict with ``max_speed_ratio``, ``max_acc_ratio`` (floats), ``speed_ratio``,
        ``acc_ratio`` (J,) per joint, ``max_speed`` [rad/s], ``max_acc`` [rad/s²]
        (J,), ``worst_speed`` and ``worst_acc`` (sample index, joint) of the largest
        ratio (None when there is nothing to difference), ``ok`` (both ratios
        ``<= 1 + RATIO_TOL``), ``n_samples``, ``duration`` [s], ``dt_min``, ``dt_max``.

    Raises:
        ValueError: bad shapes, non-finite values, non-increasing ``t``, limits <= 0.
    """
    t = _array(t, "t", (None,))
    q = _array(q, "q", (t.shape[0], None))
    J = q.shape[1]
    vlim = _limits(vel_limits, "vel_limits", J)
    alim = _limits(acc_limits, "acc_limits", J)
    _increasing(t, "t")
    M = t.shape[0]
    out: dict[str, Any] = {
        "n_samples": M,
        "duration": float(t[-1] - t[0]) if M else 0.0,
        "dt_min": float(np.diff(t).min()) if M > 1 else 0.0,
        "dt_max": float(np.diff(t).max()) if M > 1 else 0.0,
        "speed_ratio": np.zeros(J),
        "acc_ratio": np.zeros(J),
        "max_speed": np.zeros(J),
        "max_acc": np.zeros(J),
        "max_speed_ratio": 0.0,
        "max_acc_ratio": 0.0,
        "worst_speed": None,
        "worst_acc": None,
    }
    if M >= 2:
        v, a = finite_difference_rates(t, q)
        r = np.abs(v) / vlim
        k, j = np.unravel_index(int(np.argmax(r)), r.shape)
        out.update(
            speed_ratio=r.max(axis=0), max_speed=np.abs(v).max(axis=0),
            max_speed_ratio=float(r[k, j]), worst_speed=(int(k), int(j)),
        )  # fmt: skip
        if M >= 3:
            r = np.abs(a) / alim
            k, j = np.unravel_index(int(np.argmax(r)), r.shape)
            out.update(
                acc_ratio=r.max(axis=0), max_acc=np.abs(a).max(axis=0),
                max_acc_ratio=float(r[k, j]), worst_acc=(int(k) + 1, int(j)),
            )  # fmt: skip
    out["ok"] = bool(
        out["max_speed_ratio"] <= 1.0 + RATIO_TOL and out["max_acc_ratio"] <= 1.0 + RATIO_TOL
    )
    return out


def _wire_distance(s: FloatArray, sf: FloatArray, at: FloatArray) -> FloatArray:
    """∫ speed_factor ds from s[0] to ``at`` [m], the speed factor linear between samples."""
    h = np.diff(s)
    F = np.concatenate([[0.0], np.cumsum(0.5 * (sf[1:] + sf[:-1]) * h)])
    i = np.clip(np.searchsorted(s, at, side="right") - 1, 0, s.shape[0] - 2)
    r = at - s[i]
    slope = (sf[i + 1] - sf[i]) / h[i]
    return F[i] + r * (sf[i] + 0.5 * slope * r)


def _feed_of_samples(
    t: FloatArray, s_t: FloatArray, s: FloatArray, sf: FloatArray, feed_speed: float
) -> tuple[FloatArray, FloatArray]:
    """Sampled feed (M,) [m/s] by central differences and the feed ratio of every sample
    interval (M−1,) by forward differences, both of the wire distance
    ``W(s) = ∫ speed_factor ds`` at the sampled ``s_t`` (metres moved by the fastest
    wire point in the stock, so that a period that straddles a jump of the speed factor
    is measured by what the wire travelled, not by the speed factor at one point)."""
    M = t.shape[0]
    if M < 2 or not np.any(sf > 0):
        return np.zeros(M), np.zeros(max(M - 1, 0))
    W = _wire_distance(s, sf, s_t)
    ratio = np.diff(W) / np.diff(t) / feed_speed
    feed = np.empty(M)
    feed[1:-1] = (W[2:] - W[:-2]) / (t[2:] - t[:-2])
    feed[0] = ratio[0] * feed_speed
    feed[-1] = ratio[-1] * feed_speed
    return feed, ratio


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


class _SolverError(RuntimeError):
    """Internal: a solver could not produce a usable profile."""


class _StalledError(RuntimeError):
    """Internal: the path speed is zero at both ends of a stage (infinite duration)."""

    def __init__(self, stage: int) -> None:
        super().__init__(f"path speed is zero on the whole stage {stage}")
        self.stage = stage


def _backward(
    c: FloatArray, w: FloatArray, deltas: FloatArray, x_stage: FloatArray, x_end: float
) -> FloatArray:
    """Upper ends of the controllable sets K_i = [0, hi_i] (G,), in closed form.

    hi_i is the largest x ≤ x_stage_i from which some σ̈ in the stage's interval lands
    in [0, hi_{i+1}]: ``c_r x − w_r ≤ (hi_{i+1} − x)/(2Δ)`` for every row r.
    """
    G = deltas.shape[0] + 1
    inv2d = (1.0 / (2.0 * deltas))[:, None]
    k = c + inv2d
    pos = k > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        ka = np.where(pos, inv2d / k, 0.0)
        kb = np.where(pos, w / k, np.inf)
    hi = np.empty(G)
    hi[-1] = x_end
    for i in range(G - 2, -1, -1):
        hi[i] = min(x_stage[i], float(np.min(ka[i] * hi[i + 1] + kb[i])))
    return hi


def _forward(
    c: FloatArray, w: FloatArray, deltas: FloatArray, hi: FloatArray, x0: float
) -> FloatArray:
    """Greedy forward pass: the largest σ̈ keeping x_{i+1} ≤ hi_{i+1}. Returns x (G,)."""
    G = hi.shape[0]
    x = np.empty(G)
    x[0] = x0
    cl = c.tolist()
    wl = w.tolist()
    two_d = (2.0 * deltas).tolist()
    hil = hi.tolist()
    xi = x0
    for i in range(G - 1):
        ci, wi = cl[i], wl[i]
        umax = min(a * xi + b for a, b in zip(ci, wi, strict=True))
        umin = max(a * xi - b for a, b in zip(ci, wi, strict=True))
        nxt = min(hil[i + 1], xi + two_d[i] * umax)
        floor = xi + two_d[i] * umin
        if nxt < floor:  # K_{i+1} slightly optimistic (LP round-off): brake at the limit
            nxt = floor
        xi = max(nxt, 0.0)
        x[i + 1] = xi
    return x


@lru_cache(maxsize=1)
def _toppra_xbound_class() -> type:
    from toppra.constraint import LinearConstraint

    class XBoundConstraint(LinearConstraint):  # type: ignore[misc]
        """Path-velocity bound ``0 <= x <= x_hi(s_i)`` at the grid points."""

        def __init__(self, x_hi: FloatArray, dof: int) -> None:
            super().__init__()
            self.xbound = np.stack([np.zeros_like(x_hi), x_hi], axis=1)
            self.dof = dof
            self._format_string = "    path-velocity bound (joint velocity and feed)\n"

        def compute_constraint_params(self, path: Any, gridpoints: Any) -> tuple:
            return None, None, None, None, None, None, self.xbound

    return XBoundConstraint


def _toppra_controllable(
    prob: _Problem, x_hi: FloatArray, alim: FloatArray, x_end: float
) -> FloatArray:
    """Upper ends of toppra's controllable sets (G,); raises _SolverError on failure."""
    try:
        import toppra
        from toppra.algorithm import TOPPRA
        from toppra.constraint import DiscretizationType, JointAccelerationConstraint

        path = toppra.SplineInterpolator(prob.sigma, prob.q_w)
        vel = _toppra_xbound_class()(x_hi, prob.q.shape[1])
        acc = JointAccelerationConstraint(
            alim, discretization_scheme=DiscretizationType.Interpolation
        )
        inst = TOPPRA([vel, acc], path, gridpoints=prob.grid, solver_wrapper="seidel")
        K = inst.compute_controllable_sets(0.0, math.sqrt(x_end))
    except Exception as exc:  # toppra raises assorted errors on bad conditioning
        raise _SolverError(f"toppra raised {type(exc).__name__}: {exc}") from exc
    K = np.asarray(K, dtype=np.float64)
    bad = ~np.isfinite(K).all(axis=1) | (K[:, 1] < -1e-9) | (K[:, 1] < K[:, 0] - 1e-9)
    if bad.any():
        i = int(np.flatnonzero(bad)[-1])
        raise _SolverError(f"toppra: controllable set {i} of {K.shape[0]} is empty or NaN")
    return np.maximum(K[:, 1], 0.0)


def _binding(prob: _Problem, i: int, vlim: FloatArray, alim: FloatArray) -> str:
    """Name the tightest bound on the path speed at grid point i (for error messages)."""
    cands: list[tuple[float, str]] = []
    with np.errstate(divide="ignore"):
        xv = (vlim / np.abs(prob.d1[i])) ** 2
    j = int(np.argmin(xv))
    cands.append((float(xv[j]), f"joint {j + 1} velocity"))
    cands.append((float(prob.x_feed[i]), "feed"))
    st = min(i, prob.grid.shape[0] - 2)
    c, w, x_only = _stage_rows(prob, alim)
    xa = min(float(_static_bound(c[st : st + 1], w[st : st + 1], prob.deltas[st : st + 1])[0]),
             float(x_only[st]))  # fmt: skip
    cands.append((xa, "joint acceleration"))
    x, name = min(cands)
    g = int(np.clip(np.searchsorted(prob.sigma, prob.grid[i], side="right") - 1, 0,
                    prob.sigma.shape[0] - 2))  # fmt: skip
    ds_dsigma = (prob.s_w[g + 1] - prob.s_w[g]) / (prob.sigma[g + 1] - prob.sigma[g])
    return f"{name} (ds/dt <= {math.sqrt(x) * ds_dsigma:.3g} there)"


def _solve(
    prob: _Problem,
    vlim: FloatArray,
    alim: FloatArray,
    start_at_rest: bool,
    end_at_rest: bool,
    use_toppra: bool = True,
) -> tuple[FloatArray, str]:
    """x = σ̇² at the grid (G,) and the method used."""
    x_hi = _x_upper(prob, vlim)
    c, w, x_only = _stage_rows(prob, alim)
    x_end = 0.0 if end_at_rest else float(x_hi[-1])
    method = "toppra"
    hi = None
    if use_toppra:
        try:
            hi = _toppra_controllable(prob, x_hi, alim, x_end)
        except _SolverError as exc:
            method = f"reachability (fallback: {exc})"
    else:
        method = "reachability"
    if hi is None:
        x_stage = np.minimum(np.minimum(x_hi[:-1], x_only), _static_bound(c, w, prob.deltas))
        hi = _backward(c, w, prob.deltas, x_stage, x_end)
    x0 = 0.0 if start_at_rest else float(hi[0])
    x = _forward(c, w, prob.deltas, hi, x0)
    if end_at_rest:  # the forward pass may end a round-off above 0 (LP tolerance of K)
        x[-1] = 0.0
    if not np.isfinite(x).all():
        i = int(np.flatnonzero(~np.isfinite(x))[0])
        raise ValueError(
            f"time_path: no finite path speed at s = {prob.s_at(prob.grid[i]):.6g}; "
            f"binding constraint: {_binding(prob, i, vlim, alim)}"
        )
    return x, method


# --------------------------------------------------------------------------- sampling


def _sample_law(
    grid: FloatArray, x: FloatArray, dt: float, what: str
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Sample the constant-σ̈-per-stage law at t = k·dt (duration rounded up).

    Returns t (M,), σ (M,), σ̇ (M,), σ̈ (M,).
    """
    sd = np.sqrt(np.maximum(x, 0.0))
    D = np.diff(grid)
    u = np.diff(x) / (2.0 * D)
    den = sd[:-1] + sd[1:]
    stuck = den <= 0
    if stuck.any():
        raise _StalledError(int(np.flatnonzero(stuck)[0]))
    tau = np.concatenate([[0.0], np.cumsum(2.0 * D / den)])
    T = float(tau[-1])
    n = max(1, math.ceil(T / dt - 1e-9))
    if n + 1 > MAX_SAMPLES:
        raise ValueError(
            f"{what}: the timed path lasts {T:.6g} s = {n + 1} samples at dt = {dt} s, more "
            f"than MAX_SAMPLES = {MAX_SAMPLES}; split the path or raise the feed/limits"
        )
    k = T / (n * dt)  # ≤ 1: internal time per output time
    t = np.arange(n + 1) * dt
    tq = t * k
    tq[-1] = T
    idx = np.clip(np.searchsorted(tau, tq, side="right") - 1, 0, grid.shape[0] - 2)
    h = tq - tau[idx]
    sig = grid[idx] + sd[idx] * h + 0.5 * u[idx] * h * h
    sig = np.clip(sig, grid[idx], grid[idx + 1])
    sig[-1] = grid[-1]
    sdq = np.maximum(sd[idx] + u[idx] * h, 0.0) * k
    sdq[-1] = sd[-1] * k
    sddq = u[idx] * (k * k)
    return t, sig, sdq, sddq


def _timed_from_law(
    prob: _Problem,
    t: FloatArray,
    sig: FloatArray,
    sdq: FloatArray,
    sddq: FloatArray,
    dt: float,
    vlim: FloatArray,
    alim: FloatArray,
    method: str,
) -> tuple[TimedPath, FloatArray, FloatArray]:
    """The sampled trajectory, and the σ intervals (lo, hi) where it breaks a limit."""
    spl = prob.spline
    q = spl(sig)
    p1 = spl(sig, 1)
    p2 = spl(sig, 2)
    q[0] = prob.q_w[0]
    q[-1] = prob.q_w[-1]
    qd = p1 * sdq[:, None]
    qdd = p2 * (sdq * sdq)[:, None] + p1 * sddq[:, None]
    s_t = prob.s_at(sig)
    s_t[0] = prob.s[0]
    s_t[-1] = prob.s[-1]
    feed_speed = prob.feed_speed
    rep = trajectory_limits_report(t, q, vlim, alim)
    feed, f_ratio = _feed_of_samples(t, s_t, prob.s, prob.sf, feed_speed)
    gap = np.clip(np.searchsorted(prob.s, s_t, side="right") - 1, 0, prob.s.shape[0] - 2)
    inside = (prob.sf[gap] > 0) & (prob.sf[gap + 1] > 0)
    stencil = inside.copy()  # the feed's difference stencil lies in the stock too
    stencil[1:] &= inside[:-1]
    stencil[:-1] &= inside[1:]
    limited = stencil & (feed < (1.0 - FEED_HOLD_TOL) * feed_speed)
    tp = TimedPath(
        t=t, q=q, qd=qd, qdd=qdd, s_of_t=s_t, feed=feed, feed_limited=limited,
        segment=np.zeros(t.shape[0], dtype=np.int64), dt=dt, vel_limits=vlim.copy(),
        acc_limits=alim.copy(), feed_speed=feed_speed,
        max_speed_ratio=rep["max_speed_ratio"], max_acc_ratio=rep["max_acc_ratio"],
        max_feed_ratio=float(f_ratio.max()) if f_ratio.size else 0.0, method=method,
    )  # fmt: skip
    lo: list[FloatArray] = []
    hi: list[FloatArray] = []
    if tp.max_speed_ratio > 1.0 + RATIO_TOL or tp.max_feed_ratio > 1.0 + FEED_TOL:
        v = np.abs(np.diff(q, axis=0)) / (dt * vlim)
        k = np.flatnonzero((v > 1.0 + RATIO_TOL).any(axis=1) | (f_ratio > 1.0 + FEED_TOL))
        lo.append(sig[k])
        hi.append(sig[k + 1])
    if tp.max_acc_ratio > 1.0 + RATIO_TOL:
        a = np.abs(np.diff(q, 2, axis=0)) / (dt * dt * alim)
        k = np.flatnonzero((a > 1.0 + RATIO_TOL).any(axis=1))
        lo.append(sig[k])
        hi.append(sig[k + 2])
    if not lo:
        return tp, np.zeros(0), np.zeros(0)
    return tp, np.concatenate(lo), np.concatenate(hi)


# --------------------------------------------------------------------------- public


def time_path(
    s: ArrayLike,
    q: ArrayLike,
    speed_factor: ArrayLike,
    feed_speed: float,
    vel_limits: ArrayLike,
    acc_limits: ArrayLike,
    dt: float,
    start_at_rest: bool = True,
    end_at_rest: bool = True,
    safety: float = 0.98,
    *,
    solver: str = "toppra",
) -> TimedPath:
    """Time-optimal timing of a joint path under joint and feed limits.

    Args:
        s: (N,) strictly increasing path parameter of the samples (any unit), N >= 2.
        q: (N, J) joint positions [rad] along the path; consecutive samples close.
        speed_factor: (N,) >= 0, metres moved by the fastest wire point inside the
            stock per unit of ``s`` (0 where the wire is out of the stock). The feed
            bound is ``speed_factor(s)·ds/dt <= feed_speed``.
        feed_speed: wire feed bound [m/s], > 0; held (within ``FEED_HOLD_TOL``)
            wherever the joints allow it.
        vel_limits: (J,) joint velocity limits [rad/s], > 0.
        acc_limits: (J,) joint acceleration limits [rad/s²], > 0.
        dt: controller period [s] (0.002 e-Series, 0.008 CB3), > 0.
        start_at_rest: start with zero velocity; otherwise at the largest path speed
            from which the rest of the path can be followed (the caller must match it).
        end_at_rest: end with zero velocity; otherwise as fast as the limits allow.
        safety: in (0, 1], factor on the joint velocity and acceleration limits used
            by the solver, so that the sampled finite differences stay within the true
            limits. The feed bound is not scaled.
        solver: ``"toppra"`` (controllable sets by toppra, falling back to
            ``"reachability"`` when toppra fails) or ``"reachability"`` (the
            closed-form recursion of this module only).

    Returns:
        :class:`TimedPath` sampled every ``dt`` from 0 to the end; its ratios are
        measured on the sampled output against the true (unscaled) limits and are
        ``<= 1 + RATIO_TOL`` (feed ``<= 1 + FEED_TOL``).

    Raises:
        ValueError: bad input (the message names the argument and index), or no
            trajectory within the limits (the message names the constraint and where).
    """
    s_arr = _array(s, "s", (None,))
    N = s_arr.shape[0]
    if N < 2:
        raise ValueError(f"s: expected at least 2 samples, got {N}")
    _increasing(s_arr, "s")
    q_arr = _array(q, "q", (N, None))
    J = q_arr.shape[1]
    if J < 1:
        raise ValueError("q: expected at least one joint column, got shape (N, 0)")
    sf = _array(speed_factor, "speed_factor", (N,))
    neg = np.flatnonzero(sf < 0)
    if neg.size:
        i = int(neg[0])
        raise ValueError(f"speed_factor[{i}]: expected a value >= 0, got {sf[i]}")
    feed = _float(feed_speed, "feed_speed")
    vlim = _limits(vel_limits, "vel_limits", J)
    alim = _limits(acc_limits, "acc_limits", J)
    dt = _float(dt, "dt")
    safety = _float(safety, "safety")
    if safety > 1.0:
        raise ValueError(f"safety: expected a factor in (0, 1], got {safety}")
    if solver not in ("toppra", "reachability"):
        raise ValueError(f"solver: expected 'toppra' or 'reachability', got {solver!r}")
    use_toppra = solver == "toppra"

    prob = _prepare(s_arr, q_arr, sf, feed)
    scale = safety
    tp: TimedPath | None = None
    for attempt in range(MAX_TRIES):
        v_k, a_k = vlim * scale, alim * scale
        x, method = _solve(prob, v_k, a_k, start_at_rest, end_at_rest, use_toppra=use_toppra)
        try:
            law = _sample_law(prob.grid, x, dt, "time_path")
        except _StalledError as exc:
            if method != "toppra":
                raise _stall_error(prob, exc.stage, v_k, a_k) from None
            x, method = _solve(prob, v_k, a_k, start_at_rest, end_at_rest, use_toppra=False)
            method = f"reachability (fallback: toppra profile stalls at stage {exc.stage})"
            try:
                law = _sample_law(prob.grid, x, dt, "time_path")
            except _StalledError as exc2:
                raise _stall_error(prob, exc2.stage, v_k, a_k) from None
        tp, lo, hi = _timed_from_law(prob, *law, dt, vlim, alim, method)
        if lo.size == 0:
            if attempt:
                how = "grid refined" + (", limits tightened" if attempt > REFINE_ROUNDS else "")
                tp = replace(tp, method=f"{tp.method}; limits met after {attempt} round(s), {how}")
            return tp
        if attempt < REFINE_ROUNDS:  # the law is too coarse there: more stages
            prob.refine(lo, hi)
        else:  # last resort: tighter limits everywhere
            scale *= 0.995 / max(tp.max_speed_ratio, tp.max_acc_ratio, 1.0)
            if tp.max_feed_ratio > 1.0 + FEED_TOL:
                prob.feed_scale *= 0.995 / tp.max_feed_ratio
                prob.set_grid(prob.grid)
    assert tp is not None
    raise ValueError(
        f"time_path: sampled output still exceeds the limits after {MAX_TRIES} rounds "
        f"(joint speed ratio {tp.max_speed_ratio:.4f}, acceleration ratio "
        f"{tp.max_acc_ratio:.4f}, feed ratio {tp.max_feed_ratio:.4f}), first between "
        f"s = {prob.s_at(lo[0]):.6g} and {prob.s_at(hi[0]):.6g}; the path bends faster "
        f"there than dt = {dt} s resolves — resample it more densely or smooth it"
    )


def _stall_error(prob: _Problem, i: int, vlim: FloatArray, alim: FloatArray) -> ValueError:
    return ValueError(
        f"time_path: the path speed collapses to zero between s = "
        f"{prob.s_at(prob.grid[i]):.6g} and {prob.s_at(prob.grid[i + 1]):.6g}"
        f"; binding constraint: {_binding(prob, i, vlim, alim)}"
    )


def joint_move(
    q0: ArrayLike,
    q1: ArrayLike,
    vel_limits: ArrayLike,
    acc_limits: ArrayLike,
    dt: float,
    speed_scale: float = 1.0,
) -> TimedPath:
    """Synchronised point-to-point joint motion from rest to rest (approach/retract).

    All joints follow the straight segment ``q0 + σ(t)·(q1 − q0)`` and arrive
    together. ``σ(t)`` has sine-squared acceleration ramps (continuous acceleration,
    peak equal to the limit of the most constrained joint, bounded jerk) and a
    cruise at the velocity limit of the most constrained joint when the move is
    long enough. The duration is rounded up to whole periods by slowing down.

    Args:
        q0: (J,) start [rad].
        q1: (J,) goal [rad]; may equal ``q0`` (a single sample is returned).
        vel_limits: (J,) [rad/s], > 0.
        acc_limits: (J,) [rad/s²], > 0.
        dt: controller period [s], > 0.
        speed_scale: in (0, 1]: the same motion slowed down in time — velocities
            scaled by ``speed_scale``, accelerations by its square.

    Returns:
        :class:`TimedPath` with ``s_of_t`` the fraction of the move (0…1), exact
        endpoints, zero velocity and acceleration at both ends, no feed.
    """
    a0 = _array(q0, "q0", (None,))
    J = a0.shape[0]
    a1 = _array(q1, "q1", (J,))
    vlim = _limits(vel_limits, "vel_limits", J)
    alim = _limits(acc_limits, "acc_limits", J)
    dt = _float(dt, "dt")
    k_s = _float(speed_scale, "speed_scale")
    if k_s > 1.0:
        raise ValueError(f"speed_scale: expected a factor in (0, 1], got {k_s}")
    delta = a1 - a0
    D = np.abs(delta)
    moving = D > 0
    if not moving.any():
        z = np.zeros((1, J))
        return TimedPath(
            t=np.zeros(1), q=a0[None, :].copy(), qd=z, qdd=z.copy(), s_of_t=np.zeros(1),
            feed=np.zeros(1), feed_limited=np.zeros(1, dtype=bool),
            segment=np.zeros(1, dtype=np.int64), dt=dt, vel_limits=vlim, acc_limits=alim,
            feed_speed=None, max_speed_ratio=0.0, max_acc_ratio=0.0, max_feed_ratio=0.0,
            method="joint_move",
        )  # fmt: skip
    v_s = k_s * float(np.min(vlim[moving] / D[moving]))  # σ per second
    a_s = k_s * k_s * float(np.min(alim[moving] / D[moving]))  # σ per second²
    V = min(v_s, math.sqrt(a_s / 2.0))
    Ta = 2.0 * V / a_s
    T = 2.0 * Ta + (1.0 - V * Ta) / V
    n = max(1, math.ceil(T / dt - 1e-9))
    if n + 1 > MAX_SAMPLES:
        raise ValueError(
            f"joint_move: the move lasts {T:.6g} s = {n + 1} samples, more than MAX_SAMPLES"
        )
    k = T / (n * dt)
    t = np.arange(n + 1) * dt
    tau = t * k
    tau[-1] = T

    def ramp(r: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """σ, σ̇, σ̈ of the acceleration ramp at time r ∈ [0, Ta]."""
        ph = 2.0 * math.pi * r / Ta
        pos = V * (r * r / (2.0 * Ta) - Ta / (4.0 * math.pi**2) * (1.0 - np.cos(ph)))
        vel = V * (r / Ta - np.sin(ph) / (2.0 * math.pi))
        acc = V / Ta * (1.0 - np.cos(ph))
        return pos, vel, acc

    sig = np.empty(n + 1)
    sd = np.empty(n + 1)
    sdd = np.empty(n + 1)
    acc_ph = tau <= Ta
    dec_ph = tau >= T - Ta
    cru_ph = ~acc_ph & ~dec_ph
    p, v, a = ramp(tau[acc_ph])
    sig[acc_ph], sd[acc_ph], sdd[acc_ph] = p, v, a
    p, v, a = ramp(T - tau[dec_ph])
    sig[dec_ph], sd[dec_ph], sdd[dec_ph] = 1.0 - p, v, -a
    sig[cru_ph] = V * Ta / 2.0 + V * (tau[cru_ph] - Ta)
    sd[cru_ph] = V
    sdd[cru_ph] = 0.0
    sig[0], sig[-1] = 0.0, 1.0
    sd[[0, -1]] = 0.0
    sdd[[0, -1]] = 0.0
    sd *= k
    sdd *= k * k
    q = a0 + sig[:, None] * delta
    q[0] = a0
    q[-1] = a1
    rep = trajectory_limits_report(t, q, vlim, alim)
    return TimedPath(
        t=t, q=q, qd=sd[:, None] * delta, qdd=sdd[:, None] * delta, s_of_t=sig,
        feed=np.zeros(n + 1), feed_limited=np.zeros(n + 1, dtype=bool),
        segment=np.zeros(n + 1, dtype=np.int64), dt=dt, vel_limits=vlim, acc_limits=alim,
        feed_speed=None, max_speed_ratio=rep["max_speed_ratio"],
        max_acc_ratio=rep["max_acc_ratio"], max_feed_ratio=0.0, method="joint_move",
    )  # fmt: skip


def concatenate(parts: Sequence[TimedPath], dt: float) -> TimedPath:
    """Join timed paths end to start.

    Each part must be sampled every ``dt`` and start where the previous one ends
    (positions within ``CONTINUITY_TOL`` rad). The first sample of every later part is
    dropped (it duplicates the previous end), times are shifted, ``s_of_t`` is offset
    so that it is continuous and ``segment`` records the part of every sample. The
    ratios are re-measured on the joined samples against the elementwise smallest
    limits of the parts (a velocity jump at a joint shows up as an acceleration
    ratio); the feed ratio is the largest of the parts'.

    Raises:
        ValueError: no parts, a part not sampled every ``dt`` (index named), joint
            counts differ, or a discontinuity (the index of the later part named).
    """
    dt = _float(dt, "dt")
    parts = list(parts)
    if not parts:
        raise ValueError("parts: expected at least one TimedPath, got none")
    for i, p in enumerate(parts):
        if not isinstance(p, TimedPath):
            raise ValueError(f"parts[{i}]: expected a TimedPath, got {type(p).__name__}")
    J = parts[0].q.shape[1]
    for i, p in enumerate(parts):
        if p.q.shape[1] != J:
            raise ValueError(f"parts[{i}]: expected {J} joints like parts[0], got {p.q.shape[1]}")
        h = np.diff(p.t)
        if h.size and np.max(np.abs(h - dt)) > 1e-9 * max(1.0, dt):
            raise ValueError(
                f"parts[{i}]: expected samples every dt = {dt} s, got periods "
                f"{h.min():.9g}…{h.max():.9g} s"
            )
    for i in range(1, len(parts)):
        gap = np.abs(parts[i].q[0] - parts[i - 1].q[-1])
        if gap.max() > CONTINUITY_TOL:
            j = int(np.argmax(gap))
            raise ValueError(
                f"parts[{i}]: starts {gap[j]:.3g} rad away from the end of parts[{i - 1}] "
                f"(joint {j + 1}); positions must match within {CONTINUITY_TOL} rad"
            )
    keep = [slice(None)] + [slice(1, None)] * (len(parts) - 1)
    qs = [p.q[k] for p, k in zip(parts, keep, strict=True)]
    n = [x.shape[0] for x in qs]
    M = sum(n)
    s_chunks = []
    offset = 0.0
    for i, (p, k) in enumerate(zip(parts, keep, strict=True)):
        if i > 0:
            offset += float(parts[i - 1].s_of_t[-1]) - float(p.s_of_t[0])
        s_chunks.append(p.s_of_t[k] + offset)
    q = np.concatenate(qs)
    t = np.arange(M) * dt
    vlim = np.min([p.vel_limits for p in parts], axis=0)
    alim = np.min([p.acc_limits for p in parts], axis=0)
    rep = trajectory_limits_report(t, q, vlim, alim)
    feeds = {p.feed_speed for p in parts if p.feed_speed is not None}
    return TimedPath(
        t=t, q=q,
        qd=np.concatenate([p.qd[k] for p, k in zip(parts, keep, strict=True)]),
        qdd=np.concatenate([p.qdd[k] for p, k in zip(parts, keep, strict=True)]),
        s_of_t=np.concatenate(s_chunks),
        feed=np.concatenate([p.feed[k] for p, k in zip(parts, keep, strict=True)]),
        feed_limited=np.concatenate([p.feed_limited[k] for p, k in zip(parts, keep, strict=True)]),
        segment=np.repeat(np.arange(len(parts), dtype=np.int64), n), dt=dt,
        vel_limits=vlim, acc_limits=alim,
        feed_speed=feeds.pop() if len(feeds) == 1 else None,
        max_speed_ratio=rep["max_speed_ratio"], max_acc_ratio=rep["max_acc_ratio"],
        max_feed_ratio=max(p.max_feed_ratio for p in parts), method="concatenate",
    )  # fmt: skip
