"""MJCF of the robot arms: compiles, kinematics equal the robot layer's FK, inertials,
limits, actuators, and the committed models are what the generator writes."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np
import pytest

from ruledrobot.robot import MODEL_NAMES, RobotModel, load
from ruledrobot.sim import mjcf
from ruledrobot.sim.mjcf import ServoGains, physics_timestep, robot_mjcf

BASE = [0.12, -0.3, 0.45, 0.3, -0.2, 1.1]  # UR pose vector of the base in the world
TOOL = [0.01, -0.02, 0.17, 0.4, 0.1, -0.3]  # TCP in the flange frame


def _compile(xml: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    m = mujoco.MjModel.from_xml_string(xml)
    return m, mujoco.MjData(m)


def _site_pose(m, d, name: str) -> np.ndarray:
    i = m.site(name).id
    T = np.eye(4)
    T[:3, :3] = d.site_xmat[i].reshape(3, 3)
    T[:3, 3] = d.site_xpos[i]
    return T


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_kinematics_equal_fk(name, rng):
    robot = load(name).with_base(BASE).with_tool(TOOL)
    flange_model = robot.with_tool(np.eye(4))
    m, d = _compile(robot_mjcf(robot))
    q = rng.uniform(-2 * np.pi, 2 * np.pi, size=(40, 6))
    tcp = np.empty((40, 4, 4))
    flange = np.empty((40, 4, 4))
    for k in range(40):
        d.qpos[:] = q[k]
        mujoco.mj_kinematics(m, d)
        tcp[k] = _site_pose(m, d, "tcp")
        flange[k] = _site_pose(m, d, "flange")
    np.testing.assert_allclose(tcp, robot.fk(q), rtol=0, atol=1e-9)
    np.testing.assert_allclose(flange, flange_model.fk(q), rtol=0, atol=1e-9)


def test_custom_arm_with_offsets_and_no_masses(rng):
    robot = RobotModel.from_dh(
        d=[0.2, 0.05, -0.03, 0.1],
        a=[0.1, 0.4, 0.3, 0.0],
        alpha=[np.pi / 2, 0.3, -np.pi / 2, 0.0],
        theta_offset=[0.1, -0.2, 0.3, 0.0],
        base=BASE,
        tool=TOOL,
    )
    m, d = _compile(robot_mjcf(robot))
    assert m.njnt == 4 and m.nu == 12
    for qk in rng.uniform(-np.pi, np.pi, size=(20, 4)):
        d.qpos[:] = qk
        mujoco.mj_kinematics(m, d)
        np.testing.assert_allclose(_site_pose(m, d, "tcp"), robot.fk(qk), atol=1e-9)
    # massless links take their mass from the geoms (inertiafromgeom="auto")
    assert np.all(m.body_mass[m.body("link1").id :] > 0)


@pytest.mark.parametrize("name", ["ur5e", "ur10", "ur3e", "ur20"])
def test_inertials_and_gravity_torque(name, rng):
    """Link masses as catalogued, COMs where the DH table puts them, and the holding
    torque MuJoCo computes equals sum_i (z_j x (c_i - p_j)) . m_i g over the links."""
    robot = load(name).with_base(BASE)
    m, d = _compile(robot_mjcf(robot))
    links = [m.body(f"link{i + 1}").id for i in range(6)]
    np.testing.assert_allclose(m.body_mass[links], robot.link_mass, rtol=1e-12)
    q = rng.uniform(-np.pi, np.pi, size=6)
    d.qpos[:] = q
    mujoco.mj_forward(m, d)
    g = np.array([0.0, 0.0, -9.81])
    coms = []
    for i in range(6):
        sub = RobotModel.from_dh(
            robot.d[: i + 1], robot.a[: i + 1], robot.alpha[: i + 1], base=robot.base
        )
        T = sub.fk(q[: i + 1])
        coms.append(T[:3, :3] @ robot.link_com[i] + T[:3, 3])
    coms = np.array(coms)
    np.testing.assert_allclose(d.xipos[links], coms, atol=1e-12)
    expected = np.empty(6)
    for j in range(6):
        z, p = d.xaxis[j], d.xanchor[j]
        expected[j] = -sum(np.cross(z, coms[i] - p) @ (robot.link_mass[i] * g) for i in range(j, 6))
    np.testing.assert_allclose(d.qfrc_bias, expected, atol=1e-9)
    # the actuators hold the arm: gravity compensation goes through them
    np.testing.assert_allclose(d.qfrc_gravcomp, expected, atol=1e-9)
    assert np.all(m.jnt_actgravcomp == 1)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_limits_actuators_and_options(name):
    robot = load(name)
    m, _ = _compile(robot_mjcf(robot))
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert m.opt.timestep == pytest.approx(0.002)  # CB3: 8 ms period in 4 substeps
    unlimited = ~np.isfinite(robot.upper)
    np.testing.assert_array_equal(m.jnt_limited.astype(bool), ~unlimited)
    np.testing.assert_allclose(m.jnt_range[~unlimited, 1], robot.upper[~unlimited])
    np.testing.assert_allclose(m.jnt_range[~unlimited, 0], robot.lower[~unlimited])
    if name in ("ur3", "ur3e"):
        assert not m.jnt_limited[5]  # wrist 3 turns without limit
    np.testing.assert_allclose(m.jnt_actfrcrange[:, 1], robot.max_torque)
    np.testing.assert_allclose(m.jnt_actfrcrange[:, 0], -robot.max_torque)
    assert m.jnt_actfrclimited.all()
    np.testing.assert_allclose(m.dof_armature, mjcf.default_armature(robot))
    np.testing.assert_allclose(m.dof_damping, mjcf.default_damping(robot))
    gains = ServoGains.default(robot)
    assert m.nu == 18
    np.testing.assert_allclose(m.actuator_gainprm[:6, 0], gains.kp)
    np.testing.assert_allclose(m.actuator_biasprm[:6, 1], -gains.kp)
    np.testing.assert_allclose(m.actuator_gainprm[6:12, 0], gains.kv)
    np.testing.assert_allclose(m.actuator_gainprm[12:, 0], 1.0)
    assert [m.actuator(i).name for i in (0, 6, 12)] == ["pos1", "vel1", "ff1"]
    assert m.key("home") is not None


def test_servo_holds_and_tracks_home(ur5e):
    """At the home keyframe with its controls the arm stays put (gravity compensated)."""
    m, d = _compile(robot_mjcf(ur5e))
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    q0 = d.qpos.copy()
    for _ in range(500):
        mujoco.mj_step(m, d)
    assert np.abs(d.qpos - q0).max() < 1e-6


def test_payload_body():
    robot = load("ur5e").with_tool(TOOL, mass=2.5, com=[0.0, 0.01, 0.08])
    m, d = _compile(robot_mjcf(robot))
    b = m.body("payload").id
    assert m.body_mass[b] == pytest.approx(2.5)
    mujoco.mj_kinematics(m, d)
    flange = robot.with_tool(np.eye(4)).fk(np.zeros(6))
    np.testing.assert_allclose(
        d.xipos[b], flange[:3, :3] @ [0.0, 0.01, 0.08] + flange[:3, 3], atol=1e-12
    )


def test_physics_timestep():
    assert physics_timestep(0.002) == 0.002
    assert physics_timestep(0.008) == pytest.approx(0.002)
    assert physics_timestep(0.001) == 0.001
    assert physics_timestep(0.005) == pytest.approx(0.005 / 3)  # 3 substeps of 1.67 ms
    with pytest.raises(ValueError, match="control_period"):
        physics_timestep(0.0)


def test_bad_input():
    with pytest.raises(ValueError, match="model"):
        robot_mjcf("ur5e")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"servo gains kp\[1\]"):
        ServoGains([1.0, -2.0], [1.0, 1.0])
    with pytest.raises(ValueError, match="armature"):
        robot_mjcf(load("ur5e"), armature=[0.1, 0.1])
    with pytest.raises(ValueError, match=r"damping\[2\]"):
        robot_mjcf(load("ur5e"), damping=[1, 1, -1, 1, 1, 1])


def _equivalent(a: ET.Element, b: ET.Element, where: str = "") -> None:
    """Same tree, same attributes; numbers equal to 1e-12 relative (libm may differ in
    the last digit between machines), text equal otherwise."""
    here = f"{where}/{a.tag}[{a.get('name', '')}]"
    assert a.tag == b.tag, here
    assert sorted(a.attrib) == sorted(b.attrib), here
    for key, va in a.attrib.items():
        vb = b.attrib[key]
        try:
            xa = np.array(va.split(), dtype=float)
            xb = np.array(vb.split(), dtype=float)
        except ValueError:
            assert va == vb, f"{here} {key}"
            continue
        assert xa.shape == xb.shape, f"{here} {key}"
        np.testing.assert_allclose(xa, xb, rtol=1e-12, atol=1e-14, err_msg=f"{here} {key}")
    assert len(a) == len(b), here
    for ca, cb in zip(a, b, strict=True):
        _equivalent(ca, cb, here)


MODELS_DIR = Path(__file__).resolve().parents[2] / "models"


def test_committed_models_are_current(tmp_path):
    """models/*.xml are what write_models() writes now (regenerate with
    ``python scripts/write_models.py``)."""
    from ruledrobot.sim import models

    written = models.write_models(tmp_path)
    assert {p.name for p in written} == {"ur5e.xml", "ur10e.xml", models.EXAMPLE_SCENE_FILE}
    for p in written:
        committed = MODELS_DIR / p.name
        assert committed.exists(), f"{committed} is missing; run write_models()"
        text_new, text_old = p.read_text(), committed.read_text()
        if text_new != text_old:
            _equivalent(ET.fromstring(text_old), ET.fromstring(text_new), p.name)
        mujoco.MjModel.from_xml_path(str(committed))


def test_a_calibrated_arm_has_its_kinematics_and_its_nominal_shape():
    """Bodies follow the calibrated chain (TCP site = calibrated FK to 1e-9); the links keep
    their nominal shape: geoms within a few millimetres of the nominal arm's."""
    from ruledrobot.robot import random_calibration

    nominal = load("ur5e").with_tool([0.0, 0.0, 0.2, 0.0, 0.0, 0.0])
    cal = nominal.with_calibration(random_calibration("ur5e", seed=3))
    q = np.random.default_rng(0).uniform(-2, 2, (20, 6))
    positions = []
    for model in (cal, nominal):
        m = mujoco.MjModel.from_xml_string(mjcf.robot_mjcf(model))
        d = mujoco.MjData(m)
        tcp, geoms = [], []
        for qk in q:
            d.qpos[:] = qk
            mujoco.mj_forward(m, d)
            tcp.append(d.site("tcp").xpos.copy())
            geoms.append(d.geom_xpos.copy())
        positions.append((np.array(tcp), np.array(geoms)))
    np.testing.assert_allclose(positions[0][0], cal.fk(q)[:, :3, 3], atol=1e-9)
    assert np.abs(positions[0][0] - nominal.fk(q)[:, :3, 3]).max() > 1e-4  # not the nominal
    assert np.linalg.norm(positions[0][1] - positions[1][1], axis=-1).max() < 0.02
