"""Play a joint trajectory on a UR controller through ur_rtde, with monitoring and safe stops.

:func:`run_trajectory` does, in order:

1. **Checks before motion** — the trajectory against the model's joint
   position, speed and acceleration limits (ValueError naming the sample and
   joint); the controller reachable, robot mode RUNNING and safety NORMAL
   (:class:`ControllerError` otherwise).  ``dry_run=True`` stops here (and
   reports the approach move it would make).
2. **Approach** — a ``moveJ`` at reduced speed (``approach_speed``) to the
   first sample, unless the arm is already there.
3. **Motion** — ``mode="servoj"``: one ``servoJ`` per controller period
   (``initPeriod``/``waitPeriod``) with ``lookahead``/``gain``;
   ``mode="path"``: the TCP path decimated to ``path_tolerance`` and sent as
   one blended ``moveL`` path (async, monitored).
4. **Monitoring**, every period: protective and emergency stops, the
   connection, the control script, the age of the controller's data, and the
   deviation of the actual joints from the plan (distance to the nearest
   planned sample at or before the commanded one, so the servo lag does not
   count).  Any of them — or Ctrl-C — ends the motion with a safe stop:
   ``servoStop``/``stopJ``, then ``stopScript``; the RTDE watchdog set at the
   start stops the arm by itself if this process goes silent.
5. **Recording** — the actual joints and TCP at every controller timestamp,
   written next to the input as ``<name>.actual.csv``.

The result (:class:`RunResult`) tells why it stopped and ``stop_index``: the
sample the arm reached, from which ``start_index`` resumes the job.
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..io.trajectory import read_trajectory, write_trajectory
from ..robot import RobotModel, load, model_for
from ..robot.trajectory import Trajectory, TrajectoryMeta
from .decimate import decimate_tcp_path
from .limits import check_trajectory

__all__ = ["ControllerError", "RunResult", "actual_path_for", "run_trajectory"]

ROBOT_MODE_RUNNING = 7
SAFETY_MODE_NORMAL = 1
RUNTIME_PLAYING = 2

ProgressFn = Callable[[int, int], Any]


class ControllerError(RuntimeError):
    """The controller cannot run the trajectory (unreachable, not running, faulted)."""


@dataclass
class RunResult:
    """What :func:`run_trajectory` did.

    ``status``: ``"completed"``, ``"dry_run"``, ``"deviation"``,
    ``"protective_stop"``, ``"emergency_stop"``, ``"connection_lost"``,
    ``"controller_slow"``, ``"program_stopped"``, ``"command_failed"`` or
    ``"interrupted"``.  ``stop_index``: index of the input sample the arm
    reached when it stopped (pass it as ``start_index`` to resume); the
    number of samples when completed.  ``max_deviation``: largest joint
    deviation from the plan seen [rad].  ``actual``: the recorded trajectory
    (controller timestamps from 0), ``actual_path``: where it was written.
    """

    status: str
    message: str
    n_samples: int
    start_index: int = 0
    stop_index: int = 0
    stop_time: float = 0.0
    samples_sent: int = 0
    max_deviation: float = 0.0
    approach_distance: float = 0.0
    actual: Trajectory | None = None
    actual_path: Path | None = None
    checks: list[str] = field(default_factory=list)

    @property
    def completed(self) -> bool:
        return self.status in ("completed", "dry_run")

    def __str__(self) -> str:
        return (f"{self.status}: {self.message} (samples {self.start_index}..{self.stop_index} of "
                f"{self.n_samples}, max deviation {self.max_deviation:.4f} rad)")  # fmt: skip


def actual_path_for(path: str | os.PathLike[str]) -> Path:
    """``cut.csv`` -> ``cut.actual.csv`` beside it."""
    p = Path(path)
    return p.with_name(f"{p.stem}.actual.csv")


class _Recorder:
    """Collects (controller time, actual q, actual TCP) once per new controller timestamp."""

    def __init__(self) -> None:
        self.t: list[float] = []
        self.q: list[list[float]] = []
        self.tcp: list[list[float]] = []
        self.last_ts = -math.inf
        self.ts0: float | None = None

    def add(self, ts: float, q: list[float], tcp: list[float]) -> bool:
        if ts <= self.last_ts:
            return False
        if self.ts0 is None:
            self.ts0 = ts
        self.last_ts = ts
        self.t.append(ts - self.ts0)
        self.q.append(q)
        self.tcp.append(tcp)
        return True

    def trajectory(self, meta: TrajectoryMeta) -> Trajectory | None:
        if len(self.t) < 2:
            return None
        return Trajectory(np.array(self.t), np.array(self.q), np.array(self.tcp), meta)


class _Stop(Exception):
    def __init__(self, status: str, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


def _resample(t: np.ndarray, q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Samples at a uniform period ``dt`` from ``t[0]`` (linear interpolation), end included."""
    T = float(t[-1] - t[0])
    n = math.floor(T / dt + 1e-9)
    tg = t[0] + dt * np.arange(n + 1)
    if tg[-1] < t[-1] - 1e-12:
        tg = np.append(tg, t[0] + dt * (n + 1))
    qg = np.empty((tg.size, q.shape[1]))
    for j in range(q.shape[1]):
        qg[:, j] = np.interp(tg, t, q[:, j])
    return tg, qg


