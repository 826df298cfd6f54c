"""A small interpreter for standalone URScript programs (one statement list, no control flow).

It runs the programs :mod:`ruledrobot.export.urscript` writes and similar
hand-written ones, one step per control period:

* ``movej``/``movel``/``movep`` (joint vector or ``p[...]`` pose; ``a``,
  ``v``, ``r``): consecutive moves with a blend radius ``r > 0`` form one
  blended path, as on the controller;
* ``servoj(q, t=, lookahead_time=, gain=)``: sets the servo target and
  blocks for ``t`` (one control period when ``t = 0``);
* ``speedj(qd, a, t)``, ``stopj(a)``, ``stopl(a)``, ``sleep(t)``, ``sync()``;
* ``textmsg``, ``popup``, ``set_tcp(p[...])``, ``set_payload(m, cog)``,
  ``write_output_integer_register``, ``write_output_float_register``,
  ``write_output_boolean_register``, ``set_standard_digital_out``,
  ``set_configurable_digital_out``, ``set_tool_digital_out``,
  ``set_speed_slider_fraction`` (ignored: the slider belongs to the pendant).

Anything else is logged and skipped.  When the statements run out the program
ends (runtime state STOPPED) and a servo or speed motion still in force is
stopped with ``stopj(4)``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .motion import MotionError, PathMotion, Segment, StopMotion, joint_segment, linear_segment
from .program import Pose, Program, Statement

if TYPE_CHECKING:
    from .controller import Controller

__all__ = ["ScriptRunner"]

_MOVES = ("movej", "movel", "movep")


def _num(st: Statement, key: str, pos: int | None, default: float) -> float:
    if pos is not None and pos < len(st.args):
        v = st.args[pos]
    else:
        v = st.kwargs.get(key, default)
    if isinstance(v, bool) or not isinstance(v, float):
        raise MotionError(f"line {st.line}: {st.name}: {key} must be a number")
    return v


def _vec(st: Statement, pos: int = 0) -> tuple[np.ndarray, bool]:
    if pos >= len(st.args):
        raise MotionError(f"line {st.line}: {st.name}: missing target")
    v = st.args[pos]
    pose = isinstance(v, Pose)
    vals = v.values if isinstance(v, Pose) else v
    if not isinstance(vals, (list, tuple)) or len(vals) != 6:
        raise MotionError(f"line {st.line}: {st.name}: expected 6 values")
    return np.asarray(vals, dtype=float), pose


class ScriptRunner:
    """Executes a parsed standalone program on a :class:`Controller`, one period per step."""

    def __init__(self, ctrl: Controller, program: Program) -> None:
        self.c = ctrl
        self.program = program
        self.pc = 0
        self.wait_ticks = 0
        self.waiting_motion: PathMotion | StopMotion | None = None
        if program.skipped:
            first = program.skipped[0][:60]
            ctrl.log(f"program {program.name or '<line>'}: {len(program.skipped)} unsupported "
                     f"line(s) skipped, the first: {first!r}", level=2)  # fmt: skip

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
        q = c.backend.state().target_q.copy()
        q0 = q.copy()
        segs: list[Segment] = []
        while self.pc < len(stmts) and stmts[self.pc].name in _MOVES:
            st = stmts[self.pc]
            self.pc += 1
            target, pose = _vec(st)
            linear = st.name != "movej"
            a = _num(st, "a", None, 1.2 if linear else 1.4)
            v = _num(st, "v", None, 0.25 if linear else 1.05)
            r = _num(st, "r", None, 0.0)
            if linear:
                if not pose:
                    target = np.asarray(c.kin.tcp_vector(target.tolist()))
                seg = linear_segment(q, target, v, a, r, c.kin)
            else:
                if pose:
                    qt = c.kin.ik_nearest(target, q)
                    if qt is None:
                        raise MotionError(f"line {st.line}: movej: pose out of reach")
                    target = qt
                seg = joint_segment(q, target, v, a, r, c.kin)
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
        name = st.name
        if name == "servoj":
            q, _ = _vec(st)
            t = _num(st, "t", None, 0.002)
            c.set_servo(q, _num(st, "lookahead_time", None, 0.1), _num(st, "gain", None, 300.0))
            self.wait_ticks = self._ticks(t) - 1
            return True
        if name == "speedj":
            qd, _ = _vec(st)
            c.set_speed(qd, _num(st, "a", 1, 1.4))
            self.wait_ticks = self._ticks(_num(st, "t", 2, 0.0)) - 1
            return True
        if name in ("stopj", "stopl"):
            self.waiting_motion = c.stop_motion(_num(st, "a", 0, 2.0))
            return True
        if name == "sleep":
            self.wait_ticks = self._ticks(_num(st, "t", 0, 0.0)) - 1
            return True
        if name == "sync":
            return True
        if name in ("textmsg", "popup"):
            c.log(" ".join(str(a) for a in st.args))
            return False
        if name == "set_tcp":
            pose, _ = _vec(st)
            c.kin.set_tcp(pose)
            return False
        if name in ("set_payload", "set_target_payload"):
            cog = st.args[1] if len(st.args) > 1 else [0.0, 0.0, 0.0]
            c.set_payload(_num(st, "m", 0, 0.0), np.asarray(cog, dtype=float))
            return False
        if name == "write_output_integer_register":
            c.set_out_int(int(_num(st, "i", 0, 0)), int(_num(st, "v", 1, 0)))
            return False
        if name == "write_output_float_register":
            c.set_out_double(int(_num(st, "i", 0, 0)), _num(st, "v", 1, 0.0))
            return False
        if name == "write_output_boolean_register":
            b = st.args[1] if len(st.args) > 1 else False
            c.set_out_bit(int(_num(st, "i", 0, 0)), bool(b))
            return False
        if name in (
            "set_standard_digital_out",
            "set_digital_out",
            "set_configurable_digital_out",
            "set_tool_digital_out",
        ):
            n = int(_num(st, "n", 0, 0))
            b = st.args[1] if len(st.args) > 1 else False
            c.set_digital_out(name, n, bool(b))
            return False
        c.log(f"line {st.line}: {name}() is not supported by the emulator, skipped", level=2)
        return False
