"""Geometry of a hot-wire cut: chords, the wire's free degrees of freedom, tool poses.

Frames.  The rulings come with frames ``F`` (M, 4, 4) in the robot base frame:
origin on the ruling, z along it (the refined DH frames of the ``dh``
algorithm).  The wire has its own frame ``W`` in the flange frame
(:func:`wire_frame`): origin at the wire's midpoint, z from ``wire_start`` to
``wire_end``, x from the flange origin towards the wire (the bow's depth
direction).

Putting the wire on ruling i fixes 4 of the tool's 6 degrees of freedom; the
free ones are the **roll** ``psi`` about the ruling and the **slide** ``s``
along it, plus a discrete choice, whether the wire points along the ruling or
against it (**reverse**)::

    wire pose   G_i = F_i Rz(psi_i) Tz(s_i) [Rx(pi) if reverse]
    flange pose P_i = G_i W^-1

The **chord** of ruling i is the part inside the stock, ``c0_i <= z <= c1_i``
in F_i's z coordinate.  The wire covers it with ``clearance`` beyond each end
when ``c1 - L/2 + clearance <= s <= c0 + L/2 - clearance`` (L the wire length).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ...geometry import se3
from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...robot.tool import BowTool
from ...robot.wire.in_stock import (
    across_speeds,
    feed_chord,
    flange_wire_ends,
    largest_line_distance,
)
from ..job.spec import ToolSpec

__all__ = [
    "anchored_frames",
    "chords",
    "distance_from_rulings",
    "flange_poses",
    "slide_bounds",
    "speed_factor",
    "wire_frame",
    "wire_poses",
    "world_referenced",
]


def wire_frame(tool: ToolSpec | BowTool) -> FloatArray:
    """The wire frame W (4, 4) in the flange frame (see the module doc).

    Origin at the wire midpoint, z along the wire, x the bow's depth direction
    (:meth:`ruledrobot.robot.tool.BowTool.wire_frame`); ``tool`` the job's spec or the bow
    built from it."""
    return BowTool.of(tool).wire_frame()


def chords(frames: ArrayLike, stock: Box) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Return the chord parameters ``(c0, c1, hit)`` (M,) of each ruling in the stock.

    In the z coordinate of its frame (m); NaN where the ruling misses the stock.
    """
    F = np.asarray(frames, dtype=np.float64)
    return stock.clip_lines(F[:, :3, 3], F[:, :3, 2])


def anchored_frames(frames: ArrayLike, point: ArrayLike) -> FloatArray:
    """Move frames along their own z axis to the points of their rulings nearest ``point``.

    Frames (M, 4, 4) moved so that each origin is the point of its ruling nearest ``point``
    (3,) (m, robot base frame); orientation unchanged.

    The DH frames of nearly parallel rulings sit where consecutive rulings' common
    normals meet them, which can be metres away along the rulings and jump from one
    ruling to the next; a slide (the wire's position along its ruling, measured
    from the origin) means the same thing on every ruling only once the origins are
    anchored.  Foot of the perpendicular: ``o + ((point - o) . z) z``.
    """
    F = np.array(frames, dtype=np.float64)
    o, z = F[:, :3, 3], F[:, :3, 2]
    t = ((np.asarray(point, dtype=np.float64) - o) * z).sum(axis=1)
    F[:, :3, 3] = o + t[:, None] * z
    return F


#: Smallest |x| of the projected world axis for which :func:`world_referenced`
#: turns the frames (a ruling within ~6 deg of that axis leaves them as they are).
WORLD_REFERENCE_MIN = 0.1


def world_referenced(F: FloatArray) -> FloatArray:
    """Turn frames about their z axes so that x points as nearly as it can along a world axis.

    The frames (M, 4, 4); the world axis is the one the rulings are most nearly normal to.

    A roll relative to these frames is the bow's attitude in the world.  Relative to
    the DH frames it is not: their x axes (common normals) turn once with a closed
    loop, and jump at the corners and cusps of a path (a foam cutter's entry move, an
    airfoil's trailing edge, where the common normal reverses), so a constant bow
    attitude would need a jump in roll.  ``x = (v - (z.v) z) / |..|``; where a ruling
    comes within about 6 degrees of the axis (``|v - (z.v) z| <
    WORLD_REFERENCE_MIN``) the frames are returned unchanged.
    """
    z = F[:, :3, 2]
    axis = int(np.argmin(np.abs(z).mean(axis=0)))
    v = np.zeros(3)
    v[axis] = 1.0
    x = v - (z @ v)[:, None] * z
    size = np.linalg.norm(x, axis=1)
    if size.min() < WORLD_REFERENCE_MIN:
        return F.copy()
    x /= size[:, None]
    out = F.copy()
    out[:, :3, 0] = x
    out[:, :3, 1] = np.cross(z, x)
    return out


