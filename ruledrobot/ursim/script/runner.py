"""The controller's reading of one move and of one IO statement, shared by the
interpreter (:mod:`.library`) and injected paths (``Controller.build_path``).

* :func:`move_segment`: ``movej``/``movel``/``movep`` to a joint vector or a pose, as a
  segment of a blended path;
* :func:`run_io_statement`: a bound non-motion statement (messages, TCP, payload,
  registers, digital and analog outputs).
"""

from __future__ import annotations

import numpy as np

from ...robot.motion.arm_kinematics import ArmKinematics
from ...robot.motion.ur_motion import (
    MotionError,
    Segment,
    joint_segment,
    linear_segment,
)
from .host import ProgramHost
from .program import Pose, Statement

__all__ = ["move_segment", "run_io_statement"]

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
    """The segment of one move of a blended path, as the controller plans it.

    The one reading of ``movej`` / ``movel`` / ``movep`` for programs and injected paths.

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
