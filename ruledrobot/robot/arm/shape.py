"""The arm's physical shape: joint housings and link tubes per link body, and where
they are for batches of configurations.

One description for the MuJoCo model (:mod:`ruledrobot.sim.mjcf` builds its geoms
from it) and the planner's clearance checks (capsules on the same segments), so
that what the planner keeps clear is what the simulation tests.

Body ``k`` (0-based) is the link that joint ``k + 1`` turns: its frame is DH frame
``k`` - 1 turned by ``Rz(q_k + theta_offset_k)``; its segments run along its DH path
``origin -> Tz(d) -> Tx(a)``.  UR-structure arms get the real arm's side offset:
the upper arm runs ``d2 + d3 + d4`` along the shoulder axis (on the real UR the DH
plane holds the forearm), and the shoulder and elbow housings span that offset.
Lengths in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.checks import FloatArray
from ...geometry.se3 import transform_points
from .model import RobotModel

__all__ = [
    "Segment",
    "arm_capsules",
    "body_frames",
    "dh_tail",
    "link_radii",
    "link_segments",
    "rot_z",
]


def link_radii(model: RobotModel) -> FloatArray:
    """Joint-housing radius per joint [m] (J,), from the torque limits (UR-like proportions).

    ``r = 0.0185 m * (tau_max / 1 N m)^(1/4)``, clipped to [0.015, 0.12] m
    (UR5e: 0.065 m shoulder, 0.043 m wrists; UR10e: 0.079 / 0.050 m).  Arms
    without torque limits get 4.5 % of the summed DH lengths on every joint.
    """
    tau = model.max_torque
    if np.all(np.isfinite(tau)):
        return np.clip(0.0185 * tau**0.25, 0.015, 0.12)
    length = float(np.sum(np.abs(model.a)) + np.sum(np.abs(model.d)))
    return np.full(model.n_joints, float(np.clip(0.045 * length, 0.01, 0.12)))


@dataclass(frozen=True)
class Segment:
    """A primitive of a link, in its body frame.

    A ``kind`` ("capsule" or "cylinder") from ``a`` to ``b`` (3,) [m] of ``radius`` [m];
    ``part`` "joint" (a housing) or "link" (a tube)."""

    kind: str
    a: FloatArray
    b: FloatArray
    radius: float
    part: str


def rot_z(angle: float) -> FloatArray:
    """``Rz(angle)`` as a pose (4, 4)."""
    c, s = math.cos(angle), math.sin(angle)
    T = np.eye(4)
    T[0, 0], T[0, 1], T[1, 0], T[1, 1] = c, -s, s, c
    return T


def dh_tail(d: float, a: float, alpha: float) -> FloatArray:
    """``Tz(d) Tx(a) Rx(alpha)`` (4, 4): from the body frame of link i to DH frame i."""
    c, s = math.cos(alpha), math.sin(alpha)
    # exact values at multiples of pi/2 (the UR twists), like the robot layer's FK
    c = 0.0 if abs(c) < 1e-15 else c
    s = 0.0 if abs(s) < 1e-15 else s
    T = np.eye(4)
    T[1, 1], T[1, 2], T[2, 1], T[2, 2] = c, -s, s, c
    T[0, 3], T[2, 3] = a, d
    return T


def link_segments(
    model: RobotModel, radii: FloatArray | None = None
) -> tuple[list[list[Segment]], float]:
    """Primitive geometry per link body (in the body frame) and the base height [m].

    Each body gets a joint housing (cylinder along its z axis) and tubes
    along its DH path ``origin -> Tz(d) -> Tx(a)``.  UR-structure arms get
    the real arm's side offset: the upper arm runs at ``z = d2 + d3 + d4`` along
    the shoulder axis (as on the real UR, where the DH plane holds the
    forearm), and the shoulder and elbow housings span that offset.
    """
    radii = link_radii(model) if radii is None else radii
    n = model.n_joints
    ur = model.has_analytic_ik
    shoulder = float(model.d[1] + model.d[2] + model.d[3]) if ur else 0.0
    d1 = float(model.d[0])
    base_h = max(0.02, 0.5 * abs(d1))
    out: list[list[Segment]] = []
    for k in range(n):
        r = float(radii[k])
        tube = 0.8 * r
        d, a = float(model.d[k]), float(model.a[k])
        segs: list[Segment] = []
        z0, z1 = -0.9 * r, 0.9 * r
        if ur and k in (1, 2):
            z0, z1 = min(0.0, shoulder) - 0.9 * r, max(0.0, shoulder) + 0.9 * r
        if k == 0:
            # the column above the base; its housing is the base's top
            top = math.copysign(base_h + 0.002, d1) if d1 != 0.0 else 0.0
            if abs(d1) > abs(top) + 0.004:
                segs.append(
                    Segment(
                        "cylinder", np.array([0, 0, top]), np.array([0, 0, d1]), r, "link"
                    )
                )
        else:
            segs.append(
                Segment("cylinder", np.array([0, 0, z0]), np.array([0, 0, z1]), r, "joint")
            )
            if abs(d) > 1e-9:
                kind = "cylinder" if k == n - 1 else "capsule"
                segs.append(
                    Segment(
                        kind,
                        np.zeros(3),
                        np.array([0, 0, d]),
                        r if k == n - 1 else tube,
                        "link",
                    )
                )
        if abs(a) > 1e-9:
            z = shoulder if (ur and k == 1) else d
            segs.append(
                Segment("capsule", np.array([0, 0, z]), np.array([a, 0, z]), tube, "link")
            )
        out.append(segs)
    return out, base_h


def body_frames(model: RobotModel, q: ArrayLike) -> FloatArray:
    """Return the world poses (n, J, 4, 4) of the link bodies at configurations ``q`` (n, J).

    On the model's nominal table (the links' shape; a calibration moves them by millimetres)
    and with its base.
    """
    q = np.asarray(q, dtype=np.float64).reshape(-1, model.n_joints)
    nom = model.nominal
    n, J = q.shape
    out = np.empty((n, J, 4, 4))
    T = np.broadcast_to(nom.base, (n, 4, 4)).copy()
    theta = q + nom.theta_offset
    c, s = np.cos(theta), np.sin(theta)
    for k in range(J):
        R = np.zeros((n, 4, 4))
        R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1] = c[:, k], -s[:, k], s[:, k], c[:, k]
        R[:, 2, 2] = R[:, 3, 3] = 1.0
        B = T @ R
        out[:, k] = B
        T = B @ dh_tail(float(nom.d[k]), float(nom.a[k]), float(nom.alpha[k]))
    return out


def arm_capsules(
    model: RobotModel, q: ArrayLike
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Return the link segments as capsules in the world at configurations ``q`` (..., J).

    The segments of :func:`link_segments`: end points (..., S, 2, 3) [m], radii (S,) [m] and
    the body index (S,) of each (0 = the column over the base).
    """
    q = np.asarray(q, dtype=np.float64)
    shape = q.shape[:-1]
    segs, _ = link_segments(model.nominal)
    B = body_frames(model, q.reshape(-1, model.n_joints))  # (n, J, 4, 4)
    body = np.array([k for k, ss in enumerate(segs) for _ in ss], dtype=np.intp)
    radius = np.array([sg.radius for ss in segs for sg in ss], dtype=np.float64)
    ends = np.empty((len(B), len(body), 2, 3))
    i = 0
    for k, ss in enumerate(segs):  # a body's segments in its frame (no (n, S, 4, 4) gather)
        if ss:
            local = np.array([[sg.a, sg.b] for sg in ss], dtype=np.float64)  # (S_k, 2, 3)
            ends[:, i : i + len(ss)] = transform_points(B[:, k, None], local)
            i += len(ss)
    return ends.reshape(*shape, len(body), 2, 3), radius, body
