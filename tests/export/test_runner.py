"""run_trajectory end to end against the emulator: streaming, path mode, checks, faults.

The ur_rtde session runs in a child process the runner supervises; progress
reaches the caller in chunks (every 50 ms), so a fault injected from the
progress callback lands up to a chunk (25 samples at 500 Hz) plus the pipe's
latency after the sample the callback saw: ``LATE`` bounds that.
"""

from __future__ import annotations

import functools
import time
from pathlib import Path

import numpy as np
import pytest

from ruledrobot.export import ControllerError, RunResult, run_trajectory
from ruledrobot.io.trajectory import read_trajectory, write_trajectory
from ruledrobot.robot import load
from ruledrobot.robot.motion.servo import servo_time_constant
from ruledrobot.robot.motion.trajectory import Trajectory
from ruledrobot.ursim import DEFAULT_Q, Emulator, KinematicBackend
from tests.support.emulators import smooth_trajectory, start_emulator

pytest.importorskip("rtde_control")

MODEL = load("ur5e")
#: samples the session may be ahead of the progress callback (2 chunks + 20 ms, measured <= 30)
LATE = 60


def _lagged_error(
    plan: Trajectory, actual: Trajectory, max_lag: float = 0.2
) -> tuple[float, float]:
    """Smallest max joint error between the recording and the plan over time shifts; (err, lag)."""
    best = (np.inf, 0.0)
    t = actual.t - actual.t[0]
    for lag in np.arange(0.0, max_lag, 0.002):
        qp = np.stack([np.interp(t - lag, plan.t - plan.t[0], plan.q[:, j]) for j in range(6)], 1)
        err = float(np.max(np.abs(qp - actual.q)))
        if err < best[0]:
            best = (err, float(lag))
    return best


def _at_rest(emu: Emulator, wait: float = 0.15) -> bool:
    a = emu.actual_q
    time.sleep(wait)
    return bool(np.allclose(emu.actual_q, a, atol=0.0))


def test_servoj_run_follows_the_plan_and_records(emulator: Emulator, tmp_path: Path) -> None:
    traj = smooth_trajectory(q0=np.array(DEFAULT_Q) + 0.05)
    src = write_trajectory(tmp_path / "cut.csv", traj)
    calls: list[tuple[int, int]] = []
    res = run_trajectory(src, emulator.host, MODEL, progress=lambda d, n: calls.append((d, n)),
                         approach_speed=1.0, approach_acceleration=4.0,
                         mode="servoj")  # fmt: skip
    assert isinstance(res, RunResult)
    assert res.status == "completed" and res.completed, res
    assert res.stop_index == traj.t.size and res.stop is None and res.resume_index is None
    assert res.approach_distance == pytest.approx(0.05)  # moveJ to the start first
    assert res.entry is not None and res.entry.kind == "approach"
    assert calls and calls[-1][0] == calls[-1][1] == traj.n
    # the recording: written next to the input, follows the plan with the servo lag
    assert res.actual_path == tmp_path / "cut.run-001.csv"
    rec = read_trajectory(res.actual_path)
    assert rec.t.size >= traj.t.size
    err, lag = _lagged_error(traj, rec, max_lag=0.25)
    # first-order lookahead filter (tau = the default lookahead, 0.03 s): lag ~ tau (less
    # the period and the stream's own delay; 0.018 s measured under load), error ~ tau^2 qdd
    tau = servo_time_constant()
    assert err < 0.02 and 0.25 * tau < lag < 2.0 * tau + 0.05, (err, lag)
    np.testing.assert_allclose(rec.q[-1], traj.q[-1], atol=1e-4)
    assert res.max_deviation < 0.01
    assert _at_rest(emulator)
    assert emulator.runtime_state == 1  # stopScript at the end


def test_path_mode_run(emulator: Emulator) -> None:
    traj = smooth_trajectory(amplitude=(0.09, -0.07, 0.08, 0.0, 0.0, 0.0))
    res = run_trajectory(traj, emulator.host, MODEL, mode="path", path_tolerance=0.0005)
    assert res.status == "completed", res
    assert res.actual is not None and res.actual_path is None  # in-memory input: no file
    np.testing.assert_allclose(emulator.actual_q, traj.q[-1], atol=2e-4)  # 6-digit waypoints
    # max_lag 0.6 s: the emulator builds the path's moves on its clock thread (0.1-0.3 s
    # here); its clock catches up on the periods that took (controller time kept), so the
    # motion starts that much later in the recording's controller time
    err, _ = _lagged_error(traj, res.actual, max_lag=0.6)
    assert err < 0.02


