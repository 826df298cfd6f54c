"""The script port (30003): receives URScript programs; sends nothing back.

ur_rtde keeps this connection open for the whole session and writes its
control script (and re-uploads for path moves) as raw text.  A real
controller streams realtime-interface data here, which ur_rtde never reads;
the emulator stays silent.  Each complete program (see
:class:`~.program.ProgramSplitter`) goes to the controller, where it
replaces the running one.  A program beyond
:data:`~.program.MAX_PROGRAM_BYTES` (8 MiB) or a line beyond
:data:`~.program.MAX_LINE_BYTES` (64 KiB) is refused: logged at error level,
the connection closed (the stream cannot be resynchronised).
"""

from __future__ import annotations

import codecs
import logging

from .controller import Controller
from .program import ProgramSplitter
from .tcp import Connection, TcpServer

__all__ = ["ScriptPortServer"]

log = logging.getLogger("ruledrobot.export.emulator")


class ScriptPortServer(TcpServer):
    """Feeds programs received on ``port`` to the controller."""

    name = "script"

    def __init__(self, host: str, port: int, controller: Controller, **limits: float) -> None:
        super().__init__(host, port, **limits)  # type: ignore[arg-type]
        self.controller = controller
        self.programs_received = 0
        self.last_program: str = ""

    def handle(self, conn: Connection) -> None:
        splitter = ProgramSplitter()
        decoder = codecs.getincrementaldecoder("utf-8")(errors="replace")

        def on_data(data: bytes) -> None:
            for text in splitter.feed(decoder.decode(data)):
                self.programs_received += 1
                self.last_program = text[:4096]
                self.controller.load_script(text)

        try:
            self.recv_loop(conn, on_data, bufsize=1 << 18)
        except ValueError as exc:  # beyond MAX_PROGRAM_BYTES / MAX_LINE_BYTES
            self.controller.log(f"{exc}: refused, connection from {conn.peer} closed", level=1)
