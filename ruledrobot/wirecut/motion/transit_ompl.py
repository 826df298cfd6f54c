"""Joint-space routes from OMPL (the Open Motion Planning Library): RRT-Connect, time
bounded, its path simplified, for :class:`~.transit.TransitPlanner`.

OMPL is imported here and only here (``pip install ompl``, its nanobind bindings); the
transit planner imports this module when a transit needs a search, so ``import
ruledrobot`` and planning without a blocked transit never load it.

The collision model stays the planner's, in numpy: OMPL calls back ``valid`` for a
state (one configuration) and ``clear`` for a straight move between two states; the
move is one batch of samples (:meth:`~.transit.TransitPlanner.clear`).  A Python
subclass of ``ompl.base.MotionValidator`` is called by the planner and the simplifier
(the bindings' trampoline forwards ``checkMotion(s1, s2)``; its ``lastValid`` form
answers the same without the last valid state, and neither RRT-Connect nor the
simplifier's steps used here call that form).

Determinism: OMPL seeds each of its random generators from one seed generator when the
generator is made; :func:`rrt_connect` re-seeds that (``ompl.util.RNG.setSeed``) before
it makes the space, the planner and the simplifier, so the same transit gets the same
route every time — as long as the search ends by finding one, not by its time limit
(processor time, not wall time: the same on a busy machine).
OMPL's log (its note that a seed set after the first one does not make the samples of
generators already made deterministic, its planners' progress) is silenced while it runs.
The seed and the log level are the process's: searches in one process run one at a time
(a lock; the batch planner's workers are single-threaded processes anyway).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from ...geometry.checks import FloatArray

__all__ = ["rrt_connect"]

#: one search at a time per process: OMPL's seed generator and log level are global
_LOCK = threading.Lock()


def _array(state: ob.State, n: int) -> FloatArray:
    """The joints (n,) of an OMPL real-vector state."""
    return np.array([state[i] for i in range(n)], dtype=np.float64)


class _Moves(ob.MotionValidator):
    """OMPL's motion check: a straight joint move, checked in one batch by ``clear``."""

    def __init__(self, si: ob.SpaceInformation, n: int,
                 clear: Callable[[FloatArray, FloatArray], bool]) -> None:  # fmt: skip
        super().__init__(si)
        self._n = n
        self._clear = clear

    def checkMotion(self, s1: ob.State, s2: ob.State) -> bool:  # OMPL's name
        return bool(self._clear(_array(s1, self._n), _array(s2, self._n)))


def rrt_connect(
    qa: FloatArray,
    qb: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    valid: Callable[[FloatArray], bool],
    clear: Callable[[FloatArray, FloatArray], bool],
    *,
    time_limit: float,
    step: float,
    seed: int,
) -> list[FloatArray] | None:
    """Waypoints (K, each (J,)) [rad] of a route from ``qa`` to ``qb`` (both free), or None.

    RRT-Connect (Kuffner and LaValle 2000, ``ompl.geometric.RRTConnect``) in the box
    ``lower``-``upper`` (J,) [rad] of joint space, growing its trees by moves of at most
    ``step`` (joint-space Euclidean length, rad), for at most ``time_limit`` seconds of the
    calling thread's processor time (``time.thread_time``: the machine's other work does
    not eat into it, so a search that ends in time on a quiet machine does on a busy one);
    ``valid(q)`` tells whether a configuration (J,) is free, ``clear(qa, qb)`` whether the
    straight joint move between two is.  The route found is simplified by OMPL's
    ``PathSimplifier``: vertices dropped where the move that skips them is clear
    (``reduceVertices``, repeated while it drops one, at most 5 rounds), then corners cut
    between points of the path (``partialShortcutPath``) and vertices closer than the
    simplifier's tolerance merged (``collapseCloseVertices``).  ``seed``: OMPL's seed
    (module doc); the same arguments give the same waypoints.
    """
    with _LOCK:
        return _search(qa, qb, lower, upper, valid, clear, time_limit, step, seed)


def _search(
    qa: FloatArray, qb: FloatArray, lower: FloatArray, upper: FloatArray,
    valid: Callable[[FloatArray], bool], clear: Callable[[FloatArray, FloatArray], bool],
    time_limit: float, step: float, seed: int,
) -> list[FloatArray] | None:
    """:func:`rrt_connect` under its lock."""
    n = len(qa)
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        ou.RNG.setSeed(int(seed))
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for j in range(n):
            bounds.setLow(j, float(lower[j]))
            bounds.setHigh(j, float(upper[j]))
        space.setBounds(bounds)
        si = ob.SpaceInformation(space)
        si.setStateValidityChecker(lambda s: bool(valid(_array(s, n))))
        si.setMotionValidator(_Moves(si, n, clear))
        si.setup()
        start, goal = si.allocState(), si.allocState()
        for j in range(n):
            start[j], goal[j] = float(qa[j]), float(qb[j])
        pdef = ob.ProblemDefinition(si)
        pdef.setStartAndGoalStates(start, goal)
        planner = og.RRTConnect(si)
        planner.setRange(float(step))
        planner.setProblemDefinition(pdef)
        planner.setup()
        t0 = time.thread_time()
        planner.solve(ob.PlannerTerminationCondition(
            lambda: time.thread_time() - t0 > time_limit))  # fmt: skip
        if not pdef.hasExactSolution():
            return None
        path = pdef.getSolutionPath()
        simplifier = og.PathSimplifier(si)
        for _ in range(5):
            if not simplifier.reduceVertices(path):
                break
        simplifier.partialShortcutPath(path)
        simplifier.collapseCloseVertices(path)
        out = [_array(s, n) for s in path.getStates()]
    finally:
        ou.setLogLevel(level)
    out[0], out[-1] = np.array(qa, dtype=np.float64), np.array(qb, dtype=np.float64)
    return out
