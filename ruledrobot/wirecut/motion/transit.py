"""Transits between passes: joint moves that keep the arm, the bow and the wire clear of
the stock and the table.

The whole stock box counts as an obstacle during a transit (material an earlier cut
separated may still lie where it was).  Routes are tried in order, each leg a
straight joint move whose samples must keep every clearance rule (:mod:`..cut.clearance`):

1. the direct move;
2. over the top: up from the start until the bow and the wire are ``CLEAR`` above
   the stock, across, down to the goal;
3. a bidirectional rapidly-exploring random tree in joint space (RRT-connect, seeded:
   the same job gives the same route), shortened by cutting corners.

When none is clear the direct move is kept and a note says so — the plan's
collision checks then fail on it and name it.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ...geometry.checks import FloatArray
from ...geometry.se3 import transform_points
from ...robot.arm.model import RobotModel
from ...robot.arm.nearest import nearest_ik
from ..cut.clearance import MARGIN, Cell, clearance
from ..job.spec import Job

__all__ = ["CLEAR", "TransitPlanner"]

#: how far above the stock's top the bow and wire pass when a transit goes over it [m]
CLEAR = 0.05
#: joint-space length between checked samples of a move [rad]
RESOLUTION = 0.03
#: the random tree's step [rad], its iteration budget and its seed
TREE_STEP = 0.4
TREE_ITERATIONS = 1500
SEED = 20261202


def _samples(qa: FloatArray, qb: FloatArray) -> FloatArray:
    """The checked samples (n, J) of the straight joint move qa -> qb (``RESOLUTION``)."""
    n = max(2, int(np.ceil(np.abs(qb - qa).max() / RESOLUTION)) + 1)
    u = np.linspace(0.0, 1.0, n)[:, None]
    return qa + u * (qb - qa)


@dataclass(frozen=True)
class TransitPlanner:
    """Routes joint moves around the stock for one job's cell."""

    cell: Cell
    top: float  # z of the stock's highest corner [m]
    lower: FloatArray
    upper: FloatArray

    @classmethod
    def of(
        cls, job: Job, model: RobotModel, margin: float = MARGIN, cell: Cell | None = None
    ) -> TransitPlanner:
        """The transits of ``job``: its whole stock an obstacle, the table at z = 0,
        ``margin`` [m] clearance, no singularity threshold; ``cell``: the plan's cell (its
        robot, bow and stock: no bow built again), else built here."""
        if cell is None or cell.bow is None or cell.model is not model:
            cell = Cell.of(model, job.tool, job.stock, 0.0, margin, 0.0, None)
        else:
            cell = cell.with_rules(0.0, margin, 0.0, None)
        pts = job.stock.corners
        lo = np.maximum(model.lower, -2.0 * np.pi)
        hi = np.minimum(model.upper, 2.0 * np.pi)
        return cls(cell, float(pts[:, 2].max()), lo, hi)

    def free(self, q: FloatArray) -> np.ndarray:
        """(n,) bool: configurations (n, J) that keep every clearance rule and hold the
        wire out of the stock (between cuts the wire is an obstacle like the bow)."""
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
        """True when every sample of the straight joint move qa -> qb is free."""
        return bool(self.free(_samples(qa, qb)).all())

    def clear_moves(self, moves: list[tuple[FloatArray, FloatArray]]) -> np.ndarray:
        """(K,) :meth:`clear` of each move, their samples checked in one batch."""
        samples = [_samples(qa, qb) for qa, qb in moves]
        free = self.free(np.concatenate(samples))
        ends = np.cumsum([len(x) for x in samples])
        return np.array([bool(f.all()) for f in np.split(free, ends[:-1])])

    def lifted(self, q: FloatArray) -> FloatArray | None:
        """Joints nearest ``q`` with the flange raised until the bow and wire are CLEAR
        above the stock's top; None when unreachable."""
        model = self.cell.model
        P = model.fk(q)
        pts = np.concatenate([self.cell.rods.reshape(-1, 3), self.cell.wire])
        low = float((pts @ P[:3, :3].T + P[:3, 3])[:, 2].min())
        rise = self.top + CLEAR - low
        if rise <= 0.0:
            return q
        P[2, 3] += rise
        return nearest_ik(model, P, q)

    def _tree(self, qa: FloatArray, qb: FloatArray) -> list[FloatArray] | None:
        """RRT-connect from ``qa`` to ``qb`` (module doc); the waypoints, or None.

        The moves are checked in batches, the route is the one checking them one at a
        time finds: an iteration whose extension is blocked changes no tree, so the
        extensions of the iterations up to the next unblocked one are made and checked
        together (1, 2, 4, ... of them), and so are the moves of a greedy connection."""
        rng = np.random.default_rng(SEED)
        trees = [([qa], [-1]), ([qb], [-1])]
        drawn: list[FloatArray] = []  # random samples drawn ahead, in the order they are used

        def step(tree, target) -> tuple[int, FloatArray]:
            """The node of ``tree`` nearest ``target`` (max norm) and the new node one
            ``TREE_STEP`` from it towards ``target`` (``target`` itself when nearer)."""
            arr = np.asarray(tree[0])
            i = int(np.argmin(np.abs(arr - target).max(axis=1)))
            d = target - arr[i]
            span = float(np.abs(d).max())
            return i, target if span <= TREE_STEP else arr[i] + d * (TREE_STEP / span)

        def add(tree, i: int, new: FloatArray) -> int:
            tree[0].append(new)
            tree[1].append(i)
            return len(tree[0]) - 1

        def path(tree, k) -> list[FloatArray]:
            nodes, parents = tree
            out = []
            while k >= 0:
                out.append(nodes[k])
                k = parents[k]
            return out

        def connect(tree, target) -> int | None:
            """Greedy: extend ``tree`` towards ``target`` until a move is blocked or it is
            reached (the node reached, else None).  Each extension starts at the node
            the last one added (strictly the nearest to the target in the max norm, as
            :func:`step` would find it): the chain of moves is made first, as
            :func:`step` makes each, and their samples checked in batches."""
            i, new = step(tree, target)
            cur, moves = tree[0][i], []
            while True:
                moves.append((cur, new))
                if np.allclose(new, target):
                    break
                cur = new
                d = target - cur
                span = float(np.abs(d).max())
                new = target if span <= TREE_STEP else cur + d * (TREE_STEP / span)
            done, size = 0, 1
            while done < len(moves):  # batches of 1, 2, 4, ... moves: little checked past a block
                ok = self.clear_moves(moves[done : done + size])
                for _, node in moves[done : done + (len(ok) if ok.all() else int(np.argmin(ok)))]:
                    i = add(tree, i, node)
                if not ok.all():
                    return None
                done, size = done + size, 2 * size
            return i

        it, size = 0, 1
        while it < TREE_ITERATIONS:
            size = min(size, TREE_ITERATIONS - it)
            while len(drawn) < size:
                drawn.append(rng.uniform(self.lower, self.upper))
            tries = [step(trees[(it + m) % 2], drawn[m]) for m in range(size)]
            ok = self.clear_moves([(trees[(it + m) % 2][0][i], new)
                                   for m, (i, new) in enumerate(tries)])  # fmt: skip
            if not ok.any():  # no tree changed: the next iterations see the same trees
                it, drawn, size = it + size, drawn[size:], 2 * size
                continue
            m = int(np.argmax(ok))
            it, drawn, size = it + m, drawn[m + 1 :], 1
            a, b = trees[it % 2], trees[1 - it % 2]
            k = add(a, *tries[m])
            j = connect(b, a[0][k])  # the other tree greedily towards the new node
            if j is not None:
                pa, pb = path(a, k), path(b, j)
                route = pa[::-1] + pb[1:] if it % 2 == 0 else pb[::-1] + pa[1:]
                return self._shortcut(route)
            it += 1
        return None

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
        """Joint moves from ``qa`` to ``qb`` (rad) clear of the stock (module doc)."""
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
        if self.free(qa).all() and self.free(qb).all():
            waypoints = self._tree(qa, qb)
            if waypoints is not None:
                notes.append(f"transit {what}: around the stock through "
                             f"{len(waypoints) - 2} waypoints (the direct move would hit it)")
                return list(itertools.pairwise(waypoints))
        why = ""
        for name, q in (("its start", qa), ("its goal", qb)):
            broken = self.broken(q)
            if broken:
                why += f"; {name} breaks the clearance rules ({', '.join(broken)})"
        notes.append(f"transit {what}: no move clear of the stock found{why}; the direct move "
                     "is kept (see the collision checks)")  # fmt: skip
        return [(qa, qb)]

    def broken(self, q: FloatArray) -> list[str]:
        """The clearance rules the configuration ``q`` (J,) breaks (empty: free)."""
        P = self.cell.model.fk(q[None])
        out = [k for k, v in clearance(self.cell, q[None], P).items() if v.any()]
        if self._wire_in_stock(P).any():
            out.append("wire in the stock")
        if not self.cell.model.within_limits(q):
            out.append("outside the joint limits")
        return out
