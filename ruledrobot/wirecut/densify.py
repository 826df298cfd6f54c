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

from ..geometry import se3
from ..geometry.angles import wrap_near
from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..robot.tool import BowTool
from .cutpath import CutPath
from .measure import wire_points
from .timing import TimedPath
from .toolpath import chords, flange_poses, wire_poses

__all__ = ["densified", "pass_deviation", "pass_feed_error", "uneven_intervals"]


def _samples_in_intervals(
    cp: CutPath, timed: TimedPath
) -> tuple[np.ndarray, FloatArray, np.ndarray, FloatArray]:
    """For every sample the interval between rulings it lies in and its fraction there,
    whether the wire crosses the stock at both ends, and zeros (M - 1,) per interval."""
    i0, frac = cp.locate(timed.s_of_t)
    inside = cp.motion.hit[i0] & cp.motion.hit[i0 + 1]
    return i0, frac, inside, np.zeros(len(cp.frames) - 1)


def pass_deviation(cp: CutPath, timed: TimedPath, model, ends: FloatArray) -> FloatArray:
    """Per interval between rulings (M - 1,) the largest distance [m] of the timed
    wire's chord ends from the target rulings (the screw geodesic between the frames at
    the same path parameter), inside the stock; ``ends`` (M, 2, 3) the chord ends in the
    flange frame at the rulings."""
    i0, frac, inside, out = _samples_in_intervals(cp, timed)
    if not inside.any():
        return out
    k = np.flatnonzero(inside)
    f = frac[k, None, None]
    e = np.nan_to_num(ends)
    e_t = (1.0 - f) * e[i0[k]] + f * e[i0[k] + 1]
    target = se3.geodesic(cp.frames[i0[k]], cp.frames[i0[k] + 1], frac[k])
    off = wire_points(model.fk(timed.q[k]), e_t) - target[:, None, :3, 3]
    dist = np.linalg.norm(np.cross(off, target[:, None, :3, 2]), axis=-1).max(axis=1)
    np.maximum.at(out, i0[k], dist)
    return out


def pass_feed_error(
    cp: CutPath, timed: TimedPath, model, ends: FloatArray, feed_speed: float
) -> FloatArray:
    """Per interval between rulings (M - 1,) the largest relative error of the timed
    wire's feed, measured through forward kinematics, against ``feed_speed`` inside the
    stock, where the time law meant to hold the feed (not where the joints set the pace).

    The time law bounds a feed model interpolated linearly between the rulings; where
    the joint path bends within an interval, the real feed strays from it."""
    from .measure import feed_speeds

    i0, frac, inside, out = _samples_in_intervals(cp, timed)
    if not inside.any():
        return out
    e = np.nan_to_num(ends)
    f = frac[:, None, None]
    e_t = (1.0 - f) * e[i0] + f * e[i0 + 1]
    feed = feed_speeds(timed.t, model.fk(timed.q), e_t, inside)
    err = np.abs(feed / feed_speed - 1.0)
    held = inside & ~timed.feed_limited
    # the first and last samples of a run in the stock are one-sided differences
    held[1:-1] &= inside[:-2] & inside[2:]
    np.maximum.at(out, i0[held], err[held])
    return out


def uneven_intervals(cp: CutPath, share: float) -> np.ndarray:
    """Intervals between rulings (indices) inside the stock where the wire's distance per
    joint distance changes by more than ``share`` (relative) from the neighbouring
    interval.  The time law holds the feed with the larger of the two at every ruling
    (its feed bound is then safe between rulings), so a jump there slows the wire by the
    jump; halving such intervals halves the jumps."""
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


def densified(cp: CutPath, intervals: np.ndarray, model, tool, stock: Box) -> CutPath:
    """``cp`` with a ruling added halfway through each interval ``i`` (between rulings
    ``i`` and ``i + 1``) of ``intervals`` (module doc) that is longer than
    :data:`MIN_INTERVAL`."""
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
    W = BowTool.from_spec(tool).wire_frame()
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
