"""Writing a planned job (wirecut.report.files) into a staging folder, read back with the
readers a user's tools would use: the trajectory only when the verdict passes, the wire's
rulings, the target surface clipped to the block and on the demo's saddle, the report, the
job file byte for byte; and the rulings added where the surface meets the block."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ruledrobot.geometry.box import Box
from ruledrobot.geometry.surfaces import hyperbolic_paraboloid_residual
from ruledrobot.io.lines import load_lines
from ruledrobot.io.mesh import read_stl
from ruledrobot.io.outdir import StagedFolder
from ruledrobot.io.trajectory import read_trajectory
from ruledrobot.robot.verdict import Check, Verdict
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from ruledrobot.wirecut.report.files import (
    EDGE_SUBDIVISION,
    _lines_of,
    _with_edge_rulings,
    write_plan,
)

PASS = Verdict((Check("reach", "every ruling reachable", "yes", "yes", relation="==", ok=True),))
FAIL = Verdict((Check("feed_min", "lowest feed", 9.0, 9.5, "mm/s", ">=", ok=False),))


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    job_file = tmp_path_factory.mktemp("job") / "demo.toml"
    job_file.write_text(DEMO_JOB)
    plan = make_plan(load_job(job_file))
    assert plan.motion is not None
    return job_file, plan


def _write(tmp_path, plan, verdict, video=False):
    report = {"made": "here"}
    stage = StagedFolder(tmp_path / "out")
    files = write_plan(stage, plan, None, report, verdict, video=video)
    return stage, files, report


def test_a_passing_plan_writes_its_trajectory_and_files(tmp_path, planned):
    job_file, plan = planned
    stage, files, report = _write(tmp_path, plan, PASS)
    with stage:
        names = {p.name for p in stage.path.iterdir()}
        assert {"trajectory.csv", "trajectory.json", "refined.json", "surface.stl",
                "plots.png", "report.json", "job.toml"} <= names  # fmt: skip
        assert "part.stl" not in names  # the demo keeps no side: no part
        for name, p in files.items():
            assert p.is_file() and p.parent == stage.path, name
        traj = read_trajectory(files["trajectory"])
        np.testing.assert_allclose(traj.q, plan.trajectory.q, atol=1e-9)
        np.testing.assert_allclose(traj.t, plan.trajectory.t, atol=1e-9)
        assert json.loads(files["report"].read_text()) == report == {"made": "here"}
        assert files["job"].read_bytes() == job_file.read_bytes()
        assert files["plots"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        # the wire's rulings, every pass one after the other
        F = np.concatenate([cp.frames for cp in plan.passes])
        lines = load_lines(files["refined"])
        assert len(lines) == len(F)
        d = lines.plucker[:, :3]
        np.testing.assert_allclose(np.abs(np.einsum("mi,mi->m", d, F[:, :3, 2])), 1.0,
                                   atol=1e-9)  # fmt: skip
        np.testing.assert_allclose(np.cross(F[:, :3, 3], d), lines.plucker[:, 3:], atol=1e-9)
        # the target surface: inside the block, on the saddle z = x y / 0.4 of the surface
        # frame at (0.5, 0, 0.3)
        mesh = read_stl(files["surface"])
        assert len(mesh.faces) > 100
        assert plan.job.stock.contains(mesh.vertices, margin=1e-6).all()
        local = mesh.vertices - [0.5, 0.0, 0.3]
        assert np.abs(hyperbolic_paraboloid_residual(local, c=0.4)).max() < 1e-4
        # it reaches the block's faces the wire cuts through (x = 0.4 and 0.6 are
        # rulings' ends; y = +-0.1 the faces the rulings cross)
        assert np.abs(mesh.vertices[:, 1]).max() == pytest.approx(0.1, abs=1e-5)


def test_a_failing_plan_leaves_no_trajectory(tmp_path, planned):
    _, plan = planned
    stage, files, report = _write(tmp_path, plan, FAIL, video=True)
    with stage:
        names = {p.name for p in stage.path.iterdir()}
        assert "trajectory.csv" not in names and "trajectory.json" not in names
        assert {"report.json", "plots.png", "refined.json"} <= names
        assert "trajectory" not in files
        assert report["notes"] == [
            "no video: the plan fails (--video renders the cut of a plan that passes; "
            "plots.png and report.json show this one)"]
        assert json.loads(files["report"].read_text())["notes"] == report["notes"]
    assert not stage.path.exists()  # never committed: the staging folder is gone


def test_rulings_are_added_where_the_surface_enters_and_leaves_the_block():
    x = np.linspace(-0.2, 0.2, 9)  # rulings along z at x = -0.2 ... 0.2, 0.05 apart
    F = np.tile(np.eye(4), (9, 1, 1))
    F[:, 0, 3] = x
    box = Box([0.0, 0.0, 0.0], [0.22, 0.2, 0.2])  # |x| <= 0.11: rulings 2..6 cross it
    out = _with_edge_rulings(F, box)
    k = EDGE_SUBDIVISION - 1
    assert len(out) == 9 + 2 * k
    xs = out[:, 0, 3]
    assert np.all(np.diff(xs) > 0)
    np.testing.assert_array_equal(out[:, :3, :3], np.tile(np.eye(3), (len(out), 1, 1)))
    f = np.arange(1, EDGE_SUBDIVISION) / EDGE_SUBDIVISION
    np.testing.assert_allclose(np.sort(np.setdiff1d(xs, x)),
                               np.r_[-0.15 + 0.05 * f, 0.1 + 0.05 * f], atol=1e-12)  # fmt: skip
    inside = Box([0.0, 0.0, 0.0], [1.0, 0.2, 0.2])
    assert _with_edge_rulings(F, inside) is F  # no edge: unchanged


def test_lines_of_frames_are_their_z_axes():
    rng = np.random.default_rng(3)
    F = np.tile(np.eye(4), (5, 1, 1))
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    F[:, :3, :3] = q * np.sign(np.linalg.det(q))
    F[:, :3, 3] = rng.normal(size=(5, 3))
    L = _lines_of(F)
    z, o = F[:, :3, 2], F[:, :3, 3]
    for t in (-1.0, 0.0, 2.5):  # every point o + t z lies on the line: p x d = moment
        p = o + t * z
        np.testing.assert_allclose(np.cross(p, L.plucker[:, :3]), L.plucker[:, 3:], atol=1e-12)
