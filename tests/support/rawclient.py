"""A minimal RTDE client in pure Python (sockets only), for tests and benchmarks.

It speaks protocol v2 like ur_rtde does (one reply per setup request) and
decodes data packages with the official types, so it can count every
package and time its arrival, which ur_rtde (it keeps only the newest
package) cannot.  It holds no GIL in C++, so it may share a process with a
:class:`~.server.ThreadedEmulator`.
"""

from __future__ import annotations

import socket
import struct
import time
from typing import Any

from ruledrobot.protocol.rtde import (
    CONTROL_PACKAGE_PAUSE,
    CONTROL_PACKAGE_SETUP_INPUTS,
    CONTROL_PACKAGE_SETUP_OUTPUTS,
    CONTROL_PACKAGE_START,
    DATA_PACKAGE,
    GET_URCONTROL_VERSION,
    REQUEST_PROTOCOL_VERSION,
    InputRecipe,
    PacketFramer,
    pack_packet,
)
from ruledrobot.protocol.rtde_types import TYPE_FORMATS

__all__ = ["UR_RTDE_RECEIVE_RECIPE", "RawRTDEClient"]

#: the 58 outputs ur_rtde 1.6.5's RTDEReceiveInterface asks a 5.11 controller for
UR_RTDE_RECEIVE_RECIPE: tuple[str, ...] = (
    "timestamp", "target_q", "target_qd", "target_qdd", "target_current", "target_moment",
    "actual_q", "actual_qd", "actual_current", "joint_control_output", "actual_TCP_pose",
    "actual_TCP_speed", "actual_TCP_force", "target_TCP_pose", "target_TCP_speed",
    "actual_digital_input_bits", "joint_temperatures", "actual_execution_time", "robot_mode",
    "joint_mode", "safety_mode", "actual_tool_accelerometer", "speed_scaling",
    "target_speed_fraction", "actual_momentum", "actual_main_voltage", "actual_robot_voltage",
    "actual_robot_current", "actual_joint_voltage", "actual_digital_output_bits",
    "runtime_state", "standard_analog_input0", "standard_analog_input1",
    "standard_analog_output0", "standard_analog_output1", "robot_status_bits",
    "safety_status_bits", "ft_raw_wrench", "payload", "payload_cog", "payload_inertia",
    "output_int_register_2",
    *(f"output_int_register_{i}" for i in range(12, 20)),
    *(f"output_double_register_{i}" for i in range(12, 20)),
)  # fmt: skip


class RawRTDEClient:
    """One RTDE connection: negotiate, set up recipes, start, read or write data packages."""

    def __init__(self, host: str, port: int = 30004, timeout: float = 5.0) -> None:
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.framer = PacketFramer()
        self.output_names: list[str] = []
        self.output_types: list[str] = []
        self._struct: struct.Struct | None = None
        self._counts: list[int] = []
        self.inputs: dict[int, InputRecipe] = {}

    def close(self) -> None:
        try:
            self.sock.close()
        except OSError:
            pass

    def __enter__(self) -> RawRTDEClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------ low level

    def send(self, kind: int, payload: bytes = b"") -> None:
        self.sock.sendall(pack_packet(kind, payload))

    def receive(self, timeout: float = 5.0) -> tuple[int, bytes]:
        """The next packet (type, payload); TimeoutError after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while True:
            for pkt in self.framer.packets():
                return pkt
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("no RTDE packet in time")
            self.sock.settimeout(left)
            data = self.sock.recv(65536)
            if not data:
                raise ConnectionError("the controller closed the connection")
            self.framer.feed(data)

    def request(self, kind: int, payload: bytes = b"", timeout: float = 5.0) -> bytes:
        """Send a setup request and return the payload of its reply (skipping data)."""
        self.send(kind, payload)
        while True:
            k, p = self.receive(timeout)
            if k == kind:
                return p

    # ------------------------------------------------------------ protocol

    def negotiate(self, version: int = 2) -> bool:
        return self.request(REQUEST_PROTOCOL_VERSION, struct.pack(">H", version)) == b"\x01"

    def controller_version(self) -> tuple[int, int, int, int]:
        return struct.unpack(">IIII", self.request(GET_URCONTROL_VERSION))  # type: ignore[return-value]

    def setup_outputs(
        self, names: list[str] | tuple[str, ...], frequency: float = 500.0
    ) -> list[str]:
        """Output recipe; returns the types (``NOT_FOUND`` for unknown names)."""
        payload = struct.pack(">d", frequency) + ",".join(names).encode() + b","
        reply = self.request(CONTROL_PACKAGE_SETUP_OUTPUTS, payload)
        types = reply[1:].decode().split(",")
        self.output_names = list(names)
        self.output_types = types
        if "NOT_FOUND" not in types:
            self._struct = struct.Struct(">B" + "".join(TYPE_FORMATS[t] for t in types))
            self._counts = [int(TYPE_FORMATS[t][0]) if TYPE_FORMATS[t][0].isdigit() else 1
                            for t in types]  # fmt: skip
        return types

    def setup_inputs(self, names: list[str] | tuple[str, ...]) -> tuple[int, list[str]]:
        """Input recipe; returns (recipe id, types)."""
        reply = self.request(CONTROL_PACKAGE_SETUP_INPUTS, ",".join(names).encode() + b",")
        rid = reply[0]
        types = reply[1:].decode().split(",")
        if rid:
            self.inputs[rid] = InputRecipe(rid, list(names))
        return rid, types

    def start(self) -> bool:
        return self.request(CONTROL_PACKAGE_START) == b"\x01"

    def pause(self) -> bool:
        return self.request(CONTROL_PACKAGE_PAUSE) == b"\x01"

    def send_inputs(self, recipe_id: int, values: dict[str, Any]) -> None:
        """A data package for input recipe ``recipe_id`` (all its fields in ``values``)."""
        recipe = self.inputs[recipe_id]
        flat: list = []
        for name, typ in zip(recipe.names, recipe.types, strict=True):
            v = values[name]
            if typ.startswith("VECTOR"):
                flat.extend(v)
            else:
                flat.append(v)
        fmt = ">B" + "".join(TYPE_FORMATS[t] for t in recipe.types)
        self.send(DATA_PACKAGE, struct.pack(fmt, recipe_id, *flat))

    def decode(self, payload: bytes) -> dict[str, Any]:
        """Decode a data package payload with the output recipe."""
        if self._struct is None:
            raise ValueError("no valid output recipe")
        flat = self._struct.unpack(payload)
        out: dict[str, Any] = {}
        i = 1
        for name, n in zip(self.output_names, self._counts, strict=True):
            out[name] = flat[i] if n == 1 else flat[i : i + n]
            i += n
        return out

    def read_data(self, timeout: float = 5.0) -> dict[str, Any]:
        """The next data package, decoded."""
        while True:
            k, p = self.receive(timeout)
            if k == DATA_PACKAGE:
                return self.decode(p)
