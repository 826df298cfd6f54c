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
from collections.abc import Callable, Generator, Iterable
from typing import Any

import numpy as np

from ...geometry import se3
from ...robot.motion.ur_motion import PathMotion
from .functions import FUNCTIONS, bind
from .host import ProgramHost
from .program import Pose, ScriptRuntimeError, Statement
from .runner import move_segment, run_io_statement

__all__ = ["BLOCKING", "PURE", "Library", "PoseValue", "ScriptRuntimeError"]

Gen = Generator[None, None, Any]


class PoseValue(list):
    """A URScript pose ``p[x, y, z, rx, ry, rz]``: a list of 6 numbers that knows it is a pose."""

    def __repr__(self) -> str:
        return "p" + super().__repr__()


def _arg(v: object) -> object:
    """A runtime value as the argument checks take it (numbers as float, poses as Pose)."""
    if isinstance(v, bool) or isinstance(v, str):
        return v
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, PoseValue):
        return Pose(tuple(float(x) for x in v))
    if isinstance(v, list):
        return [_arg(x) for x in v]
    return v


def _vec(v: object, n: int, what: str) -> np.ndarray:
    if not isinstance(v, list) or len(v) != n:
        raise ScriptRuntimeError(f"{what}: expected a list of {n} numbers, got {v!r}")
    try:
        return np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ScriptRuntimeError(f"{what}: expected numbers, got {v!r}") from None


def _pose(v: np.ndarray | Iterable[float]) -> PoseValue:
    return PoseValue(float(x) for x in v)


def _matrix(p: object, what: str) -> np.ndarray:
    return se3.pose_from_ur_vector(_vec(p, 6, what))


_MOVES = ("movej", "movel", "movep")


