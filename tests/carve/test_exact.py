"""Ruled parts cut exactly: a hyperboloid column and a block with a hyperbolic-paraboloid
top, checked against their closed forms (tests/carve/parts.py), and planned."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.geometry import se3
from ruledrobot.geometry.box import Box
from ruledrobot.io.lines import read_lines_document

from .conftest import AT_CENTRE, AXIS_Y, cuts_alone, run_carve, write_cell
from .parts import hyperboloid_column, saddle_block, write_obj, write_stl_ascii

STOCK = Box(np.array([0.5, 0.0, 0.3]), np.array([0.2, 0.2, 0.15]))


def _ruling_points(path, step=0.001):
    doc = read_lines_document(path)
    p, d = doc.lines.point, doc.lines.direction
    t0, t1, hit = STOCK.clip_lines(p, d)
    idx = np.flatnonzero(hit)  # an open cut's end rulings lead in from outside the block
    assert len(idx) > 10 and np.all(np.diff(idx) == 1)
    return np.concatenate([p[i] + np.arange(t0[i], t1[i], step)[:, None] * d[i]
                           for i in np.flatnonzero(hit)]), doc


def _local(points, pose):
    T = se3.pose_from_ur_vector(pose)
    return (points - T[:3, 3]) @ T[:3, :3]


@pytest.mark.parametrize(("maker", "pose", "closed"), [
    (hyperboloid_column, AXIS_Y, True),
    (saddle_block, AT_CENTRE, False),
])
def test_ruled_part_is_cut_on_its_closed_form_and_plans(tmp_path, maker, pose, closed):
    """Carved, the cut checked against the closed form; the saddle's open cut planned and
    verified.  The column's loop is planned in tests/carve/test_demo_carve.py:
    ``ruledrobot demo --carve`` carves the same column (a = 60 mm, c = 300 mm, 200 mm
    along y at the block's centre; 64 x 12 facets there, 96 x 24 here) and plans its one
    loop, verified in MuJoCo: a second plan of it here would prove the same thing."""
    v, f, distance = maker()
    write_stl_ascii(tmp_path / "part.stl", v, f, scale=0.001)
    cell = write_cell(tmp_path, "part.stl", pose)
    res, report = run_carve(cell, tmp_path / "carve")
    assert res.exit_code == 0, res.output
    assert report["ok"] and report["whole"]["cuts"] == 1 and report["whole"]["setups"] == 1
    cut = report["cuts"][0]
    assert cut["kind"] == "exact" and cut["closed"] is closed and cut["gouge_mm"] == 0.0
    pts, doc = _ruling_points(tmp_path / "carve" / f"{cut['name']}.json")
    assert bool(doc.closed) is closed
    assert distance(_local(pts, pose)).max() < 0.0005  # every ruling point in the block
    assert abs(report["whole"]["excess"]) < 0.03
    part_volume = abs(np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum()) / 6
    assert report["whole"]["part_volume_l"] == pytest.approx(part_volume * 1e3, rel=1e-4)
    if not closed:  # the job as written plans and passes (MuJoCo verification included)
        plan = CliRunner().invoke(app, ["plan", str(tmp_path / "carve" / "job.toml"),
                                        "--out", str(tmp_path / "plan")])
        assert plan.exit_code == 0, plan.output
        assert "verdict: PASS" in plan.output


def test_same_cuts_from_stl_obj_and_3dm(tmp_path):
    """The column as ASCII STL in mm, binary STL in m, OBJ in cm and a 3DM mesh: the same
    cut from each (carve's reading and its cut plan; the robot's search and the files
    written are the same whatever file the part came from, and run in the tests above)."""
    from ruledrobot.io.formats.rhino_write import write_mesh_3dm
    from ruledrobot.io.mesh import write_stl

    v, f, _ = hyperboloid_column(nu=64, nz=12)
    files = {"a.stl": ("mm", write_stl_ascii(tmp_path / "a.stl", v, f, scale=0.001)),
             "b.stl": ("m", write_stl(tmp_path / "b.stl", v, f)),
             "c.obj": ("cm", write_obj(tmp_path / "c.obj", v, f, scale=0.01)),
             "d.3dm": ("mm", write_mesh_3dm(tmp_path / "d.3dm", v, f, units="mm"))}
    chords = []
    for name, (units, _) in files.items():
        cell = write_cell(tmp_path, name, AXIS_Y, units=units, name=f"{name}.toml")
        plan = cuts_alone(cell)[2]
        (cut,) = [c for c in plan.cuts if c.name == "face0"]
        lines = cut.lines
        t0, t1, hit = STOCK.clip_lines(lines.point, lines.direction)
        assert hit.all()
        chords.append(np.stack([lines.point + t0[:, None] * lines.direction,
                                lines.point + t1[:, None] * lines.direction], axis=1))
    for other in chords[1:]:  # the same rulings, within float32 rounding (binary STL, 3DM)
        assert other.shape == chords[0].shape
        assert np.abs(other - chords[0]).max() < 1e-6
