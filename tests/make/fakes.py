"""Stand-ins for carve and the planner, so that make's own logic (setups, programs, a failed
setup, what is stripped, the summary, exit codes) is tested in seconds.  The real chain is
tested on the demo column (test_demo.py) and a block out of reach (test_failures.py)."""

from __future__ import annotations

import json
from pathlib import Path

from ruledrobot.carve import CarveResult
from ruledrobot.io.atomic import atomic_write_json, atomic_write_text
from ruledrobot.io.outdir import StagedFolder
from ruledrobot.make.program import ProgramOutcome, program_check
from ruledrobot.make.viewer import ViewOutcome
from ruledrobot.robot.verdict import Check, Verdict
from ruledrobot.wirecut import PlanResult
from ruledrobot.wirecut.job.demo import DEMO_JOB

REPORT_FORMAT = "ruledrobot.plan-report/1"


def _cut(name: str, setup: int, closed: bool) -> dict:
    return {"name": name, "kind": "rough", "what": "a loop", "rulings": 24, "closed": closed,
            "setup": setup, "deviation_mm": None, "closest_mm": 0.1, "farthest_mm": 2.0,
            "gouge_mm": 0.0}  # fmt: skip


def fake_carve(setups: int = 2, ok: bool = True):
    """A carve of ``setups`` setups of one loop each, its jobs the demo job."""

    def carve(cell, out, progress=lambda msg: None) -> CarveResult:
        progress("fitting 3 regions")
        with StagedFolder(out) as stage:
            files = {}
            for k in range(1, setups + 1):
                where = stage.path / f"setup{k}" if setups > 1 else stage.path
                files[f"job{k}" if setups > 1 else "job"] = atomic_write_text(
                    where / "job.toml", DEMO_JOB)  # fmt: skip
            report = {
                "cuts": [_cut(f"loop{k}", k, True) for k in range(1, setups + 1)],
                "whole": {"part_volume_l": 1.0, "carved_volume_l": 1.05, "excess": 0.05,
                          "largest_distance_mm": 3.0, "cuts": setups, "exact_cuts": 0,
                          "rough_cuts": setups, "setups": setups},
                "baseline": None, "part": {"faces": {}}, "notes": [],
                "checks": [{"name": "no_gouge", "ok": ok, "what": "no ruling enters the part"}],
                "ok": ok}  # fmt: skip
            atomic_write_json(stage.path / "carve.json", report)
            target = stage.commit({"command": "carve"})
        files = {k: target / Path(v).relative_to(stage.path) for k, v in files.items()}
        return CarveResult(report, None, files)  # type: ignore[arg-type]

    return carve


def fake_plan(failing: set[int]):
    """A planner whose plan of the ``n``-th job planned fails (``reach``) for n in
    ``failing``; a passing plan writes a (fake) trajectory and its sidecar."""
    count = [0]

    def plan(job, out_dir, progress=None, **kw) -> PlanResult:
        count[0] += 1
        ok = count[0] not in failing
        (progress or (lambda m: None))("timing the cut")
        checks = (Check("reach", "every ruling reachable", "yes" if ok else "no", "yes",
                        relation="==", ok=ok, detail="" if ok else "out of reach by 379 mm"),)
        verdict = Verdict(checks)
        report = {"format": REPORT_FORMAT, "job": {"path": str(job.source)},
                  "feasible": ok, "verdict": verdict.as_dict(), "duration_s": 20.0 + count[0],
                  "cut_duration_s": 12.0, "cuts": [{"cut_duration_s": 10.0}]}  # fmt: skip
        with StagedFolder(out_dir) as stage:
            atomic_write_json(stage.path / "report.json", report)
            atomic_write_text(stage.path / "job.toml", job.source_bytes.decode())
            if ok:
                atomic_write_text(stage.path / "trajectory.csv", "t,q1\n0,0\n")
                atomic_write_json(stage.path / "trajectory.json", {"format": "x"})
                (stage.path / "simulation").mkdir()
                atomic_write_text(stage.path / "simulation" / "simulated.csv", "t,q1\n")
                atomic_write_json(stage.path / "simulation" / "report.json", {})
            stage.commit({"kind": "plan", "feasible": ok})
        return PlanResult(ok, report, {}, object() if ok else None, None, verdict)  # type: ignore[arg-type]

    return plan


def fake_program(trajectory, folder: Path) -> ProgramOutcome:
    """A program written as cut.script (the export is tested in tests/export)."""
    path = atomic_write_text(folder / "cut.script", "def ruledrobot_cut():\nend\n")
    return ProgramOutcome(path, "movep", "verified: fake", program_check("movep"))


def fake_view(plan_folder: Path, target: Path) -> ViewOutcome:
    """A viewer file (the export is tested in tests/view)."""
    target.parent.mkdir(parents=True, exist_ok=True)
    return ViewOutcome(atomic_write_text(target, "<html></html>"))


def stub(monkeypatch, setups: int = 2, failing: set[int] = frozenset(), carve_ok: bool = True):
    """Put the stand-ins in place of carve, the planner, the program and the viewer."""
    import ruledrobot.carve
    import ruledrobot.make.run
    import ruledrobot.wirecut

    monkeypatch.setattr(ruledrobot.carve, "carve", fake_carve(setups, carve_ok))
    monkeypatch.setattr(ruledrobot.wirecut, "plan", fake_plan(set(failing)))
    monkeypatch.setattr(ruledrobot.make.run, "write_program", fake_program)
    monkeypatch.setattr(ruledrobot.make.run, "write_view", fake_view)


def read(path: Path) -> dict:
    return json.loads(path.read_text())
