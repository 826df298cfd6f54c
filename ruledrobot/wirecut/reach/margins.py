"""Margins: how far each configuration of the wire on a ruling is from breaking a rule.

A configuration is a flange pose (a ruling, a roll about it, a slide along it, a
wire direction) and one of its 8 IK branches.  Its **margin** is one length in
metres: the smallest of

* **reach**: how far the elbow target lies inside the arm's reach
  (:func:`ruledrobot.robot.ik.workspace.reach_margin`; 0 stretched or folded); a pose a
  branch cannot reach gets ``-`` the distance it misses by
  (:func:`~ruledrobot.robot.ik.workspace.reach_excess`);
* **joint limits**: radians from the nearest joint limit (best ``2 pi``
  representative) times the joint's lever (:func:`limit_levers`: the arm's length
  for the shoulder joints, the forearm for the elbow, ``d5 + d6`` for the wrists),
  the arc the arm could still move along before the limit;
* **singularity**: ``(measure - singular_min) * (|a2| + |a3| + |d5|)``, where
  ``measure * (|a2| + |a3| + |d5|) = |sin q3 sin q5| |s|`` is the shoulder factor
  ``s`` (m) discounted by the elbow and wrist sines (0 at the planner's threshold);
* **clearance**: the free space (m) beyond the planner's safety margin between the
  arm and the stock and table, and the bow and the table — the planner's own rules
  (:func:`ruledrobot.wirecut.cut.clearance.clearance`) checked at the levels
  :attr:`Rules.levels`, so the value is quantised down to them (0, 10, 25 mm above
  the 5 mm safety margin; -5, -35, -55 mm below it).  From 45 mm on the clearance
  is **ample** and bounds nothing (the value is infinite): the margin is then the
  arm's own room — reach, limits, singularity.  (A higher level would not work as
  a bound: the arm's shoulder housing stands about 10 cm above the table on every
  UR, so the arm-table rule never holds at a 10 cm level.)  The bow against the
  stock (decided by the roll and slide alone, wherever the block is) and the bow
  and wire against the arm (decided by the tool and the wrist; the bow's hub sits a
  few centimetres from wrist 1 whatever the placement) are rules a configuration
  must keep at the safety margin, but not part of the value (:data:`GATES`).

A configuration is *acceptable* (margin >= 0) exactly when the planner would accept
it: an IK solution inside the joint limits, singularity measure >= the threshold,
every clearance rule kept at the safety margin.  :class:`Reason` says which rule
breaks first, in the order reach, joint limits, singularity, clearance.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import TYPE_CHECKING

import numpy as np

from ...geometry.angles import wrap_angle
from ...geometry.checks import FloatArray
from ...robot.ik.workspace import reach_excess, reach_margin
from ..cut.clearance import (
    ARM_STOCK,
    ARM_TABLE,
    BOW_ARM,
    BOW_STOCK,
    BOW_TABLE,
    MARGIN,
    RULES,
    SINGULAR_MIN,
    Cell,
    Posed,
    broken,
)

if TYPE_CHECKING:
    from ...robot.arm.model import RobotModel

__all__ = [
    "DEFAULT_RULES",
    "GATES",
    "REASON_TEXT",
    "Reason",
    "Rules",
    "clearance_margins",
    "joint_limit_margin",
    "kinematic_margins",
    "limit_levers",
]


class Reason(IntEnum):
    """Why a configuration fails (0: it does not)."""

    OK = 0
    OUT_OF_REACH = 1
    JOINT_LIMIT = 2
    SINGULARITY = 3
    BOW_STOCK = 4
    ARM_STOCK = 5
    BOW_ARM = 6
    BOW_TABLE = 7
    ARM_TABLE = 8
    CHORD = 9
    CLEARANCE = 10


REASON_TEXT = {
    Reason.OK: "reachable",
    Reason.OUT_OF_REACH: "out of reach",
    Reason.JOINT_LIMIT: "joint limit",
    Reason.SINGULARITY: "near a singularity",
    Reason.BOW_STOCK: BOW_STOCK,
    Reason.ARM_STOCK: ARM_STOCK,
    Reason.BOW_ARM: BOW_ARM,
    Reason.BOW_TABLE: BOW_TABLE,
    Reason.ARM_TABLE: ARM_TABLE,
    Reason.CHORD: "chord longer than the wire",
    Reason.CLEARANCE: "clearance",
}

#: the keys of :func:`~..cut.clearance.clearance` and their reasons (checked in this order)
_RULES = {REASON_TEXT[r]: r for r in (Reason.BOW_STOCK, Reason.ARM_STOCK, Reason.BOW_ARM,
                                       Reason.BOW_TABLE, Reason.ARM_TABLE)}  # fmt: skip
#: rules of the tool against the stock and the wrist: pass or fail, not part of the value
GATES = (BOW_STOCK, BOW_ARM)
#: the rules that give the clearance's value (the others: :data:`GATES`)
_VALUED = tuple(key for key in RULES if key not in GATES)


@dataclass(frozen=True)
class Rules:
    """Thresholds of the margins (m, rad).

    ``singular_min`` and ``margin`` are the planner's (:data:`~..cut.clearance.SINGULAR_MIN`,
    :data:`~..cut.clearance.MARGIN`); ``levels`` the clearance levels (m, absolute,
    ascending; ``margin`` among them) at which the clearance rules are checked (from the
    top one on the clearance is ample).
    """

    singular_min: float = SINGULAR_MIN
    margin: float = MARGIN
    levels: tuple[float, ...] = (-0.03, 0.0, MARGIN, 0.015, 0.03, 0.05)
    #: the scale of margins on pictures (m): the map's darkest green
    shown: float = 0.2

    def __post_init__(self) -> None:
        if self.margin not in self.levels or list(self.levels) != sorted(self.levels):
            raise ValueError("Rules.levels: expected ascending levels that include margin")


#: the planner's thresholds (:class:`Rules` defaults)
DEFAULT_RULES = Rules()


def limit_levers(model: RobotModel) -> FloatArray:
    """Metres per radian (6,) that turn each joint's distance to its limit into a length.

    ``|a2| + |a3|`` for joints 1-2, ``|a3|`` for the elbow, ``d5 + d6`` for the wrists."""
    g = model.nominal.ur_geometry
    arm, fore, wrist = abs(g.a2) + abs(g.a3), abs(g.a3), abs(g.d5) + abs(g.d6)
    return np.array([arm, arm, fore, wrist, wrist, wrist])


def joint_limit_margin(
    model: RobotModel, q: FloatArray, levers: FloatArray | None = None
) -> FloatArray:
    """Return the distance of joint positions ``q`` from the nearest joint limit.

    Distance (...) of ``q`` (..., 6), for the best whole-turn representative of each joint
    (negative: no representative fits): radians, or metres with ``levers`` (6,) m/rad
    (:func:`limit_levers`).

    The best representative is the one nearest the middle of the limits.
    """
    lo, hi = np.asarray(model.lower), np.asarray(model.upper)
    fin = np.isfinite(lo) & np.isfinite(hi)
    if not fin.any():
        return np.full(q.shape[:-1], np.inf)
    mid, half = 0.5 * (lo[fin] + hi[fin]), 0.5 * (hi[fin] - lo[fin])
    scale = 1.0 if levers is None else np.asarray(levers)[fin]
    qf = q[..., fin] if not fin.all() else q
    if np.all(mid == 0.0) and np.all(np.abs(qf) <= np.pi):  # principal values: no wrap
        return ((half - np.abs(qf)) * scale).min(axis=-1)
    return ((half - np.abs(wrap_angle(qf - mid))) * scale).min(axis=-1)


def kinematic_margins(
    model: RobotModel, q: FloatArray, P: FloatArray, rules: Rules
) -> tuple[FloatArray, np.ndarray]:
    """Margins (m) and reasons of every IK branch before the clearance rules.

    ``q`` (..., 8, 6) the IK solutions (NaN rows: none) of flange poses ``P``
    (..., 4, 4) in the world frame.  Returns ``(margin, reason)`` (..., 8): the least
    of reach, joint-limit and singularity margins (module doc), and the first rule a
    branch breaks (:class:`Reason`, 0 where none).
    """
    valid = ~np.isnan(q[..., 0])
    qz = np.where(valid[..., None], q, 0.0)
    g = model.nominal.ur_geometry
    scale = abs(g.a2) + abs(g.a3) + abs(g.d5)
    reach = reach_margin(model, qz)
    limit = joint_limit_margin(model, qz, limit_levers(model))
    sing = scale * (model.singularity_measure(qz) - rules.singular_min)
    margin = np.minimum(np.minimum(reach, limit), sing)
    reason = np.where(limit < 0.0, Reason.JOINT_LIMIT,
                      np.where(sing < 0.0, Reason.SINGULARITY, Reason.OK)).astype(np.int8)
    if not valid.all():
        excess, _ = reach_excess(model, P, check=False)
        margin = np.where(valid, margin, -np.maximum(excess, 0.0))
        reason = np.where(valid, reason, np.int8(Reason.OUT_OF_REACH))
    return margin, reason


def _first_failure(checks: dict[str, np.ndarray], n: int) -> np.ndarray:
    reason = np.zeros(n, dtype=np.int8)
    for key, bad in reversed(list(checks.items())):
        reason = np.where(bad, np.int8(_RULES.get(key, Reason.CLEARANCE)), reason)
    return reason


def clearance_margins(
    cell: Cell,
    q: FloatArray,
    P: FloatArray,
    rules: Rules,
    cap: FloatArray | None = None,
    depth: bool = True,
) -> tuple[FloatArray, np.ndarray]:
    """Return the clearance margins (m) and the first clearance rule broken of configurations.

    Configurations ``q`` (n, 6) with flange poses ``P`` (n, 4, 4) (world frame).

    Every rule is checked at the planner's margin.  The rules of the bow against the
    stock and against the arm (:data:`GATES`: the tool and the wrist decide them) only
    pass or fail; the others — arm against stock and table, bow against the table —
    give the value: the highest level (:attr:`Rules.levels`) at which they hold, minus
    the planner's margin, and infinite at the top level (ample clearance).  Levels
    above the margin are tried from the top, only where the result can matter: where
    ``cap`` (n,) (a margin already known from the other rules; None: no cap) exceeds
    the value of the level below; levels below the margin only with ``depth`` (else a
    failure is worth 20 mm below the lowest level).  A broken gate makes the value at
    most ``-margin``.
    ``cell.stock`` may hold one box per configuration (:class:`~.grid.RowBoxes`).

    The bodies are posed once (:class:`~..cut.clearance.Posed`: the arm's forward
    kinematics, the bow carried by ``P``) and the rules judged on them at each level, on
    the configurations the level is tried for; above the margin only the rules that give
    the value (the gates are decided at the margin).
    """
    n = len(q)
    at = Posed.of(cell, q, P)
    first = broken(cell, at, margin=rules.margin)
    reason = _first_failure(first, n)
    gate = np.zeros(n, bool)
    env = np.zeros(n, bool)
    for key, bad in first.items():
        if key in GATES:
            gate |= bad
        else:
            env |= bad
    levels = np.asarray(rules.levels)
    k0 = int(np.flatnonzero(levels == rules.margin)[0])
    floor = levels[0] - rules.margin - 0.02
    value = np.where(env, floor, 0.0)

    def kept(level: float, idx: np.ndarray) -> np.ndarray:
        stock = cell.stock.take(idx) if hasattr(cell.stock, "take") else cell.stock
        bad = np.zeros(idx.size, bool)
        for b in broken(cell, at[idx], margin=level, stock=stock, only=_VALUED).values():
            bad |= b
        return ~bad

    pending = np.flatnonzero(~env)
    upper = levels[k0:]  # the margin, then the levels above it
    for i in range(len(upper) - 1, 0, -1):
        v = np.inf if i == len(upper) - 1 else float(upper[i]) - rules.margin
        below = float(upper[i - 1]) - rules.margin
        sel = pending if cap is None else pending[cap[pending] > below]
        if sel.size:
            ok = kept(float(upper[i]), sel)
            value[sel[ok]] = v
            pending = np.setdiff1d(pending, sel[ok], assume_unique=True)
    idx = np.flatnonzero(env) if depth else np.zeros(0, np.intp)
    for level in levels[:k0][::-1]:
        if not idx.size:
            break
        ok = kept(float(level), idx)
        value[idx[ok]] = float(level) - rules.margin
        idx = idx[~ok]
    value = np.where(gate, np.minimum(value, -rules.margin), value)
    return value, reason
