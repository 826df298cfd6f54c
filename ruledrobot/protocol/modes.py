"""Controller state enumerations, with the values UR publishes over RTDE."""

from __future__ import annotations

from enum import IntEnum

__all__ = ["JointMode", "RobotMode", "RuntimeState", "SafetyMode", "SafetyStatusBit"]


class RobotMode(IntEnum):
    """``robot_mode`` (RTDE INT32; dashboard ``robotmode``)."""

    NO_CONTROLLER = -1
    DISCONNECTED = 0
    CONFIRM_SAFETY = 1
    BOOTING = 2
    POWER_OFF = 3
    POWER_ON = 4
    IDLE = 5
    BACKDRIVE = 6
    RUNNING = 7
    UPDATING_FIRMWARE = 8


class SafetyMode(IntEnum):
    """``safety_mode`` (RTDE INT32; dashboard ``safetymode``)."""

    NORMAL = 1
    REDUCED = 2
    PROTECTIVE_STOP = 3
    RECOVERY = 4
    SAFEGUARD_STOP = 5
    SYSTEM_EMERGENCY_STOP = 6
    ROBOT_EMERGENCY_STOP = 7
    VIOLATION = 8
    FAULT = 9
    VALIDATE_JOINT_ID = 10
    UNDEFINED_SAFETY_MODE = 11
    AUTOMATIC_MODE_SAFEGUARD_STOP = 12
    SYSTEM_THREE_POSITION_ENABLING_STOP = 13


class SafetyStatusBit(IntEnum):
    """Bit numbers of ``safety_status_bits`` (RTDE UINT32)."""

    NORMAL_MODE = 0
    REDUCED_MODE = 1
    PROTECTIVE_STOPPED = 2
    RECOVERY_MODE = 3
    SAFEGUARD_STOPPED = 4
    SYSTEM_EMERGENCY_STOPPED = 5
    ROBOT_EMERGENCY_STOPPED = 6
    EMERGENCY_STOPPED = 7
    VIOLATION = 8
    FAULT = 9
    STOPPED_DUE_TO_SAFETY = 10


class RuntimeState(IntEnum):
    """``runtime_state`` (RTDE UINT32): the program's state."""

    STOPPING = 0
    STOPPED = 1
    PLAYING = 2
    PAUSING = 3
    PAUSED = 4
    RESUMING = 5


class JointMode(IntEnum):
    """``joint_mode`` entries (RTDE VECTOR6INT32)."""

    SHUTTING_DOWN = 236
    PART_D_CALIBRATION = 237
    BACKDRIVE = 238
    POWER_OFF = 239
    NOT_RESPONDING = 245
    MOTOR_INITIALISATION = 246
    BOOTING = 247
    BOOTLOADER = 249
    FAULT = 252
    RUNNING = 253
    IDLE = 255
