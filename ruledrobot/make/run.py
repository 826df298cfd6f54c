"""``ruledrobot make``: a cell file in, a program per setup out, or the reasons why not.

:func:`make` carves the cell's part (:func:`ruledrobot.carve.carve`), plans every setup carve
wrote (:func:`ruledrobot.wirecut.plan`, verified in MuJoCo), writes each passing setup's
program (:mod:`.program`), draws every setup for the browser (:mod:`.viewer`) and says what
to do by hand between setups (:mod:`.setups`), all into one staged folder that replaces
``out`` whole (:class:`~ruledrobot.io.outdir.StagedFolder`)::

    out/manifest.json        every file, its size and SHA-256
    out/make.json            the summary (:mod:`.summary`)
    out/setups.txt           what to do by hand, setup by setup (when every setup passes)
    out/carve/               what `ruledrobot carve` writes (job.toml or setupN/job.toml, ...)
    out/setupN/              what `ruledrobot plan` writes for setup N, the lines files of its
                             cuts and cut.script (the program)
    out/view/setupN.html     setup N in the browser, one self-contained file

Bad input (the cell file, the part, an output folder of someone else's files) raises
ValueError before anything is written.  A setup that fails leaves the folder written with
its reasons and **no** trajectory or program in any setup (:mod:`.restage`).
"""

from __future__ import annotations

import dataclasses
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..io.atomic import atomic_write_json, atomic_write_text
from ..io.outdir import StagedFolder
from ..robot.verdict import Verdict
from .program import ProgramOutcome, no_program, write_program
from .restage import restage, strip_runnable
from .setups import Setup, hand_steps, setups_of
from .steps import STEPS_PER_SETUP, Step, StepCounter
from .summary import SetupOutcome, carve_summary, document
from .viewer import VIEW_FOLDER, write_view

__all__ = ["MakeResult", "make"]


@dataclass(frozen=True)
class MakeResult:
    """What :func:`make` did: the verdict, the folder, carve's report and each setup's outcome.

    ``ok`` (every setup passes), the folder written (``out``), carve's report (carve.json),
    each setup's outcome, what to do by hand before each setup, the notes and ``document``
    (make.json).
    """

    ok: bool
    out: Path
    carve: dict[str, Any] = field(repr=False)
    setups: tuple[SetupOutcome, ...] = ()
    hand: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    document: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def failed(self) -> tuple[SetupOutcome, ...]:
        """The setups that fail."""
        return tuple(o for o in self.setups if not o.ok)


def _outside(out: Path, *inputs: Path) -> None:
    """ValueError when an input lies in the output folder (make replaces it whole)."""
    root = Path(os.path.realpath(out))
    for given in inputs:
        if Path(os.path.realpath(given)).is_relative_to(root):
            raise ValueError(f"{given}: lies in the output folder {out}, which make replaces "
                             "whole; choose another output folder")  # fmt: skip


def _plan_setup(setup: Setup, folder: Path, final: Path, steps: StepCounter) -> SetupOutcome:
    """Plan one setup into ``folder`` and write its program; the outcome.  The job is named
    by its copy in ``final``, where the folder will be (its reports, the trajectory's
    sidecar and the program's header name a file that exists, with the same bytes)."""
    from ..wirecut import load_job, plan

    times: dict[str, float] = {}
    t = time.perf_counter()
    say = steps.start(f"plan setup {setup.number}")
    try:
        job = load_job(setup.job)
        job = dataclasses.replace(job, source=final / "job.toml")  # its bytes as loaded
        res = plan(job, folder, progress=say)
    except ValueError as exc:  # the planner refused carve's job: the setup cannot be made
        steps.done("refused")
        steps.start(f"program setup {setup.number}")
        steps.done("none")
        return SetupOutcome(setup, None, refused=f"the planner refused {setup.job.name}: {exc}")
    times["plan"] = time.perf_counter() - t
    steps.done("PASS" if res.feasible else "FAIL")
    t = time.perf_counter()
    steps.start(f"program setup {setup.number}")
    verdict, program = res.verdict, None
    if res.feasible:  # the program is information: without one, the trajectory is streamed
        program = (write_program(res.trajectory, folder) if res.trajectory is not None
                   else no_program("the plan holds no trajectory"))  # fmt: skip
        verdict = Verdict((*verdict.checks, program.check))
    here = setup.job.resolve().parent
    lines = {c.surface.file.name: c.surface.file for c in job.cuts
             if c.surface.file is not None and c.surface.file.resolve().parent == here}
    restage(folder, {"command": "make", "setup": setup.number}, add=lines)
    times["program"] = time.perf_counter() - t
    steps.done(program.mode if program is not None and program.path else "none")
    return SetupOutcome(setup, verdict, res.report, program, timings_s=times)


