"""A small interpreter for standalone URScript programs (one statement list, no control flow).

It runs the programs :mod:`ruledrobot.export.urscript` writes and similar
hand-written ones, one step per control period.  Programs arrive compiled
(:func:`~.functions.compile_program`: every statement a known function
with checked arguments in ``Statement.params``), so nothing is skipped:

* ``movej``/``movel``/``movep`` (joint vector or ``p[...]`` pose; ``a``,
  ``v``, ``r``): consecutive moves with a blend radius ``r > 0`` form one
  blended path, as on the controller;
* ``servoj(q, t=, lookahead_time=, gain=)``: sets the servo target and
  blocks for ``t`` (one control period when ``t = 0``);
* ``speedj(qd, a, t)``, ``stopj(a)``, ``stopl(a)``, ``sleep(t)``, ``sync()``;
* ``textmsg``, ``popup`` (non-blocking; the pendant's popup), ``set_tcp(p[...])``,
  ``set_payload(m, cog)``, ``set_target_payload``, ``set_payload_mass``,
  ``set_payload_cog``, ``write_output_integer_register``,
  ``write_output_float_register``, ``write_output_boolean_register``,
  ``set_standard_digital_out``, ``set_configurable_digital_out``,
  ``set_tool_digital_out``, ``set_digital_out`` (8, 9: tool),
  ``set_standard_analog_out`` / ``set_analog_out``.

Motion can still fail while the program runs (a pose out of reach): that is a
runtime error, the program stops
(:meth:`~ruledrobot.ursim.controller.machine.Controller.program_error`).
When the statements run out the program ends (runtime state STOPPED) and a
servo or speed motion still in force is stopped with ``stopj(4)``.
"""

from __future__ import annotations

import math

import numpy as np

from ...robot.motion.arm_kinematics import ArmKinematics
from ...robot.motion.ur_motion import (
    MotionError,
    PathMotion,
    Segment,
    StopMotion,
    joint_segment,
    linear_segment,
)
from .host import ProgramHost
from .program import Pose, Program, Statement

__all__ = ["ScriptRunner", "move_segment", "run_io_statement"]

_MOVES = ("movej", "movel", "movep")


def _target(v: object) -> tuple[np.ndarray, bool]:
    """A checked move target: (6 values, is it a pose)."""
    if isinstance(v, Pose):
        return np.asarray(v.values, dtype=float), True
    return np.asarray(v, dtype=float), False


def _float(st: Statement, key: str) -> float:
    return float(st.params[key])  # type: ignore[arg-type]


def move_segment(
    kin: ArmKinematics,
    q: np.ndarray,
    kind: str,
    target: np.ndarray,
    pose: bool,
    v: float,
    a: float,
    r: float,
    unreachable: str,
) -> Segment:
    """The segment of one move of a blended path, as the controller plans it: the one
    reading of ``movej`` / ``movel`` / ``movep`` for programs and injected paths.

    Parameters
    ----------
    kin : the arm's kinematics (FK with the current TCP, IK nearest a configuration).
    q : (6,) joint positions [rad] the move starts from (the previous segment's end).
    kind : ``"movej"`` (joint interpolation, :func:`joint_segment`); ``"movel"`` and
        ``"movep"`` move the TCP on a line (:func:`linear_segment`).
    target : (6,) joint positions [rad], or with ``pose`` a UR pose vector
        ``[x, y, z, rx, ry, rz]`` [m, rad] of the TCP in the robot base frame.
    pose : whether ``target`` is a pose: ``movej`` to a pose goes to its IK solution
        nearest ``q``; ``movel`` / ``movep`` to joints go to the TCP pose of those joints.
    v, a : speed and acceleration (rad/s, rad/s^2 for ``movej``; m/s, m/s^2 otherwise).
    r : blend radius [m].
    unreachable : the :class:`MotionError`'s message when a ``movej`` pose has no IK
        solution (``linear_segment`` raises its own for a line out of reach).
    """
    if kind == "movej":
        if pose:
            qt = kin.ik_nearest(target, q)
            if qt is None:
                raise MotionError(unreachable)
            target = qt
        return joint_segment(q, target, v, a, r, kin)
    if not pose:
        target = np.asarray(kin.tcp_vector(target.tolist()))
    return linear_segment(q, target, v, a, r, kin)


