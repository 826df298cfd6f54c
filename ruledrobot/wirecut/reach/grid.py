"""The grid the reachability map and the placement search sample: rulings x rolls x wire
directions, at the planner's slide, and stocks placed differently per configuration.

Frames: everything in the world frame of the job's robot model (the robot base frame
when ``[robot] base`` is the identity, the usual case).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ..cut.clearance import Cell
from ..cut.wire_geometry import chords, flange_poses, slide_bounds, wire_poses
from ..cut.wire_pose import ROLLS as WIRE_POSE_ROLLS
from ..job.spec import Job, ToolSpec
from .margins import Rules

if TYPE_CHECKING:
    from ...robot.arm.model import RobotModel

__all__ = [
    "DIRECTIONS",
    "ROLLS",
    "RULINGS",
    "RowBoxes",
    "directions_needed",
    "job_cell",
    "pass_poses",
    "planner_slide",
    "planner_slides",
    "sample_rulings",
]

#: the two wire directions, in the order of every grid's first axis
DIRECTIONS = (False, True)
#: rolls over a turn of the constant-roll model (the planner's own grid: the default
#: ``rolls`` of :class:`~..cut.wire_pose.SearchOptions`, so every roll it scores is
#: scored here): the placement search, the best constant roll of ``reach`` and of a
#: failed plan's explanation, and the move it suggests (docs/place.md, "One model")
ROLLS = WIRE_POSE_ROLLS
#: rulings sampled per pass by the constant-roll model (ends included)
RULINGS = 48


def job_cell(job: Job, model: RobotModel, rules: Rules) -> Cell:
    """The planner's cell of ``job`` (table top at z = 0, the planner's thresholds)."""
    return Cell.of(model, job.tool, job.stock, 0.0, rules.margin, rules.singular_min, None)


def directions_needed(W: FloatArray) -> tuple[bool, ...]:
    """The wire directions worth sampling.

    Both, unless reversing the wire is the same as turning the flange half a turn about its own
    axis (the wire's midpoint on the flange axis and the bow's depth direction along it, as on
    a symmetric bow). The planner's bow is symmetric about that axis, so the reversed wire then
    gives the same configurations with ``q6 + pi`` (only joint 6's whole-turn margin, at least
    pi on a UR, differs)."""
    flip = np.diag([1.0, -1.0, -1.0, 1.0])
    S = W @ flip @ np.linalg.inv(W)
    same = np.allclose(S, np.diag([-1.0, -1.0, 1.0, 1.0]), atol=1e-9)
    return (False,) if same else DIRECTIONS


def sample_rulings(m: int, n: int) -> np.ndarray:
    """Indices (<= n,) of ``n`` rulings spread evenly over ``m``, both ends included."""
    return np.unique(np.linspace(0, m - 1, max(2, min(n, m))).round().astype(np.intp))


def planner_slide(frames: FloatArray, stock: Box, tool: ToolSpec) -> tuple[FloatArray, FloatArray]:
    """Return the slide the redundancy search starts from and how much each chord is too long.

    The slide (M,) [m], and per ruling how much (m) its chord is longer than the wire allows
    (<= 0: it fits).

    The middle of the intersection of every ruling's slide interval when there is
    one, else each ruling's interval point nearest the middle of the median bounds
    (:func:`ruledrobot.wirecut.cut.wire_pose.solve_redundancy`).
    """
    c0, c1, hit = chords(frames, stock)
    lo, hi, _ = slide_bounds(c0, c1, hit, tool)
    too_long = np.where(hit, lo - hi, -np.inf)
    if not hit.any():
        return np.zeros(len(frames)), too_long
    L, H = lo[hit].max(), hi[hit].min()
    if L <= H:
        return np.full(len(frames), 0.5 * (L + H)), too_long
    centre = 0.5 * (np.median(lo[hit]) + np.median(hi[hit]))
    return np.clip(np.full(len(frames), centre), np.minimum(lo, hi), np.maximum(lo, hi)), too_long


def planner_slides(frames: FloatArray, stock: Box, tool: ToolSpec
                   ) -> tuple[list[FloatArray], FloatArray]:  # fmt: skip
    """The slides (each (M,) m) the redundancy search tries, in its order.

    The first (:func:`planner_slide`), then, when one slide covers every chord, slides a tenth
    of the common interval in from either end of it (tried when nothing works at the first);
    and ``too_long`` as :func:`planner_slide`."""
    first, too_long = planner_slide(frames, stock, tool)
    c0, c1, hit = chords(frames, stock)
    if not hit.any():
        return [first], too_long
    lo, hi, _ = slide_bounds(c0, c1, hit, tool)
    L, H = lo[hit].max(), hi[hit].min()
    if not (L <= H and H - L > 1e-6):
        return [first], too_long
    m = len(frames)
    return [first, np.full(m, L + 0.1 * (H - L)), np.full(m, H - 0.1 * (H - L))], too_long


def pass_poses(
    W: FloatArray,
    frames: FloatArray,
    slide: FloatArray,
    rolls: FloatArray,
    directions: tuple[bool, ...] = DIRECTIONS,
) -> FloatArray:
    """Return the flange poses of the wire on rulings ``frames`` for each direction and roll.

    Poses (D, K, R, 4, 4) on rulings ``frames`` (R, 4, 4) at ``slide`` (R,), for the wire
    ``directions`` (D,) (False: along the ruling) and ``rolls`` (K,) [rad]; ``W`` the wire
    frame in the flange frame.
    """
    R, K, D = len(frames), len(rolls), len(directions)
    psi = np.broadcast_to(np.asarray(rolls, float)[None, :, None], (D, K, R))
    s = np.broadcast_to(np.asarray(slide, float)[None, None, :], (D, K, R))
    rev = np.broadcast_to(np.array(directions)[:, None, None], (D, K, R))
    return flange_poses(wire_poses(frames, psi, s, rev), W)


class RowBoxes:
    """One oriented box per configuration.

    The stock of many placements at once, for the planner's clearance rules
    (:func:`ruledrobot.wirecut.cut.clearance.clearance`).

    ``box`` the stock at the job's placement and ``T`` (n, 4, 4) the rigid motion of the
    n-th configuration's placement.  :meth:`segment_hits` takes segments whose leading
    axis is the configuration (as :func:`~ruledrobot.wirecut.cut.clearance.clearance` passes
    them) and answers with :meth:`ruledrobot.geometry.box.Box.segment_hits` of that
    configuration's box.
    """

    def __init__(self, box: Box, T: FloatArray) -> None:
        self.box = box
        self.local = Box(np.zeros(3), box.size)
        # world -> box coordinates of each configuration's box: (T B)^-1
        B = box.pose
        TB = T @ B
        self._R = np.swapaxes(TB[:, :3, :3], 1, 2)
        self._t = -np.einsum("nij,nj->ni", self._R, TB[:, :3, 3])

    def take(self, idx: np.ndarray) -> RowBoxes:
        """The boxes of configurations ``idx``."""
        out = object.__new__(RowBoxes)
        out.box, out.local = self.box, self.local
        out._R, out._t = self._R[idx], self._t[idx]
        return out

    def __len__(self) -> int:
        return len(self._R)

    def _to_local(self, p: FloatArray) -> FloatArray:
        p = np.asarray(p, dtype=np.float64)
        extra = (1,) * (p.ndim - 2)
        R = self._R.reshape(len(self), *extra, 3, 3)
        t = self._t.reshape(len(self), *extra, 3)
        return np.einsum("...ij,...j->...i", R, p) + t

    def segment_hits(self, a: FloatArray, b: FloatArray, margin: float = 0.0) -> np.ndarray:
        """Whether segments ``a -> b`` (n, ..., 3) touch the n-th box grown by ``margin``."""
        return self.local.segment_hits(self._to_local(a), self._to_local(b), margin)

    def contains(self, points: FloatArray, margin: float = 0.0) -> np.ndarray:
        """Whether points (n, ..., 3) lie in the n-th box grown by ``margin``."""
        return self.local.contains(self._to_local(points), margin)
