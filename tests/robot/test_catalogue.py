"""The UR catalogue, RobotModel construction, validation and copies."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import ruledrobot.robot as rr_robot
from ruledrobot.robot import MODEL_NAMES, RobotModel, load

E_SERIES = ("ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur30")
CB3 = ("ur3", "ur5", "ur10")


def test_catalogue_names() -> None:
    assert set(MODEL_NAMES) == set(E_SERIES) | set(CB3)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_every_model_is_consistent(name: str) -> None:
    m = load(name)
    assert m.name == name
    assert m.n_joints == 6
    assert m.has_analytic_ik
    np.testing.assert_allclose(m.alpha, [np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0])
    assert m.a[0] == m.a[3] == m.a[4] == m.a[5] == 0.0
    assert m.d[1] == m.d[2] == 0.0
    assert np.all(m.a[1:3] < 0) and np.all(m.d[[0, 3, 4, 5]] > 0)
    assert np.all(m.theta_offset == 0.0)
    assert m.control_period == (0.002 if name in E_SERIES else 0.008)
    for j in (0, 1, 3, 4):
        assert m.upper[j] == 2 * np.pi and m.lower[j] == -2 * np.pi
    assert m.upper[2] == np.pi and m.lower[2] == -np.pi  # the elbow
    assert m.upper[5] == (np.inf if name in ("ur3", "ur3e") else 2 * np.pi)
    np.testing.assert_array_equal(m.lower, -m.upper)
    assert np.all(m.max_velocity >= np.pi * 2 / 3 - 1e-12)  # slowest UR joint: 120 deg/s
    assert np.all(m.max_velocity <= 2 * np.pi + 1e-12)
    assert np.all(m.max_acceleration == rr_robot.DEFAULT_ACCELERATION)
    assert np.all(m.max_torque > 0) and np.all(m.link_mass > 0)
    assert m.link_com.shape == (6, 3)
    assert m.payload is not None and m.reach is not None
    assert np.array_equal(m.base, np.eye(4)) and np.array_equal(m.tool, np.eye(4))


def test_ur5e_numbers_match_the_published_table() -> None:
    m = load("ur5e")
    np.testing.assert_array_equal(m.d, [0.1625, 0, 0, 0.1333, 0.0997, 0.0996])
    np.testing.assert_array_equal(m.a, [0, -0.425, -0.3922, 0, 0, 0])
    np.testing.assert_allclose(m.link_mass.sum(), 17.7, atol=0.01)
    np.testing.assert_allclose(m.link_com[1], [0.2125, 0, 0.11336])
    np.testing.assert_allclose(m.max_torque, [150, 150, 150, 28, 28, 28])
    np.testing.assert_allclose(m.max_velocity, np.pi)
    assert m.payload == 5.0


# UniversalRobots/Universal_Robots_ROS2_Description config/<model>/joint_limits.yaml,
# snapshot of 2024-10-14 (tag 2.4.5, commit 2221ec0f): max_effort [N m] and
# max_velocity [deg/s] of joints 1..6.  The e-Series torques are those of its
# PR #195 (2024-09-20); older copies of the files differ (UR3e 56/56/28/12/12/12,
# UR10e wrists 56, UR20/UR30 730/730/430/100/100/100).
ROS2_JOINT_LIMITS: dict[str, tuple[tuple[float, ...], tuple[float, ...]]] = {
    "ur3": ((56, 56, 28, 12, 12, 12), (180, 180, 180, 360, 360, 360)),
    "ur5": ((150, 150, 150, 28, 28, 28), (180, 180, 180, 180, 180, 180)),
    "ur10": ((330, 330, 150, 56, 56, 56), (120, 120, 180, 180, 180, 180)),
    "ur3e": ((54, 54, 28, 9, 9, 9), (180, 180, 180, 360, 360, 360)),
    "ur5e": ((150, 150, 150, 28, 28, 28), (180, 180, 180, 180, 180, 180)),
    "ur10e": ((330, 330, 150, 54, 54, 54), (120, 120, 180, 180, 180, 180)),
    "ur16e": ((330, 330, 150, 54, 54, 54), (120, 120, 180, 180, 180, 180)),
    "ur20": ((738, 738, 433, 107, 107, 107), (120, 120, 150, 210, 210, 210)),
    "ur30": ((738, 738, 433, 107, 107, 107), (120, 120, 150, 210, 210, 210)),
}


def test_limit_table_covers_the_catalogue() -> None:
    assert set(ROS2_JOINT_LIMITS) == set(MODEL_NAMES)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_torques_and_speeds_match_the_ros2_description(name: str) -> None:
    torque, speed_deg = ROS2_JOINT_LIMITS[name]
    m = load(name)
    np.testing.assert_array_equal(m.max_torque, torque)
    np.testing.assert_allclose(m.max_velocity, np.radians(speed_deg), rtol=1e-15)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_elbow_is_limited_to_half_a_turn(name: str) -> None:
    """Joint 3 is +-pi on every model (ROS joint_limits.yaml, Menagerie, universal_robot#265)."""
    m = load(name)
    assert m.lower[2] == -np.pi and m.upper[2] == np.pi
    q = np.zeros(6)
    # within the one slack of the position limits (robot.ik.path.LIMIT_TOL = 1e-9 rad)
    for q3, inside in ((np.pi, True), (-np.pi, True), (np.pi + 1e-9, True),
                       (np.pi + 3e-9, False), (-4.0, False)):
        q[2] = q3
        assert bool(m.within_limits(q)) is inside, q3
    # the analytic IK's elbow angle lies in [-pi, pi], so its solutions stay inside
    rng = np.random.default_rng(3)
    qs = rng.uniform(-np.pi, np.pi, (50, 6))
    sols = m.ik(m.fk(qs))
    ok = ~np.isnan(sols[..., 0])
    assert ok.any(axis=-1).all()
    assert np.all(np.abs(sols[..., 2][ok]) <= np.pi)
    assert np.all(m.within_limits(sols[ok]))


def test_ur3_wrist3_is_unlimited() -> None:
    for name in ("ur3", "ur3e"):
        m = load(name)
        assert m.upper[5] == np.inf and m.lower[5] == -np.inf
    np.testing.assert_allclose(load("ur3e").max_velocity[3:], 2 * np.pi)


def test_load_is_case_insensitive() -> None:
    assert load(" UR5e ").name == "ur5e"


def test_unknown_model_lists_valid_names() -> None:
    with pytest.raises(ValueError, match="ur7x") as err:
        load("ur7x")
    for name in MODEL_NAMES:
        assert name in str(err.value)
    with pytest.raises(ValueError, match="unknown"):
        load(5)  # type: ignore[arg-type]


def test_model_is_frozen_and_read_only() -> None:
    m = load("ur5e")
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.name = "x"  # type: ignore[misc]
    with pytest.raises(ValueError):
        m.d[0] = 1.0
    assert "ur5e" in repr(m)


def test_with_tool_base_limits_return_copies() -> None:
    m = load("ur5e")
    tool = np.eye(4)
    tool[2, 3] = 0.2
    mt = m.with_tool(tool, mass=1.5, com=[0, 0, 0.1])
    assert np.array_equal(m.tool, np.eye(4)) and mt.tool[2, 3] == 0.2
    assert mt.tool_mass == 1.5 and mt.tool_com[2] == 0.1
    # a UR pose vector is accepted (the controller's TCP setting)
    mv = m.with_tool([0, 0, 0.2, 0, 0, np.pi / 2])
    np.testing.assert_allclose(mv.tool[:3, 3], [0, 0, 0.2])
    np.testing.assert_allclose(mv.tool[:3, 0], [0, 1, 0], atol=1e-15)
    mb = m.with_base([1, 2, 3, 0, 0, 0])
    np.testing.assert_allclose(mb.base[:3, 3], [1, 2, 3])
    ml = m.with_limits(lower=-np.pi, upper=np.pi, acceleration=[3, 3, 3, 5, 5, 5])
    assert np.all(ml.upper == np.pi) and ml.max_acceleration[5] == 5
    np.testing.assert_array_equal(m.upper, [2 * np.pi, 2 * np.pi, np.pi] + [2 * np.pi] * 3)
    assert "tool set" in repr(mt) and "base set" in repr(mb)


def test_from_dh_custom_arm() -> None:
    m = RobotModel.from_dh([0.3, 0, 0], [0.5, 0.4, 0.1], [np.pi / 2, 0, 0], name="planar3")
    assert m.n_joints == 3 and m.name == "planar3"
    assert not m.has_analytic_ik
    assert m.max_velocity.shape == (3,)
    T = m.fk([0.0, 0.0, 0.0])
    np.testing.assert_allclose(T[:3, 3], [1.0, 0, 0.3], atol=1e-15)
    with pytest.raises(ValueError, match="needs 6 joints"):
        m.ik(T)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"a": [0, 1]}, r"a: expected a scalar or shape \(3,\)"),
        ({"lower": [0, 0, 0], "upper": [1, -1, 1]}, r"lower\[1\]"),
        ({"max_velocity": [1, 0, 1]}, r"max_velocity\[1\]"),
        ({"link_mass": [1, -1, 1]}, r"link_mass\[1\]"),
        ({"link_com": np.zeros((2, 3))}, "link_com"),
        ({"control_period": 0.0}, "control_period"),
        ({"tool": np.ones((4, 4))}, "tool"),
        ({"base": [1, 2, 3]}, "base"),
        ({"d": [0.1, np.nan, 0.0]}, r"d\[1\]"),
        ({"theta_offset": [0, 0]}, "theta_offset"),
        ({"name": ""}, "name"),
    ],
)
def test_from_dh_rejects_bad_data(kwargs: dict, match: str) -> None:
    args = {"d": [0.3, 0, 0], "a": [0.5, 0.4, 0.1], "alpha": [np.pi / 2, 0, 0]}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        RobotModel.from_dh(args.pop("d"), args.pop("a"), args.pop("alpha"), **args)


def test_non_ur_structure_names_the_entry() -> None:
    m = load("ur5e")
    alpha = m.alpha.copy()
    alpha[3] = 0.3
    bad = RobotModel.from_dh(m.d, m.a, alpha)
    with pytest.raises(ValueError, match=r"alpha\[3\]"):
        bad.ik(np.eye(4))
    a = m.a.copy()
    a[4] = 0.01
    with pytest.raises(ValueError, match=r"a\[4\]"):
        _ = RobotModel.from_dh(m.d, a, m.alpha).ur_geometry
