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


def test_a_block_out_of_reach_fails_by_reach_and_leaves_no_program(tmp_path):
    cell = write_demo_cell(tmp_path / "part")
    cell.write_text(cell.read_text().replace("[0.5, 0.0, 0.3", "[1.5, 0.0, 0.3"))  # 1 m on
    out = tmp_path / "made"
    res, text = _make(cell, out)
    assert res.exit_code == 1, res.output
    assert "make: FAIL — setup 1 fails (reach)" in text and "out of reach by up to" in text
    doc = json.loads((out / "make.json").read_text())
    assert doc["failed_setups"] == [1] and doc["setups"][0]["failed"][0]["name"] == "reach"
    assert not [p for p in out.rglob("*") if p.name in ("cut.script", "trajectory.csv")]
    assert (out / "setup1" / "report.json").is_file() and read_manifest(out)["ok"] is False
