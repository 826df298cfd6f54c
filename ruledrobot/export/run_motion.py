"""The motions of a run, in the child process: approach moveJ, servoJ stream, path program.

Each is monitored every controller period (:meth:`Session.poll`, the deviation,
a stop request from the supervisor) and raises :class:`~.run_session.Stop` to
end the motion; the caller then stops the arm safely.
"""

from __future__ import annotations

import gc
import math
import time

import numpy as np

from .run_session import Session, Stop

__all__ = ["approach", "preheat", "run_program", "stream", "wait_until"]

#: s: the end of a wait is spun, not slept (a sleep may wake this much late)
SPIN = 0.0004


def wait_until(deadline: float) -> None:
    """Return at ``time.monotonic()`` >= ``deadline``.

    Sleep, then spin the last :data:`SPIN` seconds (as ur_rtde's ``waitPeriod`` does)."""
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


def preheat(s: Session, seconds: float, heartbeat: float, level: float | None = None) -> None:
    """Heat the wire and hold still ``seconds``, monitored.

    The heat: an analog output to the set-point ``level`` when given.  For a run that starts
    inside a heat window (the resume of a cut)."""
    s.set_heat(True, level)
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
    levels: np.ndarray | None = None,
) -> None:
    """Stream ``q_grid`` by servoJ every controller period, monitored, then settle.

    After the last sample the arm holds it until settled.  ``hot`` (K,): the wire's heat at
    each grid sample (switched where it changes); ``levels`` (K,): an analog output's
    set-points as written (:func:`~.heat.written_levels` of a scheduled power; set where
    they change), instead.

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
    lv = None if levels is None else np.asarray(levels, dtype=float).tolist()
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
            if lv is not None:
                if lv[k] != s.level:
                    s.set_heat(lv[k] > 0.0, lv[k])
            elif hot is not None and bool(hot[k]) != s.hot:
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
    if (hot is not None or lv is not None) and s.hot:  # a heat window that ends with the
        s.set_heat(False)  # plan ends here, on the schedule, not after the final hold (0.7 s+)
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


def _hold(s: Session, q_grid: np.ndarray, seconds: float, upto: int, heartbeat: float) -> None:
    """A path program's ``sleep``: the arm holds still ``seconds``, monitored each period."""
    s.link.stage("hold", heartbeat)
    s.sent = max(s.sent, upto)
    dt = 1.0 / s.frequency
    deadline = time.monotonic() + max(0.0, seconds)
    while True:
        s.kick()
        qa = s.poll()
        s.check_deviation(q_grid, qa, upto, timed=False)
        s.service()
        now = time.monotonic()
        if now >= deadline:
            return
        wait_until(min(deadline, now + dt))


def _play_path(s: Session, q_grid: np.ndarray, block: list[tuple], heartbeat: float) -> float:
    """One ur_rtde path (``movePath``, async) of the moves of ``block``, monitored until the
    arm rests at its last target; the heat switches between its moves are made when the
    controller reports the move after the switch begun.  Returns the upload's seconds."""
    import rtde_control

    c = s.c
    entry = rtde_control.PathEntry
    path = rtde_control.Path()
    switches: list[tuple] = []  # (index of the move the switch precedes, on, set-point)
    moves = 0
    for op in block:
        if op[0] == "heat":
            switches.append((moves, bool(op[1]), op[2]))
            continue
        _, joint, target, v, a, r, _grid, _q = op
        kind, where = ((entry.MoveJ, entry.PositionJoints) if joint
                       else (entry.MoveL, entry.PositionTcpPose))  # fmt: skip
        path.addEntry(entry(kind, where, [*target, v, a, r]))
        moves += 1
    last = next(op for op in reversed(block) if op[0] == "move")
    end, q_end = int(last[6]), np.asarray(last[7], dtype=float)
    duration = max(0.0, (end - s.sent) / s.frequency)
    s.sent = end
    # the arm at rest before the upload: the recording's controller time runs from here (the
    # upload blocks; an emulator that builds the path late catches up on controller time,
    # so the first package after it may already be in motion)
    s.record(*s.snapshot())
    s.link.stage("path upload", 15.0)  # movePath re-uploads the control script
    t_up = time.monotonic()
    if not c.movePath(path, True):
        raise s.classify("movePath")
    upload = time.monotonic() - t_up
    s.arm_watchdog()  # the upload restarted the control script
    # the data's age is measured from here: a controller busy with the new script (the
    # emulator builds the path's moves on its clock thread) sends its data late once
    s.start_clock()
    s.link.stage("path", heartbeat)
    started = False
    t_start = time.monotonic()
    deadline = t_start + 2.0 * duration + 10.0
    while True:
        t0 = c.initPeriod()
        s.kick()
        qa = s.poll()
        s.check_deviation(q_grid, qa, end, timed=False)
        s.service()
        prog = c.getAsyncOperationProgress()
        started = started or prog >= 0
        while switches and (prog >= switches[0][0] or (prog < 0 and started)):
            s.set_heat(*switches.pop(0)[1:])
        now = time.monotonic()
        if prog < 0 and (started or now - t_start > 0.5):
            if float(np.max(np.abs(qa - q_end))) < 1e-3:
                break
            if now - t_start > 1.0 and max(abs(x) for x in s.r.getActualQd()) < 1e-4:
                raise Stop("command_failed", "the path ended away from its last target")
        if now > deadline:
            raise Stop("command_failed", "the path did not finish in time")
        c.waitPeriod(t0)
    return upload


def run_program(s: Session, q_grid: np.ndarray, ops: list[tuple], heartbeat: float) -> None:
    """Run a path program (:meth:`~.run_program.PathRun.child_ops`), monitored.

    The moves between two sleeps as one ur_rtde path, a sleep as a hold, a heat switch
    through RTDE IO.  The hold before a path is shortened by the shortest time a path of this
    run took to upload (ur_rtde re-uploads the control script for each path): the arm rests
    about as long as the plan says, and never less (a longer path takes longer to upload: the
    emulator builds its moves before it starts, 0.02 s for 19 moves, 0.8 s for 300)."""
    if not ops:
        return
    s.start_recording()
    upload = math.inf  # the shortest upload so far [s]
    i, n = 0, len(ops)
    while i < n:
        op = ops[i]
        if op[0] == "heat":
            s.set_heat(bool(op[1]), op[2])
            i += 1
        elif op[0] == "sleep":
            j = i + 1
            while j < n and ops[j][0] == "heat":
                j += 1
            early = upload if j < n and ops[j][0] == "move" and math.isfinite(upload) else 0.0
            _hold(s, q_grid, float(op[1]) - early, int(op[2]), heartbeat)
            i += 1
        else:
            j = i
            while j < n and ops[j][0] != "sleep":
                j += 1
            last = max(k for k in range(i, j) if ops[k][0] == "move")
            upload = min(upload, _play_path(s, q_grid, list(ops[i : last + 1]), heartbeat))
            i = last + 1