def test_dry_run_checks_without_motion(emulator: Emulator) -> None:
    traj = smooth_trajectory(q0=np.array(DEFAULT_Q) + 0.1)
    res = run_trajectory(traj, emulator.host, MODEL, dry_run=True)
    assert res.status == "dry_run" and res.completed and not res.moved
    assert res.approach_distance == pytest.approx(0.1)
    names = [c.name for c in res.checks]
    assert names == ["limits", "robot_model", "control_period", "kinematics",
                     "controller_ready", "entry"]  # fmt: skip
    assert res.verdict is not None and res.verdict.ok
    offline = run_trajectory(traj, None, MODEL, dry_run=True)
    assert offline.status == "dry_run" and [c.name for c in offline.checks] == ["limits",
                                                                               "controller"]
    assert not offline.checks[1].gating  # information: the controller was not contacted
    np.testing.assert_allclose(emulator.actual_q, DEFAULT_Q, atol=0)
    assert emulator.stats()["programs_received"] == 0  # no control script was uploaded


def test_limit_violations_are_refused_before_motion(emulator: Emulator) -> None:
    traj = smooth_trajectory()
    q = traj.q.copy()
    q[300:, 2] += 0.05  # a 0.05 rad step at sample 300 on joint 3: 25 rad/s
    bad = Trajectory(traj.t, q, traj.tcp, traj.meta)
    with pytest.raises(ValueError, match=r"sample 300 .*joint q3 speed"):
        run_trajectory(bad, emulator.host, MODEL)
    with pytest.raises(ValueError, match=r"joint q1 acceleration .* at speed_scale 3"):
        run_trajectory(traj, emulator.host, MODEL, speed_scale=3.0)
    q = traj.q.copy()
    q[10, 4] = 7.0
    with pytest.raises(ValueError, match=r"sample 10 .*joint q5 position 7"):
        run_trajectory(Trajectory(traj.t, q, traj.tcp, traj.meta), emulator.host, MODEL)
    np.testing.assert_allclose(emulator.actual_q, DEFAULT_Q, atol=0)
    assert emulator.stats()["programs_received"] == 0


def test_controller_not_ready_is_refused(emulator: Emulator) -> None:
    emulator.protective_stop("before the run")
    res = run_trajectory(smooth_trajectory(), emulator.host, MODEL)
    assert res.status == "refused" and not res.moved, res
    assert res.verdict is not None and [c.name for c in res.verdict.failed] == ["controller_ready"]
    assert "safety mode 3" in res.message
    assert emulator.stats()["programs_received"] == 0
    with pytest.raises(ControllerError, match="not reachable"):
        run_trajectory(smooth_trajectory(), "127.254.254.254", MODEL)  # nothing listens there


def _run_with_fault(emu: Emulator, inject, **kw) -> tuple[RunResult, Trajectory, int]:
    traj = smooth_trajectory()
    fired: list[int] = []

    def progress(done: int, total: int) -> None:
        if not fired and done >= total // 3:
            fired.append(done)
            inject(emu)

    kw.setdefault("lookahead", 0.05)
    # the servoj stream's stops (the place they are reported at, the watchdog); a forwarded
    # run's are tested in test_forward.py
    kw.setdefault("mode", "servoj")
    res = run_trajectory(traj, emu.host, MODEL, progress=progress, **kw)
    assert fired, "the fault was never injected"
    return res, traj, fired[0]


def _check_safe_stop(res: RunResult, traj: Trajectory, fired: int, emu: Emulator,
                     tol: float = 0.01, late: int = LATE) -> None:  # fmt: skip
    assert not res.completed and res.moved
    # the reported sample: reached before the fault (about one servo lag behind), or
    # ``late`` samples after it when the fault is only seen later
    assert 0 < res.stop_index <= fired + late
    assert res.stop_time == pytest.approx(traj.t[res.stop_index])
    assert res.resume_index == res.stop_index
    assert res.stop is not None and res.stop.sample == res.stop_index
    assert res.stop.phase == "move" and not res.stop.in_stock  # the synthetic trajectory
    q_stop = emu.actual_q
    assert _at_rest(emu)  # no further motion
    assert np.max(np.abs(q_stop - traj.q[res.stop_index])) < tol
    assert res.actual is not None and res.actual.t.size > 100


