"""The dashboard server (port 29999): newline-terminated text commands.

On connect the server greets with ``Connected: Universal Robots Dashboard
Server`` (ur_rtde consumes one line as the greeting).  Replies use the
wording of PolyScope 5, which clients match literally (``stop`` must answer
exactly ``Stopped``; ``get serial number`` digits only).
"""

from __future__ import annotations

import logging
from collections import deque

from ...protocol.modes import RuntimeState
from ..controller.machine import Controller
from .tcp import Connection, TcpServer

__all__ = ["GREETING", "DashboardServer"]

log = logging.getLogger("ruledrobot.ursim")

GREETING = "Connected: Universal Robots Dashboard Server"
_MAX_LINE = 4096


class DashboardServer(TcpServer):
    """Answers dashboard commands from the controller's state."""

    name = "dashboard"

    def __init__(
        self,
        host: str,
        port: int,
        controller: Controller,
        *,
        version: tuple[int, int, int, int],
        serial_number: str,
        **limits: float,
    ) -> None:
        super().__init__(host, port, **limits)  # type: ignore[arg-type]
        self.controller = controller
        self.version = version
        self.serial_number = serial_number
        #: the last commands received (shortened), for tests and diagnostics
        self.commands: deque[str] = deque(maxlen=100)

    def handle(self, conn: Connection) -> None:
        """Greet, then answer each command line (:meth:`answer`) until the client leaves.

        Lines end with a newline; empty ones get no reply.  ``quit`` or ``close`` ends the
        connection after its reply; a line longer than 4096 bytes closes it (a ValueError the server
        logs).
        """
        if not conn.sendall((GREETING + "\n").encode()):
            return
        buf = bytearray()

        def on_data(data: bytes) -> None:
            buf.extend(data)
            while True:
                nl = buf.find(b"\n")
                if nl < 0:
                    if len(buf) > _MAX_LINE:
                        raise ValueError(f"dashboard line longer than {_MAX_LINE} bytes")
                    return
                line = bytes(buf[:nl]).decode("utf-8", "replace").strip()
                del buf[: nl + 1]
                if not line:
                    continue
                reply = self.answer(line)
                if not conn.sendall((reply + "\n").encode()):
                    return
                if reply == "Disconnected":
                    conn.close()
                    return

        self.recv_loop(conn, on_data)

    def answer(self, line: str) -> str:
        """The reply to one command line."""
        self.commands.append(line[:200])
        c = self.controller
        cmd = line.strip()
        low = cmd.lower()
        major, minor, bugfix, build = self.version
        if low == "polyscopeversion":
            return f"URSoftware {major}.{minor}.{bugfix}.{build} (ruledrobot emulator)"
        if low == "version":
            return f"Version: {major}.{minor}.{bugfix}.{build}"
        if low == "get serial number":
            return self.serial_number
        if low == "get robot model":
            name = c.model.name.upper()
            return name[:-1] if name.endswith("E") else name
        if low == "is in remote control":
            return "true"
        if low == "robotmode":
            return f"Robotmode: {c.robot_mode.name}"
        if low == "safetymode":
            return f"Safetymode: {c.safety_mode.name}"
        if low == "safetystatus":
            return f"Safetystatus: {c.safety_mode.name}"
        if low == "power on":
            return "Powering on" if c.power_on() else "Failed to execute: power on"
        if low == "power off":
            c.power_off()
            return "Powering off"
        if low == "brake release":
            return "Brake releasing" if c.brake_release() else "Failed to execute: brake release"
        if low == "unlock protective stop":
            return c.unlock_protective_stop()[1]
        if low == "close safety popup":
            return "closing safety popup"
        if low == "close popup":
            c.close_popup()
            return "closing popup"
        if low.startswith("popup"):
            c.show_popup(cmd[5:].strip())
            return "showing popup"
        if low.startswith("addtolog"):
            c.log(f"dashboard: {cmd[8:].strip()}")
            return "Added log message"
        if low == "load" or low.startswith("load "):
            path = cmd[5:].strip()
            if path.endswith(".installation"):
                if c.program_path(path) is None:
                    return f"File not found: {path}"
                c.log(f"dashboard: installation {path} loaded (no effect in the emulator)")
                return f"Loading installation: {path}"
            result = c.load(path)
            if result == "ok":
                return f"Loading program: {path}"
            if result == "error":
                return f"Error while loading program: {path}"
            return f"File not found: {path}"
        if low == "get loaded program":
            return (
                f"Loaded program: {c.loaded_program}" if c.loaded_program else "No program loaded"
            )
        if low == "play":
            return "Starting program" if c.play() else "Failed to execute: play"
        if low == "pause":
            return "Pausing program" if c.pause_program() else "Failed to execute: pause"
        if low == "stop":
            c.stop_program("dashboard stop", decelerate=True)
            return "Stopped"
        if low == "running":
            playing = c.runtime_state == RuntimeState.PLAYING
            return f"Program running: {'true' if playing else 'false'}"
        if low == "programstate":
            name = (c.program.name if c.program else "") or "<unnamed>"
            return f"{c.runtime_state.name} {name}"
        if low == "isprogramsaved":
            name = (c.program.name if c.program else "") or "<unnamed>"
            return f"true {name}"
        if low == "restart safety":
            c.restart_safety()
            return "Restarting safety"
        if low == "get operational mode":
            return "NONE"
        if low.startswith("set operational mode"):
            return f"Operational mode '{cmd[20:].strip()}' is set"
        if low == "clear operational mode":
            return "No longer controlling the operational mode. "
        if low.startswith("setuserrole"):
            return f"Setting user role: {cmd[11:].strip()}"
        if low == "shutdown":
            return "Shutting down"
        if low in ("quit", "close"):
            return "Disconnected"
        return f"could not understand: '{cmd}'"
