"""Placement search: where to put the block so that the arm reaches every ruling of
every cut with the largest worst margin.

1. A grid over the region (``[x, y, yaw]``, :class:`~.regions.Region`), every
   candidate scored at once by :class:`~ruledrobot.wirecut.reach.evaluate.Evaluator`
   (the worst margin of :mod:`ruledrobot.wirecut.reach.margins` over every pass of
   every cut, the best constant roll, direction and IK branch per pass).
2. Refinement: around the best few candidates a local grid of half the step, twice.
3. The ranked candidates; the best is written as a job file and verified by the
   full planner and MuJoCo (:func:`~ruledrobot.wirecut.planner.plan`) — the next ones
   in turn when it fails (:func:`verify_best`).

The margin of a candidate is in metres (:mod:`ruledrobot.wirecut.reach.margins`):
>= 0 means every sampled ruling of every pass has a configuration the planner
accepts, with that much room.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..geometry.checks import FloatArray
from ..wirecut.cut.cutpath import CutPath
from ..wirecut.cut.passes import cut_paths
from ..wirecut.job.spec import Job
from ..wirecut.reach.evaluate import Evaluator
from .regions import AS_CLAMPED, Placement, Region, Turn, transforms

if TYPE_CHECKING:
    from ..robot.arm.model import RobotModel

__all__ = ["Candidate", "PlaceResult", "job_passes", "search", "verify_best"]


@dataclass(frozen=True)
class Candidate:
    """A scored placement.

    ``margin`` (m, the worst over every pass), ``score`` (the ranking value), ``cut_margins``
    (m, per cut scored: every cut of the job, or a setup's), ``xyz`` its ``[x, y, yaw]``."""

    placement: Placement
    margin: float
    score: float
    cut_margins: tuple[float, ...]
    exact: bool = True

    @property
    def xyz(self) -> FloatArray:
        """The placement's ``[x, y, yaw]`` (3,): [m], [m], [rad]."""
        p = self.placement
        return np.array([p.x, p.y, p.yaw])

    def as_dict(self, cut_names: list[str]) -> dict:
        """The candidate as a JSON-ready dict, lengths in mm and the yaw in degrees.

        Parameters
        ----------
        cut_names : list of str
            Names of the scored cuts, in the order of ``cut_margins``.

        Returns
        -------
        dict
            ``x_m``, ``y_m`` [m], ``yaw_deg`` [deg], ``turn`` (:attr:`.regions.Turn.label`),
            ``margin_mm`` and ``cut_margins_mm`` (cut name -> margin) [mm]."""
        p = self.placement
        return {"x_m": p.x, "y_m": p.y, "yaw_deg": float(np.degrees(p.yaw)),
                "turn": p.turn.label, "margin_mm": self.margin * 1e3,
                "cut_margins_mm": dict(zip(cut_names, (m * 1e3 for m in self.cut_margins),
                                           strict=True))}  # fmt: skip


@dataclass(frozen=True, eq=False)
class PlaceResult:
    """What :func:`search` found.

    ``ranked``: the best candidates, best first; ``current``: the job's own placement;
    ``samples`` (N, 3) every evaluated ``[x, y, yaw]`` with its ``margins`` (N,) and per cut
    ``cut_margins`` (N, n_cuts); ``rate``: candidates evaluated per minute; ``rulings`` /
    ``rolls`` / ``directions``: what each candidate checks."""

    job: Job
    region: Region
    turn: Turn
    ranked: tuple[Candidate, ...]
    current: Candidate
    samples: FloatArray = field(repr=False)
    margins: FloatArray = field(repr=False)
    cut_margins: FloatArray = field(repr=False)
    seconds: float
    rulings: int
    rolls: int
    directions: int

    @property
    def best(self) -> Candidate:
        """The best-ranked candidate (``ranked[0]``)."""
        return self.ranked[0]

    @property
    def feasible(self) -> bool:
        """Whether the best candidate's worst margin is >= 0 (every ruling reachable)."""
        return self.best.margin >= 0.0

    @property
    def rate(self) -> float:
        """Candidates evaluated per minute [1/min] (``len(margins)`` over ``seconds``)."""
        return 60.0 * len(self.margins) / max(self.seconds, 1e-9)


def job_passes(job: Job, model: RobotModel | None = None,
               progress: Callable[[str], None] | None = None) -> list[CutPath]:  # fmt: skip
    """Return the planner's passes of every cut of ``job`` at its placement.

    Their frames move with the block; the redundancy search's choice is not used.
    """
    say = progress or (lambda msg: None)
    model = job.robot_model() if model is None else model
    out: list[CutPath] = []
    for cut in job.cuts:
        say(f"refining {cut.name}")
        out += cut_paths(job, cut, model)
    return out


def search(
    job: Job,
    region: Region,
    evaluator: Evaluator,
    grid: tuple[int, int, int] = (9, 9, 9),
    refine: int = 2,
    top: int = 6,
    turn: Turn = AS_CLAMPED,
    cuts: list[int] | None = None,
    progress: Callable[[str], None] | None = None,
) -> PlaceResult:
    """Search ``region`` for the placement of ``job``'s block with the largest worst margin.

    After ``turn``; the margin of the module doc.  ``cuts`` (indices): score only these cuts
    (a setup's), default all.
    """
    say = progress or (lambda msg: None)
    t0 = time.perf_counter()
    which = list(range(len(job.cuts))) if cuts is None else list(cuts)
    xs, ms, ss, cms, exs = [], [], [], [], []

    def run(xyz: FloatArray) -> None:
        T = transforms(job, xyz, region.move, turn)
        sc = evaluator(T)
        cm = evaluator.cut_margins(sc)[:, which]
        xs.append(xyz)
        ms.append(cm.min(axis=1))
        # the ranking value of these cuts: worst margin plus the tie-break of the worst
        ss.append(cm.min(axis=1) + (sc.score - sc.margin))
        cms.append(cm)
        exs.append(sc.exact)

    say(f"scoring {int(np.prod(grid))} placements")
    xyz = region.grid(grid)
    run(xyz)
    steps = np.array([(hi - lo) / max(n - 1, 1) for (lo, hi), n in
                      zip((region.x, region.y, region.yaw), grid, strict=True)])  # fmt: skip
    offsets = np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"),
                       axis=-1).reshape(-1, 3)  # fmt: skip
    for level in range(refine):
        steps = steps / 2.0
        X = np.concatenate(xs)
        S = np.concatenate(ss)
        seeds = X[np.argsort(-S, kind="stable")[:top]]
        new = region.clip((seeds[:, None, :] + offsets[None] * steps).reshape(-1, 3))
        new = np.unique(new.round(7), axis=0)
        seen = {tuple(v) for v in np.concatenate(xs).round(7)}
        new = np.array([v for v in new if tuple(v) not in seen])
        if new.size:
            say(f"refining around the best {top} (step {level + 1} of {refine})")
            run(new)
    X, M, S, CM, E = (np.concatenate(v) for v in (xs, ms, ss, cms, exs))
    _, first = np.unique(X.round(7), axis=0, return_index=True)
    order = first[np.argsort(-S[first], kind="stable")]
    ranked = tuple(Candidate(Placement(*map(float, X[i]), move=region.move, turn=turn),
                             float(M[i]), float(S[i]), tuple(map(float, CM[i])), bool(E[i]))
                   for i in order[:10])  # fmt: skip
    seconds = time.perf_counter() - t0
    cur = _current(job, region, evaluator, turn, which)
    return PlaceResult(job, region, turn, ranked, cur, X, M, CM, seconds,
                       evaluator.rulings_checked, len(evaluator.rolls),
                       len(evaluator.directions))  # fmt: skip


