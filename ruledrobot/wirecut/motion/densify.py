"""Denser rulings where the timed joints leave the surface between them.

The time law follows a joint path through the joint solutions at the rulings; between
two rulings the wire is where those interpolated joints put it, not on the screw
motion between the rulings' frames.  Where the joint path bends hard from ruling to
ruling (the roll about the wire changing its rate, the wrist turning) that gap reaches
millimetres although the rulings are a couple of millimetres apart.  The planner
measures the wire of the timed pass against its target (:func:`pass_deviation`) and,
where an interval between rulings is off by more than a share of the tolerance, adds
the ruling halfway (the screw-geodesic midpoint of the frames, the mean roll and
slide, the joint solution nearest the mean of the neighbours) — :func:`densified` —
and times the pass again.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...geometry import se3
from ...geometry.angles import wrap_near
from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...robot.arm.model import RobotModel
from ...robot.tool import BowTool
from ...robot.wire.in_stock import WireInStock
from ..cut.cutpath import CutPath
from ..cut.wire_geometry import chords, distance_from_rulings, flange_poses, wire_poses
from ..job.spec import ToolSpec
from .timing import TimedPath

__all__ = [
    "densified", "pass_deviation", "pass_feed_error", "target_frames", "uneven_intervals",
]


def target_frames(cp: CutPath, s: FloatArray) -> tuple[np.ndarray, FloatArray]:
    """Return the interval each path parameter lies in and the target ruling's frame there.

    The interval between rulings (K,) of each path parameter ``s`` (K,), and the frame (K,
    4, 4): the screw geodesic between the interval's frames at the same fraction.
    """
    i0, frac = cp.locate(s)
    return i0, se3.geodesic(cp.frames[i0], cp.frames[i0 + 1], frac)


def pass_deviation(cp: CutPath, timed: TimedPath, wire: WireInStock) -> FloatArray:
    """Return per interval the largest distance [m] of the timed wire from the target rulings.

    Per interval between rulings (M - 1,): of the timed wire's chord ends from the target
    rulings at the same path parameter, where the wire is in the stock; ``wire`` the one
    model measured on ``timed``.
    """
    out = np.zeros(len(cp.frames) - 1)
    k = np.flatnonzero(wire.inside)
    if not k.size:
        return out
    i0, target = target_frames(cp, timed.s_of_t[k])
    np.maximum.at(out, i0, distance_from_rulings(wire.chord_points()[k], target))
    return out


def pass_feed_error(
    cp: CutPath, timed: TimedPath, wire: WireInStock, feed_speed: float
) -> FloatArray:
    """Return per interval the largest relative error of the timed wire's cutting speed.

    Per interval between rulings (M - 1,), of the one model's speed (``wire``) against
    ``feed_speed``, where the wire is in the stock and the time law meant to hold the feed
    (not where the joints set the pace).  The time law bounds a speed factor interpolated
    linearly between the rulings; where the joint path bends within an interval, the real
    feed strays.
    """
    out = np.zeros(len(cp.frames) - 1)
    held = wire.inside & ~timed.feed_limited
    if not held.any():
        return out
    err = np.abs(wire.feed / feed_speed - 1.0)
    i0, _ = cp.locate(timed.s_of_t)
    np.maximum.at(out, i0[held], err[held])
    return out


def uneven_intervals(cp: CutPath, share: float) -> np.ndarray:
    """Return the intervals in the stock where the wire's distance per joint distance jumps.

    Intervals between rulings (indices) inside the stock where the wire's distance per joint
    distance changes by more than ``share`` (relative) from the neighbouring interval.  The
    time law holds the feed with the larger of the two at every ruling (its feed bound is
    then safe between rulings), so a jump there slows the wire by the jump; halving such
    intervals halves the jumps.
    """
    m = cp.motion
    dsig = np.abs(np.diff(m.q, axis=0)).sum(axis=1)
    ratio = np.diff(cp.s) / np.maximum(dsig, 1e-12)
    both = m.hit[:-1] & m.hit[1:]
    jump = np.abs(np.diff(ratio)) / np.maximum(ratio[:-1], ratio[1:])
    bad = (jump > share) & both[:-1] & both[1:]
    return np.unique(np.r_[np.flatnonzero(bad), np.flatnonzero(bad) + 1])


#: intervals shorter than this [in the pass parameter: m of wire travel] are not split:
#: below it the joint samples are closer than the time law can tell apart usefully
MIN_INTERVAL = 2e-4


def densified(
    cp: CutPath, intervals: np.ndarray, model: RobotModel, tool: ToolSpec | BowTool, stock: Box
) -> CutPath:
    """Return ``cp`` with a ruling added halfway through each long interval of ``intervals``.

    Each interval ``i`` (between rulings ``i`` and ``i + 1``) of ``intervals`` (module doc)
    that is longer than :data:`MIN_INTERVAL`; ``tool``: the job's spec or the bow built from
    it.
    """
    m = cp.motion
    idx = np.unique(np.asarray(intervals, dtype=np.intp))
    idx = idx[np.diff(cp.s)[idx] > 2.0 * MIN_INTERVAL]
    if not idx.size:
        return cp
    half = np.full(idx.size, 0.5)
    F_mid = se3.geodesic(cp.frames[idx], cp.frames[idx + 1], half)
    S = cp.target_frames
    S_mid = se3.geodesic(S[idx], S[idx + 1], half)
    roll = 0.5 * (m.roll[idx] + m.roll[idx + 1])
    slide = 0.5 * (m.slide[idx] + m.slide[idx + 1])
    W = BowTool.of(tool).wire_frame()
    P = flange_poses(wire_poses(F_mid, roll, slide, m.reverse), W)
    sols = model.ik(P, check=False)  # (k, 8, 6)
    ref = 0.5 * (m.q[idx] + m.q[idx + 1])
    sols = wrap_near(np.nan_to_num(sols, nan=1e9), ref[:, None, :])
    best = np.argmin(np.abs(sols - ref[:, None, :]).max(axis=2), axis=1)
    q = sols[np.arange(idx.size), best]
    c0, c1, hit = chords(F_mid, stock)
    order = np.argsort(np.r_[np.arange(len(cp.frames)), idx + 0.5], kind="stable")

    def merged(a: FloatArray, b: FloatArray) -> FloatArray:
        return np.concatenate([a, b])[order]

    err = cp.kerf_error if cp.kerf_error is not None else np.zeros(len(cp.frames))
    motion = dataclasses.replace(
        m, roll=merged(m.roll, roll), slide=merged(m.slide, slide),
        flange=merged(m.flange, P), q=merged(m.q, q),
        chord=merged(m.chord, np.c_[c0, c1]), hit=merged(m.hit, hit),
    )  # fmt: skip
    s = cp.s
    a, b = cp.extended
    M = len(cp.frames)
    extended = (a + int(np.sum(idx < a)), b + int(np.sum(idx >= M - 1 - b)))
    return dataclasses.replace(
        cp, frames=merged(cp.frames, F_mid), motion=motion, extended=extended,
        surface_frames=merged(S, S_mid),
        kerf_error=merged(err, np.maximum(err[idx], err[idx + 1])),
        param=merged(s, 0.5 * (s[idx] + s[idx + 1])),
    )  # fmt: skip
