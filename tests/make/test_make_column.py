"""make on the demo column (its closed form, tests/carve's cell): the whole chain, for real.

The same block out of the arm's reach: FAIL in carve, no program (a heavy run, a minute and
more on the shared 2-core machine).  The chain that passes, a program per setup, is the run
of ``ruledrobot demo --carve`` (make on the same cell; tests/carve/test_demo_carve.py)."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from ruledrobot.carve.demo import write_demo_cell
from ruledrobot.cli import app
from ruledrobot.io.outdir import read_manifest


def _make(cell, out):
    res = CliRunner().invoke(app, ["make", str(cell), "--out", str(out)])
    return res, " ".join(res.output.split())


def test_a_block_out_of_reach_fails_in_carve_with_the_planners_words_and_no_program(tmp_path):
    """carve asks the planner's wire-pose search about every cut (issue 32, "cuts chosen
    with the robot"): 1 m on, the column's loop and every roughing loop offered are out of
    reach, so carve writes no job and names why; before, carve wrote the loop and its plan
    failed reach."""
    cell = write_demo_cell(tmp_path / "part")
    cell.write_text(cell.read_text().replace("[0.5, 0.0, 0.3", "[1.5, 0.0, 0.3"))  # 1 m on
    out = tmp_path / "made"
    res, text = _make(cell, out)
    assert res.exit_code == 1, res.output
    assert "make: FAIL" in text and "carve" in text
    doc = json.loads((out / "make.json").read_text())
    assert "cuts" in doc["carve"]["failed"] and doc["setups"] == []
    report = json.loads((out / "carve" / "carve.json").read_text())
    (check,) = [c for c in report["checks"] if c["name"] == "cuts"]
    assert "the arm cannot make its cut" in check["detail"]
    assert "no continuous IK solution" in check["detail"] and "ruledrobot place" in check["detail"]
    assert not [p for p in out.rglob("*") if p.name in ("cut.script", "trajectory.csv",
                                                         "job.toml")]  # fmt: skip
    assert read_manifest(out)["ok"] is False
