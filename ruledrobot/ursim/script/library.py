"""The URScript built-in functions of the interpreter (:mod:`.interpreter`).

Two kinds, as :mod:`.transpile` calls them:

* **blocking** (:data:`BLOCKING`, and every function of :data:`~.functions.FUNCTIONS`):
  Python generators called with ``yield from``; each ``yield`` ends the thread's share of
  one control period.  The functions of the table (moves, ``servoj``, ``speedj``,
  ``stopj``, ``sleep``, ``sync``, IO, registers, payload, messages) have their arguments
  checked by :func:`~.functions.bind` when they run (a bad value is a runtime error
  naming the line) and run as the standalone programs' statements did: consecutive moves
  with a blend radius form one blended path, started when the next statement that is not a
  move runs (or the thread ends or waits).  Sockets (:mod:`.sockets`) and ``join`` wait
  in controller time.
* **pure** (:data:`PURE`): plain calls — math, lists, strings, poses, the arm's state
  and kinematics, register and IO reads.

Units: metres, radians, seconds; poses are UR pose vectors (:class:`PoseValue`).
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable, Generator
from typing import Any

import numpy as np

from ...robot.motion.ur_motion import PathMotion
from . import poses
from .functions import FUNCTIONS, bind
from .host import ProgramHost
from .program import Pose, ScriptRuntimeError, Statement
from .runner import move_segment, run_io_statement
from .values import PoseValue, argument_of, pose_of, vector_of

__all__ = ["BLOCKING", "PURE", "Library", "PoseValue", "ScriptRuntimeError"]

Gen = Generator[None, None, Any]


_MOVES = ("movej", "movel", "movep")


class Library:
    """The built-ins bound to a controller and the interpreter's threads.

    The controller ``host``; the threads ``runtime`` (``join`` and the pending moves).
    :meth:`namespace` is what the transpiled program sees.
    """

    def __init__(self, host: ProgramHost, runtime: Any) -> None:
        self.c = host
        self.rt = runtime
        self.pending: list[tuple[str, np.ndarray, bool, float, float, float]] = []
        from .sockets import ScriptSockets

        self.sockets = ScriptSockets(host.period, bool(getattr(host, "realtime", False)))

    def namespace(self) -> dict[str, Callable[..., Any]]:
        """``b_<name>`` for every built-in."""
        ns: dict[str, Callable[..., Any]] = {}
        for name in FUNCTIONS:
            ns[f"b_{name}"] = self._table_function(name)
        for name in BLOCKING:
            ns[f"b_{name}"] = getattr(self.sockets, name, None) or getattr(self, name)
        for name in PURE:
            ns[f"b_{name}"] = (getattr(self.sockets, name, None) or getattr(poses, name, None)
                               or getattr(self, name))  # fmt: skip
        return ns

    def close(self) -> None:
        """Close the program's sockets."""
        self.sockets.close_all()

    # ------------------------------------------------------------ the table's functions
    def _table_function(self, name: str) -> Callable[..., Gen]:
        text = name in ("textmsg", "popup")  # they print any value

        def call(*args: object, **kwargs: object) -> Gen:
            if text:
                args = tuple(a if isinstance(a, str) else Library.to_str(a)
                             for a in args)  # fmt: skip
            st = Statement(name, [argument_of(a) for a in args],
                           {k: argument_of(v) for k, v in kwargs.items()}, 0, name)
            try:
                st.params = bind(st)
            except ValueError as exc:  # CompileError without a line: the interpreter adds it
                raise ScriptRuntimeError(str(getattr(exc, "reason", exc))) from None
            return self._run(st)

        call.__name__ = name
        return call

    def run_bound(self, st: Statement) -> Gen:
        """Run a call of the table whose arguments are bound (``st.params``)."""
        return self._run(st)

    def _run(self, st: Statement) -> Gen:
        c, name, a = self.c, st.name, st.params
        if name in _MOVES:
            tgt = a["q" if name == "movej" else "pose"]
            pose = isinstance(tgt, Pose)
            values = np.asarray(tgt.values if isinstance(tgt, Pose) else tgt, dtype=float)
            self.pending.append((name, values, pose, float(a["v"]), float(a["a"]),
                                 float(a["r"])))  # type: ignore[arg-type]  # fmt: skip
            if float(a["r"]) <= 0.0:  # type: ignore[arg-type]
                yield from self.flush()
            return None
        yield from self.flush()
        if name == "servoj":
            c.set_servo(np.asarray(a["q"], dtype=float), float(a["lookahead_time"]),
                        float(a["gain"]))  # type: ignore[arg-type]  # fmt: skip
            yield from self._wait(float(a["t"]))  # type: ignore[arg-type]
        elif name == "speedj":
            c.set_speed(np.asarray(a["qd"], dtype=float), float(a["a"]))  # type: ignore[arg-type]
            yield from self._wait(float(a["t"]))  # type: ignore[arg-type]
        elif name in ("stopj", "stopl"):
            stop = c.stop_motion(float(a["a"]))  # type: ignore[arg-type]
            while c.motion is stop:
                yield
        elif name == "sleep":
            yield from self._wait(float(a["t"]))  # type: ignore[arg-type]
        elif name == "sync":
            yield
        elif not run_io_statement(c, st):  # pragma: no cover - FUNCTIONS is covered above
            raise ScriptRuntimeError(f"{name}() cannot run")
        return None

    def _wait(self, t: float) -> Gen:
        """Block ``t`` seconds of controller time (at least one period)."""
        for _ in range(max(1, math.ceil(t / self.c.period - 1e-9))):
            yield

    def flush(self) -> Gen:
        """Start the pending (blended) moves as one path and wait until it ends.

        A path a pause braked (dashboard ``pause``, then ``play``) is resumed as the
        controller resumes an interrupted move: from where the arm stopped to the path's
        last target (its intermediate blend waypoints are not revisited)."""
        if not self.pending:
            return
        moves, self.pending = self.pending, []
        while moves:
            q = self.c.arm_state().target_q.copy()
            q0 = q.copy()
            segs = []
            for kind, target, pose, v, acc, r in moves:
                seg = move_segment(self.c.kin, q, kind, target, pose, v, acc, r,
                                   f"{kind}: pose p{target.tolist()} out of reach")  # fmt: skip
                segs.append(seg)
                q = seg.q_end
            motion = PathMotion(q0, segs)
            self.c.start_motion(motion)
            while self.c.motion is motion:
                yield
            # braked by a pause before its end: the last move again from where it stopped
            reached = np.abs(self.c.arm_state().target_q - q).max() < 1e-9
            moves = [] if reached or self.c.motion is not None else [(*moves[-1][:5], 0.0)]

    # ------------------------------------------------------------ math and lists
    sin, cos, tan = staticmethod(math.sin), staticmethod(math.cos), staticmethod(math.tan)
    atan, sqrt, log = staticmethod(math.atan), staticmethod(math.sqrt), staticmethod(math.log)

    @staticmethod
    def asin(f: float) -> float:
        """``asin(f)``: the arc sine of ``f`` [rad], in [-pi/2, pi/2].

        A runtime error when ``f`` lies outside [-1, 1], as UR's manual says; values within 1e-12 of
        the range (rounding) are clamped to it.
        """
        return math.asin(min(1.0, max(-1.0, f))) if abs(f) <= 1 + 1e-12 else math.asin(f)

    @staticmethod
    def acos(f: float) -> float:
        """``acos(f)``: the arc cosine of ``f`` [rad], in [0, pi].

        A runtime error when ``f`` lies outside [-1, 1], as UR's manual says; values within 1e-12 of
        the range (rounding) are clamped to it.
        """
        return math.acos(min(1.0, max(-1.0, f))) if abs(f) <= 1 + 1e-12 else math.acos(f)

    @staticmethod
    def atan2(y: float, x: float) -> float:
        """``atan2(y, x)``: the arc tangent of ``y / x`` [rad], in [-pi, pi].

        The signs of both arguments give the quadrant.
        """
        return math.atan2(y, x)

    @staticmethod
    def pow(base: float, exponent: float) -> float:
        """``pow(base, exponent)``: ``base`` raised to the power ``exponent`` (a float).

        A runtime error for a negative ``base`` with a non-integral ``exponent`` or a zero ``base``
        with a negative one, as UR's manual says.
        """
        return math.pow(base, exponent)

    @staticmethod
    def floor(f: float) -> int:
        """``floor(f)``: the largest integer not greater than ``f`` (an int)."""
        return math.floor(f)

    @staticmethod
    def ceil(f: float) -> int:
        """``ceil(f)``: the smallest integer not less than ``f`` (an int)."""
        return math.ceil(f)

    @staticmethod
    def d2r(d: float) -> float:
        """``d2r(d)``: ``d`` degrees in radians [rad]."""
        return math.radians(d)

    @staticmethod
    def r2d(r: float) -> float:
        """``r2d(r)``: ``r`` radians [rad] in degrees."""
        return math.degrees(r)

    @staticmethod
    def norm(a: object) -> float:
        """``norm(a)``: the norm of ``a``: ``|a|`` of a number, the Euclidean norm of a list.

        For a pose UR's manual says "the Euclidean norm of the pose"; the emulator takes the norm of
        its position part [m].
        """
        if isinstance(a, PoseValue):
            return float(np.linalg.norm(np.asarray(a[:3], dtype=float)))
        if isinstance(a, list):
            return float(np.linalg.norm(np.asarray(a, dtype=float)))
        return abs(a)  # type: ignore[arg-type]

    @staticmethod
    def length(v: object) -> int:
        """``length(v)``: the number of elements of a list or characters of a string (an int).

        A runtime error for another type.  ``get_list_length`` is the same function.
        """
        if isinstance(v, (list, str)):
            return len(v)
        raise ScriptRuntimeError(f"length(): expected a list or a string, got {v!r}")

    get_list_length = length

    @staticmethod
    def random() -> float:
        """``random()``: a pseudo-random float in [0, 1) (Python's generator, not seeded)."""
        return random.random()

    @staticmethod
    def to_str(v: object) -> str:
        """``to_str(val)``: the string representation of ``val``.

        Booleans as ``True`` / ``False``, lists and poses as ``[...]`` / ``p[...]``, numbers as
        Python's ``str`` writes them (``0.1 + 0.2`` gives ``0.30000000000000004``): the
        controller's own float formatting may differ.
        """
        if isinstance(v, bool):
            return "True" if v else "False"
        return repr(v) if isinstance(v, list) else str(v)

    @staticmethod
    def str_cat(a: object, b: object) -> str:
        """``str_cat(op1, op2)``: the string representations (:meth:`to_str`) of both, joined."""
        return Library.to_str(a) + Library.to_str(b)

    @staticmethod
    def str_len(s: str) -> int:
        """``str_len(str)``: the length of a string (an int).

        UR's manual returns the number of bytes, the emulator counts characters: they differ
        beyond ASCII.
        """
        return len(s)

    @staticmethod
    def to_num(s: str) -> int | float:
        """``to_num(str)``: the number ``str`` writes: an int when written as one, else a float.

        A runtime error when it is not a number.  Parsed by Python's ``int``, then ``float``, which
        also take ``1_000``, ``inf`` and ``nan``.
        """
        try:
            return int(s)
        except ValueError:
            try:
                return float(s)
            except ValueError:
                raise ScriptRuntimeError(f"to_num(): not a number: {s!r}") from None

    @staticmethod
    def binary_list_to_integer(bits: list) -> int:
        """``binary_list_to_integer(l)``: the integer the booleans of ``l`` write, bit 0 first.

        Index 0 is the least significant bit; 0 for an empty list.  UR's manual reads the list as a
        signed binary number and only its first 32 booleans; the emulator adds every bit as an
        unsigned number (a list of 32 with bit 31 set gives 2**31, not a negative int).
        """
        return sum(1 << i for i, b in enumerate(bits) if b)

    @staticmethod
    def integer_to_binary_list(x: int) -> list[bool]:
        """``integer_to_binary_list(x)``: the 32 bits of ``x`` (two's complement) as booleans.

        A list of 32, index 0 the least significant bit.
        """
        return [bool((int(x) >> i) & 1) for i in range(32)]

    # ------------------------------------------------------------ the arm
    def get_actual_joint_positions(self) -> list[float]:
        """``get_actual_joint_positions()``: the actual joint positions [rad], base to wrist 3."""
        return [float(x) for x in self.c.arm_state().q]

    def get_target_joint_positions(self) -> list[float]:
        """``get_target_joint_positions()``: the target joint positions [rad], base to wrist 3."""
        return [float(x) for x in self.c.arm_state().target_q]

    def get_actual_joint_speeds(self) -> list[float]:
        """``get_actual_joint_speeds()``: the actual joint speeds [rad/s], base to wrist 3."""
        return [float(x) for x in self.c.arm_state().qd]

    def get_target_joint_speeds(self) -> list[float]:
        """``get_target_joint_speeds()``: the target joint speeds [rad/s], base to wrist 3."""
        return [float(x) for x in self.c.arm_state().target_qd]

    def get_actual_tcp_pose(self) -> PoseValue:
        """``get_actual_tcp_pose()``: the TCP pose in the base frame [m, rad], actual.

        Forward kinematics of the actual joint positions with the active TCP.
        """
        return pose_of(self.c.kin.tcp_vector(self.get_actual_joint_positions()))

    def get_target_tcp_pose(self) -> PoseValue:
        """``get_target_tcp_pose()``: the TCP pose in the base frame [m, rad], target.

        Forward kinematics of the target joint positions with the active TCP.
        """
        return pose_of(self.c.kin.tcp_vector(self.get_target_joint_positions()))

    def get_forward_kin(self, q: list | None = None, tcp: list | None = None) -> PoseValue:
        """``get_forward_kin(q, tcp)``: the TCP pose in the base frame [m, rad] at joints ``q``.

        ``q`` [rad] defaults to the actual joint positions, ``tcp`` (a pose in the flange frame)
        to the active TCP; the kinematics are the controller's (calibrated when it is).
        """
        qv = self.get_actual_joint_positions() if q is None else vector_of(q, 6, "get_forward_kin")
        offset = None if tcp is None else vector_of(tcp, 6, "get_forward_kin")
        return pose_of(self.c.kin.fk_vector(np.asarray(qv, dtype=float), offset))

    def get_inverse_kin(self, x: list, qnear: list | None = None, maxPositionError: float = 1e-10,
                        maxOrientationError: float = 1e-10, tcp: list | None = None) -> list:
        """``get_inverse_kin(x, qnear, ...)``: joint positions [rad] putting the TCP at ``x``.

        ``x`` is a pose in the base frame [m, rad]; the solution within the joint limits nearest
        ``qnear`` (default: the actual joint positions), a runtime error when there is none.
        ``maxPositionError`` and ``maxOrientationError`` are accepted and not used (the solution is
        analytic); ``tcp=`` is a runtime error (``set_tcp`` first).
        """
        if tcp is not None:
            raise ScriptRuntimeError("get_inverse_kin(): tcp= is not emulated (set_tcp first)")
        near = self.get_actual_joint_positions() if qnear is None else qnear
        q = self.c.kin.ik_nearest(vector_of(x, 6, "get_inverse_kin"),
                                  vector_of(near, 6, "get_inverse_kin"))
        if q is None:
            raise ScriptRuntimeError(f"get_inverse_kin(): no solution for p{list(x)}")
        return [float(v) for v in q]

    def get_steptime(self) -> float:
        """``get_steptime()``: the duration of the controller's time step [s].

        0.002 s on e-Series, 0.008 s on CB3.
        """
        return float(self.c.period)

    def is_steady(self) -> bool:
        """``is_steady()``: True when the robot is fully at rest.

        The emulator: no motion planned and every actual joint speed below 1e-4 rad/s.
        """
        return bool(np.all(np.abs(self.c.arm_state().qd) < 1e-4)) and self.c.motion is None

    def is_within_safety_limits(self, pose: list, qnear: list | None = None) -> bool:
        """``is_within_safety_limits(pose, qnear)``: True when ``pose`` is reachable and allowed.

        The emulator checks that an inverse kinematics solution within the joint limits exists
        (nearest ``qnear``, default the actual joint positions); it has no other safety limits.  UR
        also takes joint positions; here any list of 6 is read as a pose.
        """
        v = vector_of(pose, 6, "is_within_safety_limits")
        near = self.get_actual_joint_positions() if qnear is None else qnear
        return self.c.kin.ik_nearest(v, vector_of(near, 6, "is_within_safety_limits")) is not None

    # ------------------------------------------------------------ registers and IO reads
    def _reg(self, key: str, i: int, top: int) -> Any:
        if isinstance(i, bool) or not isinstance(i, int) or not 0 <= i <= top:
            raise ScriptRuntimeError(f"register address must be an integer 0..{top}, got {i!r}")
        return self.c.values.get(f"{key}_{i}", 0)

    def read_input_integer_register(self, address: int) -> int:
        """``read_input_integer_register(address)``: the int in RTDE input integer register 0-47.

        A runtime error for another ``address``.
        """
        return int(self._reg("input_int_register", address, 47))

    def read_input_float_register(self, address: int) -> float:
        """``read_input_float_register(address)``: the float in RTDE input double register 0-47.

        A runtime error for another ``address``.
        """
        return float(self._reg("input_double_register", address, 47))

    def read_output_integer_register(self, address: int) -> int:
        """``read_output_integer_register(address)``: the int in RTDE output integer register 0-47.

        A runtime error for another ``address``.
        """
        return int(self._reg("output_int_register", address, 47))

    def read_output_float_register(self, address: int) -> float:
        """``read_output_float_register(address)``: the float in RTDE output double register 0-47.

        A runtime error for another ``address``.
        """
        return float(self._reg("output_double_register", address, 47))

    def _bit(self, prefix: str, address: int) -> bool:
        if isinstance(address, bool) or not isinstance(address, int) or not 0 <= address <= 127:
            raise ScriptRuntimeError(f"register address must be an integer 0..127, got "
                                     f"{address!r}")  # fmt: skip
        if address >= 64:
            return bool(self.c.values.get(f"{prefix}_bit_register_{address}", 0))
        key = f"{prefix}_bit_registers0_to_31" if address < 32 else \
            f"{prefix}_bit_registers32_to_63"  # fmt: skip
        return bool((int(self.c.values.get(key, 0)) >> (address % 32)) & 1)

    def read_input_boolean_register(self, address: int) -> bool:
        """``read_input_boolean_register(address)``: the bool in RTDE input bit register 0-127.

        A runtime error for another ``address``.
        """
        return self._bit("input", address)

    def read_output_boolean_register(self, address: int) -> bool:
        """``read_output_boolean_register(address)``: the bool in RTDE output bit register 0-127.

        A runtime error for another ``address``.
        """
        return self._bit("output", address)

    def _pin(self, word: int, n: int, top: int) -> bool:
        if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= top:
            raise ScriptRuntimeError(f"pin must be an integer 0..{top}, got {n!r}")
        return bool((word >> n) & 1)

    def get_standard_digital_out(self, n: int) -> bool:
        """``get_standard_digital_out(n)``: the level of standard digital output ``n``.

        A bool; ``n`` 0-7, a runtime error for another pin.
        """
        return self._pin(self.c.std_do, n, 7)

    def get_configurable_digital_out(self, n: int) -> bool:
        """``get_configurable_digital_out(n)``: the level of configurable digital output ``n``.

        A bool; ``n`` 0-7, a runtime error for another pin.
        """
        return self._pin(self.c.conf_do, n, 7)

    def get_tool_digital_out(self, n: int) -> bool:
        """``get_tool_digital_out(n)``: the level of tool digital output ``n``.

        A bool; ``n`` 0-1, a runtime error for another pin.
        """
        return self._pin(self.c.tool_do, n, 1)

    def join(self, handle: int) -> Gen:
        """``join``: wait until the thread ``handle`` ended."""
        yield from self.rt.join(handle)


