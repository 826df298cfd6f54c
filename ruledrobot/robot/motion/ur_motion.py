"""The controller's trajectory generator: moveJ/moveL/paths with blends, and stops.

A motion produces one joint setpoint per control period (``next(dt)``), which
the controller hands to the arm backend.  Every move is a :class:`PathMotion`
made of :class:`Segment` s:

* a **joint segment** (``movej``) runs linearly in joint space with a
  trapezoidal speed profile on the leading axis (speed in rad/s,
  acceleration in rad/s^2), every joint synchronised;
* a **linear segment** (``movel``/``movep``) runs the TCP on a straight line
  with the orientation on the shortest rotation, a trapezoidal profile on the
  path length (m/s, m/s^2; on the rotation angle for pure reorientations).
  Its joint curve is solved once, when the move starts, by analytic IK
  nearest the previous sample, starting from the current configuration.

**Blends.**  A segment with blend radius ``r`` does not stop at its
waypoint: it cruises until ``r`` (metres of TCP path, clipped to half of
either segment) is left, then ramps its speed down over the blend time
``2 r / v`` while the next segment ramps up over the same time, and the
joint displacements of the two add up (superposition: the velocity turns
linearly from one segment to the next, a parabolic blend).  Outside the
blend zones each segment is exact (straight lines stay straight); the path
passes the waypoint at a distance below ``r``.  UR's blends are circular
arcs; this has the same timing character.

:class:`StopMotion` decelerates every joint linearly to rest in the same
time (URScript ``stopj``; ``stopl`` is approximated the same way).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ...geometry.se3 import pose_from_ur_vector, ur_vector_from_pose
from .arm_kinematics import ArmKinematics

__all__ = [
    "MotionError",
    "PathMotion",
    "Profile",
    "Segment",
    "StopMotion",
    "joint_segment",
    "linear_segment",
]

Setpoint = tuple[np.ndarray, np.ndarray, np.ndarray]


class MotionError(ValueError):
    """A move cannot be executed (unreachable pose, joint jump); the program stops."""


class Profile:
    """Profile over ``distance``: ramp up in ``t_in``, cruise at ``v``, ramp down in ``t_out``.

    The ramps are linear in speed (constant acceleration).  A move from rest
    to rest is the classic trapezoid (``t_in = t_out = v / a``); a blended
    segment ramps over the blend time instead.
    """

    def __init__(self, distance: float, v: float, t_in: float, t_out: float) -> None:
        if not (distance >= 0 and v > 0 and t_in >= 0 and t_out >= 0):
            raise MotionError(
                f"profile: need distance >= 0, v > 0, ramps >= 0; got {distance}, {v}, "
                f"{t_in}, {t_out}"
            )
        self.distance = float(distance)
        self.v = float(v)
        self.t_in = float(t_in)
        self.t_out = float(t_out)
        self.d_in = 0.5 * self.v * self.t_in
        self.d_out = 0.5 * self.v * self.t_out
        cruise = self.distance - self.d_in - self.d_out
        if cruise < -1e-9 * max(1.0, self.distance):
            raise MotionError(f"profile: ramps ({self.d_in} + {self.d_out}) exceed {distance}")
        self.t_cruise = max(cruise, 0.0) / self.v
        self.duration = self.t_in + self.t_cruise + self.t_out

    @classmethod
    def trapezoid(cls, distance: float, v: float, a: float) -> Profile:
        """Rest to rest with speed ``v`` and acceleration ``a`` (triangular when short)."""
        if not (distance >= 0 and v > 0 and a > 0):
            raise MotionError(
                f"profile: need distance >= 0, v > 0, a > 0; got {distance}, {v}, {a}"
            )
        if distance * a < v * v:
            v = math.sqrt(distance * a) if distance > 0 else v
        t = v / a if distance > 0 else 0.0
        return cls(distance, v, t, t)

    def position(self, t: float) -> float:
        """Distance travelled at time ``t`` (clamped to [0, distance])."""
        if t <= 0.0:
            return 0.0
        if t >= self.duration:
            return self.distance
        if t < self.t_in:
            return 0.5 * self.v * t * t / self.t_in
        t2 = t - self.t_in
        if t2 < self.t_cruise:
            return self.d_in + self.v * t2
        rest = self.duration - t
        return self.distance - 0.5 * self.v * rest * rest / self.t_out if self.t_out > 0 else (
            self.distance)  # fmt: skip


@dataclass
class Segment:
    """One move of a path: a joint curve from ``q_start`` to ``q_end`` and its profile.

    ``curve(u)`` for ``u`` in [0, 1] gives the joints at the fraction ``u``
    of the path length ``distance`` (natural units: rad of the leading joint
    for joint moves, m of TCP path for linear ones, rad of TCP rotation for
    pure reorientations), run at speed ``v`` with acceleration ``a`` in those
    units.  ``blend``: radius [m of TCP path] of the blend into the next
    segment (0 = stop at the waypoint).  ``target``: the waypoint as given
    (joint vector or UR pose vector).
    """

    q_start: np.ndarray
    q_end: np.ndarray
    curve: Callable[[float], np.ndarray]
    distance: float
    v: float
    a: float
    blend: float
    tcp_length: float
    target: np.ndarray
    linear: bool


def joint_segment(
    q_start: np.ndarray,
    q_end: np.ndarray,
    v: float,
    a: float,
    r: float,
    kin: ArmKinematics,
) -> Segment:
    """A ``movej`` from ``q_start`` to ``q_end`` (leading-axis speed ``v``, acceleration ``a``)."""
    q0 = np.asarray(q_start, dtype=float)
    q1 = np.asarray(q_end, dtype=float)
    dq = q1 - q0
    D = float(np.max(np.abs(dq)))
    length = float(np.linalg.norm(np.subtract(kin.tcp_vector(q1)[:3], kin.tcp_vector(q0)[:3])))

    def curve(u: float) -> np.ndarray:
        return q0 + dq * u

    return Segment(q0, q1, curve, D, max(v, 1e-6), max(a, 1e-6), max(r, 0.0), length,
                   q1.copy(), False)  # fmt: skip


def _rot_log(R: np.ndarray) -> np.ndarray:
    """Rotation vector of a 3x3 rotation."""
    return ur_vector_from_pose(np.block([[R, np.zeros((3, 1))], [np.zeros((1, 3)), 1.0]]))[3:]


def linear_segment(
    q_start: np.ndarray,
    pose_end: Sequence[float],
    v: float,
    a: float,
    r: float,
    kin: ArmKinematics,
    *,
    max_joint_step: float = 0.2,
) -> Segment:
    """A ``movel`` from the TCP pose of ``q_start`` to UR pose vector ``pose_end``.

    Raises :class:`MotionError` when a pose on the line is out of reach or
    the joint curve jumps (a branch change at a singularity).
    """
    q0 = np.asarray(q_start, dtype=float)
    T0 = pose_from_ur_vector(np.asarray(kin.tcp_vector(q0)))
    T1 = pose_from_ur_vector(np.asarray(pose_end, dtype=float))
    dp = T1[:3, 3] - T0[:3, 3]
    L = float(np.linalg.norm(dp))
    w = _rot_log(T0[:3, :3].T @ T1[:3, :3])  # body-frame rotation vector
    theta = float(np.linalg.norm(w))
    n = int(min(4000, max(2, math.ceil(L / 0.0005), math.ceil(theta / 0.002)))) + 1
    u = np.linspace(0.0, 1.0, n)
    poses = np.repeat(T0[None], n, axis=0)
    poses[:, :3, 3] = T0[:3, 3] + u[:, None] * dp
    if theta > 0:
        from ...geometry.se3 import pose_from_rotvec

        Rs = pose_from_rotvec(u[:, None] * w)[:, :3, :3]
        poses[:, :3, :3] = np.einsum("ij,njk->nik", T0[:3, :3], Rs)
    qs = kin.ik_path(poses, q0)
    if qs is None:
        raise MotionError(
            f"movel to p{list(np.round(pose_end, 6))}: a pose on the line is out of reach"
        )
    qs[0] = q0
    steps = np.max(np.abs(np.diff(qs, axis=0)), axis=1)
    if steps.size and float(steps.max()) > max_joint_step:
        k = int(np.argmax(steps))
        raise MotionError(
            f"movel to p{list(np.round(pose_end, 6))}: joint jump of {steps[k]:.3f} rad at "
            f"{100 * u[k]:.1f}% of the line (singularity or branch change)"
        )

    def curve(x: float) -> np.ndarray:
        f = min(max(x, 0.0), 1.0) * (n - 1)
        k = min(int(f), n - 2)
        t = f - k
        return qs[k] + (qs[k + 1] - qs[k]) * t

    D = L if L > 1e-6 else theta
    return Segment(q0, qs[-1].copy(), curve, D, max(v, 1e-6), max(a, 1e-6), max(r, 0.0), L,
                   np.asarray(pose_end, dtype=float), True)  # fmt: skip


def _blend_profiles(segs: Sequence[Segment]) -> tuple[list[Profile], list[bool]]:
    """Speed profiles of consecutive segments with parabolic (superposition) blends.

    Segment i with blend radius r (clipped to half of either segment) runs at
    cruise speed until r is left, then ramps down over the blend time
    ``2 r / v``; segment i+1 ramps up over the same time, starting then (the
    velocity turns linearly from one segment to the next: a parabolic blend).
    Segments that start or end at rest ramp with their acceleration; a
    segment too short for its speed runs slower.  Returns the profiles and,
    per segment, whether it blends into the next.
    """
    n = len(segs)
    r_nat = [0.0] * n  # blend distance at the end of segment i, in its natural units
    for i in range(n - 1):
        a, b = segs[i], segs[i + 1]
        if a.blend <= 0 or a.distance <= 0 or b.distance <= 0:
            continue
        la = a.tcp_length if a.tcp_length > 1e-9 else a.distance
        lb = b.tcp_length if b.tcp_length > 1e-9 else b.distance
        r = min(a.blend, 0.5 * la, 0.5 * lb)
        r_nat[i] = a.distance * r / la
    profiles: list[Profile] = []
    t_prev_out = 0.0
    for i, seg in enumerate(segs):
        D, v, acc = seg.distance, seg.v, seg.a
        blend_in = i > 0 and r_nat[i - 1] > 0
        blend_out = r_nat[i] > 0
        if D <= 0:
            prof = Profile(0.0, v, 0.0, 0.0)
        elif not blend_in and not blend_out:
            prof = Profile.trapezoid(D, v, acc)
        elif blend_out:
            d_out = r_nat[i]
            if blend_in:
                t_in = min(t_prev_out, 2.0 * (D - d_out) / v)
            else:
                v = min(v, math.sqrt(2.0 * acc * (D - d_out)))  # v^2 / 2a + r <= D
                t_in = v / acc
            prof = Profile(D, v, t_in, 2.0 * d_out / v)
        else:  # blend in, stop at the end: v t_in / 2 + v^2 / 2a <= D
            t_in = min(t_prev_out, D / v)
            vmax = (-acc * t_in + math.sqrt((acc * t_in) ** 2 + 8.0 * acc * D)) / 2.0
            v = min(v, vmax)
            prof = Profile(D, v, t_in, v / acc)
        profiles.append(prof)
        t_prev_out = prof.t_out
    return profiles, [r > 0 for r in r_nat]


class PathMotion:
    """A sequence of segments executed with superposition blends; one setpoint per ``next``.

    ``progress`` is the index of the last segment started (the waypoint the
    move is heading for), as URScript's ``signal_async_progress`` reports it.
    """

    def __init__(self, q0: np.ndarray, segments: Sequence[Segment]) -> None:
        if not segments:
            raise MotionError("path: no waypoints")
        self.q0 = np.asarray(q0, dtype=float)
        self.segments = list(segments)
        self.profiles, blended = _blend_profiles(self.segments)
        starts = [0.0]
        for i, prof in enumerate(self.profiles[:-1]):
            overlap = prof.t_out if blended[i] else 0.0
            starts.append(starts[-1] + prof.duration - overlap)
        self.starts = starts
        self.duration = starts[-1] + self.profiles[-1].duration
        self.t = 0.0
        self._q_prev = self.q0.copy()
        self._qd_prev = np.zeros(6)
        self._done_offset = np.zeros(6)  # displacement of completed segments
        self._first_active = 0
        self.progress = 0

    @property
    def finished(self) -> bool:
        """Whether the path time has reached the end of the last segment."""
        return self.t >= self.duration

    @property
    def target(self) -> np.ndarray:
        """The final waypoint as given (joint vector or UR pose vector)."""
        return self.segments[-1].target

    @property
    def q_end(self) -> np.ndarray:
        """(6,) joint positions [rad] at the end of the last segment."""
        return self.segments[-1].q_end

    def position(self, t: float) -> np.ndarray:
        """Joint setpoint at time ``t`` (``t`` must not decrease between calls)."""
        q = self.q0 + self._done_offset
        i = self._first_active
        segs, starts = self.segments, self.starts
        profs = self.profiles
        while i < len(segs) and starts[i] <= t:
            seg = segs[i]
            prof = profs[i]
            tau = t - starts[i]
            D = prof.distance
            if tau >= prof.duration:
                disp = seg.q_end - seg.q_start
                if i == self._first_active:
                    self._done_offset = self._done_offset + disp
                    self._first_active += 1
            else:
                u = prof.position(tau) / D if D > 0 else 1.0
                disp = seg.curve(u) - seg.q_start
            q = q + disp
            self.progress = i
            i += 1
        return q

    def next(self, dt: float, time_scale: float = 1.0) -> Setpoint | None:
        """Advance by ``dt * time_scale`` of path time; None once the path is complete."""
        if self.t >= self.duration:
            return None
        self.t = min(self.t + dt * time_scale, self.duration)
        q = self.position(self.t)
        qd = (q - self._q_prev) / dt
        qdd = (qd - self._qd_prev) / dt
        self._q_prev, self._qd_prev = q, qd
        return q, qd, qdd


class StopMotion:
    """Decelerate all joints linearly to rest, the fastest one at ``deceleration``."""

    progress = 0

    def __init__(self, q0: np.ndarray, qd0: np.ndarray, deceleration: float) -> None:
        self.q0 = np.asarray(q0, dtype=float).copy()
        self.qd0 = np.asarray(qd0, dtype=float).copy()
        a = max(abs(float(deceleration)), 1e-6)
        self.duration = float(np.max(np.abs(self.qd0))) / a
        self.t = 0.0
        self._qd_prev = self.qd0.copy()
        self.target = self.q0 + 0.5 * self.qd0 * self.duration
        self.q_end = self.target

    @property
    def finished(self) -> bool:
        """Whether every joint has come to rest."""
        return self.t >= self.duration

    def next(self, dt: float, time_scale: float = 1.0) -> Setpoint | None:
        """Advance by ``dt`` [s] and return the setpoint ``(q, qd, qdd)``; None once at rest.

        Each (6,) [rad], [rad/s], [rad/s^2].

        ``time_scale`` is taken for the motions' common interface and ignored: a stop
        runs in real time.
        """
        if self.t >= self.duration:
            return None
        self.t = min(self.t + dt, self.duration)
        T, t = self.duration, self.t
        q = self.q0 + self.qd0 * (t - 0.5 * t * t / T)
        qd = self.qd0 * (1.0 - t / T)
        qdd = (qd - self._qd_prev) / dt
        self._qd_prev = qd
        return q, qd, qdd
