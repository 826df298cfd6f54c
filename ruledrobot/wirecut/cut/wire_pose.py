"""Choosing the wire's free degrees of freedom and the IK branch along a cut.

The wire on ruling i leaves the roll ``psi`` about the ruling, the slide ``s``
along it and the wire direction (``reverse``) free (see
:mod:`ruledrobot.wirecut.cut.wire_geometry`).  The default motion, as the issue asks, is
the refined DH frame motion with a **constant offset**: one roll, one wire
direction and — where every chord allows it — one slide for the whole cut, so
the tool inherits the smoothness of the refined SE(3) frame motion.

Search (vectorised over rulings; a Python loop over the small candidate grid):

1. slide: the midpoint of the intersection of all feasible slide intervals (and,
   when no candidate works there, slides near both ends of it); if that
   intersection is empty, each ruling takes the point of its own interval
   nearest that midpoint (reported);
2. every roll of a grid (default 36 values) x both wire directions is scored on
   a subsample of the rulings: branch-continuous path IK
   (:func:`ruledrobot.robot.path_ik`), the smallest singularity measure, the
   clearances (bow and arm vs stock and table, bow and wire vs the arm; see
   :func:`_clearance`), total joint travel; around the candidates that lose the
   fewest rulings the roll is refined;
3. candidates are verified on all rulings, best first; the first that passes
   wins;
4. when no constant roll works, the roll varies: a ladder graph over
   (roll x IK branch) per sampled ruling, nodes removed where IK fails, the
   configuration is near a singularity or the bow is not clear, edges weighted
   by the squared (wrapped) joint motion plus a roll-change penalty, solved by
   dynamic programming (Viterbi) — as semi-constrained Cartesian planners do.
   The roll sequence is smoothed and verified on every ruling on the IK branches
   the dynamic program chose.
   When that fails too, the result is infeasible and says, per reason, how many
   rulings the best candidate lost — the planner reports it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...io.words import index_ranges
from ...robot import RobotModel, path_ik, wrap_angle
from ...robot.ik.path import JUMP_THRESHOLD
from ...robot.tool import BowTool
from ..job.spec import ToolSpec
from .clearance import MARGIN, SINGULAR_MIN, Cell, clearance
from .search_memo import memoized
from .wire_geometry import chords, flange_poses, slide_bounds, wire_poses

__all__ = [
    "RedundancyResult", "SearchOptions", "bow_segments", "search_wire_pose", "solve_redundancy",
]

STRATEGIES = ("auto", "constant", "varying")
#: constant rolls scored over a turn (:attr:`SearchOptions.rolls`; the reach map and the
#: placement search sample the same grid, ``reach.grid.ROLLS``)
ROLLS = 36


@dataclass(frozen=True, eq=False)
class SearchOptions:
    """The settings of the wire-pose search (:func:`solve_redundancy`).

    One value that travels from the plan to every pass (the defaults are the planner's).

    ``rolls``: constant rolls scored; ``sample``: rulings they are scored on;
    ``singular_min``: least singularity measure; ``jump_threshold`` [rad]: largest joint
    step between rulings; ``table_z`` [m]: the table top in the base frame (None: no
    table); ``margin`` [m]: clearance of bow and arm from stock, table and each other;
    ``strategy``: "auto", "constant" or "varying"; ``q_start`` (6,): joints the motion
    starts near (the job's ``[robot] home`` when the plan has one).
    """

    rolls: int = ROLLS
    sample: int = 80
    singular_min: float = SINGULAR_MIN
    jump_threshold: float = JUMP_THRESHOLD
    table_z: float | None = 0.0
    margin: float = MARGIN
    strategy: str = "auto"
    q_start: FloatArray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.strategy not in STRATEGIES:
            raise ValueError(
                f"strategy: expected auto, constant or varying, got {self.strategy!r}"
            )

    def cell(self, model: RobotModel, tool: ToolSpec | BowTool, stock: Box) -> Cell:
        """The clearance cell of these options (built once per plan and passed down).

        The whole collision model, the arm against itself included, as the transits between the
        passes judge their ends (one model: a pass may not end where no transit may start)."""
        cell = Cell.of(model, tool, stock, self.table_z, self.margin, self.singular_min,
                       self.q_start)  # fmt: skip
        return dataclasses.replace(cell, self_collision=True)


def bow_segments(tool: ToolSpec) -> FloatArray:
    """Return the bow's rods (3, 2, 3) in the flange frame.

    See :meth:`ruledrobot.robot.tool.BowTool.segments`: an arm from each wire end back to
    the plane through the flange axis normal to the bow's depth direction, and the crossbar
    between the arms' ends.
    """
    return BowTool.from_spec(tool).segments()


@dataclass(frozen=True)
class RedundancyResult:
    """The chosen motion of the wire and the robot along the rulings (M of them)."""

    feasible: bool
    roll: FloatArray  # (M,) rad
    slide: FloatArray  # (M,) m
    reverse: bool
    flange: FloatArray = field(repr=False)  # (M, 4, 4) flange poses
    q: FloatArray = field(repr=False)  # (M, 6) joint positions
    chord: FloatArray = field(repr=False)  # (M, 2) chord parameters (NaN: no chord)
    hit: np.ndarray = field(repr=False)  # (M,) ruling crosses the stock
    min_measure: float = 0.0
    max_step: float = 0.0
    constant_slide: bool = True
    candidates: int = 0
    reasons: tuple[str, ...] = ()


@dataclass
class _Score:
    roll: float
    reverse: bool
    slide: int  # index of the slide option
    ok: bool
    travel: float
    min_measure: float
    lost: dict[str, int]


def _failures(cell: Cell, frames, roll, slide, reverse, jump: float):
    """Flange poses, path IK and, per reason, the rulings (bool masks) that fail."""
    P = flange_poses(wire_poses(frames, roll, slide, reverse), cell.W)
    ik = path_ik(cell.model, P, q_start=cell.q_start, jump_threshold=jump)
    checks = clearance(cell, ik.q, P)
    masks = {
        "no continuous IK solution": ~ik.ok,
        "near a singularity": ik.ok & (ik.measure < cell.singular_min),
        **{key: ik.ok & v for key, v in checks.items()},
    }
    return P, ik, masks


def _evaluate(cell: Cell, frames, roll, slide, reverse, jump: float):
    """Flange poses, path IK, whether all checks pass, and lost rulings per reason."""
    P, ik, masks = _failures(cell, frames, roll, slide, reverse, jump)
    lost = {key: int(v.sum()) for key, v in masks.items()}
    return P, ik, all(v == 0 for v in lost.values()), lost


def solve_redundancy(
    frames: FloatArray, stock: Box, tool: ToolSpec, model: RobotModel, **options: Any
) -> RedundancyResult:
    """Choose roll, slide, wire direction and IK branch for rulings with ``frames`` (M, 4, 4).

    ``model``: a :class:`~ruledrobot.robot.RobotModel` whose ``fk`` gives the flange
    pose (no tool set).  ``options``: fields of :class:`SearchOptions` that differ from
    its defaults (``rolls``, ``sample``, ``singular_min``, ``jump_threshold``,
    ``table_z``, ``margin``, ``strategy``, ``q_start``; TypeError for any other name).
    See the module doc for the search; :func:`search_wire_pose` is the same with the
    options as one value and the cell built once by the caller.
    """
    opts = replace(SearchOptions(), **options)
    return search_wire_pose(frames, tool, opts.cell(model, tool, stock), opts)


def search_wire_pose(
    frames: FloatArray, tool: ToolSpec, cell: Cell, options: SearchOptions
) -> RedundancyResult:
    """Run :func:`solve_redundancy` in ``cell``.

    ``cell``: robot, bow, stock, table and thresholds (the cell of ``options``,
    :meth:`SearchOptions.cell`); ``tool`` gives the wire's length and clearance.  A search
    asked again with the same inputs (carve's robot check, then the plan, in ``make``) is
    answered from :mod:`.search_memo`.
    """
    F = np.asarray(frames, dtype=np.float64)
    return memoized(lambda: _search(F, tool, cell, options),
                    "wire_pose.search", F, tool, cell, options)  # fmt: skip


def _search(
    frames: FloatArray, tool: ToolSpec, cell: Cell, options: SearchOptions
) -> RedundancyResult:
    """:func:`search_wire_pose`, computed."""
    rolls, sample, jump_threshold = options.rolls, options.sample, options.jump_threshold
    singular_min, strategy, q_start = cell.singular_min, options.strategy, cell.q_start
    model, stock = cell.model, cell.stock
    F = np.asarray(frames, dtype=np.float64)
    m = F.shape[0]
    c0, c1, hit = chords(F, stock)
    if not hit.any():
        raise ValueError("rulings: none of them crosses the stock; nothing to cut")
    lo, hi, ok = slide_bounds(c0, c1, hit, tool)
    chord = np.c_[c0, c1]
    reasons: list[str] = []

    def result(roll, slide, reverse, P, q, measure, step, n_scores) -> RedundancyResult:
        return RedundancyResult(
            True,
            roll,
            slide,
            reverse,
            P,
            q,
            chord,
            hit,
            float(measure),
            float(step),
            constant,
            n_scores,
            tuple(reasons),
        )

    def failure(reverse: bool = False, slide=None, n_scores: int = 0) -> RedundancyResult:
        empty = np.zeros(0)
        return RedundancyResult(
            False,
            empty,
            empty if slide is None else slide,
            reverse,
            np.zeros((0, 4, 4)),
            np.zeros((0, 6)),
            chord,
            hit,
            candidates=n_scores,
            reasons=tuple(reasons),
        )

    if not ok.all():
        bad = np.flatnonzero(~ok)
        longest = float(np.nanmax(c1 - c0))
        reasons.append(
            f"{bad.size} chord(s) longer than the wire allows (longest {longest * 1e3:.1f} mm, "
            f"wire {tool.wire_length * 1e3:.1f} mm less 2 x {tool.clearance * 1e3:.1f} mm "
            f"clearance), first at ruling {int(bad[0])}"
        )
        constant = False
        return failure()
    L, H = lo[hit].max(), hi[hit].min()
    constant = bool(L <= H)
    if constant:
        slide = np.full(m, 0.5 * (L + H))
    else:
        centre = 0.5 * (np.median(lo[hit]) + np.median(hi[hit]))
        slide = np.clip(np.full(m, centre), lo, hi)
        reasons.append("no single slide covers every chord: the slide varies along the cut")
    idx = np.unique(np.linspace(0, m - 1, min(sample, m)).round().astype(int))
    stride = max(1.0, (m - 1) / max(1, idx.size - 1))
    grid = np.linspace(-np.pi, np.pi, rolls, endpoint=False)
    # slide options: the middle of the common feasible interval, then (only when nothing
    # works there) slides near both of its ends
    slides = [slide]
    if constant and H - L > 1e-6:
        slides += [np.full(m, L + 0.1 * (H - L)), np.full(m, H - 0.1 * (H - L))]

    def scores_of(cands: list[tuple[float, bool, int]]) -> list[_Score]:
        """Candidates (roll, reverse, slide option) scored on the sampled rulings: the IK
        of every candidate's poses in one batch, path IK one candidate at a time, the
        clearance rules on all of them in one batch."""
        poses = [flange_poses(wire_poses(F[idx], np.full(idx.size, psi), slides[k][idx],
                                         reverse), cell.W)
                 for psi, reverse, k in cands]  # fmt: skip
        sols = model.ik(np.stack(poses), return_info=True, check=False)  # (C, n, 8, ...)
        iks = [path_ik(model, P, q_start=q_start, jump_threshold=jump_threshold * stride,
                       solutions=sols[c]) for c, P in enumerate(poses)]  # fmt: skip
        # the clearance of a candidate counts only where its IK holds: those with none
        # (a cut out of reach) are left out of the batch, exactly
        live = [c for c, ik in enumerate(iks) if ik.ok.any()]
        checks = clearance(cell, np.stack([iks[c].q for c in live]),
                           np.stack([poses[c] for c in live])) if live else {}  # fmt: skip
        row = {c: r for r, c in enumerate(live)}
        out = []
        for c, ((psi, reverse, k), ik) in enumerate(zip(cands, iks, strict=True)):
            masks = {
                "no continuous IK solution": ~ik.ok,
                "near a singularity": ik.ok & (ik.measure < singular_min),
                **{key: ik.ok & v[row[c]] for key, v in checks.items() if c in row},
            }
            lost = {key: int(v.sum()) for key, v in masks.items()}
            ok_c = all(v == 0 for v in lost.values())
            travel = float(np.abs(np.diff(ik.q, axis=0)).sum()) if ik.q.size else np.inf
            out.append(_Score(float(psi), reverse, k, ok_c, travel, float(np.min(ik.measure)),
                              lost))  # fmt: skip
        return out

    scores = scores_of([(psi, rev, 0) for rev in (False, True) for psi in grid])
    for k in range(1, len(slides)):
        if any(sc.ok for sc in scores):
            break
        scores += scores_of([(psi, rev, k) for rev in (False, True) for psi in grid])
    step = 2.0 * np.pi / rolls
    if not any(sc.ok for sc in scores):  # refine the roll around the least-bad candidates
        least_bad = sorted(scores, key=lambda sc: sum(sc.lost.values()))[:3]
        scores += scores_of([(sc.roll + frac * step, sc.reverse, sc.slide) for sc in least_bad
                             for frac in (-0.75, -0.5, -0.25, 0.25, 0.5, 0.75)])  # fmt: skip
    # feasible first, then fewest lost rulings, least joint travel, best conditioned
    order = sorted(
        scores, key=lambda sc: (not sc.ok, sum(sc.lost.values()), sc.travel, -sc.min_measure)
    )
    if strategy != "varying":
        for i, sc in enumerate(order[:12]):
            if not sc.ok and i > 0:
                break
            roll = np.full(m, sc.roll)
            P, ik, ok_c, _ = _evaluate(cell, F, roll, slides[sc.slide], sc.reverse, jump_threshold)
            if ok_c:
                return result(
                    roll,
                    slides[sc.slide],
                    sc.reverse,
                    P,
                    ik.q,
                    ik.measure.min(),
                    ik.max_step,
                    len(scores),
                )
    for reverse in (False, True) if strategy != "constant" else ():
        fine = np.linspace(-np.pi, np.pi, 2 * rolls, endpoint=False)
        found = _ladder_roll(cell, F, slide, reverse, fine, idx, jump_threshold * stride)
        if found is None:
            continue
        roll, branch = found
        P = flange_poses(wire_poses(F, roll, slide, reverse), cell.W)
        q = _follow_branch(model, P, branch, q_start)
        if q is None:
            continue
        measure = model.singularity_measure(q)
        jump = float(np.abs(np.diff(q, axis=0)).max()) if m > 1 else 0.0
        clear = not any(v.any() for v in clearance(cell, q, P).values())
        if jump <= jump_threshold and measure.min() >= singular_min and clear:
            reasons.append("no constant roll works: the roll varies along the cut")
            return result(roll, slide, reverse, P, q, measure.min(), jump, len(scores))
    best = order[0]
    _, _, masks = _failures(
        cell, F, np.full(m, best.roll), slides[best.slide], best.reverse, jump_threshold
    )
    summary = "; ".join(f"{why} at rulings {index_ranges(v)}"
                        for why, v in masks.items() if v.any())  # fmt: skip
    reasons.append(
        "no constant or varying roll works: the best constant candidate "
        f"(roll {np.degrees(best.roll):.0f} deg, "
        f"{'reversed' if best.reverse else 'along the ruling'}, of {m} rulings) fails: "
        f"{summary or 'no single failing ruling (a jump between rulings)'}"
    )
    return failure(best.reverse, slide, len(scores))


#: standard deviation [sampled rulings] of the Gaussian that smooths the dynamic
#: program's grid rolls (the roll rate drives the wrist's accelerations)
ROLL_SMOOTHING = 2.0


def _ladder_roll(
    cell: Cell,
    F,
    slide,
    reverse,
    grid: FloatArray,
    idx: np.ndarray,
    jump: float,
    roll_weight: float = 0.5,
) -> tuple[FloatArray, np.ndarray] | None:
    """Roll (M,) and IK branch (M,) per ruling from a Viterbi pass over (roll x branch)
    nodes at the sampled rulings ``idx`` (roll smoothed and interpolated, branch of the
    nearest sample); None when no path exists."""
    model = cell.model
    n, k = idx.size, grid.size
    psi = np.broadcast_to(grid, (n, k))
    P = flange_poses(
        wire_poses(F[idx][:, None], psi, np.broadcast_to(slide[idx, None], (n, k)), reverse),
        cell.W,
    )  # (n, k, 4, 4)
    q = model.ik(P, check=False)  # (n, k, 8, 6)
    valid = ~np.isnan(q).any(axis=-1)
    meas = np.where(valid, model.singularity_measure(np.nan_to_num(q)), 0.0)
    valid &= meas >= cell.singular_min
    if not valid.any(axis=(1, 2)).all():  # a sampled ruling with no node: no path (exact),
        return None  # and the clearance of every node (most of the time) is not needed
    # the clearance of the nodes still valid only (those with no IK, or near a
    # singularity, are out either way)
    at = np.nonzero(valid)
    bad = np.zeros(at[0].size, dtype=bool)
    for b in clearance(cell, q[at], P[at[:2]]).values():
        bad |= b
    valid[at] = ~bad
    qn = np.nan_to_num(q).reshape(n, k * 8, 6)
    node_ok = valid.reshape(n, k * 8)
    roll_of = np.repeat(grid, 8)
    droll = wrap_angle(roll_of[:, None] - roll_of[None, :]) ** 2
    cost = np.where(node_ok[0], 0.0, np.inf)
    back = np.zeros((n, k * 8), dtype=np.intp)
    for i in range(1, n):
        # only the reached nodes of the last ruling and the valid ones of this (the rest
        # cost inf either way; in index order, so ties break as over all nodes)
        a, b = np.flatnonzero(np.isfinite(cost)), np.flatnonzero(node_ok[i])
        if not (a.size and b.size):
            return None
        dq = wrap_angle(qn[i - 1][a][:, None, :] - qn[i][b][None, :, :])  # (A, B, 6)
        step = np.abs(dq).max(axis=-1)
        c = (dq * dq).sum(-1) + roll_weight * droll[np.ix_(a, b)]
        c = np.where(step <= jump, c, np.inf)
        total = cost[a][:, None] + c
        arg = np.argmin(total, axis=0)
        back[i, b] = a[arg]
        cost = np.full(k * 8, np.inf)
        cost[b] = total[arg, np.arange(b.size)]
        if not np.isfinite(cost).any():
            return None
    j = int(np.argmin(cost))
    if not np.isfinite(cost[j]):
        return None
    path = np.empty(n, dtype=np.intp)
    path[-1] = j
    for i in range(n - 1, 0, -1):
        path[i - 1] = back[i, path[i]]
    roll_s = np.unwrap(roll_of[path])
    # smooth the piecewise-constant grid rolls (a Gaussian over a few samples), then
    # interpolate to every ruling with a C2 cubic: a roll rate that jumps between
    # samples (piecewise-linear interpolation) makes the joints' rates jump with it,
    # and the timed motion between rulings wobble off the surface
    if n >= 3:
        from scipy.ndimage import gaussian_filter1d

        roll_s = gaussian_filter1d(roll_s, ROLL_SMOOTHING, mode="nearest")
    rulings = np.arange(F.shape[0])
    nearest = idx[np.abs(rulings[:, None] - idx[None, :]).argmin(axis=1)]
    branch = (path % 8)[np.searchsorted(idx, nearest)]
    if n >= 4:
        from scipy.interpolate import CubicSpline

        return CubicSpline(idx, roll_s, bc_type="natural")(rulings), branch
    return np.interp(rulings, idx, roll_s), branch


def _follow_branch(
    model: RobotModel, P: FloatArray, branch: np.ndarray, q_start: FloatArray | None
) -> FloatArray | None:
    """Joints (M, 6) of flange poses P on the given IK branches, unwrapped along the path
    and shifted by whole turns towards ``q_start`` (else into the limits); None when a
    branch has no solution or the path leaves the joint limits."""
    sols = model.ik(P, check=False)
    q = sols[np.arange(len(P)), branch]
    if np.isnan(q).any():
        return None
    q = np.unwrap(q, axis=0)
    ref = q[0] if q_start is None else np.asarray(q_start, dtype=np.float64)
    q = q + 2.0 * np.pi * np.round((ref - q[0]) / (2.0 * np.pi))
    for j in range(q.shape[1]):  # per joint: the whole turn that keeps it within limits
        for turn in (0.0, -2.0 * np.pi, 2.0 * np.pi):
            qj = q[:, j] + turn
            if np.all((qj >= model.lower[j]) & (qj <= model.upper[j])):
                q[:, j] = qj
                break
        else:
            return None
    return q
