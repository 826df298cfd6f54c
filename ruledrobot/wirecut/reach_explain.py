"""Why a plan found no path, in numbers a fabricator can act on: how far out of reach
and which rulings, which rule, and which way to move the block.

For every pass the redundancy search could not solve, a coarse reachability map
(:func:`~.reach.map_pass`) gives per ruling the best cell over every roll and wire
direction: the rulings no roll serves, grouped by reason, and by how much they miss
the arm's reach (:func:`~ruledrobot.robot.workspace.reach_excess`).  Then the block
is tried moved along eight horizontal directions (towards and away from the robot,
to either side and between) by 2.5 to 50 cm (:class:`~.place_eval.Evaluator`, the
whole job): the shortest move with a worst margin >= 0 is suggested.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..geometry.angles import wrap_angle
from ..geometry.checks import FloatArray
from ..robot.workspace import REACH_DIRECTIONS, reach_excess
from .clearance import Cell
from .cutpath import CutPath
from .margins import DEFAULT_RULES, REASON_TEXT, Reason
from .placement import mm
from .reach import PassMap, job_cell, map_pass
from .reach_report import ruling_ranges

if TYPE_CHECKING:
    from ..robot.model import RobotModel
    from .plan import Plan
    from .spec import Job

__all__ = ["reach_reasons", "suggest_move"]

#: shifts tried (m) along each of the eight directions
SHIFTS = (0.025, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5)
_NAMES = ("towards the robot", "towards the robot and to its left", "to the robot's left",
          "away from the robot and to its left", "away from the robot",
          "away from the robot and to its right", "to the robot's right",
          "towards the robot and to its right")  # fmt: skip


def suggest_move(
    job: Job, passes: list[CutPath], model: RobotModel | None = None
) -> tuple[str, float, FloatArray] | None:
    """The shortest horizontal move of the block that gives every sampled ruling of every
    pass a configuration with margin >= 0: ``(direction in words, distance m, new block
    centre (3,))``, or None when none of the moves tried does."""
    from .place_eval import Evaluator

    ev = Evaluator(job, list(passes), model, rulings=24, rolls=12)
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
    return _NAMES[k % 8], float(SHIFTS[k // 8]), job.stock.centre + moves[k]


def _excess_words(cell: Cell, cp: CutPath, pm: PassMap, ruling: int) -> str:
    """How far, and which way, the best configuration of a sampled ruling misses."""
    d = pm.shown
    k = int(np.argmax(pm.margin[d, :, ruling]))
    from .reach_grid import pass_poses

    P = pass_poses(cell.W, cp.frames[pm.idx[ruling:ruling + 1]], pm.slide[ruling:ruling + 1],
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
    """Extra reasons for a plan some pass of which is infeasible (module doc); () when
    every pass is feasible."""
    bad = [(k, cp) for k, cp in enumerate(plan.passes) if not cp.feasible]
    if not bad:
        return ()
    job = plan.job
    cell = job_cell(job, plan.model, DEFAULT_RULES)
    out = []
    for k, cp in bad:
        pm = map_pass(cell, job.tool, cp, k, DEFAULT_RULES, rulings=60, rolls=24)
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
        kc, worst = pm.best_constant(d)
        share = float((pm.margin[d, kc] >= 0).mean())
        out.append(f"{head}the best constant roll ({np.degrees(pm.rolls[kc]):.0f} deg) serves "
                   f"{100 * share:.0f} % of the rulings (ruledrobot reach draws the map)")
    try:
        move = suggest_move(job, plan.passes, plan.model)
    except ValueError as exc:  # a pass that cannot be scored (no chord, say)
        move = None
        out.append(f"no move suggested: {exc}")
    if move is not None:
        words, dist, centre = move
        out.append(f"moving the block {mm(dist)} mm {words} (block centre to x = "
                   f"{mm(centre[0])} mm, y = {mm(centre[1])} mm, surfaces with it) "
                   "gives every sampled ruling a configuration within the rules; "
                   "ruledrobot place searches position and yaw")
    else:
        out.append("no move of the block by up to 50 cm in any horizontal direction makes "
                   "every ruling reachable; try ruledrobot place (position and yaw), setups, "
                   "or another robot")
    return tuple(out)
