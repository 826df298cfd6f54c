"""The motions of a run, in the child process: approach moveJ, servoJ stream, moveL path.

Each is monitored every controller period (:meth:`Session.poll`, the deviation,
a stop request from the supervisor) and raises :class:`~.run_session.Stop` to
end the motion; the caller then stops the arm safely.
"""

from __future__ import annotations

import gc
import time

import numpy as np

from .run_session import Session, Stop

__all__ = ["approach", "preheat", "run_path", "stream", "wait_until"]

#: s: the end of a wait is spun, not slept (a sleep may wake this much late)
SPIN = 0.0004


def wait_until(deadline: float) -> None:
    """Return at ``time.monotonic()`` >= ``deadline``: sleep, then spin the last
    :data:`SPIN` seconds (as ur_rtde's ``waitPeriod`` does)."""
    while True:
        left = deadline - time.monotonic()
        if left <= 0.0:
            return
        if left > SPIN:
            time.sleep(left - SPIN)


def approach(
    s: Session, q0: np.ndarray, speed: float, acceleration: float, heartbeat: float
) -> None:
    """moveJ (async, monitored) to ``q0`` unless the arm is there already."""
    c, r = s.c, s.r
    qa = np.asarray(r.getActualQ())
    dist = float(np.max(np.abs(qa - q0)))
    if dist < 1e-4:
        return
    s.link.stage("approach", heartbeat + 2.0)
    if not c.moveJ([float(x) for x in q0], speed, acceleration, True):
        raise s.classify("approach moveJ")
    s.link.stage("approach", heartbeat)
    t_move = dist / speed + speed / acceleration
    deadline = time.monotonic() + 2.0 * t_move + 5.0
    s.start_clock()
    started = time.monotonic()
    while True:
        time.sleep(0.005)
        s.kick()
        qa = s.poll()
        s.service()
        done = c.getAsyncOperationProgress() < 0
        if done and float(np.max(np.abs(qa - q0))) < 1e-4:
            return
        resting = max(abs(x) for x in r.getActualQd()) < 1e-6
        if done and resting and time.monotonic() - started > 0.5:
            raise Stop(
                "command_failed",
                f"approach moveJ ended {np.max(np.abs(qa - q0)):.4f} rad from the start",
            )
        if time.monotonic() > deadline:
            raise Stop("command_failed", "approach moveJ did not reach the first sample in time")


def preheat(s: Session, seconds: float, heartbeat: float) -> None:
    """Heat the wire and hold still ``seconds`` (a run that starts inside a heat window:
    the resume of a cut), monitored."""
    s.set_heat(True)
    s.link.stage("preheat", heartbeat)
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        time.sleep(0.005)
        s.kick()
        s.poll()
        s.service()


def stream(
    s: Session,
    q_grid: np.ndarray,
    lookahead: float,
    gain: float,
    heartbeat: float,
    hot: np.ndarray | None = None,
) -> None:
    """servoJ every controller period, monitored, then hold the last sample until settled.
    ``hot`` (K,): the wire's heat at each grid sample (switched where it changes).

    The stream keeps the plan's schedule on the wall clock: sample ``k`` goes out at
    ``k`` periods after the start.  A period that overran (a switch of the heat, the
    machine busy) is made up by skipping the samples whose time has passed — a feed
    held at the plan's speed, not a wire that slows in the foam and widens the kerf;
    a slip longer than ``max_latency`` at once stops the run (``client_slow``: the
    jump would be a burst of speed).  Skipped samples (and where) and the longest slip
    are in :meth:`Session.info`."""
    c = s.c
    dt = 1.0 / s.frequency
    K = q_grid.shape[0]
    rows = q_grid.tolist()
    s.link.stage("streaming", heartbeat)
    s.start_recording()
    s.start_clock()
    # no cyclic garbage collection while streaming: a full collection walks every row
    # of the grid (hundreds of thousands of objects on a long cut), milliseconds in which
    # no command goes out; the loop makes no reference cycles, reference counting frees it
    gc.freeze()
    gc.disable()
    try:
        start = time.monotonic()
        k = 0
        while k < K:
            if hot is not None and bool(hot[k]) != s.hot:
                s.set_heat(bool(hot[k]))
            if not c.servoJ(rows[k], 0.0, 0.0, dt, lookahead, gain):
                raise s.classify(f"servoJ of grid sample {k}")
            s.sent = k
            qa = s.poll()
            s.check_deviation(q_grid, qa, k)
            s.service()
            # the next sample's time on the schedule (absolute: a wait of one period after
            # each send adds this loop's own time every period and drifts behind, and
            # keep_schedule then skipped a sample every ~85 periods on an idle machine)
            wait_until(start + (k + 1) * dt)
            k = s.keep_schedule(k, time.monotonic() - start, K)
    finally:
        gc.enable()
        gc.unfreeze()
    # hold the final target until the filter has converged
    last = rows[-1]
    deadline = time.monotonic() + 10.0 * lookahead + 0.5
    while time.monotonic() < deadline:
        t0 = c.initPeriod()
        if not c.servoJ(last, 0.0, 0.0, dt, lookahead, gain):
            raise s.classify("servoJ (final hold)")
        qa = s.poll()
        s.check_deviation(q_grid, qa, K - 1)
        s.service()
        if float(np.max(np.abs(qa - q_grid[-1]))) < 1e-5:
            break
        c.waitPeriod(t0)


def run_path(
    s: Session, q_grid: np.ndarray, rows: list[list[float]], duration: float, heartbeat: float
) -> None:
    """One blended moveL path (async), monitored until the arm rests at the end."""
    c = s.c
    if not rows:
        return
    s.start_recording()
    s.link.stage("path upload", 15.0)  # moveL(path) re-uploads the control script
    if not c.moveL(rows, True):
        raise s.classify("moveL path")
    s.arm_watchdog()  # the upload restarted the control script
    s.link.stage("path", heartbeat)
    s.start_clock()
    K = q_grid.shape[0]
    s.sent = K - 1
    started = False
    t_start = time.monotonic()
    deadline = t_start + 2.0 * duration + 10.0
    while True:
        t0 = c.initPeriod()
        s.kick()
        qa = s.poll()
        s.check_deviation(q_grid, qa, K - 1, timed=False)
        s.service()
        prog = c.getAsyncOperationProgress()
        started = started or prog >= 0
        now = time.monotonic()
        if prog < 0 and (started or now - t_start > 0.5):
            if float(np.max(np.abs(qa - q_grid[-1]))) < 1e-3:
                break
            if now - t_start > 1.0 and max(abs(x) for x in s.r.getActualQd()) < 1e-4:
                raise Stop("command_failed", "the moveL path ended away from the last sample")
        if now > deadline:
            raise Stop("command_failed", "the moveL path did not finish in time")
        c.waitPeriod(t0)
