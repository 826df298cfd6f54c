"""The formats from a job file and from ``ruledrobot convert``; a foam-cutter file planned
end to end as a UR job."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import ezdxf
import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.geometry import se3
from ruledrobot.io.formats import kind_of
from ruledrobot.io.formats.gcode import GcodeReadOptions, read_gcode
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job

from .naca import naca4, selig_text

DATA = Path(__file__).parent / "data"
runner = CliRunner()
DEMO_SURFACE = '''builtin = "hyperbolic_paraboloid"
params = { c = 0.4 }
u = [-0.12, 0.12]          # rulings at x = u (m) in the surface frame
rulings = 9                # input rulings, refined below
pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]   # surface frame in the robot base frame
'''
#: the cutter frame in the robot base frame: x (cut direction) along x, the wire (z) along
#: -y, the towers' vertical (y) up; the block's middle (x 100 mm, y 50 mm, z 400 mm of the
#: cutter frame) at the demo stock's centre (0.5, 0, 0.3)
WEDGE_POSE = "[0.4, 0.4, 0.25, 1.5707963267948966, 0.0, 0.0]"


def job_with(surface: str) -> str:
    assert DEMO_SURFACE in DEMO_JOB
    return DEMO_JOB.replace(DEMO_SURFACE, surface)


@pytest.fixture
def wedge(tmp_path):
    shutil.copy(DATA / "wedge.ngc", tmp_path / "wedge.ngc")
    return tmp_path


def test_a_foam_cutter_file_plans_and_verifies_as_a_ur_job(wedge):
    """The hand-written foam program (towers 0.8 m apart, the block 0.2 m wide in the
    middle) through `ruledrobot plan`: exit 0, every check holds, a trajectory."""
    job = wedge / "job.toml"
    job.write_text(job_with(f'gcode = {{ file = "wedge.ngc", tower_distance = 0.8 }}\n'
                            f"pose = {WEDGE_POSE}\n"))
    result = runner.invoke(app, ["plan", str(job), "--out", str(wedge / "out")])
    assert result.exit_code == 0, result.output
    report = json.loads((wedge / "out" / "report.json").read_text())
    assert report["verdict"]["ok"] is True
    assert (wedge / "out" / "trajectory.csv").is_file()


def test_job_rulings_are_the_readers_moved_by_the_pose(wedge):
    job = load_job(_write(wedge, '[surface.gcode]\nfile = "wedge.ngc"\ntower_distance = 0.8\n'
                                 'axes = "XYUV"\n', f"pose = {WEDGE_POSE}\n"))
    r = read_gcode(wedge / "wedge.ngc", GcodeReadOptions(0.8))
    T = se3.pose_from_ur_vector(json.loads(WEDGE_POSE))
    np.testing.assert_allclose(job.input_lines().plucker, r.lines.transform(T).plucker)
    assert job.surface.kind == "gcode" and job.surface.file == wedge / "wedge.ngc"


def _write(tmp, table: str, surface_fields: str = "") -> Path:
    """A job whose [surface] names a format through a sub-table."""
    text = job_with(surface_fields) + "\n" + table
    p = tmp / "job.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("surface", "message"),
    [
        ('gcode = "wedge.ngc"\n', r"job\.toml: \[surface\.gcode\] tower_distance: missing; the "
                                  r"distance between the towers"),
        ('gcode = { file = "wedge.ngc", tower_distance = 0.8, towers = 2 }\n',
         r"\[surface\.gcode\]: unknown option\(s\) towers; expected some of"),
        ('gcode = { file = "nope.ngc", tower_distance = 0.8 }\n',
         r"\[surface\.gcode\] file: no such G-code file"),
        ('gcode = { file = "wedge.ngc", tower_distance = 0.8 }\nbuiltin = "helicoid"\n',
         r"\[surface\] builtin/file/gcode/airfoil/dxf/rhino: give exactly one of"),
        ('gcode = { file = "wedge.ngc", tower_distance = 0.8, axes = "XYZ" }\n',
         r"\[surface\.gcode\] axes: axis mapping 'XYZ'"),
        ('gcode = { file = "wedge.ngc", tower_distance = 0.8, units = "in" }\n',
         r"job\.toml: \[surface\] gcode: .*wedge\.ngc: line 6: G21 says the file is in mm, but "
         r"units = 'in' was given \(unit mismatch\)"),
        ('gcode = { file = "wedge.ngc", tower_distance = 0.8 }\nu = [0, 1]\n',
         r"\[surface\] u: only for a builtin surface"),
        ('dxf = { file = "wedge.ngc", layer = "A" }\n', r"\[surface\.dxf\]: unknown option"),
        ('airfoil = { root = "wedge.ngc", span = 0.3, root_chord = 0.2 }\n',
         r"\[surface\] airfoil: .*wedge\.ngc: line 2: expected two numbers"),
    ],
)
def test_job_errors_name_file_section_and_field(wedge, surface, message):
    p = wedge / "job.toml"
    p.write_text(job_with(surface))
    with pytest.raises(ValueError, match=message):
        load_job(p)


def test_airfoil_dxf_and_rhino_jobs(tmp_path):
    (tmp_path / "root.dat").write_text(selig_text("NACA 2412", naca4("2412", 61)))
    job = load_job(_write(tmp_path, '[surface.airfoil]\nroot = "root.dat"\nspan = 0.2\n'
                                    'root_chord = 0.15\npoints = 41\n'))
    assert len(job.input_lines()) == 41 and job.surface.kind == "airfoil"
    runner.invoke(app, ["convert", str(tmp_path / "root.dat"), "--span", "0.2", "--root-chord",
                        "0.15", "--points", "41", "--to", str(tmp_path / "w.dxf")])
    runner.invoke(app, ["convert", str(tmp_path / "w.dxf"), "--to", str(tmp_path / "w.3dm")])
    for kind, name in (("dxf", "w.dxf"), ("rhino", "w.3dm")):
        other = load_job(_write(tmp_path, "", f'{kind} = "{name}"\n'))
        np.testing.assert_allclose(other.input_lines().plucker, job.input_lines().plucker,
                                   atol=1e-12)


def test_convert_round_trips_and_says_what_it_wrote(wedge):
    out = wedge / "w.json"
    r = runner.invoke(app, ["convert", str(wedge / "wedge.ngc"), "--to", str(out),
                            "--tower-distance", "0.8"])
    assert r.exit_code == 0, r.output
    assert "25 rulings" in r.output and f"wrote {out}" in r.output
    r = runner.invoke(app, ["convert", str(out), "--to", str(wedge / "again.ngc"),
                            "--out-tower-distance", "0.8", "--out-frame", "0,0,0,0,0,0",
                            "--out-heat", "m8", "--out-feed", "0.005", "--out-decimals", "3"])
    assert r.exit_code == 0, r.output
    a = read_gcode(wedge / "wedge.ngc", GcodeReadOptions(0.8))
    b = read_gcode(wedge / "again.ngc", GcodeReadOptions(0.8))
    np.testing.assert_allclose(b.ends, a.ends, atol=1e-9)
    r = runner.invoke(app, ["convert", str(wedge / "wedge.ngc"), "--to",
                            str(wedge / "w.dxf"), "--tower-distance", "0.8"])
    assert r.exit_code == 0 and ezdxf.readfile(wedge / "w.dxf").header["$INSUNITS"] == 4


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["wedge.ngc", "--to", "w.json"], r"--tower-distance: missing"),
        (["wedge.ngc", "--to", "w.json", "--tower-distance", "0.8", "--span", "1"],
         r"unknown option\(s\) --span"),
        (["wedge.ngc", "--to", "w.dxf", "--tower-distance", "0.8", "--out-heat", "m3"],
         r"w\.dxf \(dxf output\): unknown option\(s\) --out-heat; expected some of"),
        (["wedge.ngc", "--to", "w.txt", "--tower-distance", "0.8"], r"unknown file type '\.txt'"),
        (["wedge.ngc", "--to", "w.ngc", "--tower-distance", "0.8", "--out-faces", "1,2,3"],
         r"--out-faces: expected 2 comma-separated numbers"),
        (["wedge.ngc", "--to", "w.ngc", "--tower-distance", "0.8", "--out-feed-at", "faces"],
         r"faces \(--out-faces\): missing; feed_at = faces"),
        (["missing.ngc", "--to", "w.json", "--tower-distance", "0.8"],
         r"--file: no such G-code file"),
    ],
)
def test_convert_refuses_bad_input_with_exit_2_and_writes_nothing(wedge, args, message):
    args = [str(wedge / a) if a.endswith((".ngc", ".json", ".dxf", ".txt")) else a
            for a in args]
    r = runner.invoke(app, ["convert", *args])
    assert r.exit_code == 2, r.output
    import re

    assert re.search(message, " ".join(r.output.split())), r.output
    assert sorted(p.name for p in wedge.iterdir()) == ["wedge.ngc"]


def test_a_mesh_converts_to_3dm(tmp_path):
    from ruledrobot.io.mesh import write_stl

    write_stl(tmp_path / "m.stl", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    r = runner.invoke(app, ["convert", str(tmp_path / "m.stl"), "--to", str(tmp_path / "m.3dm"),
                            "--out-units", "m"])
    assert r.exit_code == 0 and "1 triangles" in r.output, r.output
    r = runner.invoke(app, ["convert", str(tmp_path / "m.stl"), "--to", str(tmp_path / "m.dxf")])
    assert r.exit_code == 2 and "converts to a Rhino model (.3dm) only" in r.output


def test_kinds_by_suffix():
    assert [kind_of(f"a{s}") for s in (".JSON", ".csv", ".ngc", ".gcode", ".tap", ".dat",
                                       ".dxf", ".3dm")] == \
        ["lines", "lines", "gcode", "gcode", "gcode", "airfoil", "dxf", "rhino"]
    with pytest.raises(ValueError, match=r"a\.dat: unknown file type '\.dat'; expected one of"):
        kind_of("a.dat", writing=True)
