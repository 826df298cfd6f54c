"""Standalone URScript programs from a trajectory, and trajectory export in four formats.

:func:`urscript_program` writes a program a UR controller runs by itself
(send it to port 30003, or load it in a Script node on the pendant; see
``docs/rtde.md``)::

    def ruledrobot_cut():
      set_tcp(p[...])                                  # the trajectory's TCP offset
      set_payload(1.0, [cx, cy, cz])                   # the trajectory's payload
      movej([q0...], a=0.5, v=0.25)                    # approach at reduced speed
      servoj([q...], t=0.002, lookahead_time=0.1, gain=300)   # one per sample
      ...
      stopj(2.0)
    end

Sent to port 30003 (or 30001/30002) the ``def`` runs as a program; in a Script
node of PolyScope the file only defines ``ruledrobot_cut()``, which a second
node must call (``docs/rtde.md``).

A trajectory with a heated wire (``meta.heat``) switches the heat output off at the
start, on where a heat window begins (the pre-heat dwell before a lead-in) and off
where it ends (after the lead-out) and at the end (:mod:`.heat`).  With a ``heat_power``
column on an analog output the program sets the output along the motion instead
(``set_standard_analog_out(n, heat_power / full_scale)``, the set-points already led
by the heat's ``lag``): a servoj program before each sample where the set-point changes
by more than :data:`~.heat.HEAT_STEP`; a path program before each run of blended moves
(a statement inside a blended run would stop the arm), at the run's mean set-point.

Every mode sets the TCP and the payload from the trajectory's metadata, so the
poses of ``movel``/``movep`` (the trajectory's TCP column) are the controller's
TCP poses, and FK(q) · TCP equals them.  ``mode="servoj"`` streams every sample
(``t`` = the time to the next sample; the last one holds for ``5 * lookahead``
so that the arm settles on it); ``mode="movep"`` / ``"movel"`` replaces the
samples by linear moves through the TCP path decimated to a tolerance, with
blends, each at the speed the trajectory has there.

Size: programs with more than :data:`WARN_MOTION_LINES` motion lines say so in
a comment and a ``textmsg``; beyond :data:`MAX_MOTION_LINES` lines or
:data:`MAX_PROGRAM_BYTES` bytes they are refused unless ``allow_long=True``
(field reports tell of programs with a few thousand targets failing and of an
18 MB program crashing a controller; stream long cuts with ``ruledrobot run``).

:func:`export_trajectory` writes a trajectory as CSV (with its sidecar), JSON,
NPZ or URScript, atomically.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from ..geometry.se3 import ur_vector_from_pose
from ..io.atomic import atomic_write_text
from ..io.trajectory import write_trajectory, write_trajectory_json, write_trajectory_npz
from ..robot import model_for
from ..robot.motion.trajectory import HEATED_PHASES, Trajectory
from ..robot.wire.cut import WIRE_TOLERANCE
from .decimate import path_steps
from .heat import HEAT_STEP, heat_levels, servo_levels, urscript_heat, written_levels
from .limits import check_trajectory
from .settings import (
    APPROACH_ACCELERATION,
    APPROACH_SPEED,
    PATH_ACCELERATION,
    PATH_BLEND,
    SERVO_GAIN,
    SERVO_LOOKAHEAD,
)
from .verify_program import (
    Move,
    Op,
    ProgramRefused,
    Sleep,
    Switch,
    check_path_program,
    refuse_unless_ok,
)

__all__ = [
    "EXPORT_FORMATS",
    "MAX_MOTION_LINES",
    "MAX_PROGRAM_BYTES",
    "WARN_MOTION_LINES",
    "ProgramRefused",
    "export_trajectory",
    "path_program",
    "program_size_note",
    "urscript_program",
]

#: formats of :func:`export_trajectory` and the file suffixes that select them
EXPORT_FORMATS = {".csv": "csv", ".json": "json", ".npz": "npz", ".script": "urscript",
                  ".urscript": "urscript"}  # fmt: skip
#: Programs with more motion lines than this carry a warning (comment, textmsg).
WARN_MOTION_LINES = 2_000
#: Programs beyond either size are refused unless ``allow_long``.
MAX_MOTION_LINES = 20_000
MAX_PROGRAM_BYTES = 2_000_000
#: servoj/lookahead ranges the controller accepts (URScript manual).
LOOKAHEAD_RANGE = (0.03, 0.2)
GAIN_RANGE = (100.0, 2000.0)


def check_servo_options(lookahead: float, gain: float) -> None:
    """ValueError unless ``lookahead`` [s] and ``gain`` are in the controller's ranges."""
    lo, hi = LOOKAHEAD_RANGE
    if not lo <= lookahead <= hi:
        raise ValueError(f"lookahead: {lookahead} s outside [{lo}, {hi}] (URScript servoj)")
    lo, hi = GAIN_RANGE
    if not lo <= gain <= hi:
        raise ValueError(f"gain: {gain} outside [{lo:g}, {hi:g}] (URScript servoj)")


