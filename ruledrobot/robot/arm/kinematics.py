"""Forward kinematics and the geometric Jacobian of a standard-DH serial chain.

Convention (classic / standard Denavit-Hartenberg, as Universal Robots publish
their tables): the transform from frame ``i-1`` to frame ``i`` is ::

    A_i(q_i) = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i),   theta_i = q_i + theta_offset_i

and the flange pose in the robot base frame is ``A_1 A_2 ... A_n``.  Joint ``i``
turns about the z axis of frame ``i-1``.

:class:`DHChain` (the table, the base and the tool) gives the poses, the Jacobian and
the skeleton of joint positions.  They work on *component arrays*: the three axes and the origin of
the running frame are kept as 12 arrays of shape ``(n,)`` and updated in
closed form per joint (a loop over the joints, never over poses), which is
cheaper than ``n`` batched 4x4 matrix products and keeps every intermediate
contiguous.  Long batches are processed in cache-sized chunks.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from .._checks import FloatArray

_CHUNK = 8192  # poses per chunk: ~30 component arrays of 64 kB stay in L2

Frame = tuple[list, list, list, list]  # x, y, z, p; each a list of 3 arrays or floats


def _start_frame(base: FloatArray) -> Frame:
    """Component form of a constant 4x4 pose (columns x, y, z, origin)."""
    return (
        [float(base[0, 0]), float(base[1, 0]), float(base[2, 0])],
        [float(base[0, 1]), float(base[1, 1]), float(base[2, 1])],
        [float(base[0, 2]), float(base[1, 2]), float(base[2, 2])],
        [float(base[0, 3]), float(base[1, 3]), float(base[2, 3])],
    )


def _snap(v: float) -> float:
    """cos/sin of a DH twist: exact 0 and +-1 where the angle is a multiple of pi/2."""
    if abs(v) < 1e-15:
        return 0.0
    if abs(abs(v) - 1.0) < 1e-15:
        return float(np.copysign(1.0, v))
    return v


def _joint_step(
    frame: Frame, c: FloatArray, s: FloatArray, d: float, a: float, ca: float, sa: float
) -> Frame:
    """Apply ``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` (c, s = cos, sin theta) to a frame."""
    x, y, z, p = frame
    xr = [c * x[k] + s * y[k] for k in range(3)]
    yr = [c * y[k] - s * x[k] for k in range(3)]
    if sa == 0.0:
        yn = yr if ca == 1.0 else [ca * v for v in yr]
        zn = z if ca == 1.0 else [ca * v for v in z]
    elif ca == 0.0:
        yn = z if sa == 1.0 else [sa * v for v in z]
        zn = [-v for v in yr] if sa == 1.0 else [-sa * v for v in yr]
    else:
        yn = [ca * yr[k] + sa * z[k] for k in range(3)]
        zn = [ca * z[k] - sa * yr[k] for k in range(3)]
    pn = list(p)
    if d != 0.0:
        pn = [pn[k] + d * z[k] for k in range(3)]
    if a != 0.0:
        pn = [pn[k] + a * xr[k] for k in range(3)]
    return xr, yn, zn, pn


def _apply_tool(frame: Frame, tool: FloatArray) -> Frame:
    """Right-multiply the frame by a constant pose ``tool`` (flange -> TCP)."""
    x, y, z, p = frame
    cols = []
    for j in range(3):
        cols.append([tool[0, j] * x[k] + tool[1, j] * y[k] + tool[2, j] * z[k] for k in range(3)])
    t = tool[:3, 3]
    pn = [p[k] + t[0] * x[k] + t[1] * y[k] + t[2] * z[k] for k in range(3)]
    return cols[0], cols[1], cols[2], pn


def _write_pose(frame: Frame, out: FloatArray) -> None:
    """Write a component frame into ``out`` of shape (n, 4, 4)."""
    x, y, z, p = frame
    flat = out.reshape(-1, 16)
    for r in range(3):
        flat[:, 4 * r + 0] = x[r]
        flat[:, 4 * r + 1] = y[r]
        flat[:, 4 * r + 2] = z[r]
        flat[:, 4 * r + 3] = p[r]
    flat[:, 12:15] = 0.0
    flat[:, 15] = 1.0


def _chain(
    q: FloatArray, alpha: FloatArray, theta_offset: FloatArray, base: FloatArray | None
) -> tuple[FloatArray, FloatArray, list[tuple[float, float]], Frame]:
    """What every pass along the chain needs: cos and sin of the joint angles (J, n),
    contiguous rows per joint; (cos, sin) of each DH twist; the start frame (the base)."""
    theta = np.ascontiguousarray((q + theta_offset).T)
    twists = [(_snap(float(np.cos(al))), _snap(float(np.sin(al)))) for al in alpha]
    return np.cos(theta), np.sin(theta), twists, _start_frame(np.eye(4) if base is None else base)


def _walk(
    frame: Frame,
    ct: FloatArray,
    st: FloatArray,
    d: FloatArray,
    a: FloatArray,
    twists: list[tuple[float, float]],
    rows: slice = slice(None),
    before: list[Frame] | None = None,
) -> Frame:
    """The frame after the last joint, from ``frame`` before joint 1; ``rows`` the poses
    (columns of ``ct``, ``st``) of this pass; ``before``, when given, gets the frame before
    each joint."""
    for j, (ca, sa) in enumerate(twists):
        if before is not None:
            before.append(frame)
        frame = _joint_step(frame, ct[j, rows], st[j, rows], float(d[j]), float(a[j]), ca, sa)
    return frame


def _broadcast(frame: Frame, n: int) -> Frame:
    """Frame components as arrays of length n (a joint-free chain keeps floats)."""
    return tuple([np.broadcast_to(v, (n,)) for v in vec] for vec in frame)  # type: ignore[return-value]


@dataclass(frozen=True, eq=False)
class DHChain:
    """A standard-DH serial chain placed in the world: its table, base and tool.

    Attributes
    ----------
    table : the DH parameters ``(d, a, alpha, theta_offset)``, (J,) each [m, m, rad, rad].
    base : optional 4x4 pose of the robot base in the world frame (None: the identity).
    tool : optional 4x4 pose of the TCP in the flange frame (None: the flange).
    """

    table: tuple[FloatArray, ...]
    base: FloatArray | None = None
    tool: FloatArray | None = None

    def fk(self, q: FloatArray) -> FloatArray:
        """Return the TCP poses (n, 4, 4) of joint positions ``q`` (n, J) [rad].

        ``q`` is already validated; ``base @ A_1(q_1) ... A_J(q_J) @ tool``.
        """
        n = q.shape[0]
        out = np.empty((n, 4, 4))
        for rows, frame, _ in self._walks(q):
            _write_pose(_broadcast(frame, rows.stop - rows.start), out[rows])
        return out

    def jacobian(self, q: FloatArray) -> FloatArray:
        """Geometric Jacobian (n, 6, J) at the TCP of joint positions ``q`` (n, J) [rad].

        Rows ``[v; omega]`` in the world frame: linear velocity of the TCP point [m/s], then
        angular velocity [rad/s] (UR's speedl order ``[xd, yd, zd, wx, wy, wz]``); column
        ``i`` = ``[z_{i-1} x (p_tcp - p_{i-1}); z_{i-1}]`` for revolute joint ``i``.
        """
        n, J = q.shape
        out = np.empty((n, 6, J))
        for rows, frame, before in self._walks(q, axes=True):
            pe = frame[3]
            blk = out[rows]
            for j, f in enumerate(before):  # z_{j}, p_{j} of the frame before joint j+1
                z, p = f[2], f[3]
                rx, ry, rz = pe[0] - p[0], pe[1] - p[1], pe[2] - p[2]
                blk[:, 0, j] = z[1] * rz - z[2] * ry
                blk[:, 1, j] = z[2] * rx - z[0] * rz
                blk[:, 2, j] = z[0] * ry - z[1] * rx
                blk[:, 3, j] = z[0]
                blk[:, 4, j] = z[1]
                blk[:, 5, j] = z[2]
        return out

    def skeleton(self, q: FloatArray) -> FloatArray:
        """The DH skeleton of configurations ``q`` (n, J): points (n, 2J + 1, 3) [m].

        Point 0 is the base origin; joint ``i`` adds the point ``d_i`` along the previous
        z axis and then its frame origin (``a_i`` along x_i), with the joint step of
        :meth:`fk`.  The tool plays no part.
        """
        n = q.shape[0]
        d, a, alpha, theta_offset = self.table
        ct, st, twists, start = _chain(q, alpha, theta_offset, self.base)
        frames: list[Frame] = []
        frames.append(_walk(start, ct, st, d, a, twists, before=frames))  # J + 1 frames
        pts = [start[3]]
        for j in range(len(twists)):
            p, z = frames[j][3], frames[j][2]
            pts.append([p[k] + float(d[j]) * z[k] for k in range(3)])
            pts.append(frames[j + 1][3])
        out = np.empty((n, len(pts), 3))
        for i, pt in enumerate(pts):
            for k in range(3):
                out[:, i, k] = pt[k]
        return out

    def _walks(
        self, q: FloatArray, axes: bool = False
    ) -> Iterator[tuple[slice, Frame, list[Frame]]]:
        """Per chunk of poses: its rows, the TCP frame and (with ``axes``) the frame before
        each joint (else an empty list)."""
        n = q.shape[0]
        d, a, alpha, theta_offset = self.table
        ct, st, twists, start = _chain(q, alpha, theta_offset, self.base)
        for lo in range(0, n, _CHUNK):
            hi = min(lo + _CHUNK, n)
            rows = slice(lo, hi)
            before: list[Frame] = []
            first = _broadcast(start, hi - lo) if axes else start
            frame = _walk(first, ct, st, d, a, twists, rows, before if axes else None)
            if self.tool is not None:
                frame = _apply_tool(frame, self.tool)
            yield rows, frame, before