class Library:
    """The built-ins bound to a controller (``host``) and the interpreter's threads
    (``runtime``: ``join`` and the pending moves); :meth:`namespace` is what the
    transpiled program sees."""

    def __init__(self, host: ProgramHost, runtime: Any) -> None:
        self.c = host
        self.rt = runtime
        self.pending: list[tuple[str, np.ndarray, bool, float, float, float]] = []
        from .sockets import ScriptSockets

        self.sockets = ScriptSockets(host.period)

    def namespace(self) -> dict[str, Callable[..., Any]]:
        """``b_<name>`` for every built-in."""
        ns: dict[str, Callable[..., Any]] = {}
        for name in FUNCTIONS:
            ns[f"b_{name}"] = self._table_function(name)
        for name in BLOCKING:
            ns[f"b_{name}"] = getattr(self.sockets, name, None) or getattr(self, name)
        for name in PURE:
            ns[f"b_{name}"] = getattr(self.sockets, name, None) or getattr(self, name)
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
            st = Statement(name, [_arg(a) for a in args], {k: _arg(v) for k, v in kwargs.items()},
                           0, name)  # fmt: skip
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
        """Start the pending (blended) moves as one path and wait until it ends."""
        if not self.pending:
            return
        moves, self.pending = self.pending, []
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

    # ------------------------------------------------------------ math and lists
    sin, cos, tan = staticmethod(math.sin), staticmethod(math.cos), staticmethod(math.tan)
    atan, sqrt, log = staticmethod(math.atan), staticmethod(math.sqrt), staticmethod(math.log)

    @staticmethod
    def asin(f: float) -> float:
        return math.asin(min(1.0, max(-1.0, f))) if abs(f) <= 1 + 1e-12 else math.asin(f)

    @staticmethod
    def acos(f: float) -> float:
        return math.acos(min(1.0, max(-1.0, f))) if abs(f) <= 1 + 1e-12 else math.acos(f)

    @staticmethod
    def atan2(y: float, x: float) -> float:
        return math.atan2(y, x)

    @staticmethod
    def pow(base: float, exponent: float) -> float:
        return math.pow(base, exponent)

    @staticmethod
    def floor(f: float) -> int:
        return math.floor(f)

    @staticmethod
    def ceil(f: float) -> int:
        return math.ceil(f)

    @staticmethod
    def d2r(d: float) -> float:
        return math.radians(d)

    @staticmethod
    def r2d(r: float) -> float:
        return math.degrees(r)

    @staticmethod
    def norm(a: object) -> float:
        if isinstance(a, PoseValue):
            return float(np.linalg.norm(np.asarray(a[:3], dtype=float)))
        if isinstance(a, list):
            return float(np.linalg.norm(np.asarray(a, dtype=float)))
        return abs(a)  # type: ignore[arg-type]

    @staticmethod
    def length(v: object) -> int:
        if isinstance(v, (list, str)):
            return len(v)
        raise ScriptRuntimeError(f"length(): expected a list or a string, got {v!r}")

    get_list_length = length

    @staticmethod
    def random() -> float:
        return random.random()

    @staticmethod
    def to_str(v: object) -> str:
        if isinstance(v, bool):
            return "True" if v else "False"
        return repr(v) if isinstance(v, list) else str(v)

    @staticmethod
    def str_cat(a: object, b: object) -> str:
        return Library.to_str(a) + Library.to_str(b)

    @staticmethod
    def str_len(s: str) -> int:
        return len(s)

    @staticmethod
    def to_num(s: str) -> int | float:
        try:
            return int(s)
        except ValueError:
            try:
                return float(s)
            except ValueError:
                raise ScriptRuntimeError(f"to_num(): not a number: {s!r}") from None

    @staticmethod
    def binary_list_to_integer(bits: list) -> int:
        return sum(1 << i for i, b in enumerate(bits) if b)

    @staticmethod
    def integer_to_binary_list(x: int) -> list[bool]:
        return [bool((int(x) >> i) & 1) for i in range(32)]

    # ------------------------------------------------------------ poses
    @staticmethod
    def pose_trans(p_from: list, p_from_to: list) -> PoseValue:
        T = _matrix(p_from, "pose_trans") @ _matrix(p_from_to, "pose_trans")
        return _pose(se3.ur_vector_from_pose(T))

    @staticmethod
    def pose_inv(p: list) -> PoseValue:
        return _pose(se3.ur_vector_from_pose(se3.inverse(_matrix(p, "pose_inv"))))

    @staticmethod
    def pose_add(p1: list, p2: list) -> PoseValue:
        a, b = _matrix(p1, "pose_add"), _matrix(p2, "pose_add")
        T = np.eye(4)
        T[:3, :3] = b[:3, :3] @ a[:3, :3]
        T[:3, 3] = a[:3, 3] + b[:3, 3]
        return _pose(se3.ur_vector_from_pose(T))

    @staticmethod
    def pose_sub(p_to: list, p_from: list) -> PoseValue:
        a, b = _matrix(p_to, "pose_sub"), _matrix(p_from, "pose_sub")
        T = np.eye(4)
        T[:3, :3] = a[:3, :3] @ b[:3, :3].T
        T[:3, 3] = a[:3, 3] - b[:3, 3]
        return _pose(se3.ur_vector_from_pose(T))

    @staticmethod
    def pose_dist(p_from: list, p_to: list) -> float:
        return float(np.linalg.norm(_vec(p_to, 6, "pose_dist")[:3] - _vec(p_from, 6,
                                                                          "pose_dist")[:3]))

    @staticmethod
    def point_dist(p_from: list, p_to: list) -> float:
        return Library.pose_dist(p_from, p_to)

    @staticmethod
    def interpolate_pose(p_from: list, p_to: list, alpha: float) -> PoseValue:
        A, B = _matrix(p_from, "interpolate_pose"), _matrix(p_to, "interpolate_pose")
        T = np.eye(4)
        T[:3, :3] = se3.geodesic(A, B, float(alpha))[:3, :3]
        T[:3, 3] = A[:3, 3] + float(alpha) * (B[:3, 3] - A[:3, 3])
        return _pose(se3.ur_vector_from_pose(T))

    # ------------------------------------------------------------ the arm
    def get_actual_joint_positions(self) -> list[float]:
        return [float(x) for x in self.c.arm_state().q]

    def get_target_joint_positions(self) -> list[float]:
        return [float(x) for x in self.c.arm_state().target_q]

    def get_actual_joint_speeds(self) -> list[float]:
        return [float(x) for x in self.c.arm_state().qd]

    def get_target_joint_speeds(self) -> list[float]:
        return [float(x) for x in self.c.arm_state().target_qd]

    def get_actual_tcp_pose(self) -> PoseValue:
        return _pose(self.c.kin.tcp_vector(self.get_actual_joint_positions()))

    def get_target_tcp_pose(self) -> PoseValue:
        return _pose(self.c.kin.tcp_vector(self.get_target_joint_positions()))

    def get_forward_kin(self, q: list | None = None, tcp: list | None = None) -> PoseValue:
        qv = self.get_actual_joint_positions() if q is None else _vec(q, 6, "get_forward_kin")
        offset = None if tcp is None else _vec(tcp, 6, "get_forward_kin")
        return _pose(self.c.kin.fk_vector(np.asarray(qv, dtype=float), offset))

    def get_inverse_kin(self, x: list, qnear: list | None = None, maxPositionError: float = 1e-10,
                        maxOrientationError: float = 1e-10, tcp: list | None = None) -> list:
        if tcp is not None:
            raise ScriptRuntimeError("get_inverse_kin(): tcp= is not emulated (set_tcp first)")
        near = self.get_actual_joint_positions() if qnear is None else qnear
        q = self.c.kin.ik_nearest(_vec(x, 6, "get_inverse_kin"), _vec(near, 6, "get_inverse_kin"))
        if q is None:
            raise ScriptRuntimeError(f"get_inverse_kin(): no solution for p{list(x)}")
        return [float(v) for v in q]

    def get_steptime(self) -> float:
        return float(self.c.period)

    def is_steady(self) -> bool:
        return bool(np.all(np.abs(self.c.arm_state().qd) < 1e-4)) and self.c.motion is None

    def is_within_safety_limits(self, pose: list, qnear: list | None = None) -> bool:
        v = _vec(pose, 6, "is_within_safety_limits")
        near = self.get_actual_joint_positions() if qnear is None else qnear
        return self.c.kin.ik_nearest(v, _vec(near, 6, "is_within_safety_limits")) is not None

    # ------------------------------------------------------------ registers and IO reads
    def _reg(self, key: str, i: int, top: int) -> Any:
        if isinstance(i, bool) or not isinstance(i, int) or not 0 <= i <= top:
            raise ScriptRuntimeError(f"register address must be an integer 0..{top}, got {i!r}")
        return self.c.values.get(f"{key}_{i}", 0)

    def read_input_integer_register(self, address: int) -> int:
        return int(self._reg("input_int_register", address, 47))

    def read_input_float_register(self, address: int) -> float:
        return float(self._reg("input_double_register", address, 47))

    def read_output_integer_register(self, address: int) -> int:
        return int(self._reg("output_int_register", address, 47))

    def read_output_float_register(self, address: int) -> float:
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
        return self._bit("input", address)

    def read_output_boolean_register(self, address: int) -> bool:
        return self._bit("output", address)

    def _pin(self, word: int, n: int, top: int) -> bool:
        if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= top:
            raise ScriptRuntimeError(f"pin must be an integer 0..{top}, got {n!r}")
        return bool((word >> n) & 1)

    def get_standard_digital_out(self, n: int) -> bool:
        return self._pin(self.c.std_do, n, 7)

    def get_configurable_digital_out(self, n: int) -> bool:
        return self._pin(self.c.conf_do, n, 7)

    def get_tool_digital_out(self, n: int) -> bool:
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
