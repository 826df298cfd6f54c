"""Path inverse kinematics: one continuous joint solution per pose of a path.

Rules (``docs/robot.md`` has the long form):

1. Every pose gets the 8 analytic solutions (:meth:`RobotModel.ik`).  A
   solution is a *candidate* when it exists and each joint has a
   representative ``q + 2 pi k`` inside the joint limits.
2. The branch sequence is chosen by dynamic programming over the candidates
   (Viterbi): the cost of a step is the weighted squared joint distance
   ``sum_j w_j wrap(q_j' - q_j)^2`` with angle differences wrapped to
   (-pi, pi], so a solution and its 2 pi equivalents count as one; the first
   sample costs its distance to ``q_start`` when given.  The result is the
   branch sequence of least total squared motion: it follows the continuous
   branch through near-singular stretches (where the wrist branch may change
   sign continuously) and switches only where it must.
3. At an exact wrist singularity (``|sin q5| < 1e-12``) q6 is free: those
   samples are solved again with q6 seeded by interpolating between the
   regular samples around them (or holding the one neighbour at a path end),
   and the branch selection is rerun, so the path stays continuous.
4. Each joint is then unwrapped (the 2 pi representative nearest the previous
   sample) and shifted by a whole number of turns into its limits: centred in
   the limits, or nearest ``q_start``.  A joint whose unwrapped motion spans
   more than its limits must be turned back by 2 pi somewhere: the turn is put
   where it keeps the longest stretches inside the limits and is flagged.
5. A step larger than ``jump_threshold`` (max over joints, rad) is flagged with
   its cause: a forced turn (:attr:`PathStatus.LIMIT_WRAP`), the previous
   branch ceasing to exist or to fit the limits at that sample or later, before
   the next switch (``BRANCH_LOST``), a nearby
   singularity (``SINGULAR``) or none of these (``JUMP``, e.g. the poses jump).
   Poses without a solution are ``UNREACHABLE`` (or ``OUT_OF_LIMITS``) and get
   NaN joints; the path continues after them.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.angles import TWO_PI, wrap_angle
from ...geometry.ranges import runs_of_indices
from .._checks import FloatArray, as_array, as_joint_vector, as_poses
from . import analytic as _ik


class PathArm(Protocol):
    """What path IK needs of an arm (:class:`~ruledrobot.robot.RobotModel` has it)."""

    n_joints: int
    lower: FloatArray
    upper: FloatArray

    @property
    def ur_geometry(self) -> _ik.URGeometry | None:
        """The UR link lengths the analytic IK solves with [m] (``RobotModel.ur_geometry``)."""
        ...

    def ik(self, T: ArrayLike, **kwargs):
        """All 8 analytic IK solutions of TCP poses ``T`` (..., 4, 4) in the world frame [m].

        Path IK calls it as ``RobotModel.ik`` takes it, with ``return_info=True``,
        ``check=False`` and a ``q6_seed`` [rad]: an :class:`~.analytic.IKSolutions` of
        (..., 8, 6) joint positions [rad].
        """
        ...

    def flange_poses(self, T: ArrayLike, *, check: bool = True) -> FloatArray:
        """Return the flange poses in the robot base frame for TCP poses ``T`` in the world frame.

        Flange poses (..., 4, 4) [m] for ``T`` (..., 4, 4): what the closed-form IK solves
        for.
        """
        ...


#: rad: a step whose largest joint change exceeds this is a jump (:func:`path_ik`'s
#: default, and the planner's between rulings: ``wirecut.cut.wire_pose``, ``reach``)
JUMP_THRESHOLD = 0.5
#: rad: a joint position up to this far beyond a limit counts as within it — the one
#: slack of the joint position limits (2 pi representatives placed here, ``RobotModel.
#: within_limits`` and ``position_ratio``, the export's limit check)
LIMIT_TOL = 1e-9
_STEP_CHUNK = 2048  # path steps per chunk when building the (8 x 8) step costs


class PathStatus(IntEnum):
    """Per-sample status of a path IK result (``PathIKResult.status``)."""

    OK = 0
    #: no IK solution: the pose is out of the arm's reach.
    UNREACHABLE = 1
    #: solutions exist but none fits the joint position limits.
    OUT_OF_LIMITS = 2
    #: the step into this sample turns a joint back by 2 pi to stay in its limits.
    LIMIT_WRAP = 3
    #: the step switches branch because the previous one has no solution (out of
    #: reach, or outside the limits) here or further along the path: the switch
    #: is forced, and put where it costs the least motion.
    BRANCH_LOST = 4
    #: a large step next to a singularity (the joints move fast for a small pose change).
    SINGULAR = 5
    #: a large step with none of the causes above (e.g. the poses themselves jump).
    JUMP = 6


_DESCRIPTION = {
    PathStatus.UNREACHABLE: "unreachable",
    PathStatus.OUT_OF_LIMITS: "no solution inside the joint limits",
    PathStatus.LIMIT_WRAP: "joint turned back by 2 pi to stay within its limits",
    PathStatus.BRANCH_LOST: "forced branch switch: the previous branch has no solution further on",
    PathStatus.SINGULAR: "large step near a singularity",
    PathStatus.JUMP: "large step",
}

_JUMPS = (PathStatus.LIMIT_WRAP, PathStatus.BRANCH_LOST, PathStatus.SINGULAR, PathStatus.JUMP)


@dataclass(frozen=True, eq=False)
class PathIKResult:
    """Joint solution of a path of N poses.

    Attributes
    ----------
    q : (N, 6) joint positions [rad], continuous, inside the limits; NaN rows
        where the pose has no solution.
    ok : (N,) bool, ``status == OK``.
    status : (N,) int8 :class:`PathStatus` codes; a jump code at sample t
        describes the step from the previous solved sample to t.
    branch : (N,) int8 analytic branch ``4 * shoulder + 2 * wrist + elbow``
        of the chosen solution, -1 where none.
    step : (N,) largest joint step [rad] from the previous solved sample (0 at
        the first solved sample, NaN where unsolved).
    max_step : the largest ``step`` [rad] (0.0 when nothing is solved).
    measure : (N,) singularity measure (scaled ``|det J|``, 0 = singular) of
        the chosen solution, NaN where unsolved.
    messages : one line per problem (runs of unreachable samples merged).
    """

    q: FloatArray
    ok: np.ndarray
    status: np.ndarray
    branch: np.ndarray
    step: FloatArray
    max_step: float
    measure: FloatArray
    messages: tuple[str, ...]

    @property
    def all_ok(self) -> bool:
        """True when every sample is solved without a flagged jump."""
        return bool(self.ok.all())

    @property
    def jumps(self) -> np.ndarray:
        """Indices of samples whose incoming step is flagged as a jump."""
        return np.flatnonzero(np.isin(self.status, [int(s) for s in _JUMPS]))

    @property
    def unreachable(self) -> np.ndarray:
        """Indices of samples without a solution (unreachable or outside the limits)."""
        return np.flatnonzero(np.isnan(self.q[:, 0]))

    def summary(self) -> str:
        """A short human-readable report."""
        n = self.q.shape[0]
        head = (
            f"{n} poses, {int(self.ok.sum())} ok, {self.unreachable.size} unsolved, "
            f"{self.jumps.size} jumps, max step {self.max_step:.4g} rad"
        )
        return "\n".join([head, *self.messages])


def _representable(x: FloatArray, lo: FloatArray, hi: FloatArray) -> np.ndarray:
    """(..., J) bool: some ``x + 2 pi k`` lies in ``[lo, hi]`` (x finite, limits may be inf)."""
    finite_lo = np.isfinite(lo)
    lo_f = np.where(finite_lo, lo, 0.0)
    # smallest representative >= lo, then compare with hi
    k = np.ceil((lo_f - LIMIT_TOL - x) / TWO_PI)
    rep = x + TWO_PI * k
    return np.where(finite_lo, rep <= hi + LIMIT_TOL, True)


def _step_costs(Q: FloatArray, feas: np.ndarray, w: FloatArray) -> FloatArray:
    """(M-1, 8, 8) cost of going from candidate i at t to candidate j at t+1."""
    M = Q.shape[0]
    C = np.empty((max(M - 1, 0), 8, 8))
    for lo in range(0, M - 1, _STEP_CHUNK):
        hi = min(lo + _STEP_CHUNK, M - 1)
        d = wrap_angle(Q[lo + 1 : hi + 1, None, :, :] - Q[lo:hi, :, None, :])
        c = np.einsum("tijk,k->tij", d * d, w)
        ok = feas[lo:hi, :, None] & feas[lo + 1 : hi + 1, None, :]
        C[lo:hi] = np.where(ok, c, np.inf)
    return C


def _viterbi(C: FloatArray, start: FloatArray) -> np.ndarray:
    """Least-cost branch sequence (M,) for step costs C (M-1, 8, 8) and start costs (8,)."""
    M = C.shape[0] + 1
    back = np.empty((M - 1, 8), dtype=np.intp)
    cost = start
    cols = np.arange(8)
    for t in range(M - 1):
        acc = cost[:, None] + C[t]
        arg = acc.argmin(axis=0)
        back[t] = arg
        cost = acc[arg, cols]
    choice = np.empty(M, dtype=np.intp)
    b = int(np.argmin(cost))
    choice[-1] = b
    for t in range(M - 2, -1, -1):
        b = int(back[t, b])
        choice[t] = b
    return choice


def _fit_joint(
    u: FloatArray, lo: float, hi: float, pref: float | None
) -> tuple[FloatArray, np.ndarray]:
    """Shift a continuous joint trajectory by whole turns into [lo, hi].

    Returns the shifted trajectory and a bool mask of samples into which a
    2 pi turn-back had to be inserted (the span exceeds the limits).
    """
    wraps = np.zeros(u.shape[0], dtype=bool)
    if not (np.isfinite(lo) or np.isfinite(hi)):
        if pref is not None:
            u = u + TWO_PI * np.round((pref - u[0]) / TWO_PI)
        return u, wraps
    umin, umax = float(u.min()), float(u.max())
    kmin = np.ceil((lo - LIMIT_TOL - umin) / TWO_PI) if np.isfinite(lo) else -np.inf
    kmax = np.floor((hi + LIMIT_TOL - umax) / TWO_PI) if np.isfinite(hi) else np.inf
    if kmin <= kmax:  # always so when one side is unlimited
        if pref is not None:
            k = np.round((pref - u[0]) / TWO_PI)
        else:  # centre the motion in the limits (around 0 when a side is unlimited)
            centre = 0.5 * (lo + hi) if np.isfinite(lo) and np.isfinite(hi) else 0.0
            k = np.round((centre - 0.5 * (umin + umax)) / TWO_PI)
        k = float(np.clip(k, kmin, kmax))
        return u + TWO_PI * k, wraps
    # the motion spans more than the limits: cut it into runs, each run shifted
    # by the number of turns that keeps it inside the limits the longest
    out = np.empty_like(u)
    s = 0
    n = u.shape[0]
    prev: float | None = pref
    while s < n:
        x = u[s]
        k_lo = np.ceil((lo - LIMIT_TOL - x) / TWO_PI)  # both limits are finite here
        k_hi = np.floor((hi + LIMIT_TOL - x) / TWO_PI)
        best_k, best_end, best_d = k_lo, s, np.inf
        for k in np.arange(k_lo, k_hi + 1):
            v = u[s:] + TWO_PI * k
            bad = (v < lo - LIMIT_TOL) | (v > hi + LIMIT_TOL)
            end = s + (int(np.argmax(bad)) if bad.any() else n - s)
            dist = 0.0 if prev is None else abs(v[0] - prev)
            if end > best_end or (end == best_end and dist < best_d):
                best_k, best_end, best_d = k, end, dist
        out[s:best_end] = u[s:best_end] + TWO_PI * best_k
        if s > 0:
            wraps[s] = True
        prev = float(out[best_end - 1])
        s = best_end
    return out, wraps


def path_ik(
    model: PathArm,
    poses: ArrayLike,
    *,
    q_start: ArrayLike | None = None,
    jump_threshold: float = JUMP_THRESHOLD,
    singular_tol: float = 0.05,
    weights: ArrayLike | None = None,
    max_messages: int = 20,
    solutions: _ik.IKSolutions | None = None,
) -> PathIKResult:
    """One continuous joint solution per TCP pose of a path.

    Parameters
    ----------
    model : a robot with analytic IK (UR structure).
    poses : (N, 4, 4) TCP poses in the world frame, in path order.
    q_start : optional (6,) current joint configuration [rad]: the first
        sample's branch and 2 pi representatives are chosen nearest to it.
    jump_threshold : a step whose largest joint change exceeds this [rad] is
        flagged (``status`` explains it).
    singular_tol : a flagged step is attributed to a singularity when one of
        the normalised factors (``|sin q5|``, ``|sin q3|``, shoulder distance /
        (|a2| + |a3| + |d5|)) at either end is below this.
    weights : (6,) per-joint weights of the squared joint distance (default 1).
    max_messages : at most this many lines in ``messages``.
    solutions : the poses' IK (``model.ik(poses, return_info=True, check=False)``) when
        the caller solved a batch of paths in one call (the wire-pose search's candidates:
        one call for all of them is many times faster than one per path).

    Returns
    -------
    :class:`PathIKResult`.
    """
    g = model.ur_geometry
    T = as_poses(poses, "poses")
    if T.ndim != 3 or T.shape[0] == 0:
        raise ValueError(f"poses: expected a path of shape (N, 4, 4) with N >= 1, got {T.shape}")
    N = T.shape[0]
    J = model.n_joints
    w = np.ones(J) if weights is None else as_joint_vector(weights, "weights", J)
    if np.any(w < 0.0):
        raise ValueError(f"weights[{int(np.argmax(w < 0.0))}]: must be >= 0")
    start = None
    if q_start is not None:
        start = as_array(q_start, "q_start", (J,))
        if start.shape != (J,):
            raise ValueError(f"q_start: expected shape ({J},), got {start.shape}")
    jump_threshold = float(as_array(jump_threshold, "jump_threshold"))
    singular_tol = float(as_array(singular_tol, "singular_tol"))
    max_messages = int(max_messages)
    lower, upper = model.lower, model.upper

    sols = model.ik(T, return_info=True, check=False) if solutions is None else solutions
    if sols.q.shape[:1] != (N,):
        raise ValueError(f"solutions: IK of {sols.q.shape[0]} poses for a path of {N}")
    Q, valid = sols.q, sols.valid
    Qz = np.where(valid[..., None], Q, 0.0)
    feas = valid & _representable(Qz, lower, upper).all(axis=-1)
    solved = feas.any(axis=1)
    idx = np.flatnonzero(solved)
    M = idx.size
    factors = np.stack([sols.wrist, sols.elbow, sols.shoulder / _scale(g)], axis=-1)

    status = np.zeros(N, dtype=np.int8)
    status[~valid.any(axis=1)] = PathStatus.UNREACHABLE
    status[valid.any(axis=1) & ~solved] = PathStatus.OUT_OF_LIMITS
    q_out = np.full((N, J), np.nan)
    branch = np.full(N, -1, dtype=np.int8)
    step = np.full(N, np.nan)
    measure = np.full(N, np.nan)

    if M > 0:
        Qc, Fc = Qz[idx], feas[idx]

        def select(Qc: FloatArray, Fc: np.ndarray) -> np.ndarray:
            if start is None:
                s0 = np.zeros(8)
            else:
                d0 = wrap_angle(Qc[0] - start)
                s0 = (d0 * d0) @ w
            s0 = np.where(Fc[0], s0, np.inf)
            return _viterbi(_step_costs(Qc, Fc, w), s0)

        choice = select(Qc, Fc)
        # exact wrist singularities: q6 is free; seed it from the regular samples around
        sing = sols.wrist[idx, choice] < _ik.WRIST_EPS
        if sing.any():
            seeds = _seeds_for_singular(Qc[np.arange(M), choice, 5], sing, start)
            ids = idx[sing]
            Qs = model.ik(T[ids], q6_seed=seeds[sing], check=False)
            vs = ~np.isnan(Qs[..., 0])
            Qs = np.where(vs[..., None], Qs, 0.0)
            Fs = vs & _representable(Qs, lower, upper).all(axis=-1)
            keep = Fs.any(axis=1)  # never trade a solved sample for an unsolved one
            rows = np.flatnonzero(sing)[keep]
            Fc[rows], Qc[rows] = Fs[keep], Qs[keep]
            choice = select(Qc, Fc)
        qsel = Qc[np.arange(M), choice]

        # continuous representatives, then whole turns into the limits
        k = np.zeros_like(qsel)
        if M > 1:
            steps = np.cumsum(wrap_angle(np.diff(qsel, axis=0)), axis=0)
            u = qsel[0] + np.concatenate([np.zeros((1, J)), steps])
            k = np.round((u - qsel) / TWO_PI)
        u = qsel + TWO_PI * k
        wraps = np.zeros(M, dtype=bool)
        for j in range(J):
            u[:, j], wj = _fit_joint(
                u[:, j],
                float(lower[j]),
                float(upper[j]),
                None if start is None else float(start[j]),
            )
            wraps |= wj
        q_out[idx] = u
        branch[idx] = choice
        measure[idx] = sols.measure[idx, choice]
        st = np.zeros(M)
        if M > 1:
            st[1:] = np.abs(np.diff(u, axis=0)).max(axis=1)
        step[idx] = st

        big = np.flatnonzero(st > jump_threshold)
        if big.size:
            # the previous branch is "lost" when it stops existing (or fitting the limits)
            # at this sample or further along, before the path changes branch again:
            # the switch is forced, the programme only chose the cheapest place for it
            change = np.flatnonzero(np.diff(choice) != 0) + 1
            lost = np.zeros(big.size, dtype=bool)
            for n_, i in enumerate(big):
                later = change[change > i]
                end = int(later[0]) if later.size else M
                lost[n_] = not Fc[i:end, choice[i - 1]].all()
            fac = factors[idx, choice].min(axis=1)
            near = np.minimum(fac[big], fac[big - 1]) < singular_tol
            code = np.where(
                wraps[big],
                PathStatus.LIMIT_WRAP,
                np.where(
                    lost,
                    PathStatus.BRANCH_LOST,
                    np.where(near, PathStatus.SINGULAR, PathStatus.JUMP),
                ),
            )
            status[idx[big]] = code

    ok = status == PathStatus.OK
    messages = _messages(model, T, status, step, idx, factors, branch, max_messages)
    finite_steps = step[np.isfinite(step)]
    return PathIKResult(
        q=q_out,
        ok=ok,
        status=status,
        branch=branch,
        step=step,
        max_step=float(finite_steps.max()) if finite_steps.size else 0.0,
        measure=measure,
        messages=messages,
    )


def _scale(g: _ik.URGeometry) -> float:
    return abs(g.a2) + abs(g.a3) + abs(g.d5)


def _seeds_for_singular(q6: FloatArray, sing: np.ndarray, start: FloatArray | None) -> FloatArray:
    """q6 seeds (M,) for the exactly singular samples of a path.

    Inside a run of singular samples q6 is free; it is interpolated linearly
    (shortest way round) from the q6 of the regular sample before the run to
    that of the regular sample after it, so the path meets both ends
    continuously.  A run at either end of the path takes the q6 of its one
    regular neighbour; a path with no regular sample takes ``q_start`` (or 0).
    """
    M = q6.shape[0]
    pos = np.arange(M)
    before = np.maximum.accumulate(np.where(~sing, pos, -1))
    after = np.minimum.accumulate(np.where(~sing, pos, M)[::-1])[::-1]
    has_b, has_a = before >= 0, after < M
    qb = q6[np.clip(before, 0, M - 1)]
    qa = q6[np.clip(after, 0, M - 1)]
    inner = has_a & has_b & (after > before)  # regular samples have before == after
    frac = np.where(inner, pos - before, 0) / np.where(inner, after - before, 1)
    default = 0.0 if start is None else float(start[5])
    seed = np.where(has_b, qb, np.where(has_a, qa, default))
    return seed + frac * wrap_angle(qa - qb)


def _messages(
    model: PathArm,
    T: FloatArray,
    status: np.ndarray,
    step: FloatArray,
    idx: np.ndarray,
    factors: FloatArray,
    branch: np.ndarray,
    max_messages: int,
) -> tuple[str, ...]:
    lines: list[str] = []
    bad = np.flatnonzero(status != PathStatus.OK)
    if bad.size == 0:
        return ()
    unsolved = bad[status[bad] == PathStatus.UNREACHABLE]
    g = model.ur_geometry
    why_code = np.zeros(status.shape[0], dtype=np.int8)
    why_R = np.zeros(status.shape[0])
    if unsolved.size:
        why_code[unsolved], why_R[unsolved] = _unreachable_detail(
            g, model.flange_poses(T[unsolved], check=False)
        )
    events: list[tuple[int, str]] = []
    for code in (PathStatus.UNREACHABLE, PathStatus.OUT_OF_LIMITS):
        sel = bad[status[bad] == code]
        for a, stop in runs_of_indices(sel):
            b = stop - 1
            span = f"sample {a}" if a == b else f"samples {a}-{b}"
            extra = ""
            if code == PathStatus.UNREACHABLE:
                extra = f" ({_describe_unreachable(g, why_code[a : b + 1], why_R[a : b + 1])})"
            events.append((a, f"{span}: {_DESCRIPTION[code]}{extra}"))
    names = ("wrist |sin q5|", "elbow |sin q3|", "shoulder distance")
    prev_solved = np.full(status.shape[0], -1)
    prev_solved[idx[1:]] = idx[:-1]
    for t in bad[np.isin(status[bad], [int(s) for s in _JUMPS])]:
        code = PathStatus(int(status[t]))
        text = f"sample {t}: {_DESCRIPTION[code]} (step {step[t]:.3g} rad"
        gap = t - prev_solved[t] - 1
        if gap > 0:
            text += f" from sample {prev_solved[t]}, across {gap} unsolved"
        if code == PathStatus.SINGULAR:
            f = factors[t, branch[t]]
            k = int(np.argmin(f))
            text += f", {names[k]} = {f[k]:.2g}"
        events.append((int(t), text + ")"))
    events.sort()
    lines = [text for _, text in events[:max_messages]]
    if len(events) > max_messages:
        lines.append(f"... and {len(events) - max_messages} more")
    return tuple(lines)


def _unreachable_detail(g: _ik.URGeometry, Tf: FloatArray) -> tuple[np.ndarray, FloatArray]:
    """Why flange poses (n, 4, 4) have no solution.

    Returns a code per pose (0: the wrist point is inside the shoulder cylinder
    ``r < |d4|``; 1: beyond the arm's reach; 2: too close to the shoulder for
    the elbow; 3: in range, but not with this tool orientation) and the
    distance ``R`` [m] of the wrist point from the shoulder in the arm plane.
    With ``p5`` the wrist point, ``rho^2 = p5x^2 + p5y^2 - d4^2``,
    ``R = |(rho, p5z - d1)|``; the elbow target lies within ``d5`` of ``R`` and
    the two-link arm reaches ``[| |a2| - |a3| |, |a2| + |a3|]``.
    """
    p5 = Tf[:, :3, 3] - g.d6 * Tf[:, :3, 2]
    r2 = p5[:, 0] ** 2 + p5[:, 1] ** 2
    R = np.sqrt(np.maximum(r2 - g.d4 * g.d4, 0.0) + (p5[:, 2] - g.d1) ** 2)
    d5 = abs(g.d5)
    code = np.full(r2.shape, 3, dtype=np.int8)
    code[R + d5 < abs(abs(g.a2) - abs(g.a3))] = 2
    code[R - d5 > abs(g.a2) + abs(g.a3)] = 1
    code[r2 < g.d4 * g.d4] = 0
    return code, R


def _describe_unreachable(g: _ik.URGeometry, code: np.ndarray, R: FloatArray) -> str:
    """One phrase per cause present in a run of unreachable samples."""
    parts = []
    if np.any(code == 0):
        parts.append(f"wrist point inside the d4 = {abs(g.d4):.4g} m cylinder about the base axis")
    if np.any(code == 1):
        parts.append(
            f"wrist point up to {R[code == 1].max():.4g} m from the shoulder, beyond "
            f"the reach {abs(g.a2) + abs(g.a3) + abs(g.d5):.4g} m"
        )
    if np.any(code == 2):
        parts.append("wrist point too close to the shoulder for the elbow")
    if np.any(code == 3):
        parts.append("the elbow cannot reach the wrist point with this tool orientation")
    return "; ".join(parts)
