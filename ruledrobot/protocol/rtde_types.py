"""RTDE variable names and their official types (protocol v2).

The table follows Universal Robots' RTDE guide as mirrored by the Universal
Robots Client Library (``src/rtde/data_package.cpp``, whose list marks the
two tool-output inputs ur_rtde uses as "not in official docs") and the names
the ``ur_rtde`` 1.6 client asks for.  Names ur_rtde knows but UR's table does
not (``actual_qdd``, ``actual_moment``) are ``NOT_FOUND``, as on a controller.
Clients decode data packages with their own hard-coded copy of this table, so
every variable must be packed with exactly its official type: a wrong size
silently shifts everything after it.

Names not in the table are answered ``NOT_FOUND`` in a recipe reply, as a real
controller does.
"""

from __future__ import annotations

import re
import struct

__all__ = [
    "INPUT_TYPES",
    "OUTPUT_TYPES",
    "TYPE_FORMATS",
    "TYPE_SIZES",
    "input_type",
    "output_type",
]

#: struct format (big-endian, without the byte-order prefix) of each RTDE type.
TYPE_FORMATS: dict[str, str] = {
    "BOOL": "B",
    "UINT8": "B",
    "UINT32": "I",
    "UINT64": "Q",
    "INT32": "i",
    "DOUBLE": "d",
    "VECTOR3D": "3d",
    "VECTOR6D": "6d",
    "VECTOR6INT32": "6i",
    "VECTOR6UINT32": "6I",
}

#: wire size in bytes of each RTDE type.
TYPE_SIZES: dict[str, int] = {k: struct.calcsize(">" + f) for k, f in TYPE_FORMATS.items()}

_V6 = "VECTOR6D"
_D = "DOUBLE"

#: Controller -> client variables (output recipes).
OUTPUT_TYPES: dict[str, str] = {
    "timestamp": _D,
    "target_q": _V6,
    "target_qd": _V6,
    "target_qdd": _V6,
    "target_current": _V6,
    "target_moment": _V6,
    "actual_q": _V6,
    "actual_qd": _V6,
    "actual_current": _V6,
    "actual_current_window": _V6,
    "actual_current_as_torque": _V6,
    "joint_control_output": _V6,
    "actual_TCP_pose": _V6,
    "actual_TCP_speed": _V6,
    "actual_TCP_force": _V6,
    "target_TCP_pose": _V6,
    "target_TCP_speed": _V6,
    "actual_digital_input_bits": "UINT64",
    "actual_configurable_digital_input_bits": "UINT64",
    "joint_temperatures": _V6,
    "actual_execution_time": _D,
    "robot_mode": "INT32",
    "joint_mode": "VECTOR6INT32",
    "safety_mode": "INT32",
    "safety_status": "INT32",
    "actual_tool_accelerometer": "VECTOR3D",
    "speed_scaling": _D,
    "target_speed_fraction": _D,
    "actual_momentum": _D,
    "actual_main_voltage": _D,
    "actual_robot_voltage": _D,
    "actual_robot_current": _D,
    "actual_joint_voltage": _V6,
    "actual_digital_output_bits": "UINT64",
    "actual_configurable_digital_output_bits": "UINT64",
    "runtime_state": "UINT32",
    "elbow_position": "VECTOR3D",
    "elbow_velocity": "VECTOR3D",
    "robot_status_bits": "UINT32",
    "safety_status_bits": "UINT32",
    "analog_io_types": "UINT32",
    "standard_analog_input0": _D,
    "standard_analog_input1": _D,
    "standard_analog_output0": _D,
    "standard_analog_output1": _D,
    "io_current": _D,
    "euromap67_input_bits": "UINT32",
    "euromap67_output_bits": "UINT32",
    "euromap67_24V_voltage": _D,
    "euromap67_24V_current": _D,
    "tool_mode": "UINT32",
    "tool_analog_input_types": "UINT32",
    "tool_analog_input0": _D,
    "tool_analog_input1": _D,
    "tool_output_voltage": "INT32",
    "tool_output_current": _D,
    "tool_temperature": _D,
    "tool_output_mode": "UINT8",
    "tool_digital_output0_mode": "UINT8",
    "tool_digital_output1_mode": "UINT8",
    "encoder0_raw": "INT32",
    "encoder1_raw": "INT32",
    "tcp_force_scalar": _D,
    "output_bit_registers0_to_31": "UINT32",
    "output_bit_registers32_to_63": "UINT32",
    "input_bit_registers0_to_31": "UINT32",
    "input_bit_registers32_to_63": "UINT32",
    "payload": _D,
    "payload_cog": "VECTOR3D",
    "payload_inertia": _V6,
    "script_control_line": "UINT32",
    "ft_raw_wrench": _V6,
    "joint_position_deviation_ratio": _D,
    "collision_detection_ratio": _D,
    "time_scale_source": "INT32",
    "tcp_offset": _V6,
}

#: Client -> controller variables (input recipes).
INPUT_TYPES: dict[str, str] = {
    "speed_slider_mask": "UINT32",
    "speed_slider_fraction": _D,
    "standard_digital_output_mask": "UINT8",
    "standard_digital_output": "UINT8",
    "configurable_digital_output_mask": "UINT8",
    "configurable_digital_output": "UINT8",
    "tool_digital_output_mask": "UINT8",
    "tool_digital_output": "UINT8",
    "standard_analog_output_mask": "UINT8",
    "standard_analog_output_type": "UINT8",
    "standard_analog_output_0": _D,
    "standard_analog_output_1": _D,
    "input_bit_registers0_to_31": "UINT32",
    "input_bit_registers32_to_63": "UINT32",
    "external_force_torque": _V6,
}

# registers: general purpose 0..47 (int, double), bit registers 64..127 (single bits)
_REGISTER = re.compile(r"^(input|output)_(int|double|bit)_register_(\d{1,3})$")
_REGISTER_TYPES = {"int": "INT32", "double": "DOUBLE", "bit": "BOOL"}


def _register_type(name: str, direction: str) -> str | None:
    m = _REGISTER.match(name)
    if m is None:
        return None
    io, kind, index = m.group(1), m.group(2), int(m.group(3))
    if kind == "bit":
        ok = 64 <= index <= 127
    else:
        ok = 0 <= index <= 47
    if not ok:
        return None
    if direction == "input" and io != "input":
        return None
    return _REGISTER_TYPES[kind]


def output_type(name: str) -> str | None:
    """The type of output variable ``name``, or None (``NOT_FOUND``).

    Input registers may be read back in output recipes, as on a real controller.
    """
    t = OUTPUT_TYPES.get(name)
    return t if t is not None else _register_type(name, "output")


def input_type(name: str) -> str | None:
    """The type of input variable ``name``, or None (``NOT_FOUND``)."""
    t = INPUT_TYPES.get(name)
    return t if t is not None else _register_type(name, "input")