class _Session:
    """One run: the two ur_rtde interfaces, the plan, monitoring and recording."""

    def __init__(
        self,
        host: str,
        model: RobotModel,
        frequency: float,
        *,
        deviation_limit: float,
        max_latency: float,
        window: int,
        watchdog: float = 0.0,
    ) -> None:
        self.host = host
        self.watchdog = watchdog
        self.model = model
        self.frequency = frequency
        self.deviation_limit = deviation_limit
        self.max_latency = max_latency
        self.window = window
        self.r: Any = None
        self.c: Any = None
        self.rec = _Recorder()
        self.max_dev = 0.0
        self.k_match = 0
        self._lag_min = math.inf
        self._wall0 = 0.0
        self._ts0 = 0.0

    # ---------------------------------------------------------------- connection

    def connect_receive(self) -> None:
        import rtde_receive

        try:
            self.r = rtde_receive.RTDEReceiveInterface(self.host, self.frequency)
        except RuntimeError as exc:
            raise ControllerError(f"controller at {self.host} not reachable: {exc}") from None

    def check_ready(self) -> None:
        r = self.r
        mode, safety = r.getRobotMode(), r.getSafetyMode()
        if mode != ROBOT_MODE_RUNNING:
            raise ControllerError(
                f"controller at {self.host}: robot mode {mode}, expected 7 (RUNNING): power on and "
                "release the brakes first"
            )
        if safety != SAFETY_MODE_NORMAL or r.isProtectiveStopped() or r.isEmergencyStopped():
            raise ControllerError(
                f"controller at {self.host}: safety mode {safety}, expected 1 (NORMAL): clear the "
                "protective or emergency stop first"
            )

    def connect_control(self) -> None:
        import rtde_control

        try:
            self.c = rtde_control.RTDEControlInterface(self.host, self.frequency)
        except RuntimeError as exc:
            raise ControllerError(f"controller at {self.host}: control interface: {exc}") from None

    def arm_watchdog(self) -> None:
        """Have the control script stop the program when this process falls silent."""
        if self.watchdog > 0:
            self.c.setWatchdog(float(self.watchdog))

    def kick(self) -> None:
        if self.watchdog > 0:
            self.c.kickWatchdog()

    def disconnect(self) -> None:
        """Close the control interface, then the receive interface.

        ur_rtde's ``disconnect()`` sleeps 0.5 s and its destructor calls it
        again: an interface nobody else holds is simply destroyed (one
        disconnect), one still referenced elsewhere is disconnected explicitly.
        """
        for name in ("c", "r"):
            iface = getattr(self, name)
            setattr(self, name, None)
            if iface is None:
                continue
            if sys.getrefcount(iface) > 2:  # this local and getrefcount's argument
                try:
                    iface.disconnect()
                except Exception:
                    pass
            del iface

    # ---------------------------------------------------------------- monitoring

    def start_clock(self) -> None:
        self._wall0 = time.monotonic()
        self._ts0 = self.r.getTimestamp()
        self._lag_min = math.inf

    def poll(self) -> np.ndarray:
        """Read the state, record it, raise :class:`_Stop` on a fault; returns actual q."""
        r, c = self.r, self.c
        if not r.isConnected() or (c is not None and not c.isConnected()):
            raise _Stop("connection_lost", "the RTDE connection to the controller was lost")
        if r.isEmergencyStopped():
            raise _Stop("emergency_stop", "the robot is emergency stopped")
        if r.isProtectiveStopped():
            raise _Stop("protective_stop", "the robot is protective stopped")
        ts = r.getTimestamp()
        qa = r.getActualQ()
        self.rec.add(ts, qa, r.getActualTCPPose())
        lag = (time.monotonic() - self._wall0) - (ts - self._ts0)
        self._lag_min = min(self._lag_min, lag)
        if lag - self._lag_min > self.max_latency:
            raise _Stop(
                "controller_slow",
                f"controller data {1e3 * (lag - self._lag_min):.0f} ms late "
                f"(limit {1e3 * self.max_latency:.0f} ms)",
            )
        if r.getRuntimeState() != RUNTIME_PLAYING:
            raise _Stop("program_stopped", "the control script stopped running on the controller")
        return np.asarray(qa)

    def track(self, plan: np.ndarray, qa: np.ndarray, upto: int) -> float:
        """Deviation of ``qa`` from the plan samples [k_match, upto]; advances ``k_match``."""
        lo = self.k_match
        hi = min(upto, lo + self.window) + 1
        d = np.max(np.abs(plan[lo:hi] - qa), axis=1)
        j = int(np.argmin(d))
        self.k_match = lo + j
        dev = float(d[j])
        self.max_dev = max(self.max_dev, dev)
        return dev

    def check_deviation(self, plan: np.ndarray, qa: np.ndarray, upto: int) -> None:
        dev = self.track(plan, qa, upto)
        if dev > self.deviation_limit:
            raise _Stop(
                "deviation",
                f"joint deviation {dev:.4f} rad from the plan exceeds the limit "
                f"{self.deviation_limit:.4f} rad",
            )

    def connection_lost(self, exc: Exception) -> bool:
        """Is this ur_rtde exception a lost connection? (socket errors, or an interface down)"""
        text = str(exc).lower()
        if any(w in text for w in ("end of file", "broken pipe", "connection", "connect",
                                    "timeout", "timed out", "reset by peer")):  # fmt: skip
            return True
        deadline = time.monotonic() + 0.05
        while time.monotonic() < deadline:
            try:
                if not self.r.isConnected() or (self.c is not None and not self.c.isConnected()):
                    return True
            except Exception:
                return True
            time.sleep(0.005)
        return False

    def diagnose(self, what: str) -> _Stop:
        """Why did a command return False?  (The receive stream may be a period behind.)"""
        deadline = time.monotonic() + 0.1
        while True:
            try:
                self.poll()
            except _Stop as stop:
                return _Stop(stop.status, stop.message)
            except Exception as exc:
                return _Stop("connection_lost", f"{what}: {exc}")
            if time.monotonic() > deadline:
                break
            time.sleep(0.004)
        if not self.r.isConnected() or not self.c.isConnected():
            return _Stop("connection_lost", f"{what}: the connection to the controller was lost")
        return _Stop("command_failed", f"{what} was refused by the controller")

    # ---------------------------------------------------------------- stopping

    def safe_stop(self, mode: str, deceleration: float) -> None:
        """servoStop / stopJ, then stopScript; every step best effort."""
        c = self.c
        if c is None:
            return
        try:
            if c.isConnected() and c.isProgramRunning():
                if mode == "servoj":
                    c.servoStop(deceleration)
                else:
                    c.stopJ(deceleration, False)
        except Exception:
            pass
        try:
            if c.isConnected() and c.isProgramRunning():
                c.stopScript()
        except Exception:
            pass

    def settle(self, timeout: float = 1.5) -> None:
        """Record until the arm rests (speed < 1e-3 rad/s for 50 ms) or ``timeout``."""
        r = self.r
        deadline = time.monotonic() + timeout
        quiet = 0.0
        while time.monotonic() < deadline:
            try:
                if not r.isConnected():
                    return
                self.rec.add(r.getTimestamp(), r.getActualQ(), r.getActualTCPPose())
                qd = max(abs(x) for x in r.getActualQd())
            except Exception:
                return
            quiet = quiet + 0.002 if qd < 1e-3 else 0.0
            if quiet >= 0.05:
                return
            time.sleep(0.002)


