"""The controller's power and safety: power on and off, brakes, protective and emergency
stops, their unlocking and release, clearing faults.

A mixin of :class:`~ruledrobot.ursim.controller.machine.Controller` (its ``lock``,
modes, motion and program control); thread safety as the controller's: every method takes ``lock``.
"""

from __future__ import annotations

import time
from threading import RLock
from typing import Any

from ...protocol.modes import RobotMode, SafetyMode, SafetyStatusBit
from ...robot.motion.ur_motion import StopMotion

__all__ = ["SAFETY_BITS", "SafetyMixin"]

#: the safety status bits (RTDE ``safety_status_bits``) of each safety mode
SAFETY_BITS = {
    SafetyMode.NORMAL: 1 << SafetyStatusBit.NORMAL_MODE,
    SafetyMode.REDUCED: 1 << SafetyStatusBit.REDUCED_MODE,
    SafetyMode.PROTECTIVE_STOP: (1 << SafetyStatusBit.PROTECTIVE_STOPPED)
    | (1 << SafetyStatusBit.STOPPED_DUE_TO_SAFETY),
    SafetyMode.RECOVERY: 1 << SafetyStatusBit.RECOVERY_MODE,
    SafetyMode.SAFEGUARD_STOP: 1 << SafetyStatusBit.SAFEGUARD_STOPPED,
    SafetyMode.SYSTEM_EMERGENCY_STOP: (1 << SafetyStatusBit.SYSTEM_EMERGENCY_STOPPED)
    | (1 << SafetyStatusBit.EMERGENCY_STOPPED),
    SafetyMode.ROBOT_EMERGENCY_STOP: (1 << SafetyStatusBit.ROBOT_EMERGENCY_STOPPED)
    | (1 << SafetyStatusBit.EMERGENCY_STOPPED),
    SafetyMode.VIOLATION: 1 << SafetyStatusBit.VIOLATION,
    SafetyMode.FAULT: 1 << SafetyStatusBit.FAULT,
}


class SafetyMixin:
    """Power and safety transitions (module doc)."""

    lock: RLock
    robot_mode: RobotMode
    safety_mode: SafetyMode
    motion: Any
    backend: Any
    fault_deceleration: float
    unlock_delay: float

    def power_on(self) -> bool:
        """Dashboard ``power on``: POWER_OFF or POWER_ON -> IDLE; False unless safety is NORMAL.

        In another robot mode nothing changes (and the answer is True).
        """
        with self.lock:
            if self.safety_mode != SafetyMode.NORMAL:
                return False
            if self.robot_mode in (RobotMode.POWER_OFF, RobotMode.POWER_ON):
                self.robot_mode = RobotMode.IDLE
            return True

    def brake_release(self) -> bool:
        """Dashboard ``brake release``: a powered robot -> RUNNING.

        False, nothing changed, unless safety is NORMAL and the robot is at least POWER_ON.
        """
        with self.lock:
            if self.safety_mode != SafetyMode.NORMAL or self.robot_mode < RobotMode.POWER_ON:
                return False
            self.robot_mode = RobotMode.RUNNING
            return True

    def power_off(self) -> None:
        """Dashboard ``power off``: the program stops, motion ends, robot mode POWER_OFF.

        No braking path is planned: the backend holds (brakes within its own limits).
        """
        with self.lock:
            self.stop_program("power off", decelerate=False)
            self.motion = None
            self.mode = "idle"
            self._hold_q = None
            self.backend.hold()
            self.robot_mode = RobotMode.POWER_OFF

    def _brake(self) -> None:
        st = self.backend.state()
        self.motion = StopMotion(st.target_q, st.target_qd, self.fault_deceleration)
        self.mode = "move"

    def protective_stop(self, reason: str = "protective stop") -> None:
        """Fault: protective stop (the arm brakes, the program stops)."""
        with self.lock:
            if self.safety_mode == SafetyMode.PROTECTIVE_STOP:
                return
            self.safety_mode = SafetyMode.PROTECTIVE_STOP
            self._fault_time = time.monotonic()
            self.log(f"protective stop: {reason}", level=1)
            self.stop_program("protective stop", decelerate=False)
            self._brake()

    def unlock_protective_stop(self) -> tuple[bool, str]:
        """Dashboard ``unlock protective stop``: (accepted, reply)."""
        with self.lock:
            if self.safety_mode != SafetyMode.PROTECTIVE_STOP:
                return True, "Protective stop releasing"
            if time.monotonic() - self._fault_time < self.unlock_delay:
                return False, (
                    f"Cannot unlock protective stop until {self.unlock_delay:g}s after occurrence. "
                    "Always inspect cause of protective stop before unlocking"
                )
            self.safety_mode = SafetyMode.NORMAL
            self.log("protective stop released")
            return True, "Protective stop releasing"

    def emergency_stop(self, reason: str = "emergency stop button pressed") -> None:
        """Fault: robot emergency stop (the arm brakes, then power goes off)."""
        with self.lock:
            if self.safety_mode == SafetyMode.ROBOT_EMERGENCY_STOP:
                return
            self.safety_mode = SafetyMode.ROBOT_EMERGENCY_STOP
            self.log(f"emergency stop: {reason}", level=1)
            self.stop_program("emergency stop", decelerate=False)
            self._brake()
            self._power_off_when_stopped = True

    def restart_safety(self) -> None:
        """Answer the dashboard's ``restart safety``: restart the safety system, then power off.

        The safety system restarts after a fault or a violation, the robot is then powered
        off.  An emergency stop stays: it is released on the robot (the button), never from
        the network.
        """
        with self.lock:
            if self.safety_mode in (SafetyMode.ROBOT_EMERGENCY_STOP,
                                    SafetyMode.SYSTEM_EMERGENCY_STOP):  # fmt: skip
                self.log("restart safety: the emergency stop is still pressed; it must be "
                         "released on the robot", level=2)  # fmt: skip
            elif self.safety_mode in (SafetyMode.FAULT, SafetyMode.VIOLATION):
                self.log(f"restart safety: {self.safety_mode.name} cleared")
                self.safety_mode = SafetyMode.NORMAL
            self.power_off()

    def release_emergency_stop(self) -> None:
        """The e-stop button is released: safety NORMAL; power on + brake release to run."""
        with self.lock:
            if self.safety_mode == SafetyMode.ROBOT_EMERGENCY_STOP:
                self.safety_mode = SafetyMode.NORMAL
                self.log("emergency stop released")

    def clear_faults(self) -> None:
        """Back to NORMAL and RUNNING at once (test helper; a real robot needs the steps)."""
        with self.lock:
            self.safety_mode = SafetyMode.NORMAL
            self.robot_mode = RobotMode.RUNNING
            self._power_off_when_stopped = False

