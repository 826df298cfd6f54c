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
     ``sf_σ = speed_factor(s(σ))·s'(σ)`` with ``s(σ)`` the monotone C¹ (PCHIP)
     interpolation of the samples, so that ``sf_σ`` is continuous (a piecewise linear
     ``s(σ)`` made it jump at every kink of the joint path, and the bound with it).
     A grid point's bound is the largest ``sf_σ`` over the stages it touches, so it
     also holds between grid points (x is linear there); stages over which ``sf_σ``
     changes by more than ``FEED_SMOOTH`` are split;
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
   and after ``MAX_TRIES`` rounds :class:`TimingFailure` is raised — as when the path
   speed collapses or the law would last more than ``MAX_SAMPLES`` periods: a
   :class:`ValueError` with where the time goes and what binds (``diagnose``).

``safety`` scales the joint limits only. The feed bound is not scaled: a constant
feed equal to ``feed_speed`` is the goal of the cut.

Modules, one job each (the way toppra splits itself): ``tolerances`` (tolerances
and limits), ``result`` (:class:`TimedPath`), ``inputs`` (the argument checks every
timing function shares), ``report`` (the finite-difference verification),
``problem`` (grid and constraint rows), ``solvers`` (toppra and the reachability
fallback), ``sampling``, ``time_law`` (:func:`time_path`), ``moves``
(:func:`joint_move`, :func:`concatenate`), ``diagnose`` (:class:`TimingFailure`).
"""

from __future__ import annotations

from ....robot.motion.rates import trajectory_limits_report
from .diagnose import Binding, TimingFailure
from .moves import concatenate, dwell, joint_move
from .result import TimedPath
from .time_law import time_path
from .tolerances import CONTINUITY_TOL, FEED_HOLD_TOL, FEED_TOL, MAX_SAMPLES, RATIO_TOL

__all__ = [
    "CONTINUITY_TOL",
    "FEED_HOLD_TOL",
    "FEED_TOL",
    "MAX_SAMPLES",
    "RATIO_TOL",
    "Binding",
    "TimedPath",
    "TimingFailure",
    "concatenate",
    "dwell",
    "joint_move",
    "time_path",
    "trajectory_limits_report",
]