def _path_waypoints(
    tcp: np.ndarray,
    t: np.ndarray,
    keep: np.ndarray,
    *,
    blend: float,
    acceleration: float,
) -> list[list[float]]:
    """moveL path rows ``[x, y, z, rx, ry, rz, v, a, r]`` for the kept samples."""
    rows = []
    p = tcp[:, :3]
    seg_len = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    lengths = np.diff(seg_len[keep])
    for n, k in enumerate(keep[1:], start=1):
        i = keep[n - 1]
        L = lengths[n - 1]
        dur = max(t[k] - t[i], 1e-6)
        v = float(np.clip(L / dur, 1e-4, 3.0))
        if n < len(keep) - 1:
            r = min(blend, 0.45 * L, 0.45 * lengths[n])
        else:
            r = 0.0
        rows.append([*map(float, tcp[k]), v, float(acceleration), float(max(r, 0.0))])
    return rows


def run_trajectory(
    traj: Trajectory | str | os.PathLike[str],
    host: str = "127.0.0.1",
    model: RobotModel | str | None = None,
    *,
    mode: str = "servoj",
    lookahead: float = 0.1,
    gain: float = 300.0,
    speed_scale: float = 1.0,
    deviation_limit: float = 0.05,
    dry_run: bool = False,
    progress: ProgressFn | None = None,
    start_index: int = 0,
    approach_speed: float = 0.25,
    approach_acceleration: float = 0.5,
    stop_deceleration: float = 4.0,
    max_latency: float = 0.1,
    path_tolerance: float = 0.0005,
    path_blend: float = 0.002,
    path_acceleration: float = 1.0,
    actual_path: str | os.PathLike[str] | None = None,
    watchdog: float = 2.0,
) -> RunResult:
    """Run a joint trajectory on the UR controller at ``host`` (ur_rtde), monitored.

    Parameters
    ----------
    traj : the trajectory, or a trajectory CSV path (the recording goes beside it).
    host : controller address (a robot, URSim, or :class:`~.emulator.Emulator`).
    model : the robot model (limits, control period) or its name; default, and it
        must agree with, the trajectory's metadata (:func:`ruledrobot.robot.model_for`).
    mode : ``"servoj"`` (stream one servoJ per controller period) or ``"path"``
        (one blended moveL path through the TCP samples decimated to
        ``path_tolerance`` m, blend radius ``path_blend`` m).
    lookahead, gain : servoJ parameters (ur_rtde accepts 0.03-0.2 s, 100-2000).
    speed_scale : play the trajectory this much faster (< 1 slower); the limits
        are checked at the scaled speed.
    deviation_limit : largest joint deviation from the plan [rad] before a safe stop.
    dry_run : check everything (limits, controller state, approach) without motion.
        With ``host=None`` the controller is not contacted.
    progress : ``progress(done, total)`` about 10 times per second.
    start_index : first sample to run (resume after a stop: ``RunResult.stop_index``).
    approach_speed, approach_acceleration : the moveJ to the first sample
        [rad/s, rad/s^2] (leading axis).
    stop_deceleration : joint deceleration of the safe stop [rad/s^2].
    max_latency : how much later than normal the controller's data may arrive [s].
    actual_path : where to write the recording (default ``<name>.actual.csv``
        beside an input file; none for an in-memory trajectory).
    watchdog : RTDE watchdog frequency [Hz] on the command register (the
        controller stops the program if this process falls silent for
        ``1/watchdog`` s); 0 disables it.

    Returns
    -------
    :class:`RunResult`.  Raises ValueError (limits, parameters) and
    :class:`ControllerError` (controller not reachable or not ready) before
    any motion.
    """
    source: Path | None = None
    if not isinstance(traj, Trajectory):
        source = Path(traj)
        traj = read_trajectory(source)
    planned = model_for(traj.meta)
    robot = planned if model is None else (load(model) if isinstance(model, str) else model)
    if robot.name != planned.name:
        raise ValueError(f"trajectory planned for a {planned.name}, not for the {robot.name} "
                         "given")  # fmt: skip
    if mode not in ("servoj", "path"):
        raise ValueError(f"mode: expected 'servoj' or 'path', got {mode!r}")
    if not 0.03 <= lookahead <= 0.2:
        raise ValueError(f"lookahead: {lookahead} s outside [0.03, 0.2] (ur_rtde's range)")
    if not 100 <= gain <= 2000:
        raise ValueError(f"gain: {gain} outside [100, 2000] (ur_rtde's range)")
    if not deviation_limit > 0:
        raise ValueError(f"deviation_limit: must be positive, got {deviation_limit}")
    n = int(traj.t.size)
    if not 0 <= start_index < n - 1:
        raise ValueError(f"start_index: {start_index} outside [0, {n - 2}] for {n} samples")
    check_trajectory(traj, robot, speed_scale=speed_scale)
    checks = [f"limits of {robot.name}: positions, speeds, accelerations at speed_scale "
              f"{speed_scale:g} — ok"]  # fmt: skip

    t_in = np.asarray(traj.t[start_index:], dtype=float)
    q_in = np.asarray(traj.q[start_index:], dtype=float)
    ts_in = (t_in - t_in[0]) / speed_scale
    dt = float(robot.control_period)
    frequency = 1.0 / dt
    t_grid, q_grid = _resample(ts_in, q_in, dt)
    grid_to_input = np.clip(np.searchsorted(ts_in, t_grid + 1e-9, side="right") - 1, 0, None)
    window = max(10, math.ceil((3.0 * lookahead + 0.1) / dt))
    if actual_path is None and source is not None:
        actual_path = actual_path_for(source)

    result = RunResult("dry_run", "", n, start_index, start_index, float(traj.t[start_index]))
    result.checks = checks

    if dry_run and host is None:
        result.message = "trajectory checked; controller not contacted"
        return result

    sess = _Session(host, robot, frequency, deviation_limit=deviation_limit,
                    max_latency=max_latency, window=window, watchdog=watchdog)  # fmt: skip
    sess.connect_receive()
    try:
        sess.check_ready()
        qa = np.asarray(sess.r.getActualQ())
        result.approach_distance = float(np.max(np.abs(qa - q_in[0])))
        checks.append(f"controller at {host}: robot RUNNING, safety NORMAL — ok")
        if dry_run:
            result.message = (
                f"trajectory and controller checked; approach move of "
                f"{result.approach_distance:.4f} rad (leading joint) not executed"
            )
            return result
        sess.connect_control()
        # the controller's TCP and payload are the trajectory's: the recording's TCP
        # column is then the same frame as the plan's
        from ..geometry.se3 import ur_vector_from_pose

        sess.c.setTcp([float(x) for x in ur_vector_from_pose(traj.meta.tcp_offset)])
        sess.c.setPayload(traj.meta.payload.mass, [float(x) for x in traj.meta.payload.cog])
        sess.arm_watchdog()
        stop = _execute(
            sess, mode, q_in, ts_in, t_grid, q_grid, traj, start_index, result,
            lookahead=lookahead, gain=gain, speed_scale=speed_scale,
            approach_speed=approach_speed, approach_acceleration=approach_acceleration,
            path_tolerance=path_tolerance, path_blend=path_blend,
            path_acceleration=path_acceleration, progress=progress,
        )  # fmt: skip
        if stop is None:
            result.status = "completed"
            result.message = "trajectory completed"
            # end of the program: leave the robot idle
            try:
                if sess.c.isProgramRunning():
                    if mode == "servoj":
                        sess.c.servoStop(stop_deceleration)
                    sess.c.stopScript()
            except Exception:
                pass
            sess.settle()
            result.stop_index = n
            result.stop_time = float(traj.t[-1])
        else:
            sess.safe_stop(mode, stop_deceleration)
            sess.settle()
            result.status, result.message = stop.status, stop.message
            # the sample the arm actually reached
            try:
                qa = np.asarray(sess.r.getActualQ())
                lo = max(0, sess.k_match - window)
                hi = max(lo, min(result.samples_sent, q_grid.shape[0] - 1))
                d = np.max(np.abs(q_grid[lo : hi + 1] - qa), axis=1)
                kg = lo + int(np.argmin(d))
            except Exception:
                kg = sess.k_match
            k_in = start_index + int(grid_to_input[min(kg, grid_to_input.size - 1)])
            result.stop_index = k_in
            result.stop_time = float(traj.t[k_in])
        result.max_deviation = sess.max_dev
    finally:
        sess.disconnect()
    rec_meta = traj.meta.replace(
        phases=(), in_stock=(), source=f"recorded by ruledrobot run on {host}: mode {mode}, "
        f"status {result.status}, input samples {start_index}..{result.stop_index} of {n}",
    )  # fmt: skip
    rec = sess.rec.trajectory(rec_meta)
    result.actual = rec
    if rec is not None and actual_path is not None:
        result.actual_path = write_trajectory(actual_path, rec)
    return result


