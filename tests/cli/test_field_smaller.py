"""The smaller things the field found (issue 22, item 8): `refine --scheme linear`, plain
numbers in messages, the file, index and field of a bad lines file, robot names in any
case, the demo's job file, --video on a failing plan, `chain` saying what it wrote, a
G-code program whose first move is a G1 naming every axis."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import ruledrobot as rr
from ruledrobot.cli import app
from ruledrobot.geometry.box import Box
from ruledrobot.geometry.checks import as_per_joint
from ruledrobot.io.formats.gcode import GcodeReadOptions, read_gcode
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job

runner = CliRunner()


def _lines_file(path: Path, n: int = 6) -> Path:
    u = np.linspace(0.0, 1.0, n)
    lines = rr.Lines.from_point_direction(np.stack([0 * u, 0 * u, 0.05 * u], 1),
                                          np.stack([np.cos(u), np.sin(u), 0 * u], 1))
    return rr.save_lines(path, lines)


def _text(result) -> str:
    return " ".join(result.output.split())


def test_refine_takes_every_scheme_the_readme_lists(tmp_path):
    src = _lines_file(tmp_path / "l.json")
    r = runner.invoke(app, ["refine", str(src), "--scheme", "linear", "--steps", "2",
                            "--out", str(tmp_path / "r.json")])  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "linear" in r.output and len(rr.load_lines(tmp_path / "r.json")) == 21


def test_numbers_in_messages_are_plain(tmp_path):
    with pytest.raises(ValueError) as exc:
        Box(np.zeros(3), np.array([0.2, 0.0, 0.1]))
    assert "got 0.0" in str(exc.value) and "np." not in str(exc.value)
    with pytest.raises(ValueError) as exc:
        as_per_joint(np.array([1.0, 1.0, -2.0, 1.0, 1.0, 1.0]), "speed", 6, minimum=0.0)
    assert "got -2.0" in str(exc.value) and "np." not in str(exc.value)
    job = tmp_path / "job.toml"
    job.write_text(DEMO_JOB.replace("size = [0.2, 0.2, 0.15]", "size = [0.2, 0.0, 0.15]"))
    assert "size = [0.2, 0.0, 0.15]" in job.read_text()
    with pytest.raises(ValueError, match=r"\[stock\] size: edge 1 must be positive, got 0\.0$"):
        load_job(job)


@pytest.mark.parametrize("multi", [False, True])
def test_a_nan_in_a_lines_file_names_the_surface_table_the_file_and_the_ruling(tmp_path, multi):
    doc = json.loads(_lines_file(tmp_path / "l.json").read_text())
    doc["lines"][3]["point"][1] = float("nan")
    (tmp_path / "l.json").write_text(json.dumps(doc))
    surface = 'file = "l.json"\npose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]\n'
    head, rest = DEMO_JOB.split("[surface]")[0], "[stock]" + DEMO_JOB.split("[stock]")[1]
    if multi:  # [[cut]] name = "top" (the demo's [cut] fields) and its [cut.surface]
        text = head + rest.replace("[cut]", '[[cut]]\nname = "top"') + \
            "\n[cut.surface]\n" + surface  # fmt: skip
    else:
        text = head + "[surface]\n" + surface + "\n" + rest
    (tmp_path / "job.toml").write_text(text)
    table = r"\[cut 'top'\.surface\]" if multi else r"\[surface\]"
    with pytest.raises(ValueError, match=table + r" file: .*l\.json: lines\[3\]\.point: "
                                         r"contains NaN"):  # fmt: skip
        load_job(tmp_path / "job.toml")


def test_robot_names_in_any_case(tmp_path):
    job = tmp_path / "job.toml"
    job.write_text(DEMO_JOB.replace('model = "ur5e"', 'model = "UR5e"'))
    assert 'model = "UR5e"' in job.read_text()
    assert load_job(job).robot.model == "ur5e"
    job.write_text(DEMO_JOB.replace('model = "ur5e"', 'model = "UR99"'))
    with pytest.raises(ValueError, match=r"\[robot\] model: unknown robot 'UR99'; expected one "
                                         r"of ur3, .* \(any case\)"):  # fmt: skip
        load_job(job)


def test_chain_says_what_it_wrote(tmp_path):
    src = _lines_file(tmp_path / "l.json")
    r = runner.invoke(app, ["chain", str(src), "--out", str(tmp_path / "c.xml")])
    assert r.exit_code == 0, r.output
    assert f"wrote {tmp_path / 'c.xml'}: a serial chain of 6 hinge joints" in _text(r)


def test_a_first_g1_naming_every_axis_places_the_wire(tmp_path):
    body = "".join(f"G1 X{10 * k} Y{20 + k} U{10 * k} V{30 - k}\n" for k in range(1, 6))
    (tmp_path / "a.ngc").write_text("G21 G90\nG1 X0 Y20 U0 V30 F300\n" + body + "M2\n")
    (tmp_path / "b.ngc").write_text("G21 G90\nG0 X0 Y20 U0 V30\nG1 F300\n" + body + "M2\n")
    a = read_gcode(tmp_path / "a.ngc", GcodeReadOptions(0.8))
    b = read_gcode(tmp_path / "b.ngc", GcodeReadOptions(0.8))
    assert len(a.lines) == 6
    np.testing.assert_allclose(a.ends, b.ends, atol=1e-15)


def test_video_on_a_failing_plan_says_why_there_is_none(tmp_path):
    job = tmp_path / "job.toml"
    job.write_text(DEMO_JOB.replace("pose = [0.5, 0.0, 0.3,", "pose = [2.5, 0.0, 0.3,")
                   .replace("centre = [0.5, 0.0, 0.3]", "centre = [2.5, 0.0, 0.3]"))  # fmt: skip
    r = runner.invoke(app, ["plan", str(job), "--out", str(tmp_path / "out"), "--video"])
    assert r.exit_code == 1
    assert "no video: the plan fails" in _text(r)
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert any(n.startswith("no video: the plan fails") for n in report["notes"])


def test_the_demo_names_the_job_file_it_leaves(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, ["demo", "--out", "d", "--no-stream", "--no-video"])
    assert r.exit_code == 0, r.output
    assert "checks of d/job.toml" in r.output and "/tmp" not in r.output.replace(
        str(tmp_path), "")
    assert json.loads(Path("d/report.json").read_text())["job"]["path"] == "d/job.toml"
    assert json.loads(Path("d/trajectory.json").read_text())["job"]["path"] == "d/job.toml"
    assert Path("d/job.toml").read_text() == DEMO_JOB