def slide_bounds(
    c0: FloatArray, c1: FloatArray, hit: np.ndarray, tool: ToolSpec
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Slides ``lo <= s <= hi`` (M,) for which the wire covers each chord with the clearance.

    ``(-inf, inf)`` where the ruling misses the stock. ``ok`` is False where the chord is
    longer than the wire allows."""
    half = 0.5 * tool.wire_length - tool.clearance
    lo = np.where(hit, c1 - half, -np.inf)
    hi = np.where(hit, c0 + half, np.inf)
    return lo, hi, lo <= hi


def _rz_tz(psi: FloatArray, s: FloatArray, reverse: FloatArray | bool) -> FloatArray:
    c, si = np.cos(psi), np.sin(psi)
    T = np.zeros((*np.shape(psi), 4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 1, 0], T[..., 1, 1] = c, -si, si, c
    T[..., 2, 2] = T[..., 3, 3] = 1.0
    T[..., 2, 3] = s
    rev = np.broadcast_to(np.asarray(reverse, dtype=bool), np.shape(psi))
    # Rx(pi): y -> -y, z -> -z
    T[..., :3, 1] = np.where(rev[..., None], -T[..., :3, 1], T[..., :3, 1])
    T[..., :3, 2] = np.where(rev[..., None], -T[..., :3, 2], T[..., :3, 2])
    return T


def wire_poses(
    frames: ArrayLike, roll: ArrayLike, slide: ArrayLike, reverse: ArrayLike | bool = False
) -> FloatArray:
    """Wire poses ``G = F Rz(roll) Tz(slide) [Rx(pi)]``.

    Frames (M, 4, 4), roll and slide broadcast to (..., M) -> (..., M, 4, 4)."""
    F = np.asarray(frames, dtype=np.float64)
    psi, s = np.broadcast_arrays(np.asarray(roll, float), np.asarray(slide, float))
    return F @ _rz_tz(psi, s, reverse)


def flange_poses(wire: ArrayLike, W: ArrayLike) -> FloatArray:
    """Flange poses ``P = G W^-1`` (..., 4, 4) of wire poses G (..., 4, 4)."""
    return np.asarray(wire, dtype=np.float64) @ se3.inverse(W)


def speed_factor(
    flange: ArrayLike, path_s: ArrayLike, tool: ToolSpec | BowTool, stock: Box, near: float
) -> FloatArray:
    """Return the metres the wire's fastest point in the stock moves per unit path parameter.

    Metres moved across the wire by its fastest point in (or, within ``near`` m, nearest)
    the stock per unit of path parameter: the time law's feed bound.

    ``flange`` (M, 4, 4) flange poses along the path at parameters ``path_s`` (M,).
    The chord and the speed across the wire come from the one model of the wire
    against the block (:func:`ruledrobot.robot.wire.in_stock.feed_chord`,
    :func:`~ruledrobot.robot.wire.in_stock.across_speeds`): where the wire is outside
    but near the block, its point nearest the block, so that the bound meets the
    chord's without a jump as the wire enters and leaves.  0 further away.  ``tool``: the
    job's spec or the bow built from it.
    """
    bow = BowTool.of(tool)
    ends = flange_wire_ends(flange, bow)
    f = feed_chord(ends, stock, near)
    if len(ends) < 2:
        return np.zeros(len(ends))
    return np.nan_to_num(across_speeds(path_s, ends, f), nan=0.0).max(axis=1)


def distance_from_rulings(points: ArrayLike, frames: ArrayLike) -> FloatArray:
    """Return the largest distance (K,) [m] of points from the lines of frames.

    Points (K, P, 3), frames (K, 4, 4) (origin, z axis): ``max_p |(x_p - o) x z|``; NaN
    points are left out (0 when all are NaN).  The wire's deviation from its target ruling,
    with the points its chord ends and the frames the target rulings at the same path
    parameter.
    """
    F = np.asarray(frames, dtype=np.float64)
    return largest_line_distance(points, F[:, :3, 3], F[:, :3, 2])
