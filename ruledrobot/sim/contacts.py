"""Contacts in a MuJoCo playback: collision events between geoms, the wire in the stock.

Contacts are detected, not simulated (see :mod:`.playback`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..robot.arm.model import RobotModel
from ..robot.wire.in_stock import chord_fractions, flange_wire_ends
from .scene import BowTool

__all__ = ["Collision", "ProgressCallback"]

#: ``progress(fraction, stage)``: fraction of the work done in [0, 1], stage name.
ProgressCallback = Callable[[float, str], None]


@dataclass(frozen=True)
class Collision:
    """A contact event: two geoms touching over ``[start, end]`` (s, sample times).

    ``depth`` is the deepest penetration seen [m] (>= 0).  Bodies are the
    MuJoCo bodies of the geoms (``link3``, ``bow``, ``world`` for the table and
    the stock).
    """

    start: float
    end: float
    geom1: str
    geom2: str
    body1: str
    body2: str
    depth: float

    def as_dict(self) -> dict[str, Any]:
        """The event for a report.

        ``start_s``, ``end_s`` [s], the geom and body names, and ``max_depth_mm`` the deepest
        penetration [mm]."""
        return {
            "start_s": self.start,
            "end_s": self.end,
            "geom1": self.geom1,
            "geom2": self.geom2,
            "body1": self.body1,
            "body2": self.body2,
            "max_depth_mm": self.depth * 1e3,
        }


def _geom_reach(mj: Any, m: Any, robot: RobotModel) -> FloatArray:
    """(ngeom, J) upper bounds of the distance of each geom's points from joint j's axis
    [m]; 0 where joint j does not move the geom (static geoms: all 0).

    A geom of a body moved by joints 1..k lies within ``r_g`` (its distance
    from that body's origin plus its bounding radius) of the origin of link k,
    and link k's origin lies within ``sum_{i=j..k-1} |a_i| + |d_i|`` of joint
    j's axis.
    """
    J = robot.n_joints
    d = mj.MjData(m)
    mj.mj_kinematics(m, d)
    jbody = np.asarray(m.jnt_bodyid[:J])  # body of joint j
    link_of_body = np.full(m.nbody, -1)
    for b in range(1, m.nbody):  # walk up to the nearest body with a joint
        a = b
        while a > 0 and a not in jbody:
            a = int(m.body_parentid[a])
        link_of_body[b] = int(np.flatnonzero(jbody == a)[0]) if a > 0 else -1
    lengths = np.abs(robot.a) + np.abs(robot.d)
    csum = np.concatenate([[0.0], np.cumsum(lengths)])
    out = np.zeros((m.ngeom, J))
    for g in range(m.ngeom):
        k = link_of_body[int(m.geom_bodyid[g])]
        if k < 0:
            continue
        origin = d.xpos[jbody[k]]
        r_g = float(np.linalg.norm(d.geom_xpos[g] - origin) + m.geom_rbound[g])
        j = np.arange(k + 1)
        out[g, : k + 1] = csum[k] - csum[j] + r_g
    return out


def _detect_collisions(
    mj: Any,
    m: Any,
    t: FloatArray,
    q: FloatArray,
    stride: int,
    reach: FloatArray,
    progress: ProgressCallback | None,
) -> tuple[Collision, ...]:
    """Contact events of the motion q (M, J), exact at every sample.

    A coarse pass checks every ``stride``-th sample with each geom's margin
    set to twice the largest distance its points can travel between two
    checked samples (``sum_j |dq_j| R_gj``, R from :func:`_geom_reach`): a pair
    penetrating at some sample between two checks is then within the margin
    at one of them.  Only the samples next to such near contacts are checked
    again, with the model's margins, one by one.
    """
    n, J = q.shape
    m.opt.disableflags &= ~int(mj.mjtDisableBit.mjDSBL_CONTACT)
    d = mj.MjData(m)
    margin0 = m.geom_margin.copy()
    hits: list[tuple[int, int, int, float]] = []
    try:
        checks = np.unique(np.append(np.arange(0, n, stride), n - 1))
        if stride > 1 and checks.size > 1:
            path = np.concatenate([np.zeros((1, J)), np.cumsum(np.abs(np.diff(q, axis=0)), 0)])
            travel = path[checks[1:]] - path[checks[:-1]]  # (windows, J) joint travel
            disp = (travel @ reach.T).max(axis=0)  # (ngeom,) largest geom travel
            m.geom_margin[:] = np.maximum(margin0, 2.05 * disp + 1e-6 * (disp > 0))
            near = np.zeros(n, dtype=bool)
            for i, k in enumerate(checks):  # coarse pass over the simulation steps
                d.qpos[:J] = q[k]
                mj.mj_kinematics(m, d)
                mj.mj_collision(m, d)
                if d.ncon:
                    near[max(0, k - stride) : k + stride + 1] = True
                if progress is not None and i % 500 == 0:
                    progress(0.8 + 0.1 * i / checks.size, "collisions")
            m.geom_margin[:] = margin0
            samples = np.flatnonzero(near)
        else:
            samples = np.arange(n)
        for i, k in enumerate(samples):  # exact pass where something came near
            d.qpos[:J] = q[k]
            mj.mj_kinematics(m, d)
            mj.mj_collision(m, d)
            nc = d.ncon
            if nc:
                con = d.contact
                for g1, g2, dist in zip(con.geom1[:nc], con.geom2[:nc], con.dist[:nc], strict=True):
                    hits.append((int(k), int(g1), int(g2), float(dist)))
            if progress is not None and i % 2000 == 0:
                progress(0.9 + 0.1 * i / max(samples.size, 1), "collisions")
    finally:
        m.geom_margin[:] = margin0
    return _events(mj, m, t, hits, 1)


def _events(
    mj: Any, m: Any, t: FloatArray, hits: list[tuple[int, int, int, float]], stride: int
) -> tuple[Collision, ...]:
    """Merge per-sample contacts into events per geom pair (gaps of one check allowed)."""
    by_pair: dict[tuple[int, int], list[tuple[int, float]]] = {}
    for k, g1, g2, dist in hits:
        key = (min(g1, g2), max(g1, g2))
        by_pair.setdefault(key, []).append((k, dist))
    out: list[Collision] = []

    def name(obj: int, i: int) -> str:
        nm = mj.mj_id2name(m, obj, i)
        return nm if nm else f"#{i}"

    geom_t = int(mj.mjtObj.mjOBJ_GEOM)
    body_t = int(mj.mjtObj.mjOBJ_BODY)
    for (g1, g2), samples in by_pair.items():
        start = prev = samples[0][0]
        depth = max(0.0, -samples[0][1])
        spans: list[tuple[int, int, float]] = []
        for k, dist in samples[1:]:
            if k - prev > stride:
                spans.append((start, prev, depth))
                start, depth = k, 0.0
            prev = k
            depth = max(depth, -dist)
        spans.append((start, prev, depth))
        b1, b2 = int(m.geom_bodyid[g1]), int(m.geom_bodyid[g2])
        for k0, k1, dep in spans:
            out.append(
                Collision(
                    start=float(t[k0]),
                    end=float(t[k1]),
                    geom1=name(geom_t, g1),
                    geom2=name(geom_t, g2),
                    body1=name(body_t, b1),
                    body2=name(body_t, b2),
                    depth=dep,
                )
            )
    out.sort(key=lambda c: (c.start, c.geom1, c.geom2))
    return tuple(out)


def _wire(
    robot: RobotModel, tool: BowTool, stock: Box | None, q: FloatArray
) -> tuple[FloatArray, FloatArray | None]:
    """Wire ends (M, 2, 3) in the base frame and the wire length inside the stock (M,) [m]
    (:func:`~ruledrobot.robot.wire.in_stock.chord_fractions`: 0 where it only touches)."""
    flange = dataclasses.replace(robot, base=np.eye(4), tool=np.eye(4)).fk(q)
    wire = flange_wire_ends(flange, tool)
    if stock is None:
        return wire, None
    lo, hi = chord_fractions(wire, stock)  # the planner's model: a touch is not inside
    return wire, np.nan_to_num(hi - lo) * tool.wire_length
