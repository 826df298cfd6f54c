"""What a make run found, per setup and as a whole: the outcome types and ``make.json``.

``make.json`` (``"format": "ruledrobot.make/1"``) holds the cell, ``ok``, carve's figures
(cuts, setups, volumes, ``excess`` = carved / part - 1, its failed checks), one entry per
setup (its folder, job, cuts, verdict, failed checks with their first line of why, the
seconds of the whole motion and of the cutting -- each cut's passes, lead-in to lead-out,
summed, the transits left out -- the program: its file and mode, or none and why, and the
viewer file), the totals, what to
do by hand between setups, the notes and the time of each step.  Paths are relative to
the make folder.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..robot.verdict import Verdict
from .program import ProgramOutcome
from .setups import Setup
from .viewer import ViewOutcome

__all__ = ["FORMAT", "SetupOutcome", "carve_summary", "document", "failed_checks"]

FORMAT = "ruledrobot.make/1"


@dataclass(frozen=True)
class SetupOutcome:
    """One setup made.

    Its :class:`~.setups.Setup`, the verdict (the plan's checks and the ``program`` check; None
    when the planner refused the job: ``refused`` says why), the plan's ``report``
    (report.json), the program and viewer outcomes, and the seconds of each step
    (``timings_s``)."""

    setup: Setup
    verdict: Verdict | None
    report: dict[str, Any] = field(default_factory=dict, repr=False)
    program: ProgramOutcome | None = None
    view: ViewOutcome | None = None
    refused: str = ""
    timings_s: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Every gating check of the plan holds (the program check is information)."""
        return self.verdict is not None and self.verdict.ok

    @property
    def duration_s(self) -> float | None:
        """The whole motion's seconds (None without a motion)."""
        return self.report.get("duration_s")

    @property
    def cut_duration_s(self) -> float | None:
        """The cutting time [s].

        Each cut's passes, lead-in to lead-out, summed (the transits between them left out;
        None without a motion)."""
        cuts = self.report.get("cuts")
        if self.duration_s is None or not cuts:
            return None
        return float(sum(c.get("cut_duration_s") or 0.0 for c in cuts))


def failed_checks(outcome: SetupOutcome) -> list[dict[str, str]]:
    """The failed checks of a setup: name and the first line of why."""
    if outcome.verdict is None:
        return [{"name": "plan", "detail": outcome.refused}]
    return [{"name": c.name, "detail": (c.detail.splitlines() or [""])[0]}
            for c in outcome.verdict.failed]  # fmt: skip


def carve_summary(report: dict[str, Any]) -> dict[str, Any]:
    """carve's figures make reports (from carve.json)."""
    w = report["whole"]
    return {"ok": report["ok"], "cuts": w["cuts"], "exact_cuts": w["exact_cuts"],
            "rough_cuts": w["rough_cuts"], "setups": w["setups"],
            "part_volume_l": w["part_volume_l"], "carved_volume_l": w["carved_volume_l"],
            "excess": w["excess"],
            "failed": [c["name"] for c in report["checks"] if not c["ok"]]}  # fmt: skip


def _total(values: list[float | None]) -> float | None:
    known = [v for v in values if v is not None]
    return round(sum(known), 3) if known and len(known) == len(values) else None


def _setup_entry(o: SetupOutcome, hand: str) -> dict[str, Any]:
    s = o.setup
    prog = o.program
    return {
        "setup": s.number, "folder": s.folder_name, "cuts": list(s.cuts), "kinds": list(s.kinds),
        "ok": o.ok,
        "verdict": o.refused if o.verdict is None else o.verdict.summary(),
        "failed": failed_checks(o),
        "duration_s": o.duration_s, "cut_duration_s": o.cut_duration_s,
        "program": None if prog is None else {
            "file": f"{s.folder_name}/{prog.path.name}" if prog.path else None,
            "mode": prog.mode or None, "what": prog.what},
        "view": None if o.view is None or o.view.path is None else
        f"{o.view.path.parent.name}/{o.view.path.name}",
        "hand": hand,
        "timings_s": {k: round(v, 3) for k, v in o.timings_s.items()},
    }  # fmt: skip


def document(cell: str, ok: bool, carve: dict[str, Any], outcomes: list[SetupOutcome],
             hand: list[str], notes: list[str],
             timings: dict[str, float]) -> dict[str, Any]:  # fmt: skip
    """The content of ``make.json`` (module doc)."""
    return {
        "format": FORMAT,
        "cell": cell,
        "ok": ok,
        "carve": carve,
        "setups": [_setup_entry(o, h) for o, h in zip(outcomes, hand, strict=False)],
        "failed_setups": [o.setup.number for o in outcomes if not o.ok],
        "totals": {"duration_s": _total([o.duration_s for o in outcomes]),
                   "cut_duration_s": _total([o.cut_duration_s for o in outcomes])},
        "hand_steps": hand,
        "notes": notes,
        "timings_s": {k: round(v, 3) for k, v in timings.items()},
    }  # fmt: skip
