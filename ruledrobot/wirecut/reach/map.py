"""The reachability map of a job: for each ruling of each pass, each roll of the wire
about it and each wire direction, whether the arm can hold the wire there and, if
not, why; the margin (:mod:`.margins`) where it can.

The passes are the planner's own (:func:`~..cut.passes.cut_paths`: refined rulings, kerf,
lead-in/out), the slide is the planner's (the chosen motion's, else the one its
search starts from), and the path the planner chose is kept to be drawn on the map
and checked against it.  Vectorised over rulings x rolls x directions x IK branches;
the clearance rules run only on the branch that can still be the best of its cell
(:func:`~.branch_bound.best_of`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ...geometry.angles import wrap_angle
from ...geometry.checks import FloatArray
from ..cut.clearance import Cell
from ..cut.cutpath import CutPath
from ..cut.passes import cut_paths
from ..cut.wire_geometry import chords, flange_poses, slide_bounds, wire_poses
from ..job.spec import Job, ToolSpec
from .branch_bound import best_of
from .grid import (
    directions_needed,
    job_cell,
    pass_poses,
    planner_slide,
    planner_slides,
    sample_rulings,
)
from .margins import DEFAULT_RULES, Reason, Rules, clearance_margins, kinematic_margins

if TYPE_CHECKING:
    from ...robot.arm.model import RobotModel

__all__ = ["PassMap", "ReachMap", "classify", "job_cell", "map_pass", "reach_map"]


def classify(
    cell: Cell, P: FloatArray, rules: Rules, q: FloatArray | None = None, depth: bool = False
) -> tuple[FloatArray, np.ndarray, np.ndarray, FloatArray]:
    """Best IK branch of each flange pose ``P`` (..., 4, 4).

    ``(margin (...) m, reason (...) int8, branch (...) int8, q (..., 6))`` (:mod:`.margins`; q
    NaN where no branch has a solution). A pose is judged by the branches that reach it; only
    when none does is it out of reach (by the least excess over the branches,
    :mod:`~ruledrobot. robot.workspace`).  ``depth``: resolve how deep failing clearances fail
    (else they are worth the value below the lowest level)."""
    shape = P.shape[:-2]
    Pf = P.reshape(-1, 4, 4)
    qs = cell.model.ik(Pf, check=False) if q is None else q.reshape(-1, 8, 6)
    km, kr = kinematic_margins(cell.model, qs, Pf, rules)
    reason = kr.copy()
    usable = ~np.isnan(qs[..., 0]) & (kr != Reason.JOINT_LIMIT)

    def evaluate(g: np.ndarray, o: np.ndarray, floor: FloatArray) -> FloatArray:
        val = km[g, o].copy()
        ok = usable[g, o]
        if ok.any():
            gi, oi = g[ok], o[ok]
            cm, cr = clearance_margins(cell, qs[gi, oi], Pf[gi], rules, cap=km[gi, oi],
                                       depth=depth)
            val[ok] = np.minimum(val[ok], cm)
            reason[gi, oi] = np.where(reason[gi, oi] == 0, cr, reason[gi, oi])
        return val

    # a pose some branch reaches is judged by the branches that reach it: "out of reach"
    # only where none does
    valid = ~np.isnan(qs[..., 0])
    bound = np.where(valid | ~valid.any(axis=1, keepdims=True), km, -np.inf)
    best, arg, _ = best_of(bound, evaluate)
    n = np.arange(len(Pf))
    r = np.where(best >= 0.0, np.int8(Reason.OK), reason[n, arg]).astype(np.int8)
    qb = qs[n, arg]
    return (best.reshape(shape), r.reshape(shape), arg.astype(np.int8).reshape(shape),
            qb.reshape(*shape, 6))  # fmt: skip


@dataclass(frozen=True, eq=False)
class PassMap:
    """The map of one pass.

    ``idx`` (R,) the sampled rulings (of ``rulings``), ``rolls`` (K,) rad; per (direction,
    roll, ruling) (2, K, R) the margin (m), the reason (:class:`~.margins.Reason`), the best IK
    branch and its joints (2, K, R, 6), and the slide (index into ``slides`` (S, R) m) where it
    is best. ``slide`` (R,) m: the planner's (``slides[0]``); ``in_stock`` (R,) whether the
    ruling crosses the stock.  The planner's choice: ``chosen_roll`` (R,) rad (None when the
    pass is infeasible), ``chosen_reverse``, and the map's verdict along it, ``path_margin`` /
    ``path_reason`` (R,) (classified at the chosen roll itself, not the nearest grid roll)."""

    cut: str
    index: int
    rulings: int
    idx: np.ndarray
    rolls: FloatArray
    margin: FloatArray = field(repr=False)
    reason: np.ndarray = field(repr=False)
    branch: np.ndarray = field(repr=False)
    q: FloatArray = field(repr=False)
    slide: FloatArray = field(repr=False)
    in_stock: np.ndarray = field(repr=False)
    feasible: bool
    chosen_roll: FloatArray | None = field(repr=False)
    chosen_reverse: bool
    path_margin: FloatArray | None = field(repr=False)
    path_reason: np.ndarray | None = field(repr=False)
    slides: FloatArray | None = field(default=None, repr=False)
    slide_index: np.ndarray | None = field(default=None, repr=False)
    #: the best constant roll of the pass (:func:`~.evaluate.constant_rolls`: the one
    #: model's, on its own grid, the same a failed plan and ``place`` report); None when
    #: not computed
    constant: object | None = field(default=None, repr=False)
    #: it in words (:func:`~.evaluate.constant_words`)
    constant_words: str | None = field(default=None, repr=False)

    @property
    def shown(self) -> int:
        """The direction to draw: the planner's, else the one with more reachable cells."""
        if self.chosen_roll is not None:
            return int(self.chosen_reverse)
        return int(np.argmax((self.margin >= 0).sum(axis=(1, 2))))