def _execute(
    sess: _Session,
    mode: str,
    q_in: np.ndarray,
    ts_in: np.ndarray,
    t_grid: np.ndarray,
    q_grid: np.ndarray,
    traj: Trajectory,
    start_index: int,
    result: RunResult,
    *,
    lookahead: float,
    gain: float,
    speed_scale: float,
    approach_speed: float,
    approach_acceleration: float,
    path_tolerance: float,
    path_blend: float,
    path_acceleration: float,
    progress: ProgressFn | None,
) -> _Stop | None:
    """Approach and motion; returns the reason for stopping, or None when completed."""
    try:
        _approach(sess, q_in[0], approach_speed, approach_acceleration)
        sess.start_clock()
        if mode == "servoj":
            _stream(sess, q_grid, lookahead, gain, result, progress)
        else:
            _run_path(sess, q_grid, traj, start_index, speed_scale, result, progress,
                      path_tolerance=path_tolerance, path_blend=path_blend,
                      path_acceleration=path_acceleration)  # fmt: skip
    except _Stop as stop:
        # drop the traceback: its frames hold the ur_rtde interfaces alive
        return _Stop(stop.status, stop.message)
    except KeyboardInterrupt:
        return _Stop("interrupted", "interrupted by the user (Ctrl-C)")
    except RuntimeError as exc:
        if sess.connection_lost(exc):
            return _Stop("connection_lost", f"the connection to the controller was lost: {exc}")
        return _Stop("command_failed", f"ur_rtde: {exc}")
    return None


