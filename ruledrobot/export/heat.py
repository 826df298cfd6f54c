"""Switching the hot wire through the robot's IO, in the three ways a run or a program
does it.

A trajectory's :class:`~ruledrobot.robot.motion.trajectory.Heat` names the output (standard,
configurable or tool digital output, or a standard analog output at a fraction of its
range) and the sample ranges with the heat on.

* :func:`urscript_heat` — the URScript statement (``set_standard_digital_out(0,
  True)`` ...), for exported programs and for the secondary program that turns the
  heat off when a run ended without its client (:func:`heat_off_program`);
* :func:`set_heat_rtde` — the same through ur_rtde's ``RTDEIOInterface`` during a
  streamed run;
* :func:`send_heat_off` — the secondary program above, sent to a controller;
* :func:`heat_from_outputs` — the heat's state read back from a run's recorded outputs.
"""

from __future__ import annotations

import socket
from typing import Any

import numpy as np

from ..protocol.primary import SECONDARY_PORT
from ..robot.motion.trajectory import Heat

__all__ = ["heat_from_outputs", "heat_off_program", "send_heat_off", "set_heat_rtde",
           "urscript_heat"]


def urscript_heat(heat: Heat, on: bool) -> str:
    """The URScript statement that switches ``heat`` on or off (no indent, no newline)."""
    if heat.kind == "analog":
        value = heat.value if on else 0.0
        return f"set_standard_analog_out({heat.index}, {value:.6g})"
    return f"set_{heat.kind}_digital_out({heat.index}, {'True' if on else 'False'})"


def heat_from_outputs(heat: Heat, outputs: np.ndarray) -> np.ndarray:
    """(M,) bool: ``heat`` on in recorded outputs ``outputs`` (M, 3): RTDE's
    ``actual_digital_output_bits`` (standard 0-7, configurable 8-15, tool 16-17) and
    ``standard_analog_output0/1`` (on above zero).  NaN rows (not read) count as off."""
    o = np.asarray(outputs, dtype=float).reshape(-1, 3)
    if heat.kind == "analog":
        return np.nan_to_num(o[:, 1 + heat.index], nan=0.0) > 0.0
    bit = heat.index + {"standard": 0, "configurable": 8, "tool": 16}[heat.kind]
    bits = np.nan_to_num(o[:, 0], nan=0.0).astype(np.int64)
    return ((bits >> bit) & 1).astype(bool)


def heat_off_program(heat: Heat) -> str:
    """A secondary program (runs beside whatever program runs, stops nothing) that turns
    the heat off: sent to the primary/secondary port when a run ends without its client
    (crash, disconnect), because a controller keeps its outputs when a program stops."""
    return f"sec ruledrobot_heat_off():\n  {urscript_heat(heat, False)}\nend\n"


def set_heat_rtde(io: Any, heat: Heat, on: bool) -> bool:
    """Switch ``heat`` through an ``rtde_io.RTDEIOInterface``; ur_rtde's return value."""
    n = heat.index
    if heat.kind == "standard":
        return bool(io.setStandardDigitalOut(n, on))
    if heat.kind == "configurable":
        return bool(io.setConfigurableDigitalOut(n, on))
    if heat.kind == "tool":
        return bool(io.setToolDigitalOut(n, on))
    return bool(io.setAnalogOutputCurrent(n, heat.value if on else 0.0))


def send_heat_off(host: str, heat: Heat, timeout: float = 2.0) -> str:
    """Send :func:`heat_off_program` to the controller's secondary interface; returns what
    happened in words (never raises: it runs on the way out of a failed run)."""
    try:
        with socket.create_connection((host, SECONDARY_PORT), timeout=timeout) as sock:
            sock.sendall(heat_off_program(heat).encode())
        return f"heat ({heat.output}) switched off through the secondary interface"
    except OSError as exc:
        return (f"heat ({heat.output}): could not reach the secondary interface of {host} to "
                f"switch it off ({exc}): CHECK THE WIRE")
