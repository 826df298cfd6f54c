"""Why a plan found no path, in numbers a fabricator can act on: how far out of reach
and which rulings, which rule, and which way to move the block.

Every figure is the one margin model's (docs/place.md, "One model"):

* which rulings no roll serves, and by how much they miss the arm's reach: a coarse
  reachability map (:func:`~.map.map_pass`, 60 rulings x the planner's 36 rolls) of
  every pass the redundancy search could not solve;
* the best constant roll and the share of the sampled rulings it serves: the
  placement search's column (:func:`~.evaluate.details`, the same function
  ``ruledrobot reach`` and ``ruledrobot place`` report); when it serves every sampled
  ruling although the planner found no constant roll, the planner's own check of every
  ruling at that roll says what fails between the samples;
* the move: the block moved along eight horizontal directions (towards and away from
  the robot, to either side and between) by 2.5 to 50 cm, scored by the same
  :class:`~.evaluate.Evaluator`; the shortest move after which a constant roll
  serves every sampled ruling of every pass is suggested.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...geometry.angles import wrap_angle
from ...geometry.checks import FloatArray
from ...io.words import mm
from ...robot.ik.workspace import REACH_DIRECTIONS, reach_excess
from ..cut.clearance import Cell
from ..cut.cutpath import CutPath
from .grid import ROLLS
from .map import PassMap, job_cell, map_pass
from .margins import DEFAULT_RULES, REASON_TEXT, Reason
from .report import ruling_ranges

if TYPE_CHECKING:
    from ...robot.arm.model import RobotModel
    from ..job.spec import Job
    from ..plan import Plan
    from .evaluate import Evaluator

__all__ = ["reach_reasons", "suggest_move"]

#: shifts tried (m) along each of the eight directions
SHIFTS = (0.025, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5)
_NAMES = ("towards the robot", "towards the robot and to its left", "to the robot's left",
          "away from the robot and to its left", "away from the robot",
          "away from the robot and to its right", "to the robot's right",
          "towards the robot and to its right")  # fmt: skip


def suggest_move(
    job: Job, passes: list[CutPath], model: RobotModel | None = None,
    evaluator: Evaluator | None = None,
) -> tuple[str, float, FloatArray, float] | None:
    """Return the shortest horizontal move of the block after which one roll serves every pass.

    One constant roll serves every sampled ruling of every pass (the placement search's
    margin >= 0, on its default grid, or ``evaluator``'s): ``(direction in words, distance
    m, new block centre (3,), worst margin m)``, or None when none of the moves tried does.
    """
    from .evaluate import Evaluator

    ev = Evaluator(job, list(passes), model) if evaluator is None else evaluator
    base = ev.model.base[:3, 3]
    u = job.stock.centre - base
    u[2] = 0.0
    u = u / np.linalg.norm(u) if np.linalg.norm(u) > 1e-9 else np.array([1.0, 0.0, 0.0])
    v = np.cross([0.0, 0.0, 1.0], u)
    angles = np.arange(8) * np.pi / 4
    dirs = -np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v  # 0: towards the robot
    moves = (np.asarray(SHIFTS)[:, None, None] * dirs[None]).reshape(-1, 3)
    T = np.repeat(np.eye(4)[None], len(moves), axis=0)
    T[:, :3, 3] = moves
    sc = ev(T)
    ok = np.flatnonzero(sc.margin >= 0.0)
    if not ok.size:
        return None
    k = ok[0]  # shifts ascending: the first that works is the shortest
    return _NAMES[k % 8], float(SHIFTS[k // 8]), job.stock.centre + moves[k], float(sc.margin[k])


def _excess_words(cell: Cell, cp: CutPath, pm: PassMap, ruling: int) -> str:
    """How far, and which way, the best configuration of a sampled ruling misses."""
    d = pm.shown
    k = int(np.argmax(pm.margin[d, :, ruling]))
    from .grid import pass_poses

    slide = pm.slide[ruling:ruling + 1]
    if pm.slides is not None and pm.slide_index is not None:  # the cell's best slide
        slide = pm.slides[pm.slide_index[d, k, ruling], ruling:ruling + 1]
    P = pass_poses(cell.W, cp.frames[pm.idx[ruling:ruling + 1]], slide,
                   pm.rolls[k:k + 1], ((False, True)[d],))[0, 0, 0]  # fmt: skip
    e, kind = reach_excess(cell.model, P, check=False)
    b = int(np.argmin(e))
    return f"{e[b] * 1e3:.0f} mm, the wrist {REACH_DIRECTIONS[int(kind[b])]}"


_JOINTS = ("shoulder pan", "shoulder lift", "elbow", "wrist 1", "wrist 2", "wrist 3")


def _joints_out(model: RobotModel, pm: PassMap, d: int, mask: np.ndarray) -> str:
    """Which joints' limits the best configurations of the rulings ``mask`` break."""
    k = np.argmax(pm.margin[d], axis=0)[mask]
    q = pm.q[d, k, np.flatnonzero(mask)]
    lo, hi = np.asarray(model.lower), np.asarray(model.upper)
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    with np.errstate(invalid="ignore"):
        out = (np.abs(wrap_angle(np.nan_to_num(q) - np.where(np.isfinite(mid), mid, 0.0)))
               > half).any(axis=0)  # fmt: skip
    names = [f"joint {j + 1} ({_JOINTS[j]})" for j in np.flatnonzero(out)]
    return "limits of " + ", ".join(names) if names else "joint limits"