@dataclass(frozen=True, eq=False)
class ReachMap:
    """The maps of every pass of a job, in the order the passes are cut."""

    job: Job
    passes: tuple[PassMap, ...]
    rules: Rules
    seconds: float


def map_pass(
    cell: Cell,
    tool: ToolSpec,
    cp: CutPath,
    index: int,
    rules: Rules,
    rulings: int = 240,
    rolls: int = 72,
    slides: int = 1,
) -> PassMap:
    """The map of one planned pass ``cp`` (see :class:`PassMap`) with the job's ``tool``.

    ``rulings`` sampled evenly (ends included), ``rolls`` evenly over a turn, and ``slides``
    slides per ruling: the planner's, then ``slides - 1`` spread over the interval in which the
    wire covers the ruling's chord (the common interval of the pass for rulings outside the
    stock); each cell keeps its best slide. A pass the planner could not solve is mapped, with
    ``slides = 1``, at every slide the planner tried (:func:`~.grid.planner_slides`)."""
    F = cp.frames
    M = len(F)
    slide, too_long = planner_slide(F, cell.stock, tool)
    if cp.motion.slide.shape == (M,):
        slide = cp.motion.slide
    idx = sample_rulings(M, rulings)
    grid = np.linspace(-np.pi, np.pi, rolls, endpoint=False)
    if slides <= 1 and not cp.feasible:  # every slide the planner tried
        options = np.stack([sl[idx] for sl in planner_slides(F, cell.stock, tool)[0]])
    else:
        options = _slide_options(F[idx], slide[idx], cell.stock, tool, slides)  # (S, R)
    dirs = directions_needed(cell.W)
    best = None
    for s, sl in enumerate(options):
        res = classify(cell, pass_poses(cell.W, F[idx], sl, grid, dirs), rules)
        if len(dirs) == 1:  # the reversed wire: the same arm with q6 + pi
            q2 = res[3].copy()
            q2[..., 5] = wrap_angle(q2[..., 5] + np.pi)
            res = tuple(np.concatenate([a, b]) for a, b in zip(res, (*res[:3], q2), strict=True))
        if best is None:
            best = [*res, np.zeros(res[0].shape, np.int8)]
            continue
        better = res[0] > best[0]
        for k in range(4):
            best[k] = np.where(better[..., None] if k == 3 else better, res[k], best[k])
        best[4] = np.where(better, np.int8(s), best[4])
    margin, reason, branch, q, slide_index = best
    bad = too_long[idx] > 0.0
    if bad.any():
        margin[..., bad] = np.minimum(margin[..., bad], -too_long[idx][bad])
        reason[..., bad] = Reason.CHORD
    chosen = path_m = path_r = None
    if cp.feasible:
        chosen = cp.motion.roll[idx]
        Pc = flange_poses(wire_poses(F[idx], chosen, slide[idx], cp.motion.reverse), cell.W)
        path_m, path_r, _, _ = classify(cell, Pc, rules)
    return PassMap(cp.name, index, M, idx, grid, margin, reason, branch, q, slide[idx],
                   ~np.isnan(cp.motion.chord[idx, 0]), cp.feasible, chosen,
                   bool(cp.motion.reverse), path_m, path_r, options, slide_index)  # fmt: skip


def _slide_options(F: FloatArray, slide: FloatArray, stock, tool: ToolSpec, n: int) -> FloatArray:
    """Slides (n, R): ``slide`` first, then ``n - 1`` spread over each ruling's interval."""
    if n <= 1:
        return slide[None]
    c0, c1, hit = chords(F, stock)
    lo, hi, _ = slide_bounds(c0, c1, hit, tool)
    common = (lo[hit].max(), hi[hit].min()) if hit.any() else (slide.min(), slide.max())
    lo = np.where(hit, lo, common[0])
    hi = np.where(hit, np.maximum(hi, lo), common[1])
    hi = np.maximum(hi, lo)
    frac = (np.arange(n - 1) + 0.5) / (n - 1)
    return np.concatenate([slide[None], lo + frac[:, None] * (hi - lo)])


def reach_map(
    job: Job,
    model: RobotModel | None = None,
    rulings: int = 240,
    rolls: int = 72,
    rules: Rules = DEFAULT_RULES,
    progress: Callable[[str], None] | None = None,
    passes: list[CutPath] | None = None,
    slides: int = 1,
) -> ReachMap:
    """Return the reachability map of every pass of ``job``.

    The planner's passes, or ``passes`` when already planned: see :class:`PassMap` and
    :func:`map_pass`.
    """
    import time

    say = progress or (lambda msg: None)
    t0 = time.perf_counter()
    model = job.robot_model() if model is None else model
    cell = job_cell(job, model, rules)
    if passes is None:
        passes = []
        for cut in job.cuts:
            say(f"the planner's passes of {cut.name}")
            passes += cut_paths(job, cut, model)
    from .evaluate import constant_rolls, constant_words

    say("the best constant roll of every pass")
    try:
        cols: list = constant_rolls(job, passes, model, rules)
    except ValueError:  # a pass that cannot be scored (no chord): the map says why
        cols = [None] * len(passes)
    maps = []
    for k, cp in enumerate(passes):
        say(f"mapping pass {k + 1} of {len(passes)} ({cp.name})")
        pm = map_pass(cell, job.tool, cp, k, rules, rulings, rolls, slides)
        words = None if cols[k] is None else constant_words(job, model, cp, cols[k])
        maps.append(dataclasses.replace(pm, constant=cols[k], constant_words=words))
    return ReachMap(job, tuple(maps), rules, time.perf_counter() - t0)