#: built-ins that may wait (generators; the table's functions are added to these)
BLOCKING = frozenset({"socket_open", "socket_read_binary_integer", "socket_read_ascii_float",
                      "socket_read_string", "socket_read_line"})  # fmt: skip
#: built-ins that return at once
PURE = frozenset({
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sqrt", "log", "pow", "floor", "ceil",
    "d2r", "r2d", "norm", "length", "get_list_length", "random", "to_str", "str_cat", "str_len",
    "to_num", "binary_list_to_integer", "integer_to_binary_list", "pose_trans", "pose_inv",
    "pose_add", "pose_sub", "pose_dist", "point_dist", "interpolate_pose",
    "get_actual_joint_positions", "get_target_joint_positions", "get_actual_joint_speeds",
    "get_target_joint_speeds", "get_actual_tcp_pose", "get_target_tcp_pose", "get_forward_kin",
    "get_inverse_kin", "get_steptime", "is_steady", "is_within_safety_limits",
    "read_input_integer_register", "read_input_float_register", "read_output_integer_register",
    "read_output_float_register", "read_input_boolean_register",
    "read_output_boolean_register", "get_standard_digital_out", "get_configurable_digital_out",
    "get_tool_digital_out", "socket_close", "socket_send_int", "socket_send_string",
    "socket_send_line", "socket_send_byte",
})  # fmt: skip
