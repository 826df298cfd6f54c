"""The work cell: bow tool, stock, table, collision classes, camera and buffers."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from ruledrobot.geometry.box import Box
from ruledrobot.robot import load
from ruledrobot.sim import BowTool, Scene, scene_mjcf
from ruledrobot.sim.scene import default_table, example_scene

BOW = BowTool([-0.2, 0.0, 0.25], [0.2, 0.0, 0.25])
Q0 = np.array([0.3, -1.6, 1.4, -1.4, -1.57, 0.0])


def _compile(xml: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    m = mujoco.MjModel.from_xml_string(xml)
    return m, mujoco.MjData(m)


def _contacts(m, d, q) -> set[tuple[str, str]]:
    d.qpos[:] = q
    mujoco.mj_forward(m, d)
    return {
        tuple(sorted((m.geom(c.geom1).name, m.geom(c.geom2).name))) for c in d.contact[: d.ncon]
    }


def test_bow_tool_geometry_matches_the_cut_planner():
    from ruledrobot.wirecut.cut.wire_pose import bow_segments
    from ruledrobot.wirecut.job.load import ToolSpec

    for a, b in (
        ([-0.2, 0.0, 0.25], [0.2, 0.0, 0.25]),
        ([-0.1, 0.05, 0.3], [0.15, -0.02, 0.2]),
        ([0.0, -0.2, 0.0], [0.0, 0.2, 0.0]),
    ):
        spec = ToolSpec(np.array(a), np.array(b), mass=0.8)
        bow = BowTool.from_spec(spec)
        np.testing.assert_allclose(bow.segments(), bow_segments(spec), atol=1e-15)
        assert bow.mass == 0.8 and bow.wire_length == pytest.approx(spec.wire_length)
        _, inertia = bow.inertia()
        assert np.all(np.linalg.eigvalsh(inertia) > 0)
        np.testing.assert_allclose(inertia, inertia.T)


def test_bow_tool_validation():
    with pytest.raises(ValueError, match="wire_start"):
        BowTool([0, 0], [1, 0, 0])
    with pytest.raises(ValueError, match="wire_end"):
        BowTool([0, 0, 0.1], [0, 0, 0.1])
    with pytest.raises(ValueError, match="arm_radius"):
        BowTool([0, 0, 0], [0.1, 0, 0], arm_radius=0.0)
    with pytest.raises(ValueError, match="mass"):
        BowTool([0, 0, 0], [0.1, 0, 0], mass=-1.0)


def test_scene_frames_and_mass(rng):
    robot = (
        load("ur5e")
        .with_base([0.1, 0.2, 0.3, 0.0, 0.0, 0.4])
        .with_tool([0.0, 0.0, 0.25, 0.0, 0.0, 0.0])
    )
    stock = Box(centre=[0.5, 0.0, 0.1], size=[0.2, 0.2, 0.2])
    m, d = _compile(scene_mjcf(robot, BOW, stock))
    flange = robot.with_tool(np.eye(4))
    for q in rng.uniform(-np.pi, np.pi, size=(10, 6)):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        F = flange.fk(q)
        for name, p in (("wire_start", BOW.wire_start), ("wire_end", BOW.wire_end)):
            np.testing.assert_allclose(d.site(name).xpos, F[:3, :3] @ p + F[:3, 3], atol=1e-9)
        T = robot.fk(q)
        np.testing.assert_allclose(d.site("tcp").xpos, T[:3, 3], atol=1e-9)
    # the stock sits in the base frame
    base = np.asarray(robot.base)
    np.testing.assert_allclose(
        d.geom("stock").xpos, base[:3, :3] @ stock.centre + base[:3, 3], atol=1e-12
    )
    np.testing.assert_allclose(m.geom("stock").size, 0.5 * stock.size)
    assert m.body_mass[m.body("bow").id] == pytest.approx(BOW.mass)
    assert m.vis.quality.offsamples == 0
    assert m.camera("cell") is not None


def test_wire_inside_stock_is_not_a_collision_but_the_bow_is():
    """A stock block around the middle of the wire touches nothing; moved onto a bow arm it
    collides with it; the wire still collides with the table and the arm."""
    robot = load("ur5e")
    F = robot.fk(Q0)
    mid = F[:3, :3] @ (0.5 * (BOW.wire_start + BOW.wire_end)) + F[:3, 3]
    around_wire = Box(centre=mid, size=[0.1, 0.1, 0.1], rotation=F[:3, :3])
    m, d = _compile(scene_mjcf(robot, BOW, around_wire))
    assert _contacts(m, d, Q0) == set()
    arm = F[:3, :3] @ BOW.segments()[0].mean(axis=0) + F[:3, 3]
    on_arm = Box(centre=arm, size=[0.05, 0.05, 0.05])
    m, d = _compile(scene_mjcf(robot, BOW, on_arm))
    assert ("bow_arm0", "stock") in _contacts(m, d, Q0)
    # the same block as a table: the wire collides with it
    m, d = _compile(scene_mjcf(robot, BOW, None, table=around_wire))
    assert _contacts(m, d, Q0) == {("table", "wire")}
    assert (m.geom("wire").contype, m.geom("wire").conaffinity) == (2, 0)
    assert m.geom("table").conaffinity & 2 and m.geom("link3_g1").conaffinity & 2


def test_clear_posture_has_no_contacts():
    m, d = _compile(example_scene().mjcf())
    assert _contacts(m, d, Q0) == set()
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    mujoco.mj_forward(m, d)
    assert d.ncon == 0


def test_default_table_covers_robot_and_stock():
    robot = load("ur10e")
    stock = Box(centre=[1.1, -0.4, 0.2], size=[0.3, 0.3, 0.4])
    table = default_table(robot, stock)
    assert table.centre[2] + 0.5 * table.size[2] == pytest.approx(0.0)  # top = base plane
    assert table.contains([[0, 0, -0.01], [1.25, -0.55, -0.01], [0.95, -0.25, -0.01]]).all()


def test_offscreen_buffer_and_options():
    m, _ = _compile(scene_mjcf(load("ur5e"), BOW, None, table=None, width=1280, height=720))
    assert (m.vis.global_.offwidth, m.vis.global_.offheight) == (1280, 720)
    assert m.ngeom > 0 and "table" not in [m.geom(i).name for i in range(m.ngeom)]
    with pytest.raises(ValueError, match="width"):
        scene_mjcf(load("ur5e"), width=3)
    with pytest.raises(ValueError, match="table"):
        scene_mjcf(load("ur5e"), table="big")
    with pytest.raises(ValueError, match="camera"):
        scene_mjcf(load("ur5e"), camera=([1, 1, 1], [1, 1, 1]))


def test_scene_from_job():
    from ruledrobot.wirecut.job.load import parse_job

    job = parse_job(
        {
            "surface": {"builtin": "hyperbolic_paraboloid", "u": [-0.1, 0.1]},
            "stock": {"centre": [0.5, 0.0, 0.2], "size": [0.2, 0.2, 0.15]},
            "robot": {"model": "ur10e", "base": [0.0, 0.0, 0.1, 0.0, 0.0, 0.0]},
            "tool": {"wire_start": [-0.2, 0.0, 0.25], "wire_end": [0.2, 0.0, 0.25], "mass": 1.5},
            "cut": {"feed_speed": 0.01},
        }
    )
    scene = Scene.from_job(job)
    assert scene.robot.name == "ur10e" and scene.tool.mass == 1.5
    m, _ = _compile(scene.mjcf())
    assert m.body("bow") is not None
