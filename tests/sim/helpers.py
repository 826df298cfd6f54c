"""Trajectories and references shared by the simulation tests."""

from __future__ import annotations

import numpy as np


def smooth_trajectory(
    duration: float = 3.0, dt: float = 0.002, q0=(0.3, -1.6, 1.4, -1.4, -1.57, 0.0), scale=1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sinusoids on every joint about ``q0``: t (M,), q (M, 6), qd (M, 6).

    Amplitudes 0.15-0.4 rad, periods 4-9 s: peak speeds <= 0.6 rad/s (a third
    of the UR5e limit), accelerations <= 0.6 rad/s^2 (below the 1.4 default).
    """
    t = np.arange(round(duration / dt) + 1) * dt
    amp = scale * np.array([0.4, 0.25, 0.3, 0.4, 0.3, 0.4])
    w = 2 * np.pi / np.array([6.0, 7.0, 5.0, 8.0, 4.0, 9.0])
    q = np.asarray(q0) + amp * np.sin(np.outer(t, w))
    qd = amp * w * np.cos(np.outer(t, w))
    return t, q, qd


def wire_pose(centre, shift_along_wire: float = 0.0, height: float = 0.0) -> np.ndarray:
    """TCP pose (4, 4) putting the middle of a wire along the flange x axis at ``centre``
    (+ ``shift_along_wire`` along it, + ``height`` up), wire along world y, flange above
    the wire (flange z pointing down)."""
    T = np.eye(4)
    T[:3, 0] = [0.0, 1.0, 0.0]
    T[:3, 1] = [1.0, 0.0, 0.0]
    T[:3, 2] = [0.0, 0.0, -1.0]
    T[:3, 3] = np.asarray(centre, dtype=float) + np.array([0.0, shift_along_wire, height])
    return T


def cartesian_move(robot, P0, P1, duration: float = 2.0, dt: float = 0.002, q_start=None):
    """Straight-line TCP motion P0 -> P1 (same orientation) with a quintic time law:
    t (M,), q (M, 6) from the robot layer's path IK."""
    t = np.arange(round(duration / dt) + 1) * dt
    s = t / duration
    s = 10 * s**3 - 15 * s**4 + 6 * s**5
    P = np.repeat(np.asarray(P0, dtype=float)[None], t.size, axis=0)
    P[:, :3, 3] = (1 - s)[:, None] * P0[:3, 3] + s[:, None] * P1[:3, 3]
    res = robot.path_ik(P, q_start=q_start)
    assert res.all_ok, res.messages
    return t, res.q
