"""The primary and secondary client interfaces (ports 30001, 30002): robot state at 10 Hz.

A UR controller serves its state to any client on these ports: on connection a
*version message* (the controller software version, the one the dashboard
reports), then a *robot-state message* at once and every 100 ms.  The emulator's
robot-state message holds two sub-packages (layouts in
:mod:`ruledrobot.protocol.primary`):

* robot mode data (0): the controller time [us], power, emergency and
  protective stop, program running / paused, robot mode, control mode 0
  (position), the speed slider and speed scaling; "real robot connected /
  enabled" are false (an emulator, as URSim in simulation);
* KinematicsInfo (5): the DH table the emulator's kinematics use, bit for bit
  (a calibration's effective table with its checksums and status, or the
  nominal table with checksums 0 and status 2 "linearised").

Both ports also take URScript, as on a controller: each complete program goes
to the controller exactly as on the script port (30003).  The primary port of
a real controller sends other robot messages too (key, text, error code,
runtime exception); the emulator sends none of them.

Bounds, as for RTDE: sockets are non-blocking (no send ever waits), the kernel
send buffer is small (:data:`SEND_BUFFER`), connections with queued bytes are
written to only when one ``poll()`` says their socket takes data, and a
connection whose queue passes :data:`MAX_BACKLOG` is closed by its own thread.
The messages are built and sent by one publisher thread (:class:`PrimaryPublisher`)
that never takes the controller's lock, and one thread per server reads every
client (``single_thread``: no thread per connection): a slow, silent or closing
client costs only itself and never touches the controller clock.  A connection is idle (and
may be evicted when the server is full) once it has neither sent anything nor
taken any data for ``idle_timeout`` seconds.
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
import time
from collections.abc import Callable, Sequence

from ...protocol.modes import RobotMode, RuntimeState, SafetyMode
from ...protocol.primary import (
    KinematicsInfo,
    RobotModeData,
    Version,
    kinematics_info_subpackage,
    robot_mode_subpackage,
    robot_state_message,
    version_message,
)
from ..controller.machine import Controller
from .script import ProgramReceiver
from .tcp import Connection, QueuedConnection, TcpServer, writable_fds

__all__ = [
    "MAX_BACKLOG",
    "PUBLISH_PERIOD",
    "SEND_BUFFER",
    "PrimaryConnection",
    "PrimaryPublisher",
    "PrimaryServer",
    "robot_state",
]

log = logging.getLogger("ruledrobot.ursim")

#: seconds between robot-state messages (10 Hz, as a controller sends them)
PUBLISH_PERIOD = 0.1
#: bytes queued for a client beyond which it is disconnected: about 20 s of messages
#: after the kernel buffers are full
MAX_BACKLOG = 64 * 1024
#: kernel send buffer of a primary connection [bytes] (Linux doubles it)
SEND_BUFFER = 16 * 1024
#: the version message's project name, as a controller sends it
PROJECT = "URControl"

_E_STOPS = (SafetyMode.ROBOT_EMERGENCY_STOP, SafetyMode.SYSTEM_EMERGENCY_STOP)


class PrimaryConnection(QueuedConnection):
    """One client of the primary or secondary interface."""

    kind = "primary"
    programs: ProgramReceiver | None = None

    def idle_for(self, now: float) -> float:
        """Seconds since the client last sent anything or took any data."""
        return 0.0 if self.broken else now - max(self.last_rx, self.last_tx)


class PrimaryServer(TcpServer):
    """The primary (30001) or secondary (30002) interface of a :class:`Controller`.

    ``hello()`` gives the bytes a new connection gets first (the version message and
    the current state);
    :meth:`publish` (the publisher thread) sends a robot-state message to every
    connection.
    """

    nonblocking = True
    single_thread = True  # one reader thread for all clients: they mostly listen

    def __init__(
        self,
        host: str,
        port: int,
        controller: Controller,
        hello: Callable[[], bytes],
        *,
        name: str = "primary",
        max_backlog: int = MAX_BACKLOG,
        **limits: float,
    ) -> None:
        super().__init__(host, port, **limits)  # type: ignore[arg-type]
        self.name = name
        self.controller = controller
        self.hello = hello
        self.max_backlog = int(max_backlog)
        self.messages = 0  # robot-state messages queued, all connections
        self.dropped = 0  # connections closed because they did not read
        self.programs_received = 0

    def make_connection(self, sock: socket.socket, addr: tuple) -> Connection:
        """A :class:`PrimaryConnection` with a small send buffer and ``hello()`` already queued.

        The kernel send buffer is :data:`SEND_BUFFER`; the greeting (version message, then the
        current robot state) is queued before the publisher can send to the connection.
        """
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)
        conn = PrimaryConnection(sock, addr)
        conn.kind = self.name
        # before the connection is registered (the publisher cannot send to it yet): the
        # version message first, and the state at once (a client reading the kinematics
        # need not wait for the next period)
        conn.push(self.hello(), self.max_backlog)
        return conn

    def on_data(self, conn: Connection, data: bytes) -> None:
        """URScript from a client: each complete program goes to the controller."""
        assert isinstance(conn, PrimaryConnection)
        if conn.programs is None:
            conn.programs = ProgramReceiver(self.controller, self._received)
        try:
            conn.programs.feed(data)
        except ValueError as exc:  # beyond MAX_PROGRAM_BYTES / MAX_LINE_BYTES
            self.controller.log(f"{exc}: refused, connection from {conn.peer} closed", level=1)
            conn.close()

    def _received(self, text: str) -> None:
        self.programs_received += 1

    def publish(self, message: bytes) -> int:
        """Queue ``message`` for every connection, never blocking; returns how many."""
        conns = [c for c in self.connections()
                 if isinstance(c, PrimaryConnection) and not c.closed and not c.broken]  # fmt: skip
        writable = writable_fds([c for c in conns if c.backlog])
        for conn in conns:
            try:
                conn.push(message, self.max_backlog, not conn.backlog or
                          conn.sock.fileno() in writable)  # fmt: skip
            except Exception as exc:  # this connection only
                log.warning("%s: closing %s: %s", self.name, conn.peer, exc)
                conn.close()
            if conn.broken:  # it did not read (or its socket failed): the reader closes it
                self.dropped += 1
                self._wakeup()
        self.messages += len(conns)
        return len(conns)


def robot_state(ctrl: Controller, kinematics: bytes, reserved: bool = True) -> bytes:
    """The robot-state message of ``ctrl`` now.

    Robot mode data and ``kinematics`` (the KinematicsInfo sub-package). Reads the controller
    without its lock (single attribute reads; the values are at most one period old)."""
    robot_mode = ctrl.robot_mode
    safety = ctrl.safety_mode
    runtime = ctrl.runtime_state
    values = ctrl.values
    mode = RobotModeData(
        timestamp=round(ctrl.time * 1e6),
        real_robot_connected=False,
        real_robot_enabled=False,
        power_on=robot_mode >= RobotMode.POWER_ON,
        emergency_stopped=safety in _E_STOPS,
        protective_stopped=safety == SafetyMode.PROTECTIVE_STOP,
        program_running=runtime == RuntimeState.PLAYING,
        program_paused=runtime == RuntimeState.PAUSED,
        robot_mode=int(robot_mode),
        control_mode=0,
        target_speed_fraction=float(values.get("target_speed_fraction", 1.0)),  # type: ignore[arg-type]
        speed_scaling=float(values.get("speed_scaling", 1.0)),  # type: ignore[arg-type]
        target_speed_fraction_limit=1.0,
    )
    return robot_state_message([robot_mode_subpackage(mode, reserved=reserved), kinematics])


class PrimaryPublisher:
    """The thread that sends a robot-state message to every primary/secondary client.

    Every :data:`PUBLISH_PERIOD` s (an absolute schedule; a late wake-up skips ahead, it
    never sends a burst).  Nothing is sent while ``frozen`` is set.
    """

    def __init__(
        self,
        controller: Controller,
        servers: Sequence[PrimaryServer],
        kinematics: KinematicsInfo,
        version: tuple[int, int, int, int],
        frozen: threading.Event,
        period: float = PUBLISH_PERIOD,
    ) -> None:
        self.controller = controller
        self.servers = tuple(servers)
        self.kinematics = kinematics
        self._kin = kinematics_info_subpackage(kinematics)
        self.version = Version(PROJECT, *version, date="ruledrobot emulator")
        self._reserved = self.version.major >= 5  # 5.x robot mode data has a reserved byte
        self.frozen = frozen
        self.period = float(period)
        self.sent = 0  # messages built
        self.errors = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def hello(self) -> bytes:
        """What a new connection gets first.

        The version message (timestamp: the controller time [us]) and the current robot-state
        message."""
        return version_message(self.version, round(self.controller.time * 1e6)) + self.message()

    def message(self) -> bytes:
        """The robot-state message now (:func:`robot_state`: robot mode data and KinematicsInfo)."""
        return robot_state(self.controller, self._kin, self._reserved)

    def start(self) -> None:
        """Start the publisher thread (a daemon)."""
        self._thread = threading.Thread(target=self._run, name="emu-primary-publish", daemon=True)
        self._thread.start()

    def close(self, timeout: float = 1.0) -> None:
        """Stop the publisher thread; wait up to ``timeout`` [s] for it to end."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def _run(self) -> None:
        next_t = time.monotonic()
        while not self._stop.is_set():
            if not self.frozen.is_set():
                try:
                    msg = self.message()
                    self.sent += 1
                    for srv in self.servers:
                        srv.publish(msg)
                except Exception:  # never let one message end the stream
                    self.errors += 1
                    if self.errors & (self.errors - 1) == 0:
                        log.exception("primary interface: publishing failed (%d times so far)",
                                      self.errors)  # fmt: skip
            next_t += self.period
            now = time.monotonic()
            if next_t < now:  # late (a stall): skip ahead instead of sending a burst
                next_t = now + self.period
            self._stop.wait(next_t - now)