def _approach(sess: _Session, q0: np.ndarray, speed: float, acceleration: float) -> None:
    """moveJ (async, monitored) to the first sample when the arm is not there."""
    c, r = sess.c, sess.r
    qa = np.asarray(r.getActualQ())
    dist = float(np.max(np.abs(qa - q0)))
    if dist < 1e-4:
        return
    if not c.moveJ([float(x) for x in q0], speed, acceleration, True):
        raise sess.diagnose("approach moveJ")
    # trapezoid time of the leading axis, plus margin
    t_move = dist / speed + speed / acceleration
    deadline = time.monotonic() + 2.0 * t_move + 5.0
    sess.start_clock()
    started = time.monotonic()
    while True:
        time.sleep(0.005)
        sess.kick()
        qa = sess.poll()
        done = c.getAsyncOperationProgress() < 0
        if done and float(np.max(np.abs(qa - q0))) < 1e-4:
            return
        resting = max(abs(x) for x in r.getActualQd()) < 1e-6
        if done and resting and time.monotonic() - started > 0.5:
            raise _Stop(
                "command_failed",
                f"approach moveJ ended {np.max(np.abs(qa - q0)):.4f} rad from the start",
            )
        if time.monotonic() > deadline:
            raise _Stop("command_failed", "approach moveJ did not reach the first sample in time")


