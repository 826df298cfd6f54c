"""Play a joint trajectory on a UR controller through ur_rtde: checks, confirmation,
monitoring, safe stops, resume, recording.

:func:`run_trajectory` does, in order:

1. **Checks before motion** (a :class:`~ruledrobot.robot.verdict.Verdict`):
   the trajectory against the model's joint limits (ValueError naming the
   sample and joint when it fails: bad input); the controller's robot model and
   control period against the trajectory's (dashboard, :mod:`.run_checks`);
   the controller kinematics (information: not read yet); robot mode RUNNING
   and safety NORMAL; where the run enters the trajectory (:mod:`.run_plan`:
   continue, replay the kerf, or approach); in mode ``"path"`` the path program of the
   samples from the entry, its motion generated and measured against the plan
   (:mod:`.run_program`).  A failing check refuses the run (status ``"refused"``);
   ``dry_run=True`` stops here.
2. **Confirmation** — ``confirm(plan)`` (a :class:`RunPlan`: the checks and the
   approach move) must return True; none given means confirmed.
3. **Motion**, in a child process (:mod:`.run_child`) that alone loads ur_rtde,
   supervised (:mod:`.run_supervisor`): a hang is killed, a crash survived;
   the recording streams out in chunks as it is made.
4. **Result** (:class:`RunResult`): status, where it stopped (sample, time,
   phase, wire in the stock), the resume sample, the recording
   ``<stem>.run-NNN.csv`` (never overwritten).
5. **The run's verdict** from what the robot did (:mod:`.run_verdict`): the recording
   measured by the one model of the wire against the block — feed in the block, the
   actual wire from the planned one, samples skipped with the wire in the foam, the
   longest slip — in ``RunResult.run_verdict`` / ``measures`` and in the recording's
   sidecar (``"run"``).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np

from ..io.atomic import atomic_write_json
from ..io.trajectory import read_trajectory, sidecar_path, write_trajectory
from ..robot import RobotModel, load, model_for
from ..robot.motion.trajectory import Trajectory
from ..robot.verdict import Check, Verdict
from . import settings  # the defaults a run shares with the exported program
from .forward import ForwardSettings
from .heat import (
    heat_from_outputs,
    heat_levels,
    heat_power_from_outputs,
    send_heat_off,
    servo_levels,
    written_levels,
)
from .limits import check_trajectory
from .run_checks import controller_checks, kinematics_check, query_dashboard, readiness_check
from .run_plan import Entry, inside_mask, plan_entry, recording_path_for, resample, stop_place
from .run_program import PathRun, plan_path_run
from .run_result import ControllerError, RunMode, RunPlan, RunResult
from .run_supervisor import Child, ChildGone
from .run_verdict import (
    DEVIATION_LIMIT,
    MAX_LATENCY,
    RunMeasures,
    align_recording,
    measure_run,
)
from .urscript import check_servo_options, plan_wire_tolerance

__all__ = ["ControllerError", "RunMode", "RunPlan", "RunResult", "run_trajectory"]

ProgressFn = Callable[[int, int], Any]


def _validate(
    traj: Trajectory,
    robot: RobotModel,
    planned: RobotModel,
    mode: str,
    lookahead: float,
    gain: float,
    deviation_limit: float,
    start_index: int,
) -> str:
    if robot.name != planned.name:
        raise ValueError(f"trajectory planned for a {planned.name}, not for the {robot.name} given")
    mode = mode.value if isinstance(mode, Enum) else str(mode)
    mode = "servoj" if mode == "stream" else mode  # the streaming mode's other name
    if mode not in ("forward", "servoj", "path"):
        raise ValueError(f"mode: expected 'forward', 'servoj' or 'path', got {mode!r}")
    check_servo_options(lookahead, gain)
    if not deviation_limit > 0:
        raise ValueError(f"deviation_limit: must be positive, got {deviation_limit}")
    n = traj.n
    if not 0 <= start_index < n - 1:
        raise ValueError(f"start sample {start_index} outside [0, {n - 2}] for {n} samples")
    return mode


def run_trajectory(
    traj: Trajectory | str | os.PathLike[str],
    host: str | None = "127.0.0.1",
    model: RobotModel | str | None = None,
    *,
    mode: str | RunMode = "forward",
    lookahead: float = settings.SERVO_LOOKAHEAD,
    gain: float = settings.SERVO_GAIN,
    speed_scale: float = 1.0,
    deviation_limit: float = DEVIATION_LIMIT,
    dry_run: bool = False,
    progress: ProgressFn | None = None,
    start_index: int = 0,
    confirm: Callable[[RunPlan], bool] | None = None,
    force_kinematics: bool = False,
    approach_speed: float = settings.APPROACH_SPEED,
    approach_acceleration: float = settings.APPROACH_ACCELERATION,
    resume_tolerance: float = 0.005,
    resume_window: float = 1.0,
    stop_deceleration: float = 4.0,
    max_latency: float = MAX_LATENCY,
    path_tolerance: float | None = None,
    path_blend: float = settings.PATH_BLEND,
    path_acceleration: float = settings.PATH_ACCELERATION,
    actual_path: str | os.PathLike[str] | None = None,
    watchdog: float = 2.0,
    heartbeat: float = 1.0,
    stop_budget: float = 1.0,
    connect_timeout: float = 15.0,
    wire_tolerance: float | None = None,
    buffer: float = settings.FORWARD_BUFFER,
    stop_time: float = settings.FORWARD_STOP_TIME,
) -> RunResult:
    """Run a joint trajectory on the UR controller at ``host`` (ur_rtde), checked and monitored.

    Parameters
    ----------
    traj : the trajectory, or a trajectory CSV path (the recording goes beside it).
    host : controller address (a robot, URSim, or :class:`~ruledrobot.ursim.process.Emulator`);
        None only with ``dry_run`` (the controller is not contacted).
    model : the robot model or its name; default, and it must agree with, the
        trajectory's metadata (:func:`ruledrobot.robot.model_for`).
    mode : ``"forward"`` (the default: the samples forwarded ahead of time to a program
        that plays them on the controller's clock, :mod:`.forward`), ``"servoj"`` (one
        servoJ per controller period, streamed on this computer's clock) or
        ``"path"`` (the path program an export writes for the samples the run plays,
        :mod:`.run_program`: ``movel`` /
        ``movej`` at the plan's speeds with ``path_blend`` m blends and ``path_acceleration``
        m/s^2, sleeps, heat switches; the TCP path decimated to ``path_tolerance`` m, by
        default a quarter of ``wire_tolerance``; its motion generated and measured against
        the plan before motion: check ``path_program``); a :class:`RunMode` or its value.
    lookahead, gain : servoJ parameters (ur_rtde accepts 0.03-0.2 s, 100-2000).
    speed_scale : play the trajectory this much faster (< 1 slower); the limits
        are checked at the scaled speed.
    deviation_limit : largest joint deviation from the plan [rad] before a safe stop.
    dry_run : check everything (limits, controller, entry) without motion.
    progress : ``progress(sample, n_samples)`` about 20 times per second, ``sample``
        the input sample the arm is at; it may raise KeyboardInterrupt (a safe stop).
    start_index : the sample to start or resume from (``--resume N``); where the
        run actually enters is decided by :func:`~.run_plan.plan_entry` with
        ``resume_tolerance`` [rad] and ``resume_window`` [s].
    confirm : ``confirm(plan) -> bool`` before motion (False: ``"cancelled"``).
    force_kinematics : run although the controller's kinematics (KinematicsInfo) differ
        from the trajectory's or cannot be read (the check becomes information).
    approach_speed, approach_acceleration : the entry moveJ [rad/s, rad/s^2].
    stop_deceleration : joint deceleration of the safe stop [rad/s^2].
    max_latency : how much later than normal the controller's data may arrive [s].
    actual_path : where to write the recording; default ``<stem>.run-NNN.csv``
        (the first free number) beside an input file, none for an in-memory one.
    watchdog : RTDE watchdog frequency [Hz] of the control script: the controller
        stops the program by itself ``1/watchdog`` s after the last command; 0 off.
    heartbeat : the longest the ur_rtde process may stay silent while moving [s].
    stop_budget : the longest the safe stop (servoStop/stopJ, stopScript) may take [s].
    connect_timeout : the longest a connection step may take [s].
    buffer : forward mode: the longest stall of this computer the motion rides through
        unchanged [s]; a longer one ends in a controlled stop along the path, heat off.
    stop_time : forward mode: the controlled stop's duration [s].
    wire_tolerance : the largest distance of the actual wire from the planned wire in the
        block [m], in the run's verdict and the path program's check; default the plan's
        (``meta.cut.wire_tolerance``: the job's ``[cut] wire_tolerance``, the strictest of
        its passes'; 0.5 mm for a trajectory that names no cut).

    Returns
    -------
    :class:`RunResult`; after motion ``run_verdict`` (what the robot did to the cut,
    :mod:`.run_verdict`) decides with the status whether the run holds (``ok``).
    Raises ValueError (bad input, limits) and :class:`ControllerError` (the controller
    cannot be reached) before any motion.
    """
    source: Path | None = None
    if not isinstance(traj, Trajectory):
        source = Path(traj)
        traj = read_trajectory(source)
    planned = model_for(traj.meta)
    if model is None or (isinstance(model, str) and model.strip().lower() == planned.name):
        robot = planned  # the plan's arm: its kinematics and the limits it was planned in
    else:
        robot = load(model) if isinstance(model, str) else model
    mode = _validate(traj, robot, planned, mode, lookahead, gain, deviation_limit, start_index)
    if mode == "forward":  # its settings checked now: bad input, before any motion
        ForwardSettings(robot.control_period, buffer, stop_time, lookahead, gain)
    if host is None and not dry_run:
        raise ValueError("host: a controller address is needed unless dry_run")
    check_trajectory(traj, robot, speed_scale=speed_scale)
    wire_tolerance = plan_wire_tolerance(traj, wire_tolerance)
    n = traj.n
    checks = [
        Check(
            "limits",
            f"joint limits of the {robot.name} (speed scale {speed_scale:g})",
            "within",
            "positions, speeds, accelerations",
            "",
            "",
            True,
        )
    ]
    result = RunResult(status="dry_run", message="", n_samples=n, start_index=start_index,
                       stop_index=start_index, stop_time=float(traj.t[start_index]),
                       requested_index=start_index)  # nothing moved yet: stopped where it starts

    def make_plan(entry: Entry | None) -> RunPlan:
        return RunPlan(Verdict(tuple(checks)), entry, host, mode, traj, approach_speed, speed_scale)

    if host is None:
        if mode == "path":  # the program from the sample asked for: measured, not sent
            program = plan_path_run(traj, start_index, speed_scale=speed_scale,
                                    tolerance=path_tolerance, blend=path_blend,
                                    acceleration=path_acceleration,
                                    wire_tolerance=wire_tolerance)  # fmt: skip
            checks.append(program.verdict_check())
            result.program_check = program.check
        checks.append(
            Check.info(
                "controller",
                "controller (model, period, state, entry)",
                "not contacted (dry run without a host)",
            )
        )
        result.verdict = make_plan(None).verdict
        result.message = "trajectory checked; controller not contacted"
        if not result.verdict.ok:
            result.status = "refused"
            result.message = "; ".join(c.detail or c.label for c in result.verdict.failed)
        return result
    try:
        info = query_dashboard(host, timeout=min(connect_timeout, 5.0))
    except ConnectionError as exc:
        raise ControllerError(f"controller at {host} not reachable: {exc}") from None
    checks.extend(controller_checks(traj.meta, info))
    kin_check, controller_kin = kinematics_check(
        traj.meta, host, timeout=min(connect_timeout, 5.0), force=force_kinematics
    )
    checks.append(kin_check)
    result.controller_kinematics = controller_kin
    dt = float(robot.control_period)
    cfg = {
        "host": host,
        "frequency": 1.0 / dt,
        "watchdog": watchdog,
        "deviation_limit": deviation_limit,
        "max_latency": max_latency,
        "connect_timeout": connect_timeout,
    }
    child = Child(cfg)
    try:
        return _run(
            child,
            traj,
            source,
            checks,
            make_plan,
            result,
            mode,
            host,
            dt,
            dict(
                lookahead=lookahead,
                gain=gain,
                speed_scale=speed_scale,
                dry_run=dry_run,
                progress=progress,
                confirm=confirm,
                approach_speed=approach_speed,
                approach_acceleration=approach_acceleration,
                resume_tolerance=resume_tolerance,
                resume_window=resume_window,
                stop_deceleration=stop_deceleration,
                path_tolerance=path_tolerance,
                path_blend=path_blend,
                path_acceleration=path_acceleration,
                actual_path=actual_path,
                heartbeat=heartbeat,
                stop_budget=stop_budget,
                connect_timeout=connect_timeout,
                watchdog=watchdog,
                max_latency=max_latency,
                deviation_limit=deviation_limit,
                wire_tolerance=wire_tolerance,
                buffer=buffer,
                stop_time=stop_time,
            ),
        )
    finally:
        child.close()


def _run(
    child: Child,
    traj: Trajectory,
    source: Path | None,
    checks: list[Check],
    make_plan: Callable[[Entry | None], RunPlan],
    result: RunResult,
    mode: str,
    host: str,
    dt: float,
    o: dict,
) -> RunResult:
    try:
        msg = child.wait_for(("state", "error"))
    except ChildGone as gone:
        raise ControllerError(
            f"controller at {host}: the ur_rtde client failed while "
            f"connecting ({gone}): {child.log_tail(3)}"
        ) from None
    if msg[0] == "error":
        raise ControllerError(msg[1])
    state = msg[1]
    result.priority = str(state.get("priority", ""))
    result.realtime = bool(state.get("realtime", False))
    checks.append(readiness_check(host, state))
    entry = plan_entry(
        traj,
        np.asarray(state["q"]),
        result.requested_index,
        tolerance=o["resume_tolerance"],
        window=o["resume_window"],
        approach_speed=o["approach_speed"],
        approach_acceleration=o["approach_acceleration"],
    )
    checks.append(entry.check)
    program: PathRun | None = None
    if mode == "path" and entry.check.ok:
        # the program of the samples the run plays, its motion measured before anything
        # is sent (the check refuses a program that would not cut as planned)
        program = plan_path_run(traj, entry.sample, speed_scale=o["speed_scale"],
                                tolerance=o["path_tolerance"], blend=o["path_blend"],
                                acceleration=o["path_acceleration"],
                                wire_tolerance=o["wire_tolerance"])  # fmt: skip
        checks.append(program.verdict_check())
        result.program_check = program.check
    plan = make_plan(entry)
    result.verdict, result.entry = plan.verdict, entry
    if not plan.verdict.ok:
        result.status = "refused"
        result.message = "; ".join(c.detail or c.label for c in plan.verdict.failed)
        return result
    if o["dry_run"]:
        result.message = (
            f"trajectory and controller checked; entry: {entry.kind} at sample "
            f"{entry.sample}, approach of {entry.distance:.4f} rad (leading joint) "
            "not executed"
        )
        return result
    if o["confirm"] is not None and not o["confirm"](plan):
        result.status, result.message = "cancelled", "not confirmed: nothing moved"
        return result
    return _move(child, traj, source, result, entry, state, mode, host, dt, o, program)


def _move(
    child: Child,
    traj: Trajectory,
    source: Path | None,
    result: RunResult,
    entry: Entry,
    state: dict,
    mode: str,
    host: str,
    dt: float,
    o: dict,
    program: PathRun | None = None,
) -> RunResult:
    k0 = entry.sample
    n = traj.n
    speed_scale = o["speed_scale"]
    t_in = np.asarray(traj.t[k0:], dtype=float)
    ts_in = (t_in - t_in[0]) / speed_scale
    t_grid, q_grid = resample(ts_in, np.asarray(traj.q[k0:], dtype=float), dt)
    grid_to_input = np.clip(np.searchsorted(ts_in, t_grid + 1e-9, side="right") - 1, 0, None)
    window = max(10, math.ceil((3.0 * o["lookahead"] + 0.1) / dt))
    ops: list[tuple] = []
    if program is not None:  # the grid sample at each input sample's time

        def grid_of(k: int) -> int:
            return min(round(float(ts_in[k]) / dt), t_grid.size - 1)

        ops = program.child_ops(grid_of)
    from ..geometry.se3 import ur_vector_from_pose

    motion = {
        "mode": mode,
        "q_grid": q_grid,
        "program": ops,
        "lookahead": o["lookahead"],
        "gain": o["gain"],
        "window": window,
        "approach_speed": o["approach_speed"],
        "approach_acceleration": o["approach_acceleration"],
        "stop_deceleration": o["stop_deceleration"],
        "stop_budget": o["stop_budget"],
        "heartbeat": o["heartbeat"],
        "connect_timeout": o["connect_timeout"] + 5.0,
        "tcp_offset": [float(x) for x in ur_vector_from_pose(traj.meta.tcp_offset)],
        "mass": traj.meta.payload.mass,
        "cog": [float(x) for x in traj.meta.payload.cog],
        "checked_q": state["q"],
        "moved_tolerance": 1e-3,
        "heat": _heat_message(traj, k0, grid_to_input, mode, dt, o),
        "buffer": o["buffer"],
        "stop_time": o["stop_time"],
    }
    result.start_index = k0
    child.send("go", motion)
    progress = o["progress"]

    def on_progress(info: dict) -> None:
        if progress is not None:
            kg = min(int(info["k_match"]), grid_to_input.size - 1)
            progress(k0 + int(grid_to_input[kg]), n)

    out = child.supervise(
        on_progress if progress is not None else None,
        stop_bound=o["heartbeat"] + o["stop_budget"] + 4.0,
    )
    info = out.info
    result.timeline = out.timeline
    result.status, result.message = out.status, out.message
    result.max_deviation = float(info["max_dev"])
    result.samples_sent = int(info["sent"])
    result.samples_skipped = int(info.get("skipped", 0))
    result.max_slip = float(info.get("max_slip", 0.0))
    t0 = info.get("recording_t0")
    result.recording_t0 = None if t0 is None else float(t0)
    if out.status in ("client_died", "client_hung") or out.killed:
        if o["watchdog"] > 0:
            result.message += (
                f"; the controller's RTDE watchdog stops the program "
                f"{1.0 / o['watchdog']:g} s after the last command it received"
            )
        result.client = f"{out.exit}\n{out.log}".strip()
    heat = traj.meta.heat
    if heat is not None and result.status != "completed":
        # the child switches the heat off on every stop it lives through; a crashed or
        # hung client cannot, and a controller keeps its outputs when the program stops
        result.message += "; " + send_heat_off(host, heat)
    rec = _recording(out.chunks, traj, host, mode, result)
    if result.status == "completed":
        result.stop_index, result.stop_time = n, float(traj.t[-1])
        if progress is not None:
            progress(n, n)
    else:
        kg = int(info["k_match"])
        if rec is not None:
            lo = max(0, kg - window)
            hi = max(lo, min(max(int(info["sent"]), kg), q_grid.shape[0] - 1))
            d = np.max(np.abs(q_grid[lo : hi + 1] - rec.q[-1]), axis=1)
            kg = lo + int(np.argmin(d))
        k_in = k0 + int(grid_to_input[min(kg, grid_to_input.size - 1)])
        result.stop_index, result.stop_time = k_in, float(traj.t[k_in])
        result.stop = stop_place(traj, k_in)
    to_input = k0 + grid_to_input
    skips = [(int(to_input[a]), int(to_input[b - 1]) + 1)
             for a, b in info.get("skipped_ranges", ())]  # fmt: skip
    if rec is not None:
        tags = np.concatenate([c[3] for c in out.chunks])
        # a recorded sample the live match did not tag (the child silent while the
        # controller plays on, forwarded, up to its buffer) is matched in a window that
        # reaches past what the controller can play alone
        ahead = o["buffer"] if mode == "forward" else 0.0
        kg = align_recording(q_grid, rec.q, tags, window + math.ceil(ahead / dt))
        plan_index = to_input[np.clip(kg, 0, to_input.size - 1)]
    else:
        plan_index = np.zeros(0, dtype=np.int64)
    heat = traj.meta.heat
    hot_rec = None  # the heat as the controller's outputs reported it, per recorded sample
    power = None  # its power [W/m]: the analog output times its full scale
    if rec is not None and heat is not None:
        outputs = np.concatenate([c[4] for c in out.chunks])
        hot_rec, power = heat_from_outputs(heat, outputs), heat_power_from_outputs(heat, outputs)
    # a run that entered from rest with the wire in the block (a resume in the kerf): its
    # resume mark (ramp, pre-heat) is allowed and said (run_verdict.measure_run)
    in_block = entry.kind == "continue" and bool(inside_mask(traj)[entry.sample])
    entry_in_block = (heat.preheat if heat is not None else 0.0) if in_block else None
    measures = measure_run(traj, rec, plan_index, status=result.status,
                           message=result.message, skipped_ranges=skips, hot=hot_rec,
                           entry_in_block=entry_in_block,
                           max_slip=result.max_slip, max_latency=o["max_latency"],
                           max_deviation=result.max_deviation,
                           deviation_limit=o["deviation_limit"], speed_scale=speed_scale,
                           wire_tolerance=o["wire_tolerance"], power=power)  # fmt: skip
    result.measures, result.run_verdict = measures, measures.verdict
    if rec is not None:  # the recording measures itself with the cut carried over to it;
        # its heat_power: the analog output the controller reported, times its full scale
        rec = Trajectory(rec.t, rec.q, rec.tcp,
                         rec.meta.replace(cut=measures.cut, in_stock=measures.in_stock), power)
    result.actual = rec
    if rec is not None:
        if o["actual_path"] is not None:
            result.actual_path = write_trajectory(o["actual_path"], rec)
        elif source is not None:
            result.actual_path = write_trajectory(recording_path_for(source), rec)
        if result.actual_path is not None:
            _write_run(result.actual_path, result, measures, source, speed_scale)
    return result


def _write_run(path: Path, result: RunResult, measures: RunMeasures, source: Path | None,
               speed_scale: float) -> None:  # fmt: skip
    """The run's figures and verdict into the recording's sidecar (``"run"``)."""
    side = sidecar_path(path)
    doc = json.loads(side.read_text(encoding="utf-8"))
    doc["run"] = {
        "plan": None if source is None else str(source),
        "status": result.status,
        "message": result.message,
        "entry": None if result.entry is None else result.entry.kind,
        "requested_index": result.requested_index,
        "start_index": result.start_index,
        "stop_index": result.stop_index,
        "samples_sent": result.samples_sent,
        "max_deviation_rad": result.max_deviation,
        "speed_scale": speed_scale,
        "priority": result.priority,
        "ok": result.ok,
        **measures.as_dict(),
    }
    atomic_write_json(side, doc)


def _heat_message(traj: Trajectory, k0: int, grid_to_input: np.ndarray, mode: str,
                  dt: float, o: dict) -> dict | None:  # fmt: skip
    """The heat the child switches: the output and, per grid sample, on or off, and with
    a scheduled power on an analog output the set-points as written (``levels``): on a
    servo motion (streamed, forwarded) as the arm reaches the samples
    (:func:`~.heat.servo_levels`, grid period ``dt``)."""
    heat = traj.meta.heat
    if heat is None:
        return None
    levels = heat_levels(traj)
    if levels is not None:
        levels = levels[k0 + grid_to_input]
        if mode != "path":
            levels = servo_levels(levels, dt, o["lookahead"], o["gain"])
    written = None if levels is None else written_levels(levels)
    on = heat.on(traj.n)[k0 + grid_to_input] if written is None else written > 0.0
    return {"kind": heat.kind, "index": heat.index, "value": heat.value,
            "preheat": heat.preheat, "hot": on.tolist(),
            "levels": None if written is None else written.tolist()}  # fmt: skip


def _recording(
    chunks: list, traj: Trajectory, host: str, mode: str, result: RunResult
) -> Trajectory | None:
    if not chunks:
        return None
    t = np.concatenate([c[0] for c in chunks])
    if t.size < 2:
        return None
    q = np.concatenate([c[1] for c in chunks])
    tcp = np.concatenate([c[2] for c in chunks])
    meta = traj.meta.replace(
        phases=(),
        in_stock=(),
        # the controller reports its TCP through its own kinematics
        kinematics=result.controller_kinematics or traj.meta.kinematics,
        source=f"recorded by ruledrobot run on {host}: mode {mode}, "
        f"status {result.status}, entry {result.entry.kind if result.entry else '-'} at input "
        f"sample {result.start_index} of {traj.n}",
    )
    return Trajectory(t, q, tcp, meta)