def run_io_statement(c: ProgramHost, st: Statement) -> bool:
    """Run a non-motion statement (I/O, registers, TCP, payload, messages); False if not one."""
    name, a = st.name, st.params
    if name in ("textmsg", "popup"):
        text = " ".join(str(x) for x in (a.get("s1", a.get("s")), a.get("s2", "")) if x != "")
        c.log(text, level=1 if a.get("error") else 2 if a.get("warning") else 3)
        if name == "popup":
            c.show_popup(f"{a['title']}: {text}")
    elif name == "set_tcp":
        pose, _ = _target(a["pose"])
        c.kin.set_tcp(pose)
    elif name in ("set_payload", "set_target_payload", "set_payload_mass"):
        cog = a.get("cog")
        c.set_payload(_float(st, "m"), None if cog is None else np.asarray(cog, dtype=float))
    elif name == "set_payload_cog":
        c.set_payload(None, np.asarray(a["CoG"], dtype=float))
    elif name == "write_output_integer_register":
        c.set_out_int(int(a["address"]), int(a["value"]))  # type: ignore[call-overload]
    elif name == "write_output_float_register":
        c.set_out_double(int(a["address"]), _float(st, "value"))  # type: ignore[call-overload]
    elif name == "write_output_boolean_register":
        c.set_out_bit(int(a["address"]), bool(a["value"]))  # type: ignore[call-overload]
    elif name in ("set_standard_digital_out", "set_configurable_digital_out",
                  "set_tool_digital_out", "set_digital_out"):  # fmt: skip
        n = int(a["n"])  # type: ignore[call-overload]
        kind = {"set_standard_digital_out": "standard", "set_configurable_digital_out":
                "configurable", "set_tool_digital_out": "tool"}.get(name)  # fmt: skip
        if kind is None:  # set_digital_out: 0-7 standard, 8-9 tool
            kind, n = ("tool", n - 8) if n >= 8 else ("standard", n)
        c.set_digital_out(kind, n, bool(a["b"]))
    elif name in ("set_standard_analog_out", "set_analog_out"):
        c.set_analog_out(int(a["n"]), _float(st, "f"))  # type: ignore[call-overload]
    else:
        return False
    return True


class ScriptRunner:
    """Executes a parsed standalone program on a controller, one period per step.

    The controller is seen through :class:`~ruledrobot.ursim.script.host.ProgramHost`.
    """

    def __init__(self, host: ProgramHost, program: Program) -> None:
        self.c = host
        self.kin = host.kin
        self.program = program
        self.pc = 0
        self.wait_ticks = 0
        self.waiting_motion: PathMotion | StopMotion | None = None

    @property
    def line(self) -> int:
        """Line number of the statement being executed (0 when done)."""
        st = self.program.statements
        return st[self.pc].line if self.pc < len(st) else 0

    def step(self) -> None:
        c = self.c
        if self.waiting_motion is not None:
            if c.motion is self.waiting_motion:
                return
            self.waiting_motion = None
        if self.wait_ticks > 0:
            self.wait_ticks -= 1
            return
        stmts = self.program.statements
        budget = 10000  # non-blocking statements per period
        while self.pc < len(stmts) and budget > 0:
            budget -= 1
            st = stmts[self.pc]
            if st.name in _MOVES:
                self._moves()
                return
            self.pc += 1
            if self._statement(st):
                return
        if self.pc >= len(stmts):
            c.program_finished()

    def _ticks(self, t: float) -> int:
        return max(1, math.ceil(t / self.c.period - 1e-9))

    def _moves(self) -> None:
        """Start the blended group of moves at ``pc``."""
        c = self.c
        stmts = self.program.statements
        q = c.arm_state().target_q.copy()
        q0 = q.copy()
        segs: list[Segment] = []
        while self.pc < len(stmts) and stmts[self.pc].name in _MOVES:
            st = stmts[self.pc]
            self.pc += 1
            target, pose = _target(st.params["q" if st.name == "movej" else "pose"])
            a, v, r = _float(st, "a"), _float(st, "v"), _float(st, "r")
            seg = move_segment(self.kin, q, st.name, target, pose, v, a, r,
                               f"line {st.line}: movej: pose out of reach")  # fmt: skip
            segs.append(seg)
            q = seg.q_end
            if r <= 0.0:
                break
        motion = PathMotion(q0, segs)
        c.start_motion(motion)
        self.waiting_motion = motion

    def _statement(self, st: Statement) -> bool:
        """Run one statement; True when it blocks this period."""
        c = self.c
        name, a = st.name, st.params
        if name == "servoj":
            q, _ = _target(a["q"])
            c.set_servo(q, _float(st, "lookahead_time"), _float(st, "gain"))
            self.wait_ticks = self._ticks(_float(st, "t")) - 1
            return True
        if name == "speedj":
            qd, _ = _target(a["qd"])
            c.set_speed(qd, _float(st, "a"))
            self.wait_ticks = self._ticks(_float(st, "t")) - 1
            return True
        if name in ("stopj", "stopl"):
            self.waiting_motion = c.stop_motion(_float(st, "a"))
            return True
        if name == "sleep":
            self.wait_ticks = self._ticks(_float(st, "t")) - 1
            return True
        if name == "sync":
            return True
        if run_io_statement(c, st):
            return False
        # compile_program admits only the functions above
        raise MotionError(f"line {st.line}: {name}() cannot run")  # pragma: no cover