def _stream(
    sess: _Session,
    q_grid: np.ndarray,
    lookahead: float,
    gain: float,
    result: RunResult,
    progress: ProgressFn | None,
) -> None:
    """servoJ every controller period, monitored, then hold the last sample until settled."""
    c = sess.c
    dt = 1.0 / sess.frequency
    K = q_grid.shape[0]
    every = max(1, int(0.1 / dt))
    sess.rec = _Recorder()  # the recording starts with the trajectory
    rows = q_grid.tolist()
    for k in range(K):
        t0 = c.initPeriod()
        if not c.servoJ(rows[k], 0.0, 0.0, dt, lookahead, gain):
            raise sess.diagnose(f"servoJ of sample {k}")
        result.samples_sent = k
        qa = sess.poll()
        sess.check_deviation(q_grid, qa, k)
        if progress is not None and k % every == 0:
            progress(k, K)
        c.waitPeriod(t0)
    # hold the final target until the filter has converged
    last = rows[-1]
    deadline = time.monotonic() + 10.0 * lookahead + 0.5
    while time.monotonic() < deadline:
        t0 = c.initPeriod()
        if not c.servoJ(last, 0.0, 0.0, dt, lookahead, gain):
            raise sess.diagnose("servoJ (final hold)")
        qa = sess.poll()
        sess.check_deviation(q_grid, qa, K - 1)
        if float(np.max(np.abs(qa - q_grid[-1]))) < 1e-5:
            break
        c.waitPeriod(t0)
    if progress is not None:
        progress(K, K)


