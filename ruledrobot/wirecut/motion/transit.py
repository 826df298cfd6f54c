"""Transits between passes: joint moves that keep the arm, the bow and the wire clear of
the stock, the table and the arm itself.

The whole stock box counts as an obstacle during a transit (material an earlier cut
separated may still lie where it was), and so does the wire.  The collision model is the
cell's whole one (:mod:`..cut.clearance` with ``self_collision``): every link of the arm
against the others and the base (:data:`~..cut.clearance.ARM_ARM`), the bow, its hub and
the wire against every link, arm and bow against the stock and the table (z = 0), the
wire out of the stock, the joints within their limits.  Routes are tried in order, each
leg a straight joint move whose samples (:meth:`TransitPlanner.samples`) must all be free:

1. the direct move;
2. over the top: up from the start until the bow and the wire are ``CLEAR`` above
   the stock, across, down to the goal;
3. a search in joint space by OMPL (:func:`.transit_ompl.rrt_connect`: RRT-Connect within
   the joint limits, at most ``TIME_LIMIT`` s, seeded — the same job gives the same
   route — its path simplified by OMPL's ``PathSimplifier``), then waypoints dropped
   greedily while the move that skips them is clear (every waypoint is a stop).

When none is found the plan fails: :meth:`TransitPlanner.route` raises
:class:`TransitNotFound` with what the start, the goal and the direct move break
(:class:`TransitFailure`), the plan's ``transits`` check names the transit and those
bodies, and no move through them is kept.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass

import numpy as np

from ...geometry.checks import FloatArray
from ...geometry.se3 import transform_points
from ...robot.arm.model import RobotModel
from ...robot.arm.nearest import nearest_ik
from ...robot.arm.shape import link_segments
from ...robot.tool import BowTool
from ..cut.clearance import MARGIN, Cell, base_capsule, clearance
from ..job.spec import Job

__all__ = ["CLEAR", "SEED", "TIME_LIMIT", "TREE_STEP", "TransitFailure", "TransitNotFound",
           "TransitPlanner", "joint_reach"]  # fmt: skip

#: how far above the stock's top the bow and wire pass when a transit goes over it [m]
CLEAR = 0.05
#: the search's time limit per transit [s of processor time] (a search that finds its
#: route earlier ends then), its tree's longest move (joint-space Euclidean length) [rad]
#: and OMPL's seed
TIME_LIMIT = 2.0
TREE_STEP = 0.5
SEED = 20261202
#: wire in the stock: the rule's name beside the clearance rules' (``broken``)
WIRE_IN_STOCK = "wire in the stock"
#: the joints outside their limits
OUT_OF_LIMITS = "outside the joint limits"


def joint_reach(cell: Cell) -> FloatArray:
    """Return per joint ``j`` the most any point of the arm and bow moves per radian of ``j``.

    (J,) ``R_j`` [m / rad]: a bound on the distance of any point of the arm's capsules
    (their radius included), the bow, its hub and the wire from joint ``j``'s axis, at every
    configuration.

    Body ``k``'s frame origin lies within ``sum_{i=j}^{k-1} (|d_i| + |a_i|)`` of body ``j``'s
    (the nominal DH table: the links' shape), and its capsules within their largest end
    distance from their own origin plus their radius; the bow's points are flange-frame
    points of the last body's DH tail.  A point's distance from the axis is at most its
    distance from a point of the axis (body ``j``'s origin)."""
    nom = cell.model.nominal
    J = nom.n_joints
    segs, _ = link_segments(nom)
    hop = np.abs(nom.d) + np.abs(nom.a)  # (J,) body k origin -> body k + 1 origin
    own = np.array([max((max(np.linalg.norm(sg.a), np.linalg.norm(sg.b)) + sg.radius
                         for sg in ss), default=0.0) for ss in segs])  # fmt: skip
    tool = [np.linalg.norm(cell.rods.reshape(-1, 3), axis=1).max() + BowTool.arm_radius,
            np.linalg.norm(cell.wire, axis=1).max() + BowTool.arm_radius]
    if cell.hub is not None:
        tool.append(np.linalg.norm(cell.hub, axis=1).max() + cell.hub_radius)
    reach = np.empty(J)
    for j in range(J):
        to_body = np.r_[0.0, np.cumsum(hop[j:])]  # distance of body k's origin, k = j ... J
        bodies = (to_body[: J - j] + own[j:]).max()
        reach[j] = max(bodies, to_body[J - j] + max(tool))
    return reach


@dataclass(frozen=True)
class TransitFailure:
    """A transit no route was found for.

    ``what``: which one, in words ("from 'top' to 'side'"); ``start``, ``goal``: the rules its
    start and its goal break (empty: free); ``move``: the rules the direct move breaks (the
    union over its samples); ``searched``: the search ran (start and goal free) and found
    nothing in ``time_limit`` s."""

    what: str
    start: tuple[str, ...]
    goal: tuple[str, ...]
    move: tuple[str, ...]
    searched: bool
    time_limit: float
    #: the transit's start and goal joints (J,) [rad]
    qa: tuple[float, ...] = ()
    qb: tuple[float, ...] = ()

    def sentence(self) -> str:
        """The failure in words.

        The transit, why no search could run or that it found nothing, and the bodies in the
        direct move's way."""
        why = []
        for name, rules in (("its start", self.start), ("its goal", self.goal)):
            if rules:
                why.append(f"{name}: {', '.join(rules)}")
        if self.searched:
            why.append(f"no route found in {self.time_limit:g} s (direct, over the stock, "
                       "OMPL RRT-Connect)")  # fmt: skip
        if self.move:
            why.append(f"the direct move: {', '.join(self.move)}")
        return f"transit {self.what}: " + "; ".join(why)


class TransitNotFound(RuntimeError):
    """No clear route for a transit (:class:`TransitFailure` in ``failure``)."""

    def __init__(self, failure: TransitFailure) -> None:
        super().__init__(failure.sentence())
        self.failure = failure


@dataclass(frozen=True)
class TransitPlanner:
    """Routes joint moves clear of the cell for one job (module doc).

    ``cell``: the clearance cell with self-collision on; ``top``: z of the stock's highest
    corner [m]; ``lower``, ``upper`` (J,): the joint limits (within +-2 pi) [rad];
    ``reach`` (J,): :func:`joint_reach` [m / rad]; ``step``: the largest Cartesian step
    [m] of any point between two checked samples of a move; ``time_limit``: the search's
    time per transit [s]."""

    cell: Cell
    top: float
    lower: FloatArray
    upper: FloatArray
    reach: FloatArray
    step: float
    time_limit: float = TIME_LIMIT

    @classmethod
    def of(
        cls, job: Job, model: RobotModel, margin: float = MARGIN, cell: Cell | None = None,
        time_limit: float = TIME_LIMIT,
    ) -> TransitPlanner:
        """The transits of ``job``.

        Its whole stock an obstacle, the table at z = 0, ``margin`` [m] clearance, the arm
        against itself, no singularity threshold; ``cell``: the plan's cell (its robot, bow and
        stock: no bow built again), else built here; ``time_limit``: the search's per transit
        [s].

        The step between checked samples: ``step = min(r_min, 2 margin)``, with ``r_min``
        the thinnest radius of the model (the arm's capsules, the bow's rods and wire,
        its hub, half the stock's smallest edge).  A move of ``dq`` moves no point farther
        than ``sum_j R_j |dq_j|`` (:func:`joint_reach`), so a move is checked at ``n =
        ceil(sum_j R_j |dq_j| / step) + 1`` samples (:meth:`samples`) — in the max norm a
        joint step of ``step / sum_j R_j`` at most (:attr:`resolution`).  Between two
        samples every point is within ``step / 2`` of where it was at one of them, so
        nothing steps through anything (two bodies move at most ``2 step <= 2 r_min``
        relative to each other, less than the width of their contact zone, ``2 (r_1 +
        r_2) >= 4 r_min``), and a point kept ``margin`` from the stock and the table at
        the samples keeps ``margin - step / 2 >= 0`` between them."""
        if cell is None or cell.bow is None or cell.model is not model:
            cell = Cell.of(model, job.tool, job.stock, 0.0, margin, 0.0, None)
        else:
            cell = cell.with_rules(0.0, margin, 0.0, None)
        cell = dataclasses.replace(cell, self_collision=True)
        pts = job.stock.corners
        lo = np.maximum(model.lower, -2.0 * np.pi)
        hi = np.minimum(model.upper, 2.0 * np.pi)
        segs, _ = link_segments(model.nominal)
        radii = [sg.radius for ss in segs for sg in ss] + [base_capsule(model)[1]]
        radii += [BowTool.arm_radius, 0.5 * float(np.min(job.stock.size))]
        if cell.hub is not None:
            radii.append(cell.hub_radius)
        step = min(radii) if margin <= 0.0 else min(min(radii), 2.0 * margin)
        return cls(cell, float(pts[:, 2].max()), lo, hi, joint_reach(cell), step, time_limit)

    @property
    def resolution(self) -> float:
        """The joint step [rad] between checked samples of a move of every joint at once (max norm).

        ``step / sum_j R_j``."""
        return self.step / float(self.reach.sum())

    def samples(self, qa: FloatArray, qb: FloatArray) -> FloatArray:
        """The checked samples (n, J) of the straight joint move qa -> qb, both ends included.

        ``n = ceil(sum_j R_j |qb_j - qa_j| / step) + 1`` (:meth:`of`)."""
        travel = float(self.reach @ np.abs(qb - qa))
        n = max(2, int(np.ceil(travel / self.step)) + 1)
        u = np.linspace(0.0, 1.0, n)[:, None]
        return qa + u * (qb - qa)

    def free(self, q: FloatArray) -> np.ndarray:
        """Return which configurations keep every clearance rule and the joint limits.

        (n,) bool of configurations (n, J): every clearance rule kept, the arm's against
        itself included, the wire held out of the stock (between cuts the wire is an
        obstacle like the bow) and the joints within their limits.
        """
        q = np.atleast_2d(q)
        P = self.cell.model.fk(q)
        bad = np.zeros(len(q), dtype=bool)
        for v in clearance(self.cell, q, P).values():
            bad |= v
        bad |= self._wire_in_stock(P)
        return ~bad & self.cell.model.within_limits(q)

    def _wire_in_stock(self, P: FloatArray) -> np.ndarray:
        w = transform_points(P, self.cell.wire)
        return self.cell.stock.segment_hits(w[:, 0], w[:, 1], self.cell.margin)

    def clear(self, qa: FloatArray, qb: FloatArray) -> bool:
        """True when every sample of the straight joint move qa -> qb is free.

        Every eighth sample is checked first (a blocked move is usually blocked over many
        samples), the others only when those are free."""
        q = self.samples(qa, qb)
        if len(q) > 16 and not self.free(q[::8]).all():
            return False
        return bool(self.free(q).all()) if len(q) <= 16 else bool(
            self.free(np.delete(q, np.s_[::8], axis=0)).all())

    def clear_moves(self, moves: list[tuple[FloatArray, FloatArray]]) -> np.ndarray:
        """(K,) :meth:`clear` of each move, their samples checked in one batch."""
        samples = [self.samples(qa, qb) for qa, qb in moves]
        free = self.free(np.concatenate(samples))
        ends = np.cumsum([len(x) for x in samples])
        return np.array([bool(f.all()) for f in np.split(free, ends[:-1])])

    def lifted(self, q: FloatArray) -> FloatArray | None:
        """Return the joints nearest ``q`` with the flange raised clear of the stock, or None.

        Raised until the bow and wire are CLEAR above the stock's top; None when
        unreachable.
        """
        model = self.cell.model
        P = model.fk(q)
        pts = np.concatenate([self.cell.rods.reshape(-1, 3), self.cell.wire])
        low = float((pts @ P[:3, :3].T + P[:3, 3])[:, 2].min())
        rise = self.top + CLEAR - low
        if rise <= 0.0:
            return q
        P[2, 3] += rise
        return nearest_ik(model, P, q)

    def search(self, qa: FloatArray, qb: FloatArray) -> list[FloatArray] | None:
        """Return a route from ``qa`` to ``qb`` by OMPL's RRT-Connect, or None.

        A route of waypoints, each (J,), from ``qa`` to ``qb`` (both free) by
        :func:`.transit_ompl.rrt_connect`, its waypoints then dropped greedily while the
        move that skips them is clear; None when none is found within the time limit.  The
        search box: the joint limits, and per joint at most pi beyond the start and the goal
        (a route turns no joint a whole turn more than it must).
        """
        from .transit_ompl import rrt_connect

        lo = np.minimum(np.maximum(self.lower, np.minimum(qa, qb) - np.pi), np.minimum(qa, qb))
        hi = np.maximum(np.minimum(self.upper, np.maximum(qa, qb) + np.pi), np.maximum(qa, qb))
        route = rrt_connect(qa, qb, lo, hi, lambda q: bool(self.free(q).all()), self.clear,
                            time_limit=self.time_limit, step=TREE_STEP, seed=SEED)  # fmt: skip
        return None if route is None else self._shortcut(route)

    def _shortcut(self, route: list[FloatArray]) -> list[FloatArray]:
        """Drop waypoints while the move that skips them stays clear (greedy, from the
        start: the farthest waypoint reachable in one move)."""
        out = [route[0]]
        i = 0
        while i < len(route) - 1:
            j = len(route) - 1
            while j > i + 1 and not self.clear(route[i], route[j]):
                j -= 1
            out.append(route[j])
            i = j
        return out

    def route(
        self, qa: FloatArray, qb: FloatArray, notes: list[str], what: str
    ) -> list[tuple[FloatArray, FloatArray]]:
        """Joint moves from ``qa`` to ``qb`` (rad) clear of the cell (module doc).

        A note says when the direct move was not. Raises :class:`TransitNotFound` when no route
        is found (``what`` names the transit in its words)."""
        qa, qb = np.asarray(qa, dtype=np.float64), np.asarray(qb, dtype=np.float64)
        if np.allclose(qa, qb):
            return []
        if self.clear(qa, qb):
            return [(qa, qb)]
        ua, ub = self.lifted(qa), self.lifted(qb)
        if ua is not None and ub is not None:
            legs = [(qa, ua), (ua, ub), (ub, qb)]
            if all(np.allclose(a, b) or self.clear(a, b) for a, b in legs):
                notes.append(f"transit {what}: over the stock (the direct move would hit it)")
                return [(a, b) for a, b in legs if not np.allclose(a, b)]
        start, goal = tuple(self.broken(qa)), tuple(self.broken(qb))
        if not start and not goal:
            waypoints = self.search(qa, qb)
            if waypoints is not None:
                notes.append(f"transit {what}: around the stock through "
                             f"{len(waypoints) - 2} waypoints (the direct move would hit it)")
                return list(itertools.pairwise(waypoints))
        raise TransitNotFound(TransitFailure(
            what, start, goal, tuple(self.broken_along(qa, qb)), not start and not goal,
            self.time_limit, tuple(qa.tolist()), tuple(qb.tolist())))  # fmt: skip

    def broken(self, q: FloatArray) -> list[str]:
        """The clearance rules the configuration ``q`` (J,) breaks (empty: free)."""
        return self.broken_along(q, q)

    def broken_along(self, qa: FloatArray, qb: FloatArray) -> list[str]:
        """Return the clearance rules some sample of the straight joint move qa -> qb breaks.

        In the rules' order (:data:`~..cut.clearance.RULES`, then the wire in the stock and
        the joint limits).
        """
        q = self.samples(qa, qb)
        P = self.cell.model.fk(q)
        out = [k for k, v in clearance(self.cell, q, P).items() if v.any()]
        if self._wire_in_stock(P).any():
            out.append(WIRE_IN_STOCK)
        if not self.cell.model.within_limits(q).all():
            out.append(OUT_OF_LIMITS)
        return out
