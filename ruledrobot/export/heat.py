"""Switching the hot wire through the robot's IO, in the three ways a run or a program
does it.

A trajectory's :class:`~ruledrobot.robot.motion.trajectory.Heat` names the output (standard,
configurable or tool digital output, or a standard analog output at a fraction of its
range) and the sample ranges with the heat on.  A trajectory with a ``heat_power`` column
on an analog output in mode ``constant`` or ``constant_kerf`` (docs/kerf.md) sets the
output along the motion instead:
:func:`heat_levels` are its set-points (``heat_power / full_scale``), and
:func:`written_levels` the ones a program or a run writes (where they change by more
than :data:`HEAT_STEP`), and along a servoj motion :func:`servo_levels` (the set-points
as the arm, trailing its command, reaches them).

* :func:`urscript_heat` — the URScript statement (``set_standard_digital_out(0,
  True)`` ...), for exported programs and for the secondary program that turns the
  heat off when a run ended without its client (:func:`heat_off_program`);
* :func:`set_heat_rtde` — the same through ur_rtde's ``RTDEIOInterface`` during a
  streamed run;
* :func:`send_heat_off` — the secondary program above, sent to a controller;
* :func:`heat_from_outputs` — the heat's state read back from a run's recorded outputs,
  :func:`heat_power_from_outputs` its power (an analog output's fraction times its full
  scale), and :func:`motion_power` the power along any motion of the plan (a recording, a
  program's generated motion) for the face error.
"""

from __future__ import annotations

import socket
from typing import Any

import numpy as np

from ..protocol.primary import SECONDARY_PORT
from ..robot.motion.servo import servo_time_constant, servo_track
from ..robot.motion.trajectory import Heat, Trajectory

__all__ = ["HEAT_STEP", "heat_from_outputs", "heat_levels", "heat_off_program",
           "heat_power_from_outputs", "motion_power", "send_heat_off", "servo_levels",
           "set_heat_rtde",
           "urscript_heat", "written_levels"]

#: the smallest change of an analog heat set-point that a program or a run writes, as a
#: fraction of the output's range (0.2 %: the wire's power follows it within 0.2 % of full
#: scale, a few statements per second on a speed ramp)
HEAT_STEP = 0.002


def heat_levels(traj: Trajectory) -> np.ndarray | None:
    """The analog set-point (M,) of each sample of ``traj``, or None.

    ``heat_power / full_scale`` clipped to [0, 1] (:meth:`Heat.ratio`); None unless the
    heat schedules the power
    (:attr:`Heat.schedules_power`: an analog output in mode ``constant`` or
    ``constant_kerf``) and the trajectory has a ``heat_power`` column (otherwise the
    output switches on and off by the heat windows)."""
    heat = traj.meta.heat
    if heat is None or not heat.schedules_power or traj.heat_power is None:
        return None
    return heat.ratio(traj.heat_power)


def written_levels(levels: np.ndarray, step: float = HEAT_STEP) -> np.ndarray:
    """The set-points (M,) as a program or a run writes them.

    A value is written at each sample where the band of width ``step`` changes (zero is
    a band of its own: off and on are always written) and where ``levels`` comes to rest
    (a held value after a change), and held until the next: the smallest set-point of
    the samples it holds for.  So the output is within ``step`` of ``levels`` everywhere,
    never above it (a wire a band hotter than planned where it stands at a corner stop
    would burn), and equal to it where it holds (a ramp ends on its exact value, e.g.
    the threshold)."""
    lv = np.asarray(levels, dtype=np.float64)
    if lv.size == 0:
        return lv.copy()
    band = np.where(lv > 0.0, np.floor(lv / step) + 1.0, 0.0)
    change = np.r_[True, band[1:] != band[:-1]]
    change[1:-1] |= (lv[1:-1] != lv[:-2]) & (lv[1:-1] == lv[2:])
    return np.minimum.reduceat(lv, np.flatnonzero(change))[np.cumsum(change) - 1]


def servo_levels(levels: np.ndarray, dt: float, lookahead: float, gain: float,
                 step: float = HEAT_STEP) -> np.ndarray:  # fmt: skip
    """The set-points (M,) of a servoj motion's samples, set as the arm reaches them.

    ``levels`` (M,), one per control period ``dt`` [s] commanded, passed through the
    servo's tracking law (:func:`~ruledrobot.robot.motion.servo.servo_track` with
    ``lookahead`` [s], ``gain``): the arm trails its command, so a power scheduled for the
    plan's speed, written on the command's clock, heats the wire for a speed it does not
    have yet (docs/kerf.md, "The heat on the robot").  Where the response is within a
    quarter ``step`` of the set-point it tracks, the set-point itself (an exponential
    tail never reaches a threshold it approaches); off (0) where the set-point is off:
    the heat switches off on the command's clock, as it does on a digital output."""
    lv = np.asarray(levels, dtype=np.float64)
    y = servo_track(lv, dt, servo_time_constant(lookahead, gain))
    return np.where((np.abs(y - lv) < 0.25 * step) | (lv <= 0.0), lv, y)