def _run_path(
    sess: _Session,
    q_grid: np.ndarray,
    traj: Trajectory,
    start_index: int,
    speed_scale: float,
    result: RunResult,
    progress: ProgressFn | None,
    *,
    path_tolerance: float,
    path_blend: float,
    path_acceleration: float,
) -> None:
    """One blended moveL path (async), monitored until the arm rests at the end."""
    c = sess.c
    tcp = np.asarray(traj.tcp[start_index:], dtype=float)
    t = (np.asarray(traj.t[start_index:], dtype=float) - traj.t[start_index]) / speed_scale
    keep = decimate_tcp_path(tcp, path_tolerance, 10 * path_tolerance)
    rows = _path_waypoints(tcp, t, keep, blend=path_blend, acceleration=path_acceleration)
    if not rows:
        return
    sess.rec = _Recorder()  # the recording starts with the trajectory
    if not c.moveL(rows, True):
        raise sess.diagnose("moveL path")
    sess.arm_watchdog()  # the path upload restarted the control script
    sess.start_clock()
    K = q_grid.shape[0]
    total = len(rows)
    started = False
    t_start = time.monotonic()
    deadline = t_start + 2.0 * float(t[-1]) + 10.0
    last_report = 0.0
    while True:
        t0 = c.initPeriod()
        sess.kick()
        qa = sess.poll()
        sess.check_deviation(q_grid, qa, K - 1)
        prog = c.getAsyncOperationProgress()
        if prog >= 0:
            started = True
            result.samples_sent = int(keep[min(prog + 1, len(keep) - 1)])
        now = time.monotonic()
        if progress is not None and now - last_report > 0.1:
            last_report = now
            progress(max(prog, 0), total)
        if prog < 0 and (started or now - t_start > 0.5):
            if float(np.max(np.abs(qa - q_grid[-1]))) < 1e-3:
                break
            if now - t_start > 1.0 and max(abs(x) for x in sess.r.getActualQd()) < 1e-4:
                raise _Stop("command_failed", "the moveL path ended away from the last sample")
        if now > deadline:
            raise _Stop("command_failed", "the moveL path did not finish in time")
        c.waitPeriod(t0)
    result.samples_sent = K - 1
    if progress is not None:
        progress(total, total)