def _num(x: float, digits: int) -> str:
    s = f"{float(x):.{digits}g}"
    return "0" if s in ("-0", "0") else s


def _vec(v: np.ndarray, digits: int) -> str:
    return "[" + ", ".join(_num(x, digits) for x in v) + "]"


def plan_wire_tolerance(traj: Trajectory, wire_tolerance: float | None = None) -> float:
    """Return the wire tolerance [m]: ``wire_tolerance``, or the plan's, or 0.5 mm.

    The plan's: the strictest of its cuts', from the sidecar's ``cut``; 0.5 mm for a
    trajectory that names no cut."""
    if wire_tolerance is not None:
        return float(wire_tolerance)
    return traj.meta.cut.wire_tolerance if traj.meta.cut is not None else WIRE_TOLERANCE


def path_program(
    traj: Trajectory,
    *,
    tolerance: float | None = None,
    angle_tolerance: float | None = None,
    blend: float = PATH_BLEND,
    acceleration: float = PATH_ACCELERATION,
    wire_tolerance: float | None = None,
) -> list[Op]:
    """Return the statements of a movel/movep program of ``traj`` after its initial ``movej``.

    Moves, sleeps and heat switches (:func:`~.decimate.path_steps`; docs/rtde.md).

    Waypoints: every phase start, the wire entering and leaving the stock, every heat
    switch, both ends of a dwell; the decimation's tolerances default to a quarter of
    the stricter of ``wire_tolerance`` and the faces' tolerances (``face_error``: the
    part's millimetres) at the wire's ends (position, and angle times half the wire)."""
    meta = traj.meta
    n = traj.n
    wire_tolerance = plan_wire_tolerance(traj, wire_tolerance)
    heat = meta.heat.on(n) if meta.heat is not None else None
    levels = heat_levels(traj)
    if levels is not None:  # the scheduled power: on where its set-point is above zero
        heat = levels > 0.0
    bounds = [x for p in meta.phases for x in (p.start, p.stop)]
    bounds += [x for r in meta.in_stock for x in r]
    strict = np.zeros(n, dtype=bool) if meta.phases else np.ones(n, dtype=bool)
    for p in meta.phases:
        if p.name in HEATED_PHASES:  # the wire near or in the stock: speed within 2 %
            strict[p.start : p.stop] = True
    strict |= traj.inside_stock() | (heat if heat is not None else False)
    faces = meta.cut.faces if meta.cut is not None else ()
    strictest = min([wire_tolerance, *(f.tolerance for f in faces)])
    tol = 0.25 * strictest if tolerance is None else tolerance
    if angle_tolerance is None:
        half = 0.5 * meta.cut.wire_length if meta.cut is not None else 0.2
        angle_tolerance = tol / half
    steps = path_steps(traj.t, traj.tcp, traj.q, boundaries=bounds, heat=heat, strict=strict,
                       tolerance=tol, angle_tolerance=angle_tolerance, blend=blend)  # fmt: skip
    robot = model_for(meta)
    joint_acc = float(np.min(robot.max_acceleration))
    ops: list[Op] = []
    hot = False  # the program switched the heat off before its first move
    tcp, p = traj.tcp, traj.tcp[:, :3]
    group = _group_levels(steps, levels) if levels is not None else {}
    level = 0.0
    for i, s in enumerate(steps):
        if i in group:  # the scheduled power: one set-point per run of blended moves
            x = group[i]
            if (x > 0.0) != (level > 0.0) or abs(x - level) > HEAT_STEP:
                ops.append(Switch(x > 0.0, x))
                level = x
        elif heat is not None and levels is None and s.heat != hot:
            ops.append(Switch(s.heat))
            hot = s.heat
        if s.kind == "dwell":
            ops.append(Sleep(s.seconds))
        elif s.kind == "joint":
            ops.append(Move(traj.q[s.stop].copy(), joint_acc, max(s.v, 1e-5), s.r, joint=True))
        else:
            # v: the move's own length (rotation for a pure reorientation) in the plan's time
            chord = float(np.linalg.norm(p[s.stop] - p[s.start]))
            v = chord / s.seconds if chord > 1e-6 else s.v
            ops.append(Move(tcp[s.stop].copy(), acceleration, float(np.clip(v, 1e-5, 3.0)),
                            s.r))  # fmt: skip
    return ops


