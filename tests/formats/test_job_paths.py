"""Relative paths of a job's input files are taken from the job file's folder, for every
format, from any working folder (issue 22, item 1), and a missing file is named by its
format."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.io.calibration import save_calibration
from ruledrobot.robot import random_calibration
from ruledrobot.wirecut.job.load import load_job

from .naca import naca4, selig_text
from .test_job_cli import DATA, WEDGE_POSE, job_with

runner = CliRunner()
GCODE = f'gcode = {{ file = "wedge.ngc", tower_distance = 0.8 }}\npose = {WEDGE_POSE}\n'
#: a [surface] of each kind; relative names only (the job lives in jobs/foreign/)
SURFACES = {
    "gcode": (GCODE, "", "wedge.ngc"),
    "gcode table": (f"pose = {WEDGE_POSE}\n",
                    '[surface.gcode]\nfile = "wedge.ngc"\ntower_distance = 0.8\n', "wedge.ngc"),
    "airfoil": ('airfoil = { root = "root.dat", tip = "sub/../tip.dat", span = 0.2, '
                'root_chord = 0.15, tip_chord = 0.1, points = 41 }\n', "", "root.dat"),
    "dxf": ('dxf = "w.dxf"\n', "", "w.dxf"),
    "rhino": ('rhino = { file = "./w.3dm" }\n', "", "w.3dm"),
    "lines": ('file = "w.json"\n', "", "w.json"),
}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    """A folder of input files of every format (written once)."""
    d = tmp_path_factory.mktemp("inputs")
    shutil.copy(DATA / "wedge.ngc", d / "wedge.ngc")
    (d / "root.dat").write_text(selig_text("NACA 2412", naca4("2412", 41)))
    (d / "tip.dat").write_text(selig_text("NACA 0012", naca4("0012", 41)))
    for to in ("w.dxf", "w.json"):
        r = runner.invoke(app, ["convert", str(d / "root.dat"), "--span", "0.2", "--root-chord",
                                "0.15", "--points", "41", "--to", str(d / to)])
        assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["convert", str(d / "w.dxf"), "--to", str(d / "w.3dm")])
    assert r.exit_code == 0, r.output
    save_calibration(d / "robot.calib.json", random_calibration("ur5e", seed=3))
    return d


def _job_in_subfolder(root: Path, inputs: Path, kind: str) -> Path:
    """``root/jobs/foreign/job.toml`` with every input file beside it."""
    folder = root / "jobs" / "foreign"
    shutil.copytree(inputs, folder)
    (folder / "sub").mkdir()
    surface, table, _ = SURFACES[kind]
    text = job_with(surface).replace("[robot]\n", '[robot]\ncalibration = "robot.calib.json"\n')
    assert 'calibration = "robot.calib.json"' in text
    (folder / "job.toml").write_text(text + "\n" + table)
    return folder / "job.toml"


@pytest.mark.parametrize("kind", list(SURFACES))
def test_relative_paths_are_taken_from_the_job_files_folder(tmp_path, inputs, kind, monkeypatch):
    """From the parent folder (``jobs/foreign/job.toml``), from the job's own folder and
    from an unrelated one (an absolute job path): the same files, joined once."""
    job_file = _job_in_subfolder(tmp_path, inputs, kind)
    folder = job_file.parent
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    expect = folder / SURFACES[kind][2]
    seen = []
    for cwd, name in ((tmp_path, "jobs/foreign/job.toml"), (folder, "job.toml"),
                      (elsewhere, str(job_file))):  # fmt: skip
        monkeypatch.chdir(cwd)
        job = load_job(name)
        assert (cwd / job.surface.file).resolve() == expect.resolve()
        assert job.robot.calibration is not None
        seen.append(job.input_lines().plucker)
    for other in seen[1:]:
        assert (other == seen[0]).all()


@pytest.mark.parametrize(
    ("surface", "message"),
    [
        ('gcode = { file = "nope.ngc", tower_distance = 0.8 }\n',
         r"\[surface\.gcode\] file: no such G-code file: jobs/foreign/nope\.ngc$"),
        ('airfoil = { root = "root.dat", tip = "nope.dat", span = 0.2, root_chord = 0.15 }\n',
         r"\[surface\.airfoil\] tip: no such airfoil file: jobs/foreign/nope\.dat$"),
        ('dxf = "nope.dxf"\n', r"\[surface\.dxf\] file: no such DXF file: jobs/foreign/nope\.dxf$"),
        ('rhino = "nope.3dm"\n',
         r"\[surface\.rhino\] file: no such 3DM file: jobs/foreign/nope\.3dm$"),
        ('file = "nope.json"\n', r"\[surface\] file: no such lines file: jobs/foreign/nope\.json$"),
        ('file = "sub"\n',
         r"\[surface\] file: expected a lines file, jobs/foreign/sub is a folder"),
    ],
)
def test_a_missing_file_is_named_by_its_format_and_path(tmp_path, inputs, surface, message,
                                                        monkeypatch):  # fmt: skip
    job_file = _job_in_subfolder(tmp_path, inputs, "lines")
    job_file.write_text(job_with(surface))
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match=r"^jobs/foreign/job\.toml: " + message):
        load_job("jobs/foreign/job.toml")


def test_plan_from_the_parent_folder_with_a_gcode_table(tmp_path, inputs, monkeypatch):
    """``ruledrobot plan jobs/foreign/job.toml`` from the parent folder: plans (exit 0)."""
    _job_in_subfolder(tmp_path, inputs, "gcode table")
    text = (tmp_path / "jobs/foreign/job.toml").read_text()
    (tmp_path / "jobs/foreign/job.toml").write_text(
        text.replace('calibration = "robot.calib.json"\n', ""))
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, ["plan", "jobs/foreign/job.toml", "--out", "out"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "out" / "trajectory.csv").is_file()
    # viewed from another folder: the job's G-code is not found from there, not needed
    from ruledrobot.view.folder import read_plan_folder

    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    seen = read_plan_folder(tmp_path / "out")
    assert seen.job.stock is not None
    assert any("gcode file" in n and "not needed to view" in n for n in seen.notes), seen.notes
