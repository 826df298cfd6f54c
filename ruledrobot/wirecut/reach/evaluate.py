"""Scoring many placements of a job's block at once: the worst margin over every pass.

A placement moves the block (and every cut surface with it) by a rigid motion T of
the base frame (:mod:`ruledrobot.place.regions`); the wire's poses move with it, ``P_c = T_c P``.
For each candidate and pass, every **column** — a wire direction, a roll about the
wire and an IK branch, held along the whole pass (the planner's constant offset;
a feasible path never changes analytic branch, since every branch change crosses a
singularity) — gets the worst margin over the sampled rulings (:mod:`.margins`), and
the pass gets its best column.  A candidate's margin is the worst over its passes.

Vectorised over candidates x directions x rolls x rulings x branches for the IK and
the kinematic margins; the clearance rules run for the most promising columns only,
best bound first, until no remaining column can beat the best one found
(:func:`~.branch_bound.best_of`), with every candidate's stock in one call
(:class:`~.grid.RowBoxes`).  Ties between columns and candidates whose margins
are equal (the clearance is quantised) are broken by the kinematic margin
(reach, limits, singularity): the score is ``margin + TIE * kinematic``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ...geometry.checks import FloatArray
from ...robot.ik.path import JUMP_THRESHOLD
from ..cut.clearance import BOW_STOCK, clearance
from ..cut.cutpath import CutPath
from ..job.spec import Job
from .branch_bound import best_of
from .grid import (
    ROLLS,
    RULINGS,
    RowBoxes,
    directions_needed,
    job_cell,
    pass_poses,
    planner_slides,
    sample_rulings,
)
from .margins import (
    DEFAULT_RULES,
    Reason,
    Rules,
    clearance_margins,
    kinematic_margins,
    limit_levers,
)

if TYPE_CHECKING:
    from ...robot.arm.model import RobotModel

__all__ = ["TIE", "ColumnDetail", "Evaluator", "PassSample", "Scores", "constant_rolls",
           "constant_words", "details"]

#: weight of the kinematic margin in the score (ties of the quantised clearance)
TIE = 1e-3
#: poses (candidates x directions x rolls x rulings) per IK batch
CHUNK_POSES = 120_000
#: the clearance of a column is screened on every SCREEN-th sampled ruling first
SCREEN = 6


@dataclass(frozen=True, eq=False)
class PassSample:
    """A pass as the search samples it.

    Its cut (index, name), the sampled rulings ``idx`` (R,), the flange poses ``P0`` (2, K, R,
    4, 4) at the job's placement, ``bow_ok`` (2, K, R) whether the bow clears the stock there
    (a rule placement does not change), and ``too_long`` (m, > 0 when a chord is longer than
    the wire allows)."""

    cut: int
    name: str
    idx: np.ndarray
    P0: FloatArray = field(repr=False)
    bow_ok: np.ndarray = field(repr=False)
    too_long: float
    #: rulings of the pass (the sample's indices count into them)
    rulings: int = 0
    #: the planner's other slides (near both ends of the common interval), tried when
    #: nothing works at the first: ``(P0, bow_ok)`` each
    ends: tuple = field(default=(), repr=False)

    def slide(self, j: int) -> tuple[FloatArray, np.ndarray]:
        """``(P0, bow_ok)`` of slide option ``j`` (0: the planner's first)."""
        return (self.P0, self.bow_ok) if j == 0 else self.ends[j - 1]


@dataclass(frozen=True, eq=False)
class Scores:
    """Scores of C candidates.

    ``margin`` (C,) m, the worst over passes; per pass ``pass_margin`` (C, n) m and ``column``
    (C, n) the best column (index into directions x rolls x branches); ``score`` (C,) the
    ranking value (module doc); ``exact`` (C,) False where the search of columns was cut short."""

    margin: FloatArray
    score: FloatArray
    pass_margin: FloatArray
    column: np.ndarray
    exact: np.ndarray

    def take(self, idx: np.ndarray) -> Scores:
        """The scores of candidates ``idx`` (K,), in that order."""
        return Scores(*(getattr(self, f.name)[idx] for f in dataclasses.fields(self)))

    @classmethod
    def concat(cls, parts: list[Scores]) -> Scores:
        """The scores of consecutive batches of candidates, in order."""
        return cls(*(np.concatenate([getattr(p, f.name) for p in parts])
                     for f in dataclasses.fields(cls)))  # fmt: skip


class Evaluator:
    """Scores placements of ``job`` (see the module doc).

    ``passes``: the planner's passes at the job's placement (their frames are what
    moves); ``rulings`` sampled per pass, ``rolls`` over a turn; ``max_rounds`` rounds
    of ``per_round`` columns per candidate and pass at most (None: until exact).  A
    calibrated arm is scored on its nominal table (its FK differs by millimetres, and
    the closed-form IK is about 30 times faster than the calibrated one); the
    verification plans on the calibration.
    """

    def __init__(self, job: Job, passes: list[CutPath], model: RobotModel | None = None,
                 rulings: int = RULINGS,
                 rolls: int = ROLLS, rules: Rules = DEFAULT_RULES, per_round: int = 8,
                 max_rounds: int | None = None) -> None:  # fmt: skip
        self.job = job
        self.model = (job.robot_model() if model is None else model).nominal
        self.rules = rules
        self.cell = job_cell(job, self.model, rules)
        self.rolls = np.linspace(-np.pi, np.pi, rolls, endpoint=False)
        self.directions = directions_needed(self.cell.W)
        self.rulings = rulings
        self.per_round, self.max_rounds = per_round, max_rounds
        names = [c.name for c in job.cuts]
        self.samples: list[PassSample] = []
        for cp in passes:
            F = cp.frames
            slides, too_long = planner_slides(F, job.stock, job.tool)
            idx = sample_rulings(len(F), rulings)
            opts = []
            for slide in slides:
                P0 = pass_poses(self.cell.W, F[idx], slide[idx], self.rolls, self.directions)
                bow = clearance(self.cell, np.zeros((*P0.shape[:-2], 6)), P0)
                opts.append((P0, ~bow[BOW_STOCK]))
            self.samples.append(PassSample(names.index(cp.name), cp.name, idx, *opts[0],
                                           float(np.max(too_long)), len(F),
                                           tuple(opts[1:])))  # fmt: skip

    def subset(self, cuts: list[int]) -> Evaluator:
        """This evaluator for the passes of ``cuts`` only (indices into the job's cuts).

        :meth:`cut_margins` is then inf for the others."""
        import copy

        out = copy.copy(self)
        out.samples = [s for s in self.samples if s.cut in cuts]
        return out

    #: what went wrong while scoring (a distributed scorer's chunks scored here instead)
    notes: tuple[str, ...] | list[str] = ()

    def engine_info(self) -> dict[str, object]:
        """Where the candidates are scored (``place.json``): in this process."""
        return {"kind": "in-process"}

    @property
    def rulings_checked(self) -> int:
        """Rulings each candidate checks (over all passes)."""
        return int(sum(s.idx.size for s in self.samples))

    def cut_margins(self, scores: Scores) -> FloatArray:
        """Per cut (C, n_cuts) the worst margin of its passes."""
        out = np.full((len(scores.margin), len(self.job.cuts)), np.inf)
        for k, s in enumerate(self.samples):
            out[:, s.cut] = np.minimum(out[:, s.cut], scores.pass_margin[:, k])
        return out

    def __call__(self, T: FloatArray) -> Scores:
        """Scores of candidate placements T (C, 4, 4) (rigid motions of the base frame)."""
        T = np.asarray(T, dtype=np.float64).reshape(-1, 4, 4)
        per = max(1, CHUNK_POSES // max(s.P0[..., 0, 0].size for s in self.samples))
        return Scores.concat([self._chunk(T[i:i + per]) for i in range(0, len(T), per)])

    def _chunk(self, T: FloatArray) -> Scores:
        C, n = len(T), len(self.samples)
        pm = np.empty((C, n))
        score = np.empty((C, n))
        col = np.empty((C, n), dtype=np.intp)
        exact = np.ones(C, bool)
        for k, s in enumerate(self.samples):
            best, score[:, k], col[:, k], ex = self._pass(T, s)
            pm[:, k] = best
            exact &= ex
        worst = np.argmin(score, axis=1)
        return Scores(pm.min(axis=1), score[np.arange(C), worst], pm, col, exact)

    def _pass(
        self, T: FloatArray, s: PassSample
    ) -> tuple[FloatArray, FloatArray, np.ndarray, np.ndarray]:
        """The best column of pass ``s`` per candidate: at the planner's first slide, and
        where nothing works there, at its slides near either end of the interval (as the
        planner tries them); a column index counts on over the slides."""
        best, score, arg, exact = self._columns(T, *s.slide(0), s)
        n = len(self.directions) * len(self.rolls) * 8
        for j in range(1, len(s.ends) + 1):
            need = np.flatnonzero(best < 0.0)
            if not need.size:
                break
            b2, s2, a2, e2 = self._columns(T[need], *s.slide(j), s)
            better = s2 > score[need]
            w = need[better]
            best[w], score[w], arg[w] = b2[better], s2[better], a2[better] + j * n
            exact[need] &= e2
        return best, score, arg, exact

    def _columns(
        self, T: FloatArray, P0: FloatArray, bow_ok: np.ndarray, s: PassSample
    ) -> tuple[FloatArray, FloatArray, np.ndarray, np.ndarray]:
        model, rules = self.model, self.rules
        C, K, R = len(T), len(self.rolls), s.idx.size
        D = len(self.directions)
        P = T[:, None, None, None] @ P0[None]  # (C, D, K, R, 4, 4)
        q = model.ik(P, check=False)  # (C, D, K, R, 8, 6)
        km, kr = kinematic_margins(model, q, P, rules)
        bow = bow_ok[None, ..., None]
        km = np.where(bow, km, np.minimum(km, -rules.margin))
        if s.too_long > 0.0:
            km = np.minimum(km, -s.too_long)
        usable = ~np.isnan(q[..., 0]) & (kr != Reason.JOINT_LIMIT) & bow
        kin = km.min(axis=3).reshape(C, D * K * 8)  # each column's worst over the rulings
        # the clearance is checked on every SCREEN-th ruling first, the rest only for the
        # columns that can still beat their candidate's best
        first = np.zeros(R, bool)
        first[::SCREEN] = True

        def clear(g, d, k, b, rows: np.ndarray) -> FloatArray:
            """Worst clearance margin (m,) of columns over the rulings ``rows``."""
            use = usable[g[:, None], d[:, None], k[:, None], rows[None, :], b[:, None]]  # (m, r)
            gi, ri = np.nonzero(use)
            out = np.full(len(g), np.inf)
            if gi.size:
                r = rows[ri]
                cell = dataclasses.replace(self.cell, stock=RowBoxes(self.job.stock, T[g[gi]]))
                cm, _ = clearance_margins(cell, q[g[gi], d[gi], k[gi], r, b[gi]],
                                          P[g[gi], d[gi], k[gi], r], rules,
                                          cap=km[g[gi], d[gi], k[gi], r, b[gi]],
                                          depth=False)  # fmt: skip
                np.minimum.at(out, gi, cm)
            return out

        def evaluate(g: np.ndarray, o: np.ndarray, floor: FloatArray) -> FloatArray:
            d, k, b = np.unravel_index(o, (D, K, 8))
            base = np.minimum(kin[g, o], self._travel_margin(q[g, d, k, :, b]))
            val = np.minimum(base, clear(g, d, k, b, np.flatnonzero(first)))
            val = val + TIE * base
            go = np.flatnonzero(val > floor)
            if go.size:
                rest = clear(g[go], d[go], k[go], b[go], np.flatnonzero(~first))
                val[go] = np.minimum(val[go] - TIE * base[go], rest) + TIE * base[go]
            return val

        bound = kin + TIE * kin
        best, arg, exact = best_of(bound, evaluate, self.per_round, self.max_rounds)
        d, k, b = np.unravel_index(arg, (D, K, 8))
        base = np.minimum(kin[np.arange(C), arg], self._travel_margin(q[np.arange(C), d, k, :, b]))
        return best - TIE * base, best, arg, exact

    def _travel_margin(self, q: FloatArray) -> FloatArray:
        """Per column (m,) of joints ``q`` (m, R, 6) along the pass: the radians left when
        each joint's unwrapped travel is centred in its limits, times the joint's lever
        (:func:`~.margins.limit_levers`; inf for unlimited joints)."""
        lo, hi = np.asarray(self.model.lower), np.asarray(self.model.upper)
        span = hi - lo
        fin = np.isfinite(span)
        if not fin.any():
            return np.full(len(q), np.inf)
        qq = np.unwrap(np.nan_to_num(q[..., fin]), axis=1)
        travel = qq.max(axis=1) - qq.min(axis=1)
        left = (0.5 * (span[fin] - travel) * limit_levers(self.model)[fin]).min(axis=-1)
        return left


@dataclass(frozen=True, eq=False)
class ColumnDetail:
    """One pass of one placement in detail.

    Its best column — the **best constant roll** (``reverse``, ``roll`` rad, IK ``branch``: the
    one with the largest worst margin, the search's choice) —, per sampled ruling (R,) the
    margin (m) and the reason it fails (:class:`~.margins.Reason`), and which part of the
    margin is the least there (``limit``: "reach", "joint limits", "singularity", "clearance"
    or a reason). ``worst`` (m) is the column's value as the search scores it: the least of the
    rulings' margins and of ``travel`` (the joints' travel along the pass centred in their
    limits, m); ``rulings`` the rulings of the pass."""

    name: str
    idx: np.ndarray
    reverse: bool
    roll: float
    branch: int
    margin: FloatArray = field(repr=False)
    reason: np.ndarray = field(repr=False)
    limit: tuple[str, ...] = field(repr=False)
    q: FloatArray = field(repr=False)
    worst: float = 0.0
    travel: float = np.inf
    rulings: int = 0
    #: the slide option (:func:`~.grid.planner_slides`, 0: the planner's first)
    slide: int = 0

    @property
    def served(self) -> np.ndarray:
        """(R,) whether the column keeps each sampled ruling within the rules."""
        return self.margin >= 0.0

    @property
    def share(self) -> float:
        """The share of the sampled rulings the column serves."""
        return float(self.served.mean())

    @property
    def roll_deg(self) -> int:
        """The roll in whole degrees, in (-180, 180]."""
        deg = round(float(np.degrees(self.roll))) % 360
        return deg - 360 if deg > 180 else deg

    def label(self) -> str:
        """``-150 deg, along the ruling, IK branch 3``."""
        return (f"{self.roll_deg} deg, {'wire reversed' if self.reverse else 'along the ruling'}"
                f", IK branch {self.branch}")

    def percent(self) -> str:
        """Return the share served in whole percent.

        ``100`` only when every sampled ruling is served and ``0`` only when none is.
        """
        p = 100.0 * self.share
        return str(int(min(max(round(p), 1), 99)) if 0.0 < p < 100.0 else int(p))

    def words(self) -> str:
        """Return the best constant roll of the pass in words.

        The same sentence wherever it is said: a failed plan, ``reach``, ``place``.
        """
        k = int(np.argmin(self.margin))
        where = (f"worst margin {self.worst * 1e3:.0f} mm at ruling {int(self.idx[k])}: "
                 f"{self.limit[k]}")
        n = self.idx.size
        if self.worst >= 0.0:
            return (f"a constant roll of the wire ({self.label()}) serves all {n} sampled "
                    f"rulings (worst margin {self.worst * 1e3:.0f} mm)")
        if self.served.all():
            return (f"the best constant roll ({self.label()}) keeps all {n} sampled rulings "
                    f"within the rules, but the joints' travel along the pass leaves "
                    f"{self.travel * 1e3:.0f} mm to their limits")
        return (f"the best constant roll ({self.label()}) serves {self.percent()} % of the "
                f"{n} sampled rulings ({where})")


def details(ev: Evaluator, T: FloatArray) -> list[ColumnDetail]:
    """The best column of every pass for the placement T (4, 4), ruling by ruling.

    The same margins the search scores (:meth:`Evaluator.__call__`), the bow's gate and a chord
    longer than the wire included."""
    from ...robot.ik.workspace import reach_margin
    from .margins import REASON_TEXT, joint_limit_margin, limit_levers

    sc = ev(T[None])
    model, rules = ev.model, ev.rules
    g = model.nominal.ur_geometry
    scale = abs(g.a2) + abs(g.a3) + abs(g.d5)
    out = []
    K = len(ev.rolls)
    for k, s in enumerate(ev.samples):
        j, d, kk, b = np.unravel_index(sc.column[0, k], (len(s.ends) + 1, len(ev.directions),
                                                         K, 8))  # fmt: skip
        P0, bow_ok = s.slide(int(j))
        P = T @ P0[d, kk]  # (R, 4, 4)
        qs = model.ik(P, check=False)  # (R, 8, 6)
        q = qs[:, b]
        km, kr = kinematic_margins(model, qs, P, rules)  # every branch: each its own excess
        km, kr = km[:, b], kr[:, b]
        ok = ~np.isnan(q[:, 0])
        bow = bow_ok[d, kk]
        parts = {
            "reach": np.where(ok, reach_margin(model, np.nan_to_num(q)), -np.inf),
            "joint limits": joint_limit_margin(model, np.nan_to_num(q), limit_levers(model)),
            "singularity": scale * (model.singularity_measure(np.nan_to_num(q))
                                    - rules.singular_min),
        }
        clear = np.full(len(P), np.inf)
        creason = np.zeros(len(P), np.int8)
        use = ok & bow & (kr != Reason.JOINT_LIMIT)
        if use.any():
            cell = dataclasses.replace(ev.cell, stock=RowBoxes(ev.job.stock, np.repeat(
                T[None], int(use.sum()), axis=0)))
            clear[use], creason[use] = clearance_margins(cell, q[use], P[use], rules,
                                                         depth=False)
        parts["clearance"] = np.where(bow, clear, np.minimum(clear, -rules.margin))
        margin = np.minimum(km, parts["clearance"])
        reason = np.where(kr != 0, kr, np.where(margin < 0, creason, 0))
        reason = np.where(~bow & (reason == 0), Reason.BOW_STOCK, reason)
        if s.too_long > 0.0:  # a chord longer than the wire: no column serves
            margin = np.minimum(margin, -s.too_long)
            reason = np.where(reason == 0, Reason.CHORD, reason)
        names = list(parts)
        stack = np.stack([parts[n] for n in names])
        limit = tuple(REASON_TEXT[Reason(r)] if r else names[int(i)]
                      for r, i in zip(reason, stack.argmin(axis=0), strict=True))  # fmt: skip
        travel = float(ev._travel_margin(q[None])[0])
        out.append(ColumnDetail(s.name, s.idx, bool(ev.directions[d]), float(ev.rolls[kk]),
                                int(b), margin, reason.astype(np.int8), limit, q,
                                float(sc.pass_margin[0, k]), travel, s.rulings,
                                int(j)))  # fmt: skip
    return out


def constant_rolls(job: Job, passes: list[CutPath], model: RobotModel | None = None,
                   rules: Rules = DEFAULT_RULES) -> list[ColumnDetail]:  # fmt: skip
    """The best constant roll of every pass of ``job`` where the job places its block.

    The one model's fact (docs/place.md, "One model") that a failed plan's explanation,
    ``ruledrobot reach`` and ``ruledrobot place`` all report — :class:`Evaluator` on its
    default grid (:data:`~.grid.RULINGS` rulings x :data:`~.grid.ROLLS` rolls), at the identity
    placement."""
    ev = Evaluator(job, list(passes), model, rules=rules)
    return details(ev, np.eye(4))


#: the planner's joint step threshold between rulings (rad; ``SearchOptions``)
JUMP = JUMP_THRESHOLD


def constant_words(job: Job, model: RobotModel, cp: CutPath, col: ColumnDetail) -> str:
    """The best constant roll ``col`` of a pass in words.

    Of a pass the planner could not solve (:mod:`.explain`) never "serves all" without what
    fails between the samples (the planner's own check of every ruling at that roll), so that
    it never stands beside the planner's "no constant roll works" as a contradiction."""
    if cp.feasible or (col.worst < 0.0 and not col.served.all()):
        return col.words()
    from ...io.words import index_ranges
    from ..cut.wire_pose import _failures
    from .grid import planner_slides

    F = cp.frames
    slide = planner_slides(F, job.stock, job.tool)[0][col.slide]
    q0 = col.q[0] if not np.isnan(col.q[0]).any() else None
    cell = dataclasses.replace(job_cell(job, model, DEFAULT_RULES), q_start=q0)
    _, _, masks = _failures(cell, F, np.full(len(F), col.roll), slide, col.reverse, JUMP)
    fails = "; ".join(f"{why} at rulings {index_ranges(v)}" for why, v in masks.items() if v.any())
    n = col.idx.size
    head = (f"the best constant roll ({col.label()}) keeps all {n} sampled rulings within the "
            f"rules (worst margin {col.worst * 1e3:.0f} mm)")
    if col.worst < 0.0:
        head = (f"the best constant roll ({col.label()}) keeps all {n} sampled rulings within "
                f"the rules, but the joints' travel along the pass leaves "
                f"{col.travel * 1e3:.0f} mm to their limits")
    if fails:
        return (f"{head}, but not every ruling between them: the planner's check of all "
                f"{len(F)} rulings at that roll fails: {fails}")
    return (f"{head}, and the planner's check of all {len(F)} rulings at that roll on that IK "
            "branch holds: the search, which follows the branch nearest its start, missed it")