def _group_levels(steps: tuple, levels: np.ndarray) -> dict[int, float]:
    """The analog set-point of each run of blended path steps (a statement between two
    blended moves would end the blend: the arm would stop there), keyed by the run's first
    step: the mean of the samples' set-points over the run (their time mean: the plan's
    samples are evenly spaced)."""
    out: dict[int, float] = {}
    first = 0
    for i, s in enumerate(steps):
        if s.r > 0.0 and i + 1 < len(steps):
            continue  # blended into the next step: the same run
        a, b = steps[first].start, s.stop
        out[first] = float(np.mean(levels[a:b])) if b > a else float(levels[a])
        first = i + 1
    return out


def program_size_note(motion_lines: int, size: int) -> str | None:
    """A warning for a long program (None when it is short)."""
    if motion_lines <= WARN_MOTION_LINES:
        return None
    return (f"long program: {motion_lines:,} motion lines, {size / 1e6:.1f} MB; controllers "
            f"have failed on programs of a few thousand targets: prefer streaming "
            f"(ruledrobot run) or a path mode (movep/movel)")  # fmt: skip


def urscript_program(
    traj: Trajectory,
    *,
    mode: str = "servoj",
    lookahead: float = SERVO_LOOKAHEAD,
    gain: float = SERVO_GAIN,
    approach_speed: float = APPROACH_SPEED,
    approach_acceleration: float = APPROACH_ACCELERATION,
    tolerance: float | None = None,
    angle_tolerance: float | None = None,
    blend: float = PATH_BLEND,
    acceleration: float = PATH_ACCELERATION,
    wire_tolerance: float | None = None,
    verify: bool = True,
    name: str = "ruledrobot_cut",
    digits: int = 10,
    allow_long: bool = False,
) -> str:
    """A standalone URScript program playing ``traj`` (see the module docstring).

    Parameters
    ----------
    traj : the trajectory; its metadata gives the TCP offset and payload set by the
        program, and the robot (control period).
    mode : ``"servoj"`` (one ``servoj`` per sample), ``"movep"`` or ``"movel"``
        (decimated linear moves of the TCP column, with blends).
    lookahead, gain : servoj parameters (0.03-0.2 s, 100-2000).
    approach_speed, approach_acceleration : the initial ``movej`` [rad/s, rad/s^2].
    tolerance, angle_tolerance : decimation of the path modes [m, rad]; default a
        quarter of ``wire_tolerance`` at the wire's ends (:func:`path_program`).
    blend : blend radius of the path modes [m] (clipped to 45 % of the shorter
        neighbouring segment; none into a dwell, a heat switch or a rest of the plan).
    acceleration : tool acceleration of the path modes [m/s^2].
    wire_tolerance : the wire's largest distance from the planned wire in the stock [m]
        (default: the plan's, ``meta.cut.wire_tolerance``; 0.5 mm without one).
    verify : (path modes) generate the program's motion and measure it against the plan
        before writing (:mod:`.verify_program`): a program whose feed or wire breaks the
        plan's tolerances raises :class:`ProgramRefused` (a ``ValueError``) with the
        numbers.
    name : the program's function name.
    digits : significant digits of every number.
    allow_long : write programs beyond :data:`MAX_MOTION_LINES` / :data:`MAX_PROGRAM_BYTES`.
    """
    if not isinstance(traj, Trajectory):
        raise ValueError(f"trajectory: expected a ruledrobot Trajectory, got {type(traj).__name__}")
    robot = model_for(traj.meta)
    check_trajectory(traj, robot)  # a program never carries motion beyond the limits
    if mode not in ("servoj", "movep", "movel"):
        raise ValueError(f"mode: expected 'servoj', 'movep' or 'movel', got {mode!r}")
    if not name.isidentifier():
        raise ValueError(f"name: {name!r} is not a URScript identifier")
    check_servo_options(lookahead, gain)
    t, q = traj.t, traj.q
    period = float(robot.control_period)
    meta = traj.meta
    body = io.StringIO()
    w = body.write
    verified = ""
    heat = meta.heat
    on = heat.on(t.size) if heat is not None else np.zeros(t.size, dtype=bool)
    w(f"  set_tcp(p{_vec(ur_vector_from_pose(meta.tcp_offset), digits)})\n")
    w(f"  set_payload({_num(meta.payload.mass, digits)}, {_vec(meta.payload.cog, digits)})\n")
    if heat is not None:  # cold until the first pre-heat, whatever the output was
        w(f"  {urscript_heat(heat, False)}\n")
    w('  textmsg("ruledrobot: moving to the start")\n')
    w(f"  movej({_vec(q[0], digits)}, a={_num(approach_acceleration, digits)}, "
      f"v={_num(approach_speed, digits)})\n")  # fmt: skip
    w('  textmsg("ruledrobot: cut")\n')
    if mode == "servoj":
        # the last servoj holds the final sample while the lookahead filter settles
        settle = max(period, 5.0 * lookahead)
        dts = np.append(np.diff(t), settle) if t.size > 1 else np.array([settle])
        la, g = _num(lookahead, digits), _num(gain, digits)
        was = False
        levels = heat_levels(traj)  # set as the arm, trailing its servoj, reaches them
        written = None if levels is None else written_levels(
            servo_levels(levels, traj.period, lookahead, gain))
        level = 0.0  # the program set the output to 0 first
        for k, (qk, dt) in enumerate(zip(q, dts, strict=True)):
            if written is not None:
                if written[k] != level:
                    level = float(written[k])
                    w(f"  {urscript_heat(heat, level > 0.0, level)}\n")  # type: ignore[arg-type]
            elif heat is not None and on[k] != was:
                w(f"  {urscript_heat(heat, bool(on[k]))}\n")
                was = bool(on[k])
            w(f"  servoj({_vec(qk, digits)}, t={_num(dt, digits)}, lookahead_time={la}, "
              f"gain={g})\n")  # fmt: skip
        w("  stopj(2.0)\n")
        motion_lines = t.size
    else:
        ops = path_program(traj, tolerance=tolerance, angle_tolerance=angle_tolerance,
                           blend=blend, acceleration=acceleration)  # fmt: skip
        if verify:
            check = check_path_program(traj, ops,
                                       wire_tolerance=plan_wire_tolerance(traj, wire_tolerance))
            refuse_unless_ok(check, mode)
            verified = f"verified (its motion, generated at the control period): {check.summary()}"
        for op in ops:
            if isinstance(op, Switch):
                w(f"  {urscript_heat(heat, op.on, op.value)}\n")  # type: ignore[arg-type]
            elif isinstance(op, Sleep):
                w(f"  sleep({_num(op.seconds, digits)})\n")
            else:
                target = _vec(op.pose, digits) if op.joint else f"p{_vec(op.pose, digits)}"
                w(f"  {'movej' if op.joint else mode}({target}, a={_num(op.a, digits)}, "
                  f"v={_num(op.v, digits)}, r={_num(op.r, digits)})\n")  # fmt: skip
        motion_lines = sum(1 for op in ops if not isinstance(op, Switch))
    if heat is not None:
        w(f"  {urscript_heat(heat, False)}\n")
    w('  textmsg("ruledrobot: done")\n')
    size = body.tell()
    if not allow_long and (motion_lines > MAX_MOTION_LINES or size > MAX_PROGRAM_BYTES):
        raise ValueError(
            f"URScript program: {motion_lines:,} motion lines, {size / 1e6:.1f} MB — beyond the "
            f"safe size ({MAX_MOTION_LINES:,} lines, {MAX_PROGRAM_BYTES / 1e6:g} MB). Stream it "
            "with `ruledrobot run`, use mode movep/movel, or pass allow_long (--allow-long)"
        )
    out = io.StringIO()
    out.write(f"def {name}():\n")
    out.write(f"  # ruledrobot trajectory program: {t.size} samples, {traj.duration:.3f} s, "
              f"robot {robot.name}, mode {mode}\n")  # fmt: skip
    out.write(f"  # kinematics {meta.kinematics.source} {meta.kinematics.checksum}\n")
    if meta.source:
        out.write(f"  # from: {meta.source}\n")
    if meta.job:
        out.write(f"  # job: {meta.job.get('path')} sha256 {meta.job.get('sha256')}\n")
    if verified:
        out.write(f"  # {verified}\n")
    note = program_size_note(motion_lines, size)
    if note:
        out.write(f"  # {note}\n")
        out.write(f'  textmsg("ruledrobot: {note.split(":")[0]}: {motion_lines} motion lines")\n')
    out.write(body.getvalue())
    out.write("end\n")
    return out.getvalue()