def urscript_heat(heat: Heat, on: bool, value: float | None = None) -> str:
    """The URScript statement that switches ``heat`` on or off (no indent, no newline).

    An analog output goes to ``value`` (a set-point of :func:`heat_levels`) when given,
    else to ``heat.value`` when on and 0 when off."""
    if heat.kind == "analog":
        level = value if value is not None else (heat.value if on else 0.0)
        return f"set_standard_analog_out({heat.index}, {level:.6g})"
    return f"set_{heat.kind}_digital_out({heat.index}, {'True' if on else 'False'})"


def heat_from_outputs(heat: Heat, outputs: np.ndarray) -> np.ndarray:
    """Return (M,) bool: whether ``heat`` is on in recorded outputs ``outputs`` (M, 3).

    The outputs: RTDE's ``actual_digital_output_bits`` (standard 0-7, configurable 8-15,
    tool 16-17) and ``standard_analog_output0/1`` (on above zero).  NaN rows (not read)
    count as off."""
    o = np.asarray(outputs, dtype=float).reshape(-1, 3)
    if heat.kind == "analog":
        return np.nan_to_num(o[:, 1 + heat.index], nan=0.0) > 0.0
    bit = heat.index + {"standard": 0, "configurable": 8, "tool": 16}[heat.kind]
    bits = np.nan_to_num(o[:, 0], nan=0.0).astype(np.int64)
    return ((bits >> bit) & 1).astype(bool)


def heat_power_from_outputs(heat: Heat, outputs: np.ndarray) -> np.ndarray | None:
    """The wire power set-point (M,) [W/m] in recorded outputs (M, 3), or None.

    As :func:`heat_from_outputs` reads them: the analog output's fraction times
    ``heat.full_scale``
    (NaN rows: 0); None unless the heat is an analog output with a full scale."""
    if heat.kind != "analog" or heat.full_scale is None:
        return None
    o = np.asarray(outputs, dtype=float).reshape(-1, 3)
    return np.nan_to_num(o[:, 1 + heat.index], nan=0.0) * heat.full_scale


def motion_power(traj: Trajectory, idx: np.ndarray, power: np.ndarray | None,
                 hot: np.ndarray | None) -> np.ndarray | None:  # fmt: skip
    """The wire's power set-point (R,) [W/m] along a motion of ``traj``, or None.

    The motion (a run's recording, a program's generated motion) is matched to plan
    samples ``idx`` (R,); the power: its
    analog output times the full scale (``power``, :func:`heat_power_from_outputs`) where
    the heat schedules it (:attr:`Heat.schedules_power`), else the plan's ``heat_power`` at
    the matched sample where the output was on (``hot`` (R,); all on when None); None
    without a power model (the cut's constant kerf is judged then)."""
    heat = traj.meta.heat
    if heat is not None and heat.schedules_power and power is not None:
        return np.asarray(power, dtype=float)[: idx.size]
    if traj.heat_power is None:
        return None
    planned = traj.heat_power[idx]
    if heat is None or hot is None:
        return planned
    return np.where(np.asarray(hot, dtype=bool)[: idx.size], planned, 0.0)


def heat_off_program(heat: Heat) -> str:
    """Return a secondary program that turns the heat off.

    A secondary program runs beside whatever program runs and stops nothing.  It is sent to
    the primary/secondary port when a run ends without its client (crash, disconnect),
    because a controller keeps its outputs when a program stops."""
    return f"sec ruledrobot_heat_off():\n  {urscript_heat(heat, False)}\nend\n"


def set_heat_rtde(io: Any, heat: Heat, on: bool, value: float | None = None) -> bool:
    """Switch ``heat`` through an ``rtde_io.RTDEIOInterface``; ur_rtde's return value.

    An analog output goes to ``value`` when given, as :func:`urscript_heat`."""
    n = heat.index
    if heat.kind == "standard":
        return bool(io.setStandardDigitalOut(n, on))
    if heat.kind == "configurable":
        return bool(io.setConfigurableDigitalOut(n, on))
    if heat.kind == "tool":
        return bool(io.setToolDigitalOut(n, on))
    level = value if value is not None else (heat.value if on else 0.0)
    return bool(io.setAnalogOutputCurrent(n, float(level)))


def send_heat_off(host: str, heat: Heat, timeout: float = 2.0) -> str:
    """Send :func:`heat_off_program` to the controller's secondary interface.

    Returns what happened in words (never raises: it runs on the way out of a failed run)."""
    try:
        with socket.create_connection((host, SECONDARY_PORT), timeout=timeout) as sock:
            sock.sendall(heat_off_program(heat).encode())
        return f"heat ({heat.output}) switched off through the secondary interface"
    except OSError as exc:
        return (f"heat ({heat.output}): could not reach the secondary interface of {host} to "
                f"switch it off ({exc}): CHECK THE WIRE")
