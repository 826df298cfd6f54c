"""The controller's registers, inputs and outputs: what clients read and write besides
motion (RTDE input/output registers, digital and analog outputs with their log, the
payload, the popup, the RTDE watchdog).

A mixin of :class:`~ruledrobot.ursim.controller.machine.Controller`: it uses the
controller's ``lock``,
``values``, ``time`` and program control, and keeps its own state in the attributes
the controller's constructor sets (``std_do``, ``conf_do``, ``tool_do``,
``analog_out``, ``io_log``, ``_watch_*``).  Thread safety as the controller's: every
method takes ``lock``.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from threading import RLock
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...protocol.modes import RuntimeState

__all__ = ["IOMixin", "int32"]

IN_INT = [f"input_int_register_{i}" for i in range(48)]
IN_DOUBLE = [f"input_double_register_{i}" for i in range(48)]
OUT_INT = [f"output_int_register_{i}" for i in range(48)]
OUT_DOUBLE = [f"output_double_register_{i}" for i in range(48)]


def int32(v: int) -> int:
    """``v`` wrapped to a signed 32-bit integer (RTDE INT32 registers)."""
    v = int(v) & 0xFFFFFFFF
    return v - (1 << 32) if v >= 1 << 31 else v


class IOMixin:
    """Registers, outputs and their log, payload, popup, watchdog (module doc)."""

    lock: RLock
    values: dict[str, Any]
    time: float
    runtime_state: Any
    last_input_names: frozenset[str]
    std_do: int
    conf_do: int
    tool_do: int
    analog_out: list[float]
    io_log: deque[tuple[float, int, int, int, float, float]]
    _io_last: tuple[int, int, int, float, float]
    popup: str | None
    speed_fraction: float

    def in_int(self, i: int) -> int:
        """RTDE input integer register ``i`` (0-47), as a client last set it (0 before)."""
        return self.values.get(IN_INT[i], 0)  # type: ignore[return-value]

    def in_double(self, i: int) -> float:
        """RTDE input double register ``i`` (0-47), as a client last set it (0.0 before)."""
        return self.values.get(IN_DOUBLE[i], 0.0)  # type: ignore[return-value]

    def set_out_int(self, i: int, value: int) -> None:
        """Set RTDE output integer register ``i`` (0-47) to ``value`` wrapped to int32."""
        self.values[OUT_INT[i]] = int32(value)

    def set_out_double(self, i: int, value: float) -> None:
        """Set RTDE output double register ``i`` (0-47)."""
        self.values[OUT_DOUBLE[i]] = float(value)

    def set_out_bit(self, i: int, value: bool) -> None:
        """Set RTDE output bit register ``i`` (0-127); another ``i`` is ignored.

        Bits 0-63 live in the words ``output_bit_registers0_to_31`` and
        ``output_bit_registers32_to_63``, bits 64-127 each in ``output_bit_register_<i>``.
        """
        with self.lock:
            if 64 <= i <= 127:
                self.values[f"output_bit_register_{i}"] = int(value)
            elif 0 <= i <= 63:
                key = "output_bit_registers0_to_31" if i < 32 else "output_bit_registers32_to_63"
                word = int(self.values[key])  # type: ignore[call-overload]
                bit = 1 << (i % 32)
                self.values[key] = (word | bit) if value else (word & ~bit)

    def apply_inputs(self, values: dict[str, object], names: Sequence[str]) -> None:
        """Apply a client's input data package (registers, I/O masks, speed slider)."""
        with self.lock:
            self.values.update(values)
            self.last_input_names = frozenset(names)
            if self._watch_name is not None and self._watch_name in self.last_input_names:
                self._watch_last = self.time
            if "standard_digital_output_mask" in values:
                m = int(values["standard_digital_output_mask"])  # type: ignore[call-overload]
                b = int(values.get("standard_digital_output", 0))  # type: ignore[call-overload]
                self.std_do = (self.std_do & ~m) | (b & m)
            if "configurable_digital_output_mask" in values:
                m = int(values["configurable_digital_output_mask"])  # type: ignore[call-overload]
                b = int(values.get("configurable_digital_output", 0))  # type: ignore[call-overload]
                self.conf_do = (self.conf_do & ~m) | (b & m)
            if "tool_digital_output_mask" in values:
                m = int(values["tool_digital_output_mask"]) & 3  # type: ignore[call-overload]
                b = int(values.get("tool_digital_output", 0))  # type: ignore[call-overload]
                self.tool_do = (self.tool_do & ~m) | (b & m)
            if int(values.get("speed_slider_mask", 0)) & 1:  # type: ignore[call-overload]
                f = float(values.get("speed_slider_fraction", 1.0))  # type: ignore[arg-type]
                self.speed_fraction = min(max(f, 0.0), 1.0)
            if "standard_analog_output_mask" in values:
                m = int(values["standard_analog_output_mask"])  # type: ignore[call-overload]
                for k in (0, 1):
                    if m & (1 << k):
                        x = float(values.get(f"standard_analog_output_{k}", 0.0))  # type: ignore[arg-type]
                        self.analog_out[k] = min(max(x, 0.0), 1.0)
            self._note_io()

    def set_digital_out(self, kind: str, n: int, value: bool) -> None:
        """A digital output.

        ``kind`` ``"standard"`` (pins 0-7), ``"configurable"`` (0-7) or ``"tool"`` (0-1);
        ValueError for another kind or pin."""
        top = {"standard": 7, "configurable": 7, "tool": 1}.get(kind)
        if top is None:
            raise ValueError(f"digital output kind: expected standard, configurable or tool, "
                             f"got {kind!r}")  # fmt: skip
        if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= top:
            raise ValueError(f"{kind} digital output: pin must be 0..{top}, got {n!r}")
        with self.lock:
            bit = 1 << n
            if kind == "configurable":
                self.conf_do = (self.conf_do | bit) if value else (self.conf_do & ~bit)
            elif kind == "tool":
                self.tool_do = (self.tool_do | bit) if value else (self.tool_do & ~bit)
            else:
                self.std_do = (self.std_do | bit) if value else (self.std_do & ~bit)
            self._note_io()

    def set_analog_out(self, n: int, fraction: float) -> None:
        """Standard analog output ``n`` (0-1) to ``fraction`` (0..1 of its range)."""
        if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= 1:
            raise ValueError(f"standard analog output: pin must be 0..1, got {n!r}")
        f = float(fraction)
        if not 0.0 <= f <= 1.0:
            raise ValueError(f"standard analog output {n}: value must be in [0, 1], got {f!r}")
        with self.lock:
            self.analog_out[n] = f
            self._note_io()

    def _note_io(self) -> None:
        """Append the outputs to :attr:`io_log` when they changed (caller holds the lock)."""
        now = (self.std_do, self.conf_do, self.tool_do, self.analog_out[0], self.analog_out[1])
        if now != self._io_last:
            self._io_last = now
            self.io_log.append((self.time, *now))

    def set_payload(self, mass: float | None, cog: ArrayLike | None) -> None:
        """Payload mass [kg] and centre of gravity [m] (flange frame); None keeps the value."""
        with self.lock:
            if mass is not None:
                self.values["payload"] = float(mass)
            if cog is not None:
                self.values["payload_cog"] = tuple(float(x) for x in np.asarray(cog).reshape(3))

    def show_popup(self, text: str) -> None:
        """The pendant shows a popup (a compile error, URScript ``popup``)."""
        with self.lock:
            self.popup = text

    def close_popup(self) -> None:
        """Dashboard ``close popup``."""
        with self.lock:
            self.popup = None

    def set_watchdog(self, name: str, min_frequency: float, action: str = "stop") -> None:
        """URScript ``rtde_set_watchdog``: act when input ``name`` is not updated in time.

        ``action`` is ``"stop"`` (stop the program, the arm brakes), ``"pause"``
        or ``"ignore"``; a frequency <= 0 removes the watchdog.  It ends with
        the program that set it.
        """
        with self.lock:
            if min_frequency <= 0 or action == "ignore":
                self._watch_name = None
                return
            self._watch_name = name
            self._watch_timeout = 1.0 / float(min_frequency)
            self._watch_action = action
            self._watch_last = self.time

    def _check_watchdog(self) -> None:
        if self._watch_name is None or self.runtime_state != RuntimeState.PLAYING:
            return
        silent = self.time - self._watch_last
        if silent > self._watch_timeout:
            name = self._watch_name
            self._watch_name = None
            self.log(f"RTDE watchdog: {name} not updated for {silent:.3f} s", level=1)
            if self._watch_action == "pause":
                self.pause_program()
            else:
                self.stop_program("RTDE watchdog", decelerate=True)

