"""A UR controller emulator that the real ``ur_rtde`` client can drive.

``Emulator(host, model, calibration=None)`` serves RTDE (30004), the dashboard
(29999), the script port (30003) and the primary and secondary client
interfaces (30001, 30002) on a loopback address, with a simulated arm behind
them (:class:`KinematicBackend` by default; any :class:`ArmBackend` plugs in);
with a calibration it is that robot (its KinematicsInfo, its FK and IK).
See ``docs/rtde.md`` for the protocol coverage, faults and timing.

Sub-packages that follow a request through the emulator: ``ports/`` (the servers:
``rtde``, ``dashboard``, ``script``, ``primary``, on ``tcp``), ``script/`` (URScript:
``program`` parsing, ``functions``, the standalone ``runner``, ur_rtde's control-script
register protocol ``handshake``, and ``host``, what a running program sees of the
controller), ``controller/`` (the state machine ``machine``, its ``registers`` and
``safety``), ``arm/`` (the ``backend`` interface and kinematic arm, the MuJoCo
``physics`` arm, the ``emulated`` catalogue model and its KinematicsInfo); on top
``server`` (:class:`ThreadedEmulator`, :func:`serve`), ``process`` (:class:`Emulator`:
the emulator in a child process, so that a ur_rtde client in this process does not
deadlock it), ``clock`` (:class:`ClockStats`) and ``faults``.  The UR vocabulary
(modes, RTDE types and packets, the primary interface's packets) is
:mod:`ruledrobot.protocol`, shared with the runner; the trajectory generator
(moveJ/moveL/movep with blends, stops) and the per-tick kinematics are the robot
layer's :mod:`ruledrobot.robot.motion.ur_motion` and
:mod:`ruledrobot.robot.motion.arm_kinematics`, shared with the verification of
exported programs.
"""

from __future__ import annotations

from ..protocol.modes import JointMode, RobotMode, RuntimeState, SafetyMode, SafetyStatusBit
from .arm.backend import HARDWARE_ACCELERATION, ArmBackend, ArmState, KinematicBackend
from .clock import ClockStats
from .controller.machine import DEFAULT_Q, Controller
from .process import EMBEDDED_HOST, Emulator, embedded_emulator
from .script.handshake import Command
from .server import ThreadedEmulator, serve

__all__ = [
    "DEFAULT_Q",
    "EMBEDDED_HOST",
    "HARDWARE_ACCELERATION",
    "ArmBackend",
    "ArmState",
    "ClockStats",
    "Command",
    "Controller",
    "Emulator",
    "JointMode",
    "KinematicBackend",
    "RobotMode",
    "RuntimeState",
    "SafetyMode",
    "SafetyStatusBit",
    "ThreadedEmulator",
    "embedded_emulator",
    "serve",
]