def test_protective_stop_during_run_then_resume(emulator: Emulator) -> None:
    res, traj, fired = _run_with_fault(emulator, lambda e: e.protective_stop("injected"))
    assert res.status == "protective_stop", res
    _check_safe_stop(res, traj, fired, emulator)
    # the job resumes from the reported sample once the stop is cleared
    refused = run_trajectory(traj, emulator.host, MODEL, start_index=res.stop_index)
    assert refused.status == "refused" and "safety mode 3" in refused.message
    emulator.clear_faults()
    res2 = run_trajectory(traj, emulator.host, MODEL, start_index=res.stop_index, lookahead=0.05,
                          mode="servoj")
    assert res2.status == "completed", res2
    assert res2.entry is not None and res2.entry.kind == "continue"
    assert abs(res2.start_index - res.stop_index) <= 5  # the sample the arm rests at
    assert res2.approach_distance < 1e-3
    np.testing.assert_allclose(emulator.actual_q, traj.q[-1], atol=1e-4)


def test_emergency_stop_during_run(emulator: Emulator) -> None:
    res, traj, fired = _run_with_fault(emulator, lambda e: e.emergency_stop())
    assert res.status == "emergency_stop", res
    _check_safe_stop(res, traj, fired, emulator)
    assert emulator.robot_mode == 3  # power off after the e-stop


def test_dropped_connection_during_run(emulator: Emulator) -> None:
    """The emulator closes every connection mid-run (and refuses new ones for 1 s).  ur_rtde
    1.6.5 sometimes crashes (SIGSEGV/SIGABRT) on this: the runner survives it, because the
    session runs in a child process (status ``client_died`` then), and reports either way."""
    t_fault: list[float] = []

    def inject(e: Emulator) -> None:
        t_fault.append(time.monotonic())
        e.drop_connections(refuse_for=1.0)

    res, traj, fired = _run_with_fault(emulator, inject)
    elapsed = time.monotonic() - t_fault[0]
    # ur_rtde may also hang on the dropped socket: the runner kills it after 1 s
    assert res.status in ("connection_lost", "client_died", "client_hung"), res
    assert elapsed < 4.5  # the runner's bound for any stop (docs/rtde.md)
    # the client cannot stop the arm: the RTDE watchdog (2 Hz) stops the program,
    # after the servo target of the last sample sent: the stop sample is the last
    # confirmed one, the arm rests a little further along the plan
    assert emulator.wait_for(lambda: emulator.runtime_state != 2, timeout=2.0)
    _check_safe_stop(res, traj, fired, emulator, tol=0.06)
    assert any("RTDE watchdog" in e[2] for e in emulator.events)


def test_slow_controller_during_run(emulator: Emulator) -> None:
    res, traj, fired = _run_with_fault(emulator, lambda e: e.set_slow(0.3), max_latency=0.1)
    assert res.status == "controller_slow", res
    emulator.set_slow(0.0)
    # the stream stalls: the runner notices after max_latency, streaming on until then
    _check_safe_stop(res, traj, fired, emulator, tol=0.06, late=100 + LATE)


def test_deviation_stop(request: pytest.FixtureRequest) -> None:
    # joint 3 of this arm is limited to 0.03 rad/s: it cannot follow the plan (0.24 rad/s)
    slow_arm = functools.partial(KinematicBackend, max_velocity=[3.0, 3.0, 0.03, 3.0, 3.0, 3.0])
    emu = start_emulator(request.node.nodeid, model="ur5e", backend=slow_arm, unlock_delay=0.0)
    try:
        traj = smooth_trajectory()
        res = run_trajectory(traj, emu.host, MODEL, deviation_limit=0.02)
        assert res.status == "deviation", res
        assert res.max_deviation > 0.02
        assert 0 < res.stop_index < traj.t.size // 2
        assert _at_rest(emu)
        assert np.max(np.abs(emu.actual_q - traj.q[res.stop_index])) < 0.03
    finally:
        emu.close()


def test_ctrl_c_stops_safely(emulator: Emulator) -> None:
    def progress(done: int, total: int) -> None:
        if done >= total // 4:
            raise KeyboardInterrupt

    traj = smooth_trajectory(duration=1.0, amplitude=(0.06, -0.05, 0.06, 0.05, 0.06, -0.06))
    res = run_trajectory(traj, emulator.host, MODEL, progress=progress, lookahead=0.05)
    assert res.status == "interrupted", res
    assert 0 < res.stop_index < traj.t.size // 2
    assert _at_rest(emulator)
    assert emulator.runtime_state == 1  # servoStop, then stopScript
