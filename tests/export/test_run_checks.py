"""The runner's controller checks: robot model and period from the dashboard, the
kinematics (KinematicsInfo) compared, a silent dashboard bounded in time, refusal
of a trajectory planned for another robot, confirmation."""

from __future__ import annotations

import socket
import threading
import time

import numpy as np
import pytest

from ruledrobot.export import RunPlan, run_trajectory
from ruledrobot.export.run_checks import ControllerInfo, controller_checks, query_dashboard
from ruledrobot.robot import load
from ruledrobot.robot.motion.trajectory import TrajectoryMeta
from ruledrobot.ursim import DEFAULT_Q, Emulator
from tests.support.emulators import smooth_trajectory

pytest.importorskip("rtde_control")


@pytest.mark.parametrize(
    ("model", "version", "robot", "period"),
    [("UR5", (5, 11, 1), "ur5e", 0.002), ("UR5", (3, 15, 7), "ur5", 0.008),
     ("UR10", (5, 9, 0), "ur10e", 0.002), ("UR16", (5, 11, 1), "ur16e", 0.002),
     ("UR20", (5, 15, 0), "ur20", 0.002), ("UR3", (3, 12, 0), "ur3", 0.008)],
)  # fmt: skip
def test_controller_info_names_the_catalogue_model(model, version, robot, period) -> None:
    info = ControllerInfo("h", model, "URSoftware x", version)
    assert info.robot == robot and info.control_period == period


def test_model_and_period_mismatch_fail() -> None:
    e5 = ControllerInfo("127.0.0.9", "UR5", "URSoftware 5.11.1.108318 (x)", (5, 11, 1))
    ok = {c.name: c for c in controller_checks(TrajectoryMeta.for_model(load("ur5e")), e5)}
    assert ok["robot_model"].ok and ok["control_period"].ok
    ur10e = {c.name: c for c in controller_checks(TrajectoryMeta.for_model(load("ur10e")), e5)}
    assert not ur10e["robot_model"].ok and ur10e["control_period"].ok
    assert "planned for a ur10e" in ur10e["robot_model"].detail
    assert "is a ur5e" in ur10e["robot_model"].detail
    cb3 = {c.name: c for c in controller_checks(TrajectoryMeta.for_model(load("ur5")), e5)}
    assert not cb3["robot_model"].ok and not cb3["control_period"].ok
    assert "500 Hz" in cb3["control_period"].detail and "125 Hz" in cb3["control_period"].detail
    # a controller that does not say what it is: fails closed
    mute = ControllerInfo("h", "could not understand: 'get robot model'", "", None)
    checks = {c.name: c for c in controller_checks(TrajectoryMeta.for_model(load("ur5e")), mute)}
    assert not checks["robot_model"].ok and not checks["control_period"].ok


def test_a_silent_dashboard_is_bounded_in_time(host: str) -> None:
    srv = socket.create_server((host, 29999))
    held: list[socket.socket] = []
    stop = threading.Event()

    def accept() -> None:
        srv.settimeout(0.1)
        while not stop.is_set():
            try:
                held.append(srv.accept()[0])  # accepted, never answered
            except OSError:
                pass

    th = threading.Thread(target=accept, daemon=True)
    th.start()
    try:
        t0 = time.monotonic()
        with pytest.raises(ConnectionError, match="no answer"):
            query_dashboard(host, timeout=0.5)
        assert time.monotonic() - t0 < 1.0
    finally:
        stop.set()
        th.join(2.0)
        srv.close()
        for s in held:
            s.close()


def test_a_ur10e_trajectory_is_refused_by_a_ur5e_controller(emulator: Emulator) -> None:
    traj = smooth_trajectory(model="ur10e")
    res = run_trajectory(traj, emulator.host)
    assert res.status == "refused" and not res.moved, res
    assert [c.name for c in res.verdict.failed] == ["robot_model", "kinematics"]  # UR10e DH too
    assert "planned for a ur10e" in res.message and "is a ur5e" in res.message
    assert emulator.stats()["programs_received"] == 0  # no control script, no motion


def test_confirmation_shows_the_approach_and_can_decline(emulator: Emulator) -> None:
    traj = smooth_trajectory(q0=np.array(DEFAULT_Q) + 0.1)
    plans: list[RunPlan] = []

    def decline(plan: RunPlan) -> bool:
        plans.append(plan)
        return False

    res = run_trajectory(traj, emulator.host, confirm=decline)
    assert res.status == "cancelled" and not res.moved and not res.completed
    (plan,) = plans
    assert plan.verdict.ok and plan.entry is not None and plan.entry.kind == "approach"
    text = "\n".join(plan.describe())
    assert "moveJ to sample 0" in text and "0.1000 rad" in text and "about 0.9 s" in text
    assert emulator.stats()["programs_received"] == 0
    np.testing.assert_allclose(emulator.actual_q, DEFAULT_Q, atol=0)
