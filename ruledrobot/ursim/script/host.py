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
    def in_int(self, i: int) -> int:
        """The RTDE input integer register ``i`` (0-47), as a client last set it."""
        ...

    def in_double(self, i: int) -> float:
        """The RTDE input double register ``i`` (0-47), as a client last set it."""
        ...

    def set_out_int(self, i: int, value: int) -> None:
        """Set RTDE output integer register ``i`` (0-47); the controller wraps it to int32."""
        ...

    def set_out_double(self, i: int, value: float) -> None:
        """Set RTDE output double register ``i`` (0-47)."""
        ...

    def set_out_bit(self, i: int, value: bool) -> None:
        """Set RTDE output bit register ``i`` (0-127)."""
        ...

    # ---------------------------------------------------------------- IO, messages
    def set_digital_out(self, kind: str, n: int, value: bool) -> None:
        """Set digital output ``n`` of ``kind`` to ``value``; the controller logs the change.

        ``kind`` ``"standard"`` (pins 0-7), ``"configurable"`` (0-7) or ``"tool"`` (0-1); the
        controller raises ValueError for another kind or pin.  Every change of the outputs goes to
        the controller's output log (``io_log``).
        """
        ...

    def set_analog_out(self, n: int, fraction: float) -> None:
        """Set standard analog output ``n`` (0-1) to ``fraction`` (0-1) of its range.

        The controller raises ValueError for another pin or a fraction outside [0, 1].
        """
        ...

    def set_payload(self, mass: float | None, cog: ArrayLike | None) -> None:
        """Set the payload: ``mass`` [kg], centre of gravity ``cog`` [m] in the flange frame.

        None keeps that value; the controller publishes them (RTDE ``payload``, ``payload_cog``).
        """
        ...

    def set_watchdog(self, name: str, min_frequency: float, action: str = "stop") -> None:
        """Watch RTDE input ``name``: ``rtde_set_watchdog``.

        When the input is not updated within ``1 / min_frequency`` [s] the controller stops the
        program (``action`` ``"stop"``) or pauses it (``"pause"``); ``"ignore"`` or a frequency <= 0
        [Hz] removes the watchdog.  It ends with the program.
        """
        ...

    def show_popup(self, text: str) -> None:
        """Show ``text`` as the pendant's popup (until the dashboard's ``close popup``)."""
        ...

    def log(self, message: str, level: int = 3) -> None:
        """Add ``message`` to the controller's log at ``level`` (0 exception ... 3 info).

        The controller keeps its last events and cuts long messages (``MAX_LOG_MESSAGE``).
        """
        ...

    # ---------------------------------------------------------------- motion
    def start_motion(self, motion: PathMotion | StopMotion) -> None:
        """Run ``motion`` from the next period on, replacing the one running.

        The runner sees it end when :attr:`motion` is no longer that object.
        """
        ...

    def stop_motion(self, deceleration: float) -> StopMotion:
        """Brake from the current setpoint to rest at ``deceleration`` [rad/s^2] (``stopj``).

        Returns the stop motion, which is then :attr:`motion`.
        """
        ...

    def set_servo(self, q: ArrayLike, lookahead_time: float, gain: float) -> None:
        """Servo the joints to ``q`` [rad], shape (6,), smoothed (``servoj``).

        ``lookahead_time`` [s] and ``gain`` set the smoothing.  The controller ignores it while the
        robot may not move (robot mode not RUNNING, or safety not NORMAL or REDUCED).
        """
        ...

    def set_speed(self, qd: ArrayLike, acceleration: float) -> None:
        """Run the joints at ``qd`` [rad/s], shape (6,), reached at ``acceleration`` [rad/s^2].

        ``speedj``; the controller ignores it while the robot may not move.
        """
        ...

    def build_path(self, waypoints: Sequence[PathWaypoint]) -> PathMotion:
        """One blended path through ``waypoints`` from the current setpoint (not started).

        Each waypoint is a movej, movel or movep target (joint positions [rad] or a pose in the base
        frame [m, rad]) with its speed, acceleration and blend radius [m].
        """
        ...

    # ---------------------------------------------------------------- program life
    def program_finished(self) -> None:
        """The program reached its end: the controller logs it and stops it (STOPPED)."""
        ...

    def stop_program(self, reason: str = "", *, decelerate: bool = True) -> None:
        """End the running program (runtime state STOPPED); ``reason`` is logged.

        With ``decelerate`` an arm still moving brakes.
        """
        ...

    def protective_stop(self, reason: str = "protective stop") -> None:
        """Protective stop: safety PROTECTIVE_STOP, the program stops, the arm brakes."""
        ...