def make(cell: str | os.PathLike[str] | None, out: str | os.PathLike[str],
         progress: Callable[[Step], None] | None = None,
         prepare: Callable[[Path], Path] | None = None) -> MakeResult:  # fmt: skip
    """Make the part of the cell file ``cell`` into ``out`` (module doc).

    ``progress`` receives a :class:`~.steps.Step` at each step's start, message and end.
    ``prepare(folder)``: writes the cell into the staged folder and returns its path
    (the demo, whose part is made in the folder; ``cell`` is then None).  ValueError on
    bad input, nothing written."""
    from ..carve import carve, load_cell

    t0 = time.perf_counter()
    out = Path(out)
    if prepare is None:
        if cell is None:
            raise ValueError("make: no cell file given")
        spec = load_cell(cell)  # bad input named before the output folder is touched
        _outside(out, Path(cell), spec.part.file)
    steps = StepCounter(progress, 1)
    timings: dict[str, float] = {}
    with StagedFolder(out) as stage:
        cell_path = Path(prepare(stage.path)) if prepare is not None else Path(cell)  # type: ignore[arg-type]
        if prepare is not None:
            spec = load_cell(cell_path)
        say = steps.start("carve")
        t = time.perf_counter()
        carved = carve(cell_path, stage.path / "carve", progress=say)
        timings["carve"] = time.perf_counter() - t
        steps.done("PASS" if carved.ok else "FAIL")
        setups = setups_of(carved) if carved.ok else []
        steps.total = 1 + STEPS_PER_SETUP * len(setups)
        outcomes = [_plan_setup(s, stage.path / s.folder_name, stage.target / s.folder_name,
                                steps) for s in setups]  # fmt: skip
        notes = _views(outcomes, stage.path, steps)
        ok = carved.ok and bool(outcomes) and all(o.ok for o in outcomes)
        why = "" if ok else _why(carved.ok, outcomes)
        if not ok:
            for o in outcomes:
                if (stage.path / o.setup.folder_name).is_dir():
                    strip_runnable(stage.path / o.setup.folder_name, why)
            outcomes = [_removed(o, why) for o in outcomes]
        programs = {o.setup.number: o.program.path.name if o.program and o.program.path
                    else None for o in outcomes}  # fmt: skip
        hand = hand_steps(setups, spec, programs, blocked="" if ok else why)
        if ok:
            atomic_write_text(stage.path / "setups.txt", "\n\n".join(hand) + "\n")
        for o in outcomes:
            timings.update({f"{k} setup {o.setup.number}": v for k, v in o.timings_s.items()})
        timings["total"] = time.perf_counter() - t0
        named = (cell_path.relative_to(stage.path).as_posix()
                 if cell_path.is_relative_to(stage.path) else str(cell_path))  # fmt: skip
        doc = document(named, ok, carve_summary(carved.report), outcomes, hand, notes, timings)
        atomic_write_json(stage.path / "make.json", doc)
        target = stage.commit({"command": "make", "ok": ok, "cell": doc["cell"]})
    return MakeResult(ok, target, carved.report, tuple(outcomes), tuple(hand), tuple(notes), doc)


def _views(outcomes: list[SetupOutcome], folder: Path, steps: StepCounter) -> list[str]:
    """Write each setup's viewer file (in place in ``outcomes``); the notes."""
    notes = []
    for k, o in enumerate(outcomes):
        steps.start(f"viewer setup {o.setup.number}")
        plan_folder = folder / o.setup.folder_name
        if not plan_folder.is_dir():
            steps.done("none")
            continue
        t = time.perf_counter()
        view = write_view(plan_folder, folder / VIEW_FOLDER / f"{o.setup.folder_name}.html")
        if view.note:
            notes.append(view.note)
        outcomes[k] = SetupOutcome(o.setup, o.verdict, o.report, o.program, view, o.refused,
                                   {**o.timings_s, "viewer": time.perf_counter() - t})  # fmt: skip
        steps.done("written" if view.path else "none")
    return notes


def _removed(o: SetupOutcome, why: str) -> SetupOutcome:
    """The outcome with its program marked removed (a failed run keeps none)."""
    if o.program is None or o.program.path is None:
        return o
    gone = ProgramOutcome(None, o.program.mode, f"{o.program.what}; removed: {why}",
                          o.program.check)  # fmt: skip
    return dataclasses.replace(o, program=gone)


def _why(carve_ok: bool, outcomes: list[SetupOutcome]) -> str:
    if not carve_ok:
        return "make: carve fails"
    if not outcomes:
        return "make: carve made no cut"
    bad = [str(o.setup.number) for o in outcomes if not o.ok]
    return f"make: setup {', '.join(bad)} fail{'s' if len(bad) == 1 else ''}"
