"""``ruledrobot place``: search, verify, and fall back to setups; the files it writes.

Output folder (written whole, swapped in at the end):

* ``job.toml`` — the job with the best verified placement filled in, and ``plan/`` —
  its plan (trajectory and program when it passes);
* ``margin.png`` — :mod:`.plot`; ``place.json`` — region, settings, the
  measured rate, the job's own placement, the ranked candidates, the verification,
  the setups;
* when no single placement serves a job of several cuts and turns are allowed:
  ``setup1/``, ``setup2/`` ... (each a ``job.toml`` with its cuts and a ``plan/``) and
  ``setups.txt``, what the operator does between them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_json, atomic_write_text
from ..io.outdir import StagedFolder
from ..wirecut.cut.cutpath import CutPath
from ..wirecut.job.spec import Job
from ..wirecut.plan import job_reference
from ..wirecut.reach.evaluate import Evaluator, details
from ..wirecut.reach.grid import ROLLS, RULINGS
from ..wirecut.reach.margins import Rules
from .plot import plot_place
from .regions import Region, Turn, transforms
from .search import Candidate, PlaceResult, Verified, job_passes, search, verify_best
from .setups import MAX_SETUPS, SetupPlan, operator_steps, plan_setups

__all__ = ["PLACE_FORMAT", "PlaceOutcome", "limiting", "run_place"]

PLACE_FORMAT = "ruledrobot.place/1"


@dataclass(frozen=True, eq=False)
class PlaceOutcome:
    """What :func:`run_place` did.

    The search, the verification of its best, the setups (when needed) with their
    verifications, the operator's steps, the files, whether it ends with something that passes
    the planner (``ok``) and lines to print."""

    result: PlaceResult
    verified: Verified | None
    setups: SetupPlan | None
    setup_checks: tuple[Verified, ...]
    steps: tuple[str, ...]
    files: dict[str, Path] = field(default_factory=dict)
    ok: bool = False
    lines: tuple[str, ...] = ()
    #: the last word when nothing passes: whether the planner ran and what it found
    closing: str = ""


def limiting(ev: Evaluator, T: np.ndarray) -> str:
    """Where and why the placement T (4, 4) has its worst margin, in words.

    The best constant roll of its worst pass
    (:meth:`~ruledrobot.wirecut.reach.evaluate.ColumnDetail.words`, the sentence a failed plan
    and ``ruledrobot reach`` say of the same pass)."""
    cols = details(ev, T)
    if not cols:
        return ""
    d = min(cols, key=lambda c: c.worst)
    where = f"cut '{d.name}': " if len(ev.job.cuts) > 1 else ""
    return f"{where}{d.words()}"


def _cand_line(c: Candidate) -> str:
    return f"{c.placement.describe()}: worst margin {c.margin * 1e3:.0f} mm"


def run_place(
    job: Job,
    region: Region,
    out: str | Path,
    *,
    grid: tuple[int, int, int] = (9, 9, 9),
    refine: int = 2,
    turns: tuple[Turn, ...] = (),
    tries: int = 3,
    rulings: int = RULINGS,
    rolls: int = ROLLS,
    verify: bool = True,
    progress: Callable[[str], None] | None = None,
    program: Callable[[object, Path], Path] | None = None,
    scorer: Callable[[Evaluator], Evaluator] | None = None,
    passes: list[CutPath] | None = None,
) -> PlaceOutcome:
    """Search ``region`` for ``job``'s block, verify the best, split into setups if need be.

    The search is :func:`~.search.search`; the best is verified with the planner and MuJoCo,
    and, when no single placement serves, the cuts are split into setups over the allowed
    ``turns`` (:mod:`.setups`); the files (module doc) are written into ``out``.
    ``program(trajectory, folder)`` writes the robot program of every plan that passes into
    its folder (``cut.script`` from the command line).  ``scorer(evaluator)`` returns what
    scores the candidates: the evaluator itself by default, one that scores them on Dask
    workers from the command line (:class:`ruledrobot.batch.place.DistributedEvaluator`).
    ``passes``: the planner's passes of the job at its placement when the caller has them
    (a plan's, :attr:`~ruledrobot.wirecut.plan.Plan.passes`); by default
    :func:`~.search.job_passes`.
    """
    say = progress or (lambda msg: None)
    out = Path(out)
    model = job.robot_model()
    with StagedFolder(out) as stage:
        passes = job_passes(job, model, say) if passes is None else list(passes)
        ev = Evaluator(job, passes, model, rulings=rulings, rolls=rolls, rules=Rules())
        if scorer is not None:
            ev = scorer(ev)
        res = search(job, region, ev, grid, refine, progress=say)
        lines = [f"scored {len(res.margins)} placements in {res.seconds:.1f} s "
                 f"({res.rate:.0f} per minute; each checks {res.rulings} rulings x "
                 f"{res.rolls} rolls x {res.directions} wire direction(s) x 8 IK branches)"]
        cur_T = res.current.placement.transform(job)
        lines.append(f"as the job places it: worst margin {res.current.margin * 1e3:.0f} mm "
                     f"({limiting(ev, cur_T)})")  # fmt: skip
        lines.append(f"best found: {_cand_line(res.best)} "
                     f"({limiting(ev, res.best.placement.transform(job))})")  # fmt: skip
        edge = region.edges(res.best.xyz)
        if edge:
            lines.append(f"note: the best lies on the edge of the searched region ({edge}); "
                         "a wider range may hold a better placement")
        verified = None
        if not verify and res.feasible:  # the best, unverified: its job file only
            from .job_file import write_job_file

            write_job_file(res.best.placement.job(job),
                           stage.path / "job.toml", check_as=out / "job.toml",
                           note=f"placed by ruledrobot place (not verified): "
                                f"{res.best.placement.describe()}")  # fmt: skip
        if verify and res.feasible:
            verified = verify_best(job, list(res.ranked), stage.path, out, tries, progress=say,
                                   program=program)
            lines += [f"verified: {t}" for t in verified.tried]
        single_ok = res.feasible and (not verify or verified.candidate is not None)
        setups, checks, steps = None, (), ()
        if not single_ok and len(job.cuts) > 1 and turns:
            small = tuple(max(3, min(g, 7)) for g in grid)
            setups = plan_setups(job, region, ev, turns, small, refine, say)
            allowed = ", ".join(t.label for t in turns)
            if setups is None:
                lines.append(f"no grouping of the cuts into at most {MAX_SETUPS} setups (the "
                             f"block as clamped or turned {allowed}) serves the job either")
            else:
                lines.append(f"{len(setups.setups)} setups (turns allowed: {allowed}): worst "
                             f"margin {setups.margin * 1e3:.0f} mm; setups.txt says what to do")
            if setups is not None:
                steps = tuple(operator_steps(job, setups))
                if verify:
                    checks = tuple(
                        verify_best(job, list(s.ranked), stage.path / f"setup{s.number}",
                                    out / f"setup{s.number}", tries, cuts=list(s.cuts),
                                    note=f"setup {s.number} of {len(setups.setups)}: "
                                         + steps[s.number - 1], progress=say, program=program)
                        for s in setups.setups)  # fmt: skip
                atomic_write_text(stage.path / "setups.txt", "\n\n".join(steps) + "\n")
                for s, c in zip(setups.setups, checks, strict=False):
                    lines += [f"setup {s.number} verified: {t}" for t in c.tried]
        if not res.feasible and setups is None:
            lines.append(f"no placement in the region serves the job: the best worst margin "
                         f"found is {res.best.margin * 1e3:.0f} mm (a constant roll of the "
                         "wire on every sampled ruling, the planner's first choice; a "
                         "varying roll is not scored)")  # fmt: skip
        ok = single_ok if setups is None else (
            not verify or all(c.candidate is not None for c in checks))  # fmt: skip
        if single_ok and verify:
            ok = True
        ran = bool(verified is not None and verified.tried) or any(c.tried for c in checks)
        closing = ""
        if not ok:
            closing = ("nothing found passes the planner (place.json says what was tried)"
                       if ran else "the planner was not run: no placement found has a worst "
                       "margin >= 0 (place.json has the best ones found)")  # fmt: skip
        b = res.best.placement
        yaws = np.linspace(*region.yaw, 37) if region.yaw[1] > region.yaw[0] else None
        sweep = None
        if yaws is not None:
            xyz = np.c_[np.full(37, b.x), np.full(37, b.y), yaws]
            sweep = (yaws, ev(transforms(job, xyz, region.move, b.turn)).margin)
        plot_place(stage.path / "margin.png", res,
                   [s.candidate for s in setups.setups] if setups else None, sweep)  # fmt: skip
        lines += list(ev.notes)  # a scorer's notes (chunks scored here)
        doc = _document(job, res, verified, setups, checks, steps, ev, lines, ok)
        doc["closing"] = closing or None
        atomic_write_json(stage.path / "place.json", doc)
        target = stage.commit({"kind": "place", "ok": ok})
    files = {"place": target / "place.json", "margin": target / "margin.png"}
    if single_ok and verified is not None:
        files |= {"job": target / "job.toml", "plan": target / "plan"}
    elif res.feasible and not verify:
        files["job"] = target / "job.toml"
    if setups is not None:
        files["setups"] = target / "setups.txt"
        for s in setups.setups:
            files[f"setup{s.number}"] = target / f"setup{s.number}"
    return PlaceOutcome(res, verified, setups, checks, steps, files, ok, tuple(lines), closing)


def _document(job: Job, res: PlaceResult, verified: Verified | None, setups: SetupPlan | None,
              checks: tuple[Verified, ...], steps: tuple[str, ...], ev: Evaluator,
              lines: list[str], ok: bool) -> dict:  # fmt: skip
    names = [c.name for c in job.cuts]
    reg = res.region
    return {
        "format": PLACE_FORMAT,
        "job": job_reference(job),
        "robot": job.robot.model,
        "ok": ok,
        "move": reg.move,
        "region": {"x_m": list(reg.x), "y_m": list(reg.y),
                   "yaw_deg": [float(np.degrees(v)) for v in reg.yaw]},
        "margin": "the worst over every sampled ruling of every pass of the best constant "
                  "roll, wire direction and IK branch, of the least of reach, joint-limit, "
                  "singularity and clearance room, in mm (docs/place.md)",
        "search": {"evaluated": len(res.margins), "seconds": res.seconds,
                   "per_minute": res.rate, "rulings_per_candidate": res.rulings,
                   "rolls": res.rolls, "wire_directions": res.directions,
                   "ik_branches": 8, "exact": bool(all(c.exact for c in res.ranked)),
                   "engine": ev.engine_info()},
        "as_placed": res.current.as_dict(names),
        "ranked": [c.as_dict(names) for c in res.ranked],
        "verified": None if verified is None else {
            "tried": list(verified.tried),
            "chosen": None if verified.candidate is None else verified.candidate.as_dict(names),
        },
        "setups": None if setups is None else [
            {"setup": s.number, "cuts": [names[i] for i in s.cuts],
             "placement": s.candidate.as_dict([names[i] for i in s.cuts]),
             "operator": steps[k],
             "verified": None if not checks else list(checks[k].tried),
             "passes": None if not checks else checks[k].candidate is not None}
            for k, s in enumerate(setups.setups)],
        "lines": list(lines),
    }  # fmt: skip