def _current(job: Job, region: Region, ev: Evaluator, turn: Turn, which: list[int]) -> Candidate:
    """The job's own placement, scored."""
    sc = ev(turn.matrix(job.stock)[None])
    cm = ev.cut_margins(sc)[0, which]
    if region.move == "stock":
        c = job.stock.centre
        pl = Placement(float(c[0]), float(c[1]), 0.0, "stock", turn)
    else:
        pl = Placement(0.0, 0.0, 0.0, "robot", turn)
    return Candidate(pl, float(cm.min()), float(cm.min() + sc.score[0] - sc.margin[0]),
                     tuple(map(float, cm)), bool(sc.exact[0]))  # fmt: skip


@dataclass(frozen=True, eq=False)
class Verified:
    """The outcome of verifying candidates with the full planner.

    The candidate that passed (None: none did), the job file written for it, the plan's result,
    and a line per candidate tried."""

    candidate: Candidate | None
    job_file: Path | None
    plan: object | None = field(repr=False)
    tried: tuple[str, ...]


def verify_best(
    job: Job,
    candidates: list[Candidate],
    folder: Path,
    final: Path | None = None,
    tries: int = 3,
    cuts: list[int] | None = None,
    note: str = "",
    progress: Callable[[str], None] | None = None,
    program: Callable[[object, Path], Path] | None = None,
) -> Verified:
    """Write and plan the candidates' job files in turn until one passes MuJoCo verification.

    The job files go into ``folder`` (``job.toml``), the plans with MuJoCo verification into
    ``plan/``, until one passes (at most ``tries``, only candidates with a margin >= 0).
    ``final``: where ``folder`` will finally be (relative paths in the job file are written
    for it).  ``cuts``: the cuts kept (a setup's; default all).  ``program(trajectory,
    folder)``: writes the robot program of the plan that passes (the command line writes
    ``cut.script``).
    """
    import dataclasses

    from ..wirecut.job.load import load_job
    from ..wirecut.planner import plan
    from .job_file import write_job_file

    say = progress or (lambda msg: None)
    tried: list[str] = []
    final = folder if final is None else final
    for k, cand in enumerate([c for c in candidates if c.margin >= 0.0][:tries]):
        moved = cand.placement.job(job)
        if cuts is not None:
            moved = dataclasses.replace(moved, cuts=tuple(moved.cuts[i] for i in cuts))
        say(f"verifying candidate {k + 1} with the planner and MuJoCo")
        text = note or f"placed by ruledrobot place: {cand.placement.describe()}"
        path = write_job_file(moved, folder / "job.toml", keep_cuts=cuts, note=text,
                              check_as=final / "job.toml")  # fmt: skip
        res = plan(load_job(path), folder / "plan")
        line = (f"{cand.placement.describe()}: margin {cand.margin * 1e3:.0f} mm; plan "
                f"{'PASS' if res.feasible else 'FAIL'}")
        if not res.feasible:
            line += f" ({res.verdict.summary()})"
        tried.append(line)
        if res.feasible:
            if program is not None:
                program(res.trajectory, folder)
            return Verified(cand, path, res, tuple(tried))
    import shutil

    (folder / "job.toml").unlink(missing_ok=True)  # nothing that failed stays runnable
    shutil.rmtree(folder / "plan", ignore_errors=True)
    return Verified(None, None, None, tuple(tried))
