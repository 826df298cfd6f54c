"""``ruledrobot demo --carve``: the column made from its closed form, carved, planned: PASS.

The demo is ``ruledrobot make`` on the column's cell file (written into the make folder's
``part/``): its one run is also the test of make's whole chain that passes, for real (the
chain that fails, tests/make/test_make_column.py; make's own logic, tests/make with fakes)."""

from __future__ import annotations

import hashlib
import json

import numpy as np
from typer.testing import CliRunner

from ruledrobot.carve.demo import column_mesh
from ruledrobot.cli import app
from ruledrobot.io.lines import read_lines_document
from ruledrobot.io.outdir import read_manifest


def test_the_demo_column_is_closed_and_on_its_closed_form():
    v, f = column_mesh()
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, count = np.unique(edges, axis=0, return_counts=True)
    assert (count == 2).all()
    side = np.abs(v[:, 0]) + np.abs(v[:, 2]) > 1e-9
    x, y, z = v[side].T
    assert np.allclose(x**2 + z**2, 0.06**2 * (1 + y**2 / 0.3**2), atol=1e-12)


def test_demo_carve_carves_the_column_in_one_exact_loop_and_plans_it(tmp_path):
    out = tmp_path / "demo"
    res = CliRunner().invoke(app, ["demo", "--carve", "--out", str(out)])
    assert res.exit_code == 0, res.output
    report = json.loads((out / "carve" / "carve.json").read_text())
    assert [c["kind"] for c in report["cuts"]] == ["exact"]
    assert abs(report["whole"]["excess"]) < 0.03
    # every ruling point in the block on the closed form (part frame at the block's centre)
    lines = read_lines_document(out / "carve" / f"{report['cuts'][0]['name']}.json").lines
    t = np.linspace(-0.07, 0.07, 15)
    p = (lines.point[:, None] + t[None, :, None] * lines.direction[:, None]).reshape(-1, 3)
    x, y, z = (p - [0.5, 0.0, 0.3]).T
    inside = np.abs(y) <= 0.1
    F = x**2 + z**2 - 0.06**2 * (1 + y**2 / 0.3**2)
    g = 2 * np.sqrt(x**2 + z**2 + (0.06**2 * y / 0.3**2) ** 2)
    assert (np.abs(F) / g)[inside].max() < 5e-4
    # make's demo (docs/make.md): the setup planned, its program and viewer file
    plan = json.loads((out / "setup1" / "report.json").read_text())
    assert plan["verdict"]["ok"]
    assert (out / "part" / "column.stl").is_file()
    text = " ".join(res.output.split())
    assert "make: PASS — 1 setup" in text
    setup = out / "setup1"
    for name in ("cut.script", "trajectory.csv", "trajectory.json", "report.json", "job.toml",
                 "face0.json"):  # fmt: skip
        assert (setup / name).is_file(), name
    assert (out / "view" / "setup1.html").stat().st_size > 500_000
    assert (out / "setups.txt").is_file()
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
                  "Setup 1: clamp the 200 x 200 x 150 mm block"):  # fmt: skip
        assert words in text, words
    assert set(read_manifest(out)["files"]) >= {"setup1/cut.script", "view/setup1.html",
                                                "setup1/trajectory.csv", "make.json"}
