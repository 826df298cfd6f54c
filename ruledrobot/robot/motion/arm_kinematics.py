"""Single-configuration kinematics for the controller loop.

The 500 Hz loop needs the TCP pose and speed of one configuration per tick;
:meth:`RobotModel.fk` is vectorised for batches and costs ~0.2 ms on one
sample, so the per-tick work here is plain Python float arithmetic (~20 us).
IK goes through :meth:`RobotModel.ik` (all 8 analytic solutions) and picks
the solution nearest a given configuration, as URScript's
``get_inverse_kin(x, qnear)`` does.

A calibrated model (:meth:`RobotModel.with_calibration`) gives the calibrated
chain everywhere: the TCP pose and speed, FK, IK (the model's IK refines the
nominal closed form on the calibrated chain).  Only the elbow position comes
from the nominal table: the DH frames of a calibrated table sit on the common
normals of the nearly parallel axes 2-4, metres away from the arm (frame 3 of
a calibrated UR5e can lie 175 m out), while the nominal elbow is within
millimetres of the real one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.angles import wrap_angle, wrap_near
from ...geometry.se3 import pose_from_ur_vector, ur_vector_from_pose
from ..arm.model import RobotModel

__all__ = ["ArmKinematics", "rotvec_from_rows"]

Vec = tuple[float, ...]


def _mat_mul(A: Sequence[Sequence[float]], B: Sequence[Sequence[float]]) -> list[list[float]]:
    return [
        [
            A[i][0] * B[0][j] + A[i][1] * B[1][j] + A[i][2] * B[2][j] + A[i][3] * B[3][j]
            for j in range(4)
        ]
        for i in range(4)
    ]


_DHRow = tuple[float, float, float, float, float]


def _dh_rows(model: RobotModel) -> list[_DHRow]:
    """Per joint ``(d, a, cos alpha, sin alpha, theta_offset)``."""
    return [
        (float(d), float(a), math.cos(al), math.sin(al), float(off))
        for d, a, al, off in zip(model.d, model.a, model.alpha, model.theta_offset, strict=True)
    ]


def _chain(
    base: list[list[float]], rows: Sequence[_DHRow], q: Sequence[float]
) -> list[list[list[float]]]:
    """World poses (rows) of DH frames 0..len(rows) (pure Python floats)."""
    T = base
    out = [T]
    for (d, a, ca, sa, off), qi in zip(rows, q, strict=False):
        th = qi + off
        ct, st = math.cos(th), math.sin(th)
        A = (
            (ct, -st * ca, st * sa, a * ct),
            (st, ct * ca, -ct * sa, a * st),
            (0.0, sa, ca, d),
            (0.0, 0.0, 0.0, 1.0),
        )
        T = _mat_mul(T, A)
        out.append(T)
    return out


def rotvec_from_rows(R: Sequence[Sequence[float]]) -> Vec:
    """Rotation vector (angle in [0, pi]) of a rotation matrix given as rows (pure Python)."""
    m00, m01, m02 = R[0][0], R[0][1], R[0][2]
    m10, m11, m12 = R[1][0], R[1][1], R[1][2]
    m20, m21, m22 = R[2][0], R[2][1], R[2][2]
    tr = m00 + m11 + m22
    # Shepperd: the largest of w, x, y, z first
    if tr >= max(m00, m11, m22):
        w = 0.5 * math.sqrt(max(1.0 + tr, 0.0))
        f = 0.25 / w
        x, y, z = (m21 - m12) * f, (m02 - m20) * f, (m10 - m01) * f
    elif m00 >= m11 and m00 >= m22:
        x = 0.5 * math.sqrt(max(1.0 + m00 - m11 - m22, 0.0))
        f = 0.25 / x
        w, y, z = (m21 - m12) * f, (m01 + m10) * f, (m02 + m20) * f
    elif m11 >= m22:
        y = 0.5 * math.sqrt(max(1.0 - m00 + m11 - m22, 0.0))
        f = 0.25 / y
        w, x, z = (m02 - m20) * f, (m01 + m10) * f, (m12 + m21) * f
    else:
        z = 0.5 * math.sqrt(max(1.0 - m00 - m11 + m22, 0.0))
        f = 0.25 / z
        w, x, y = (m10 - m01) * f, (m02 + m20) * f, (m12 + m21) * f
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-12:
        return (2.0 * x, 2.0 * y, 2.0 * z)
    k = 2.0 * math.atan2(s, w) / s
    return (x * k, y * k, z * k)


class ArmKinematics:
    """FK, TCP speed and nearest-solution IK of one arm; the TCP offset can change.

    ``model`` gives the DH table, base and tool; :meth:`set_tcp` replaces the
    tool (URScript ``set_tcp``) for every later call.
    """

    def __init__(self, model: RobotModel) -> None:
        if model.n_joints != 6:
            raise ValueError(f"model {model.name!r}: the emulator needs 6 joints")
        self._dh = _dh_rows(model)
        # the elbow (frame 3) of the nominal table for a calibrated arm (see the module doc)
        self._elbow_dh = None if model.calibration is None else _dh_rows(model.nominal)[:3]
        self._base = [list(map(float, row)) for row in model.base]
        self.set_model(model)

    def set_model(self, model: RobotModel) -> None:
        """Use ``model`` (same DH table) from now on, e.g. after a TCP change."""
        self.model = model
        self._tool = [list(map(float, row)) for row in model.tool]
        self.tcp_offset: Vec = tuple(float(x) for x in ur_vector_from_pose(model.tool))

    def set_tcp(self, tcp: ArrayLike) -> None:
        """Set the TCP offset (UR pose vector in the flange frame)."""
        self.set_model(self.model.with_tool(np.asarray(tcp, dtype=float)))

    # ------------------------------------------------------------ forward

    def frames(self, q: Sequence[float]) -> list[list[list[float]]]:
        """World poses (rows) of DH frames 0..6 and the TCP (8 entries)."""
        out = _chain(self._base, self._dh, q)
        out.append(_mat_mul(out[-1], self._tool))
        return out

    def tcp_vector(self, q: Sequence[float]) -> Vec:
        """TCP pose as a UR vector ``[x, y, z, rx, ry, rz]``."""
        T = self.frames(q)[-1]
        return (T[0][3], T[1][3], T[2][3], *rotvec_from_rows(T))

    def state(self, q: Sequence[float], qd: Sequence[float]) -> tuple[Vec, Vec, Vec]:
        """(TCP UR vector, TCP speed [v, omega] in the base frame, elbow position)."""
        F = self.frames(q)
        T = F[-1]
        p = (T[0][3], T[1][3], T[2][3])
        vx = vy = vz = wx = wy = wz = 0.0
        for i in range(6):
            Fi = F[i]
            z = (Fi[0][2], Fi[1][2], Fi[2][2])
            r = (p[0] - Fi[0][3], p[1] - Fi[1][3], p[2] - Fi[2][3])
            w = qd[i]
            wx += z[0] * w
            wy += z[1] * w
            wz += z[2] * w
            vx += (z[1] * r[2] - z[2] * r[1]) * w
            vy += (z[2] * r[0] - z[0] * r[2]) * w
            vz += (z[0] * r[1] - z[1] * r[0]) * w
        E = F[3] if self._elbow_dh is None else _chain(self._base, self._elbow_dh, q)[-1]
        elbow = (E[0][3], E[1][3], E[2][3])
        return (*p, *rotvec_from_rows(T)), (vx, vy, vz, wx, wy, wz), elbow

    def fk_vector(self, q: ArrayLike, tcp: ArrayLike | None = None) -> np.ndarray:
        """TCP UR vector of ``q`` (6,), with an optional TCP offset instead of the current one."""
        model = self.model if tcp is None else self.model.with_tool(np.asarray(tcp, dtype=float))
        return ur_vector_from_pose(model.fk(np.asarray(q, dtype=float)))

    # ------------------------------------------------------------ inverse

    def ik_nearest(
        self,
        pose: ArrayLike,
        qnear: ArrayLike,
        *,
        within_limits: bool = True,
    ) -> np.ndarray | None:
        """The IK solution of a UR pose vector nearest ``qnear`` (joint-space distance).

        Each joint is taken as the 2 pi representative nearest ``qnear``; with
        ``within_limits`` solutions outside the joint limits are skipped.
        Returns None when the pose is out of reach.
        """
        T = pose_from_ur_vector(np.asarray(pose, dtype=float))
        return self.ik_nearest_pose(T, qnear, within_limits=within_limits)

    def ik_nearest_pose(
        self, T: np.ndarray, qnear: ArrayLike, *, within_limits: bool = True
    ) -> np.ndarray | None:
        """As :meth:`ik_nearest`, for a 4x4 pose."""
        qn = np.asarray(qnear, dtype=float)
        try:
            sols = self.model.ik(T, q6_seed=float(qn[5]))
        except ValueError:
            return None
        sols = sols[~np.isnan(sols[:, 0])]
        if sols.shape[0] == 0:
            return None
        sols = wrap_near(sols, qn)
        if within_limits:
            ok = np.all((sols >= self.model.lower) & (sols <= self.model.upper), axis=1)
            sols = sols[ok]
            if sols.shape[0] == 0:
                return None
        k = int(np.argmin(np.sum((sols - qn) ** 2, axis=1)))
        return sols[k]

    def ik_path(self, poses: np.ndarray, q0: ArrayLike) -> np.ndarray | None:
        """Joint path following TCP poses (N, 4, 4), each step nearest the previous one.

        The first pose takes the solution nearest ``q0``.  Returns None when a
        pose is out of reach.
        """
        q = np.asarray(q0, dtype=float)
        try:
            sols = self.model.ik(poses, q6_seed=float(q[5]), check=False)
        except ValueError:
            return None
        # fast path: stay on the branch of the first sample (continuous away from
        # singularities); fall back to sample-by-sample nearest solutions otherwise
        first = sols[0][~np.isnan(sols[0][:, 0])]
        if first.shape[0]:
            d = np.sum((wrap_near(sols[0], q) - q) ** 2, axis=1)
            b = int(np.nanargmin(d))
            branch = sols[:, b, :]
            if not np.isnan(branch).any():
                steps = wrap_angle(np.diff(branch, axis=0))
                if steps.size == 0 or float(np.max(np.abs(steps))) < 0.05:
                    start = wrap_near(branch[0], q)
                    return start + np.concatenate([np.zeros((1, 6)), np.cumsum(steps, axis=0)])
        out = np.empty((poses.shape[0], 6))
        for k in range(poses.shape[0]):
            s = sols[k]
            s = s[~np.isnan(s[:, 0])]
            if s.shape[0] == 0:
                return None
            s = wrap_near(s, q)
            q = s[int(np.argmin(np.sum((s - q) ** 2, axis=1)))]
            out[k] = q
        return out