def export_trajectory(
    traj: Trajectory,
    path: str | os.PathLike[str],
    fmt: str | None = None,
    **urscript_options: object,
) -> Path:
    """Write ``traj`` to ``path`` as ``"csv"``, ``"json"``, ``"npz"`` or ``"urscript"`` (atomic).

    ``fmt`` defaults to the suffix (:data:`EXPORT_FORMATS`).  CSV is the project's
    trajectory format (the CSV and its sidecar ``.json``); JSON is
    ``{"format": "ruledrobot.trajectory/1", "meta": {sidecar fields}, "header": [...],
    "t": [...], "q": [[...]], "tcp": [[...]]}``; NPZ holds arrays ``t``, ``q``,
    ``tcp`` and ``meta`` (the sidecar fields as JSON text); URScript is
    :func:`urscript_program` (``urscript_options`` go to it).  Returns the path.
    """
    p = Path(path)
    if fmt is None:
        fmt = EXPORT_FORMATS.get(p.suffix.lower())
        if fmt is None:
            raise ValueError(
                f"{p}: cannot tell the format from the suffix {p.suffix!r}; pass fmt= one of "
                "'csv', 'json', 'npz', 'urscript'"
            )
    if fmt == "csv":
        return write_trajectory(p, traj)
    if fmt == "json":
        return write_trajectory_json(p, traj)
    if fmt == "npz":
        return write_trajectory_npz(p, traj)
    if fmt == "urscript":
        return atomic_write_text(p, urscript_program(traj, **urscript_options))  # type: ignore[arg-type]
    raise ValueError(f"fmt: expected 'csv', 'json', 'npz' or 'urscript', got {fmt!r}")
