"""Corners of a pass: where the wire's travel turns sharply, it stops.

A foam cutter's program is a polygon of straight tower moves whose corners are
meant: the entry into the block, an airfoil's trailing edge (the wire goes out
along the upper surface and comes back along the lower one), the exit.  Refined
along its own polygon (the ``linear`` scheme, the default for G-code), the path
keeps them.  No arm can carry the wire through a kink at the feed — the direction
of travel would change in no time, an unbounded acceleration — and a CNC foam
cutter does not either: it slows to a stop there.  Timed as one piece, the time
law passes a kink at a reduced but finite speed and the sampled trajectory cuts
the corner (the wire leaves the surface, the measured feed jumps).

So a pass is timed **between its corners**, every piece from rest to rest
(:func:`time_between_corners`), with a wait of :data:`CORNER_DWELL` at a corner inside
the stock (the arm under servoj settles on the corner before it turns), and the samples
of the slow-down, the wait and the speed-up at a corner inside the stock are the
**corner stops** (:func:`corner_stop_mask`): the
verdict's lowest feed is measured outside them, the report counts them (the kerf
is wider where the wire stops).  The wire's deviation is checked everywhere.

A node is a corner when the travel of either wire point ``o ± (L/2) z`` (``o`` the
frame origin, anchored nearest the stock centre; ``L`` the wire length) turns by
more than :data:`CORNER_ANGLE` between the steps before and after it.  On a
refined smooth surface the turn per node is a fraction of a degree (the demo's at
most 0.1 degree); the corners of a polygon keep their full angle.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from itertools import pairwise

import numpy as np

from ...geometry.checks import FloatArray
from ...geometry.lines import point_nearest_origin
from ...robot.motion.servo import servo_settle_time
from .timing import TimedPath, concatenate, dwell, time_path

__all__ = [
    "CORNER_ANGLE",
    "CORNER_DWELL",
    "CORNER_JOIN",
    "corner_dwell",
    "corner_nodes",
    "corner_stop_mask",
    "polygon_corners",
    "time_between_corners",
]

#: Turn of the wire's travel [rad] above which a node is a corner where the wire stops.
CORNER_ANGLE = np.radians(30.0)
#: s: the wait at a corner stop in the stock: the arm under servoj trails its command by
#: the servo's time constant and creeps on after the command stops; turning before it
#: settles rounds the corner (a 40 degree corner at 20 mm/s without the wait: 0.5 mm,
#: face_error 0.32 mm on the emulator); the default servo's settle time, 0.5 s
CORNER_DWELL = servo_settle_time()
#: s: two slow runs of the joints less than this apart are one approach to a corner stop
#: (:func:`corner_stop_mask`).  Before a concave corner the chord ends are re-spaced
#: towards the offset profile's corner point by different factors (docs/kerf.md, "Sharp
#: corners"), a kink of the wire's rigid motion a few samples before the stop: the time
#: law slows there (tapered profile: 6.9 mm/s against 8), is let back to the feed for a
#: sample, then stops.  That slow-down is the corner's own (its offset makes it) and the
#: wire never holds the feed in between, so it is counted with the stop (the kerf's
#: compensation at the stop is the heat schedule's, as for the stop itself).
CORNER_JOIN = 0.02


def corner_nodes(frames: FloatArray, half_length: float, angle: float = CORNER_ANGLE) -> np.ndarray:
    """Return the interior nodes of a pass where the wire's travel turns more than ``angle``.

    Indices (K,); ``angle`` [rad] (see the module doc).  ``frames`` (M, 4, 4),
    ``half_length`` [m].
    """
    F = np.asarray(frames, dtype=np.float64)
    return _turning(F[:, :3, 3], F[:, :3, 2], half_length, angle)


def polygon_corners(
    plucker: FloatArray, centre: FloatArray, half_length: float, angle: float = CORNER_ANGLE
) -> np.ndarray:
    """Return the corners of a foam cutter's polygon of moves (:func:`corner_nodes` of lines).

    Lines (N, 6) (Plücker ``[l, m]``), each taken at its point nearest ``centre`` (3,) [m]:
    the corners are where refinement splits the polygon (:func:`~..cut.passes.refine_cut`).
    """
    L = np.asarray(plucker, dtype=np.float64)
    L = L / np.linalg.norm(L[:, :3], axis=1, keepdims=True)
    z, p0 = L[:, :3], point_nearest_origin(L)
    o = p0 + ((np.asarray(centre, dtype=np.float64) - p0) * z).sum(axis=1)[:, None] * z
    return _turning(o, z, half_length, angle)


def _turning(o: FloatArray, z: FloatArray, half_length: float, angle: float) -> np.ndarray:
    if o.shape[0] < 3:
        return np.zeros(0, dtype=np.int64)
    turn = np.zeros(o.shape[0] - 2)
    for sign in (-1.0, 1.0):
        d = np.diff(o + sign * half_length * z, axis=0)
        n = np.linalg.norm(d, axis=1)
        moving = (n[:-1] > 1e-9) & (n[1:] > 1e-9)
        cos = (d[:-1] * d[1:]).sum(axis=1) / np.maximum(n[:-1] * n[1:], 1e-300)
        a = np.arccos(np.clip(cos, -1.0, 1.0))
        turn = np.maximum(turn, np.where(moving, a, 0.0))
    return np.flatnonzero(turn > angle) + 1


def time_between_corners(
    s: FloatArray,
    q: FloatArray,
    speed_factor: FloatArray | Callable[[int, int], FloatArray],
    feed_speed: float,
    vel_limits: FloatArray,
    acc_limits: FloatArray,
    dt: float,
    corners: np.ndarray,
) -> TimedPath:
    """Time the pass in pieces split at ``corners``, each from rest to rest, joined.

    :func:`~.timing.time_path` of each piece between ``corners`` (node indices), joined by
    :func:`~.timing.concatenate` (``s_of_t`` stays the pass's parameter).  Without corners,
    the pass in one piece.

    ``speed_factor``: (N,) for the whole pass, or a function of a piece's first and last
    node giving its own (so that its differences never reach across a corner, where a
    central difference of two directions would take the wire's speed for less than it
    is: 0.7 of it at a right angle)."""
    cuts = [0, *(int(c) for c in corners), len(s) - 1]

    def factor(a: int, b: int) -> FloatArray:
        return speed_factor(a, b) if callable(speed_factor) else speed_factor[a : b + 1]

    timed = [
        time_path(s[a : b + 1], q[a : b + 1], factor(a, b), feed_speed,
                  vel_limits, acc_limits, dt)
        for a, b in pairwise(cuts)
    ]  # fmt: skip
    parts = [timed[0]]
    for before, after in pairwise(timed):
        if before.feed_limited[-1] or after.feed_limited[0]:  # a stop in the stock
            parts.append(corner_dwell(before, vel_limits, acc_limits, dt))
        parts.append(after)
    return parts[0] if len(parts) == 1 else concatenate(parts, dt)


def corner_dwell(before: TimedPath, vel_limits: FloatArray, acc_limits: FloatArray,
                 dt: float, duration: float = CORNER_DWELL) -> TimedPath:  # fmt: skip
    """Return the wait at a corner stop in the stock.

    ``before``'s last pose held ``duration`` s, on its path parameter, a corner stop's
    samples (``feed_limited``)."""
    d = dwell(before.q[-1], duration, vel_limits, acc_limits, dt)
    return dataclasses.replace(d, s_of_t=np.full(d.t.size, before.s_of_t[-1]),
                               feed_limited=np.ones(d.t.size, dtype=bool))  # fmt: skip


def corner_stop_mask(timed: TimedPath, s_corners: FloatArray, join: int = 0) -> np.ndarray:
    """Return the samples (M,) of the feed-limited runs of ``timed`` that reach a corner.

    The runs of feed-limited samples (slowed by the joints, inside the stock) that reach a
    corner at path parameters ``s_corners``; runs apart by at most ``join`` samples (and
    those between) are one run: the approach to a stop (:data:`CORNER_JOIN`).
    """
    fl = np.asarray(timed.feed_limited, dtype=bool)
    if not fl.any() or len(s_corners) == 0:
        return np.zeros(fl.shape, dtype=bool)
    if join > 0:  # close the gaps of at most join samples between two slow runs
        i = np.arange(fl.size)
        prev = np.maximum.accumulate(np.where(fl, i, -1))
        nxt = np.minimum.accumulate(np.where(fl, i, fl.size)[::-1])[::-1]
        fl = fl | ((prev >= 0) & (nxt < fl.size) & (nxt - prev - 1 <= join))
    starts = fl & ~np.r_[False, fl[:-1]]
    run = np.cumsum(starts) * fl  # 1.. per run, 0 outside
    at = np.clip(np.searchsorted(timed.s_of_t, s_corners), 0, fl.size - 1)
    near = np.r_[run[at], run[np.maximum(at - 1, 0)], run[np.minimum(at + 1, fl.size - 1)]]
    ids = np.unique(near[near > 0])
    return np.isin(run, ids) & fl
