"""What a running program may use of the controller: the interface between the
controller (:class:`~ruledrobot.ursim.controller.machine.Controller`) and the program runners
(:class:`~.handshake.ControlScript` for ur_rtde's control script,
:class:`~.interpreter.Interpreter` for every other program).

The runners see the controller only through :class:`ProgramHost`, so neither
imports the controller (no import circle) and neither reaches into its parts:
the arm's state comes from :meth:`ProgramHost.arm_state`, its kinematics from
the ``kin`` the host declares.  Units: radians, metres, seconds; poses are UR
pose vectors ``[x, y, z, rx, ry, rz]`` in the base frame.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Protocol

from numpy.typing import ArrayLike

from ...robot.motion.arm_kinematics import ArmKinematics
from ...robot.motion.ur_motion import PathMotion, StopMotion
from ..arm.backend import ArmState
from .program import PathWaypoint

__all__ = ["ProgramHost"]


class ProgramHost(Protocol):
    """The controller as a program sees it (one control period per runner step)."""

    #: the arm's kinematics (FK, IK nearest a configuration, TCP offset), calibrated
    #: when the controller is
    kin: ArmKinematics
    #: control period [s] (0.002 on e-Series, 0.008 on CB3)
    period: float
    #: the trajectory generator's current motion (None when idle)
    motion: PathMotion | StopMotion | None
    #: names of the input registers the client set in its last data package
    last_input_names: frozenset[str]
    #: the actual joint positions of the last periods, newest last
    history: deque[list[float]]
    #: the published RTDE values by name (registers: ``input_int_register_0``, ...)
    values: dict[str, object]
    #: standard, configurable and tool digital output bits
    std_do: int
    conf_do: int
    tool_do: int

    def arm_state(self) -> ArmState:
        """The arm's state after the last period (actual and target joints)."""
        ...

    # ---------------------------------------------------------------- registers
    def in_int(self, i: int) -> int: ...
    def in_double(self, i: int) -> float: ...
    def set_out_int(self, i: int, value: int) -> None: ...
    def set_out_double(self, i: int, value: float) -> None: ...
    def set_out_bit(self, i: int, value: bool) -> None: ...

    # ---------------------------------------------------------------- IO, messages
    def set_digital_out(self, kind: str, n: int, value: bool) -> None: ...
    def set_analog_out(self, n: int, fraction: float) -> None: ...
    def set_payload(self, mass: float | None, cog: ArrayLike | None) -> None: ...
    def set_watchdog(self, name: str, min_frequency: float, action: str = "stop") -> None: ...
    def show_popup(self, text: str) -> None: ...
    def log(self, message: str, level: int = 3) -> None: ...

    # ---------------------------------------------------------------- motion
    def start_motion(self, motion: PathMotion | StopMotion) -> None: ...
    def stop_motion(self, deceleration: float) -> StopMotion: ...
    def set_servo(self, q: ArrayLike, lookahead_time: float, gain: float) -> None: ...
    def set_speed(self, qd: ArrayLike, acceleration: float) -> None: ...
    def build_path(self, waypoints: Sequence[PathWaypoint]) -> PathMotion: ...

    # ---------------------------------------------------------------- program life
    def program_finished(self) -> None: ...
    def stop_program(self, reason: str = "", *, decelerate: bool = True) -> None: ...
    def protective_stop(self, reason: str = "protective stop") -> None: ...
