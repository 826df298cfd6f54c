"""The script port (30003): receives URScript programs; sends nothing back.

ur_rtde keeps this connection open for the whole session and writes its
control script (and re-uploads for path moves) as raw text.  A real
controller streams realtime-interface data here, which ur_rtde never reads;
the emulator stays silent.  Each complete program (see
:class:`~ruledrobot.ursim.script.program.ProgramSplitter`) goes to the controller, where it
replaces the running one.  A program beyond
:data:`~ruledrobot.ursim.script.program.MAX_PROGRAM_BYTES` (8 MiB) or a line beyond
:data:`~ruledrobot.ursim.script.program.MAX_LINE_BYTES` (64 KiB) is refused: logged at error level,
the connection closed (the stream cannot be resynchronised).
"""

from __future__ import annotations

import codecs
import logging
from collections.abc import Callable

from ..controller.machine import Controller
from ..script.program import ProgramSplitter
from .tcp import Connection, TcpServer

__all__ = ["ProgramReceiver", "ScriptPortServer", "receive_programs"]

log = logging.getLogger("ruledrobot.ursim")


class ScriptPortServer(TcpServer):
    """Feeds programs received on ``port`` to the controller."""

    name = "script"

    def __init__(self, host: str, port: int, controller: Controller, **limits: float) -> None:
        super().__init__(host, port, **limits)  # type: ignore[arg-type]
        self.controller = controller
        self.programs_received = 0
        self.last_program: str = ""

    def handle(self, conn: Connection) -> None:
        """Hand ``conn``'s URScript to the controller program by program, counting them.

        :func:`receive_programs`; ``programs_received`` and ``last_program`` (its first 4096
        characters) record what arrived.
        """
        def received(text: str) -> None:
            self.programs_received += 1
            self.last_program = text[:4096]

        receive_programs(self, conn, self.controller, received)


class ProgramReceiver:
    """The receiver that cuts one connection's URScript into programs for the controller.

    ``received(text)`` is called first.  :meth:`feed` raises ValueError beyond
    :data:`~ruledrobot.ursim.script.program.MAX_PROGRAM_BYTES` or
    :data:`~ruledrobot.ursim.script.program.MAX_LINE_BYTES` (the connection must then close:
    the stream cannot be resynchronised).
    """

    def __init__(
        self, controller: Controller, received: Callable[[str], None] | None = None
    ) -> None:
        self.controller = controller
        self.received = received
        self._splitter = ProgramSplitter()
        self._decoder = codecs.getincrementaldecoder("utf-8")(errors="replace")

    def feed(self, data: bytes) -> None:
        """Decode ``data`` and hand each program it completes to the controller.

        UTF-8, undecodable bytes replaced; a character cut between two chunks waits for the next.
        Raises ValueError beyond the size bounds (see the class).
        """
        for text in self._splitter.feed(self._decoder.decode(data)):
            if self.received is not None:
                self.received(text)
            self.controller.load_script(text)


def receive_programs(
    server: TcpServer,
    conn: Connection,
    controller: Controller,
    received: Callable[[str], None] | None = None,
) -> None:
    """Read URScript from ``conn`` until it closes (:class:`ProgramReceiver`).

    A program or line beyond the bounds is refused: logged at error level, the connection
    closed."""
    receiver = ProgramReceiver(controller, received)
    try:
        server.recv_loop(conn, receiver.feed, bufsize=1 << 18)
    except ValueError as exc:  # beyond MAX_PROGRAM_BYTES / MAX_LINE_BYTES
        controller.log(f"{exc}: refused, connection from {conn.peer} closed", level=1)
