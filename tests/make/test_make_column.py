"""make on the demo column (its closed form, tests/carve's cell): the whole chain, for real.

Two heavy runs (a minute each on the shared 2-core machine): the column in the demo's
block, PASS, a program per setup; the same block out of the arm's reach, FAIL, no program."""

from __future__ import annotations

import hashlib
import json

from typer.testing import CliRunner

from ruledrobot.carve.demo import write_demo_cell
from ruledrobot.cli import app
from ruledrobot.io.outdir import read_manifest


def _make(cell, out):
    res = CliRunner().invoke(app, ["make", str(cell), "--out", str(out)])
    return res, " ".join(res.output.split())


def test_make_on_the_demo_column_writes_a_program_per_setup(tmp_path):
    cell = write_demo_cell(tmp_path / "part")
    out = tmp_path / "made"
    res, text = _make(cell, out)
    assert res.exit_code == 0, res.output
    setup = out / "setup1"
    for name in ("cut.script", "trajectory.csv", "trajectory.json", "report.json", "job.toml",
                 "face0.json"):  # fmt: skip
        assert (setup / name).is_file(), name
    assert (out / "view" / "setup1.html").stat().st_size > 500_000
    assert (out / "carve" / "carve.json").is_file() and (out / "setups.txt").is_file()
    doc = json.loads((out / "make.json").read_text())
    assert doc["ok"] and doc["carve"]["cuts"] == 1 and len(doc["setups"]) == 1
    assert doc["setups"][0]["cuts"] == ["face0"] and doc["setups"][0]["program"]["mode"]
    assert abs(doc["carve"]["excess"]) < 0.03
    # the sidecar and the program name the setup's own job file, which holds those bytes
    meta = json.loads((setup / "trajectory.json").read_text())
    assert meta["job"]["path"] == str(setup / "job.toml")
    assert hashlib.sha256((setup / "job.toml").read_bytes()).hexdigest() == meta["job"]["sha256"]
    script = (setup / "cut.script").read_text()
    assert f"# job: {setup / 'job.toml'}" in script and "# verified" in script
    # the summary names setups, cuts, the verdict, the excess, the time, the steps by hand
    for words in ("1 cut in 1 setup", "face0", "PASS", "excess material", "robot time",
                  "Setup 1: clamp the 200 x 200 x 150 mm block", "make: PASS"):  # fmt: skip
        assert words in text, words
    assert set(read_manifest(out)["files"]) >= {"setup1/cut.script", "view/setup1.html",
                                                "setup1/trajectory.csv", "make.json"}


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