def reach_reasons(plan: Plan) -> tuple[str, ...]:
    """Extra reasons for a plan some pass of which is infeasible (module doc).

    () when every pass is feasible."""
    from .evaluate import Evaluator, constant_words, details

    bad = [(k, cp) for k, cp in enumerate(plan.passes) if not cp.feasible]
    if not bad:
        return ()
    job = plan.job
    cell = job_cell(job, plan.model, DEFAULT_RULES)
    out = []
    try:
        ev = Evaluator(job, list(plan.passes), plan.model)
        cols = details(ev, np.eye(4))
    except ValueError as exc:  # a pass that cannot be scored (no chord, say)
        ev, cols = None, None
        out.append(f"no constant roll or move scored: {exc}")
    for k, cp in bad:
        pm = map_pass(cell, job.tool, cp, k, DEFAULT_RULES, rulings=60, rolls=ROLLS)
        d = pm.shown
        head = f"{cp.name}: " if len(job.cuts) > 1 else ""
        best = pm.margin[d].max(axis=0)
        at = pm.reason[d][np.argmax(pm.margin[d], axis=0), np.arange(pm.idx.size)]
        for r in np.unique(at[best < 0]):
            mask = (best < 0) & (at == r)
            every = (pm.reason[d][:, mask] == r).all()
            text = f"{head}rulings {ruling_ranges(pm, mask)} (of {pm.rulings}): "
            text += (f"{REASON_TEXT[Reason(r)]} at every roll of the wire" if every else
                     f"no roll of the wire works, the nearest miss: {REASON_TEXT[Reason(r)]}")
            if r == Reason.JOINT_LIMIT:
                text += f" ({_joints_out(plan.model, pm, d, mask)})"
            if r == Reason.OUT_OF_REACH:
                worst = int(np.flatnonzero(mask)[np.argmin(best[mask])])
                text += (f"; out of reach by up to {_excess_words(cell, cp, pm, worst)} "
                         f"(ruling {pm.idx[worst]})")
            out.append(text)
        if cols is not None:
            out.append(f"{head}{constant_words(job, plan.model, cp, cols[k])} "
                       "(ruledrobot reach draws the map)")
    move = None if ev is None else suggest_move(job, plan.passes, plan.model, ev)
    if move is not None:
        words, dist, centre, margin = move
        out.append(f"moving the block {mm(dist)} mm {words} (block centre to x = "
                   f"{mm(centre[0])} mm, y = {mm(centre[1])} mm, surfaces with it) lets one "
                   "constant roll of the wire serve every sampled ruling of every pass "
                   f"(worst margin {margin * 1e3:.0f} mm); ruledrobot place searches "
                   "position and yaw")
    elif ev is not None:
        out.append("no move of the block by up to 50 cm in any horizontal direction lets a "
                   "constant roll of the wire serve every sampled ruling; try ruledrobot "
                   "place (position and yaw), setups, or another robot")
    return tuple(out)
