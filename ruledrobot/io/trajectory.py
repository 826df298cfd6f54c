"""Joint trajectory files: CSV ``t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz``.

One row per controller period (500 Hz on e-Series, 125 Hz on CB3): time from
the start (s), joint positions (rad), TCP pose in the robot base frame as a UR
pose vector (m, rotation vector in rad).  Lines starting with ``#`` are
comments (the writer records the robot model and period there).
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..geometry._arrays import FloatArray, as_float_array
from ..geometry.se3 import pose_from_ur_vector, ur_vector_from_pose
from .atomic import atomic_write_text
from .text import read_user_text

__all__ = ["HEADER", "Trajectory", "read_trajectory", "write_trajectory"]

HEADER = ["t", "q1", "q2", "q3", "q4", "q5", "q6", "x", "y", "z", "rx", "ry", "rz"]


@dataclass(frozen=True)
class Trajectory:
    """A sampled joint trajectory: ``t`` (M,) s, ``q`` (M, 6) rad, ``tcp`` (M, 6) UR vectors."""

    t: FloatArray
    q: FloatArray = field(repr=False)
    tcp: FloatArray = field(repr=False)
    comments: tuple[str, ...] = ()

    @property
    def period(self) -> float:
        """The median sampling period (s)."""
        return float(np.median(np.diff(self.t))) if self.t.size > 1 else 0.0

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if self.t.size else 0.0

    def tcp_poses(self) -> FloatArray:
        """TCP poses (M, 4, 4)."""
        return pose_from_ur_vector(self.tcp)


def write_trajectory(
    path: str | os.PathLike[str],
    t: ArrayLike,
    q: ArrayLike,
    tcp: ArrayLike,
    comments: tuple[str, ...] | list[str] = (),
) -> Path:
    """Write a trajectory CSV atomically.  ``tcp``: (M, 4, 4) poses or (M, 6) UR vectors."""
    t = as_float_array(t, "t")
    q = as_float_array(q, "q", (6,))
    tcp = np.asarray(tcp, dtype=np.float64)
    if tcp.shape[-2:] == (4, 4):
        tcp = ur_vector_from_pose(tcp)
    tcp = as_float_array(tcp, "tcp", (6,))
    if t.ndim != 1 or q.shape[0] != t.size or tcp.shape[0] != t.size:
        raise ValueError(
            f"trajectory: t {t.shape}, q {q.shape} and tcp {tcp.shape} must have the same length"
        )
    if t.size > 1 and np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        raise ValueError(f"t[{k}]: times must increase strictly")
    buf = io.StringIO()
    for c in comments:
        buf.write(f"# {c}\n")
    buf.write(",".join(HEADER) + "\n")
    data = np.concatenate([t[:, None], q, tcp], axis=1)
    np.savetxt(buf, data, delimiter=",", fmt="%.10g")
    return atomic_write_text(path, buf.getvalue())


def read_trajectory(path: str | os.PathLike[str]) -> Trajectory:
    """Read a trajectory CSV; ValueError names the file and line of any problem."""
    p, text = read_user_text(path, "trajectory file")
    comments: list[str] = []
    rows: list[list[float]] = []
    header_seen = False
    for lineno, raw in enumerate(text.splitlines(), start=1):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#"):
            comments.append(s[1:].strip())
            continue
        cells = [c.strip() for c in s.split(",")]
        if not header_seen:
            if [c.lower() for c in cells] != HEADER:
                raise ValueError(f"{p}: line {lineno}: expected the header {','.join(HEADER)}")
            header_seen = True
            continue
        if len(cells) != len(HEADER):
            raise ValueError(f"{p}: line {lineno}: expected {len(HEADER)} values, got {len(cells)}")
        try:
            values = [float(c) for c in cells]
        except ValueError:
            raise ValueError(f"{p}: line {lineno}: not a number in {s!r}") from None
        if not np.all(np.isfinite(values)):
            raise ValueError(f"{p}: line {lineno}: contains NaN or infinity")
        if rows and values[0] <= rows[-1][0]:
            raise ValueError(f"{p}: line {lineno}: time {values[0]} does not increase")
        rows.append(values)
    if not header_seen:
        raise ValueError(f"{p}: empty file; expected the header {','.join(HEADER)}")
    if not rows:
        raise ValueError(f"{p}: no samples after the header")
    data = np.asarray(rows)
    return Trajectory(data[:, 0], data[:, 1:7], data[:, 7:], tuple(comments))
