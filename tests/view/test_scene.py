"""The scene description of a plan folder, checked against MuJoCo and the plan's own files."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from ruledrobot.geometry.box import Box
from ruledrobot.geometry.se3 import matrix_from_quaternion, pose_from_ur_vector
from ruledrobot.io.mesh import read_stl
from ruledrobot.io.trajectory import read_trajectory
from ruledrobot.sim import Scene
from ruledrobot.sim._mujoco import mujoco
from ruledrobot.view import NotAPlanFolder, build_scene, read_plan_folder
from ruledrobot.view.clearance import contacts_along, near_misses
from ruledrobot.view.geoms import geom_meshes
from ruledrobot.wirecut.job.load import load_job


def _model(folder):
    mj = mujoco()
    job = load_job(folder / "job.toml")
    return mj, mj.MjModel.from_xml_string(Scene.from_job(job, robot=job.robot_model()).mjcf())


def test_geom_poses_are_mujocos_own_at_the_samples(plan_folder, scene):
    """What the viewer sends for each geom is MuJoCo's geom_xpos / geom_xmat at that sample."""
    mj, model = _model(plan_folder)
    data = mj.MjData(model)
    tl = scene.timeline
    traj = read_trajectory(plan_folder / "trajectory.csv")
    ids = [g.geom_id for g in scene.geoms]
    assert len(ids) == sum(int(model.geom_group[g]) < 3 for g in range(model.ngeom))
    for k in (0, tl.t.size // 3, tl.t.size - 1):
        np.testing.assert_array_equal(tl.q[k], traj.q[tl.sample[k]])
        assert tl.t[k] == traj.t[tl.sample[k]]
        data.qpos[:6] = traj.q[tl.sample[k]]
        mj.mj_kinematics(model, data)
        np.testing.assert_allclose(tl.geom_pos[k], data.geom_xpos[ids], atol=1e-12)
        R = matrix_from_quaternion(tl.geom_quat[k])
        np.testing.assert_allclose(R.reshape(-1, 9), data.geom_xmat[ids], atol=1e-9)
    # frames are trajectory samples, about fps apart, ending on the last one
    assert tl.sample[-1] == traj.n - 1
    assert np.allclose(np.diff(tl.t[:-1]), 0.05)


def test_the_wire_lies_on_the_planned_rulings(plan_folder, scene):
    """The scene's wire (MuJoCo's sites) is the trajectory's wire frame, and inside the stock
    it lies on the planned surface within the job's wire tolerance."""
    tl = scene.timeline
    traj = read_trajectory(plan_folder / "trajectory.csv")
    W = pose_from_ur_vector(traj.tcp[tl.sample])  # base = world here (job base is zero)
    mid = tl.wire.mean(axis=1)
    # the CSV keeps the TCP to about 1e-9 m: agreement to 10 nm, not bit for bit
    np.testing.assert_allclose(mid, W[:, :3, 3], atol=1e-8)
    axis = tl.wire[:, 1] - tl.wire[:, 0]
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    np.testing.assert_allclose(axis, W[:, :3, 2], atol=1e-8)
    # chord ends during the cut against a dense sampling of surface.stl (0.1 mm spacing)
    mesh = read_stl(plan_folder / "surface.stl")
    tri = mesh.vertices[mesh.faces]
    u, v = np.meshgrid(np.linspace(0, 1, 25), np.linspace(0, 1, 25))
    keep = (u + v) <= 1.0
    u, v = u[keep], v[keep]
    pts = (tri[:, None, 0] * (1 - u - v)[:, None] + tri[:, None, 1] * u[:, None]
           + tri[:, None, 2] * v[:, None]).reshape(-1, 3)  # fmt: skip
    from scipy.spatial import cKDTree

    cut = tl.phase == "cut"
    ends = tl.chord[cut].reshape(-1, 3)
    ends = ends[np.isfinite(ends).all(axis=1)]
    assert len(ends) > 100
    # the chord ends lie on the stock faces, where the sampled mesh has its border
    dist, _ = cKDTree(pts).query(ends)
    report = json.loads((plan_folder / "report.json").read_text())
    tol = 0.5  # mm, the job's [cut] wire_tolerance
    assert report["max_planned_wire_deviation_mm"] < tol
    assert dist.max() * 1e3 < tol, dist.max()


def test_figures_agree_with_the_report(plan_folder, scene):
    tl = scene.timeline
    report = json.loads((plan_folder / "report.json").read_text())
    traj = read_trajectory(plan_folder / "trajectory.csv")
    # phases are the sidecar's
    for p in traj.meta.phases:
        inside = (tl.sample >= p.start) & (tl.sample < p.stop)
        assert set(tl.phase[inside]) <= {p.name}
    assert {"approach", "lead_in", "cut", "lead_out"} <= set(tl.phase)
    # feed: shown only inside the stock, within the report's measured range
    cut = tl.phase == "cut"
    feed = tl.feed[cut & np.isfinite(tl.feed)] * 1e3
    assert feed.size > 0.8 * cut.sum()
    assert report["min_feed_speed_mm_s"] - 0.05 <= feed.min()
    assert feed.max() <= report["max_feed_speed_mm_s"] + 0.05
    assert np.isnan(tl.feed[tl.phase == "approach"]).all()
    assert tl.speed_ratio.max() <= report["max_joint_speed_ratio"] + 1e-9
    sing = tl.singularity[np.isin(tl.phase, ("lead_in", "cut", "lead_out"))]
    assert sing.min() >= report["min_singularity_measure"] - 1e-9
    assert scene.ok and scene.verdict.startswith("PASS")
    assert scene.limits["feed_set"] == pytest.approx(0.04)
    assert [c.name for c in scene.checks][:3] == ["reach", "verified", "collisions"]


def test_static_parts_are_in_the_world(plan_folder, scene):
    assert {"surface"} <= set(scene.meshes)
    assert len(scene.rulings) == json.loads((plan_folder / "report.json").read_text())[
        "rulings_in_stock"]  # fmt: skip
    lo = scene.stock.centre - 0.5 * scene.stock.size - 1e-9
    hi = scene.stock.centre + 0.5 * scene.stock.size + 1e-9
    r = scene.rulings.reshape(-1, 3)
    assert ((r >= lo) & (r <= hi)).all()
    names = {g.name for g in scene.geoms}
    assert {"table", "stock", "base", "bow_arm0", "wire_visual"} <= names
    assert "wire" not in names  # the contact wire is MuJoCo's hidden group 3


def test_a_failed_plan_is_shown_without_motion_and_says_why(failed_folder):
    assert not (failed_folder / "trajectory.csv").exists()
    scene = build_scene(failed_folder)
    assert scene.timeline is None and not scene.ok
    assert scene.verdict.startswith("FAIL")
    assert "no trajectory" in scene.notes[0] and "verified" in scene.notes[0]
    failed = [c for c in scene.checks if c.gating and not c.ok]
    assert "verified" in [c.name for c in failed]
    assert len(scene.rulings) > 0 and "surface" in scene.meshes  # the cut is still shown


def test_not_a_plan_folder_is_refused_by_name(tmp_path, plan_folder):
    with pytest.raises(NotAPlanFolder, match="no such folder"):
        read_plan_folder(tmp_path / "missing")
    with pytest.raises(NotAPlanFolder, match=r"no report\.json"):
        read_plan_folder(tmp_path)
    with pytest.raises(NotAPlanFolder, match=r"ruledrobot\.plan-report/1"):
        read_plan_folder(plan_folder / "simulation")
    (tmp_path / "f").write_text("x")
    with pytest.raises(NotAPlanFolder, match="not a folder"):
        read_plan_folder(tmp_path / "f")


def test_a_moved_plan_folder_still_opens(tmp_path, plan_folder):
    """The job of a plan may name files beside it; the viewer needs neither them nor the
    folder's old place (and says what it worked around)."""
    copy = tmp_path / "moved"
    shutil.copytree(plan_folder, copy)
    job = (copy / "job.toml").read_text()
    job = job.replace('builtin = "hyperbolic_paraboloid"', 'file = "gone.json"')
    job = job.replace("params = { c = 0.4 }\n", "").replace("u = [-0.12, 0.12]", "")
    (copy / "job.toml").write_text(job)
    folder = read_plan_folder(copy)
    assert any("gone.json" in n for n in folder.notes)
    assert folder.trajectory is not None and folder.rulings is not None


def test_geom_meshes_lie_on_the_primitive_surfaces(plan_folder):
    mj, model = _model(plan_folder)
    meshes = {g.name: g for g in geom_meshes(mj, model)}
    cap = meshes["bow_bar"]
    r, half = model.geom_size[cap.geom_id][:2]
    v = cap.vertices.astype(float)
    z = np.clip(v[:, 2], -half, half)
    sdf = np.linalg.norm(v - np.c_[0 * z, 0 * z, z], axis=1) - r
    assert np.abs(sdf).max() < 1e-6
    box = meshes["stock"]
    np.testing.assert_allclose(np.abs(box.vertices), np.broadcast_to(
        model.geom_size[box.geom_id], box.vertices.shape), rtol=1e-6)  # fmt: skip
    assert meshes["stock"].static and not meshes["link2_g1"].static
    assert meshes["stock"].rgba[3] < 1.0  # drawn translucent, as in the video


def test_near_misses_and_collisions_are_located(plan_folder, scene):
    """Lowering the shoulder from the first planned pose drives the bow into the stock:
    MuJoCo's contacts give a near miss while it closes in, then a collision, each with a
    place and a time."""
    mj, model = _model(plan_folder)
    traj = read_trajectory(plan_folder / "trajectory.csv")
    q = np.repeat(traj.q[:1], 60, axis=0)
    q[:, 1] -= np.linspace(0.0, 0.9, 60)  # shoulder lift: the bow sinks onto the block
    t = np.linspace(0.0, 5.9, 60)
    contacts = contacts_along(mj, model, q, 0.02)
    events = near_misses(contacts, t, np.full(60, "approach"), 0.02)
    hit = events[0]
    assert hit.kind == "collision" and hit.distance_mm < 0 and "deep" in hit.sentence
    assert hit.start < hit.time  # the run starts while the parts are still apart
    grown = Box(scene.stock.centre, scene.stock.size + 0.02)
    assert "stock" in hit.what and grown.contains(hit.position)
    # up to the first contact, only near misses
    k = int(np.flatnonzero(t >= hit.start)[0])
    before = [c for c in contacts if c.index <= k and c.distance > 0]
    early = near_misses(before, t, np.full(60, "approach"), 0.02)
    assert early and all(e.kind == "near miss" and 0 < e.distance_mm < 20 for e in early)
    # structure (link 1 turning above the table at a fixed height) is never an event
    assert not any("link1_g0" in e.what for e in events)


def test_the_demo_folder_has_no_events_but_a_closest_approach_list_is_possible(scene):
    assert all(e.kind == "near miss" for e in scene.events)
    for e in scene.events:
        assert e.position is not None and 0 <= e.distance_mm <= 20
