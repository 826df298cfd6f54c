"""The RTDE server (port 30004): protocol negotiation, recipes, and the data stream.

Per connection: ``V`` (protocol version 1 or 2) -> ``v`` (controller
version) -> ``O`` (output recipe, with a frequency in v2) and ``I`` (input
recipes, ids 1, 2, ... in setup order) -> ``S`` (start streaming) / ``P``
(pause).  Exactly one reply per request and nothing unsolicited before the
``S`` reply (ur_rtde reads one message per setup request).  Input data
packages (``U``) are applied to the controller whether or not the connection
is started (ur_rtde's IO interface never sends ``S``).

Streaming: the controller's clock thread calls :meth:`RTDEServer.publish`
once per control period; each started connection gets a data package when its
own frequency is due, on the decimation grid of the controller clock: a
125 Hz stream on a 500 Hz controller gets the ticks that are multiples of 4
(timestamps multiples of 8 ms), from its first package on, whenever it was
started (:func:`due`).

A slow client costs only itself.  The sockets are non-blocking (a send never
waits), the kernel send buffer is bounded (:data:`SEND_BUFFER`), a
connection with queued bytes is only written to when one ``poll()`` for all
of them says its socket takes data (every socket call hands the GIL to
whichever thread wants it, so 100 stuck clients must not cost 100 calls per
period; at most :data:`SEND_BUDGET` of a period is spent sending, the rest
is queued for the next), and a connection whose queue passes ``max_backlog`` bytes
(:data:`MAX_BACKLOG`, 256 KiB) is marked broken and closed by its own thread, as a real
controller drops clients that do not read.  The ``slow controller`` fault
holds every data package back by ``delay`` seconds.

Malformed input (bad header, unknown packet type, wrong data size, unknown
recipe id, non-finite doubles) closes that connection and is logged; the
other connections are not affected.
"""

from __future__ import annotations

import contextlib
import logging
import math
import random
import socket
import struct
import threading
import time
from collections import deque
from collections.abc import Mapping

from ...protocol.rtde import (
    CONTROL_PACKAGE_PAUSE,
    CONTROL_PACKAGE_SETUP_INPUTS,
    CONTROL_PACKAGE_SETUP_OUTPUTS,
    CONTROL_PACKAGE_START,
    DATA_PACKAGE,
    GET_URCONTROL_VERSION,
    HEADER_SIZE,
    MAX_PACKET_SIZE,
    REQUEST_PROTOCOL_VERSION,
    TEXT_MESSAGE,
    InputRecipe,
    OutputRecipe,
    PacketFramer,
    ProtocolError,
    RecipeKey,
    pack_packet,
    parse_names,
    parse_output_setup,
)
from ...protocol.rtde_types import TYPE_SIZES
from ..controller.machine import Controller
from .tcp import Connection, QueuedConnection, TcpServer, quick_ack, writable_fds

__all__ = ["RTDEConnection", "RTDEServer", "StreamStats", "due"]

log = logging.getLogger("ruledrobot.ursim")


#: bytes queued for a client beyond which it is disconnected: about 2.2 s of ur_rtde's
#: 58-variable stream at 500 Hz (576 KiB/s), after the kernel buffers (another 0.4 s)
#: are full: a client stalled as long as ur_rtde's own receive timeout (2.5 s) keeps its
#: connection (a forwarded run rides through a stall of its buffer and more; at 256 KiB,
#: 0.45 s, a 1 s stall of the runner closed it: issue 31)
MAX_BACKLOG = 1280 * 1024

#: the fraction of a control period the clock may spend in socket calls per publish
SEND_BUDGET = 0.4

#: kernel send buffer of an RTDE connection [bytes] (Linux doubles it): about 0.1 s of
#: ur_rtde's 58-variable recipe at 500 Hz
SEND_BUFFER = 64 * 1024


def due(tick: int, ratio: float) -> bool:
    """Return whether a stream of ``ratio`` is due at controller ``tick``.

    ``ratio`` = frequency / controller frequency.

    True at the ticks where ``floor(tick * ratio)`` steps: every tick for
    ratio 1, the multiples of 4 for 1/4 (125 Hz on 500 Hz), of 5 for 1/5.
    """
    return math.floor(tick * ratio + 1e-9) != math.floor((tick - 1) * ratio + 1e-9)


def _fit(reply: bytes) -> bytes:
    """A setup reply that fits a packet; one that does not (thousands of ``NOT_FOUND``)
    becomes a bare failure (recipe id 0, no types)."""
    return reply if HEADER_SIZE + len(reply) <= MAX_PACKET_SIZE else b"\x00"


class StreamStats:
    """Counters of one connection's stream."""

    def __init__(self) -> None:
        self.packages = 0
        self.bytes = 0


class RTDEConnection(QueuedConnection):
    """Protocol state of one RTDE client."""

    kind = "rtde"

    def __init__(self, sock: socket.socket, addr: tuple) -> None:
        super().__init__(sock, addr)
        self.protocol_version = 1
        self.output: OutputRecipe | None = None
        self.inputs: dict[int, InputRecipe] = {}
        self.started = False
        self.delayed: deque[tuple[float, bytes]] = deque()
        self.stats = StreamStats()
        self.owned: set[str] = set()

    def idle_for(self, now: float) -> float:
        """A started stream is in use (it receives data every period), never idle."""
        return 0.0 if self.started and not self.broken else now - self.last_rx

    def reply(self, kind: int, payload: bytes, max_backlog: int = MAX_BACKLOG) -> None:
        """Queue a reply (never blocks; a client that does not read them is closed)."""
        self.push(pack_packet(kind, payload), max_backlog)


class RTDEServer(TcpServer):
    """RTDE on ``port`` (30004), feeding a :class:`Controller`.

    ``version``: (major, minor, bugfix, build) reported to ``v`` requests.
    """

    name = "rtde"
    nonblocking = True

    def __init__(
        self,
        host: str,
        port: int,
        controller: Controller,
        version: tuple[int, int, int, int],
        *,
        max_backlog: int = MAX_BACKLOG,
        **limits: float,
    ) -> None:
        super().__init__(host, port, **limits)  # type: ignore[arg-type]
        self.controller = controller
        self.version = version
        self.max_backlog = max_backlog
        self.delay = 0.0
        self.jitter = 0.0
        self._owners: dict[str, int] = {}
        self._owner_lock = threading.Lock()
        self._rng = random.Random(1)
        self.protocol_errors = 0
        self.publish_errors = 0

    def make_connection(self, sock: socket.socket, addr: tuple) -> Connection:
        # a bounded kernel buffer: a client that stops reading is "stuck" (no more send
        # attempts, see publish) within a fraction of a second instead of after megabytes
        """An :class:`RTDEConnection` with its kernel send buffer bounded to :data:`SEND_BUFFER`."""
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)
        return RTDEConnection(sock, addr)

    # ------------------------------------------------------------ reading

    def handle(self, conn: Connection) -> None:
        """Read ``conn``'s packets and answer them until it closes; a protocol error closes it.

        Each setup request gets exactly one reply; an input data package is applied to the
        controller at once and its TCP acknowledgement sent at once (:func:`~.tcp.quick_ack`).  A
        protocol error is counted (``protocol_errors``) and logged.
        """
        assert isinstance(conn, RTDEConnection)
        framer = PacketFramer()

        def on_data(data: bytes) -> None:
            # input packages get no reply: acknowledge them at once, or a client's next
            # package waits up to 40 ms for the ACK (Nagle; see quick_ack)
            quick_ack(conn.sock)
            framer.feed(data)
            for kind, payload in framer.packets():
                self._packet(conn, kind, payload)

        try:
            self.recv_loop(conn, on_data)
        except ProtocolError as exc:
            self.protocol_errors += 1
            log.warning("rtde: closing %s: protocol error: %s", conn.peer, exc)

    def on_close(self, conn: Connection) -> None:
        """Release the input names ``conn`` had set up: another client may now set them up."""
        assert isinstance(conn, RTDEConnection)
        with self._owner_lock:
            for name in conn.owned:
                if self._owners.get(name) == id(conn):
                    del self._owners[name]

    def _packet(self, conn: RTDEConnection, kind: int, payload: bytes) -> None:
        if kind == REQUEST_PROTOCOL_VERSION:
            if len(payload) != 2:
                raise ProtocolError(f"protocol version request with {len(payload)} bytes")
            (version,) = struct.unpack(">H", payload)
            ok = version in (1, 2)
            if ok:
                conn.protocol_version = version
            conn.reply(REQUEST_PROTOCOL_VERSION, bytes([int(ok)]))
        elif kind == GET_URCONTROL_VERSION:
            if payload:
                raise ProtocolError("controller version request with a payload")
            conn.reply(GET_URCONTROL_VERSION, struct.pack(">IIII", *self.version))
        elif kind == CONTROL_PACKAGE_SETUP_OUTPUTS:
            freq, names = parse_output_setup(payload, conn.protocol_version)
            base = 1.0 / self.controller.period
            freq = base if freq is None else min(freq, base)
            if conn.started:
                conn.reply(CONTROL_PACKAGE_SETUP_OUTPUTS, bytes([0]))
                return
            recipe = OutputRecipe(1, names, freq)
            if recipe.ok:
                conn.output = recipe
            elif recipe.too_large:
                conn.output = None
                log.info("rtde: %s asked for %d outputs: a %d-byte package, beyond RTDE's "
                         "64 KiB: refused", conn.peer, len(names),
                         sum(TYPE_SIZES[t] for t in recipe.types) + 4)  # fmt: skip
            else:
                missing = [n for n, t in zip(names, recipe.types, strict=True) if t == "NOT_FOUND"]
                log.info("rtde: %s asked for unknown outputs %s", conn.peer, missing)
            conn.reply(CONTROL_PACKAGE_SETUP_OUTPUTS, _fit(recipe.reply()))
        elif kind == CONTROL_PACKAGE_SETUP_INPUTS:
            names = parse_names(payload, "input setup")
            if conn.started:
                conn.reply(CONTROL_PACKAGE_SETUP_INPUTS, bytes([0]))
                return
            recipe = InputRecipe(len(conn.inputs) + 1, names)
            if recipe.ok and recipe.recipe_id <= 255:
                with self._owner_lock:
                    taken = [n for n in names if self._owners.get(n, id(conn)) != id(conn)]
                    if taken:
                        types = ["IN_USE" if n in taken else t
                                 for n, t in zip(names, recipe.types, strict=True)]  # fmt: skip
                        conn.reply(CONTROL_PACKAGE_SETUP_INPUTS,
                                   _fit(bytes([0]) + ",".join(types).encode()))  # fmt: skip
                        return
                    for n in names:
                        self._owners[n] = id(conn)
                        conn.owned.add(n)
                conn.inputs[recipe.recipe_id] = recipe
            conn.reply(CONTROL_PACKAGE_SETUP_INPUTS, _fit(recipe.reply()))
        elif kind == CONTROL_PACKAGE_START:
            ok = conn.output is not None
            conn.started = ok
            conn.reply(CONTROL_PACKAGE_START, bytes([int(ok)]))
        elif kind == CONTROL_PACKAGE_PAUSE:
            conn.started = False
            conn.reply(CONTROL_PACKAGE_PAUSE, bytes([1]))
        elif kind == DATA_PACKAGE:
            if not payload:
                raise ProtocolError("data package without a recipe id")
            recipe = conn.inputs.get(payload[0])
            if recipe is None:
                raise ProtocolError(f"data package for unknown input recipe {payload[0]}")
            values = recipe.unpack(payload[1:])
            self.controller.apply_inputs(values, recipe.names)
        elif kind == TEXT_MESSAGE:
            log.info("rtde: text message from %s: %r", conn.peer, payload[:200])
        else:  # pragma: no cover - the framer only passes known types
            raise ProtocolError(f"unexpected packet type {kind}")

    # ------------------------------------------------------------ streaming

    def publish(self, state: Mapping[str, object], now: float, tick: int | None = None) -> None:
        """Send a data package to each started connection whose frequency is due at ``tick``.

        ``tick``: the controller tick ``state`` belongs to (default: the
        controller's tick count); ``now``: the clock's time [s] (for the slow
        fault).  Connections with the same output recipe share one packed
        package.  A connection that cannot be served (its package cannot be
        packed, its socket fails) is closed with one log line; the others are
        served as if nothing happened.
        """
        period = self.controller.period
        if tick is None:
            tick = self.controller.ticks
        packed: dict[RecipeKey, bytes | Exception] = {}
        conns = [c for c in self.connections()
                 if isinstance(c, RTDEConnection) and not c.closed and not c.broken]  # fmt: skip
        # connections with queued bytes: one poll() for all of them instead of a send
        # attempt each (every socket call hands the GIL to whichever thread wants it)
        writable = writable_fds([c for c in conns if c.backlog])
        # at most SEND_BUDGET of the period for socket calls; the rest is queued and goes
        # out next period; the order rotates so that no connection is always last
        deadline = time.perf_counter() + SEND_BUDGET * period
        k = tick % len(conns) if conns else 0
        for conn in conns[k:] + conns[:k]:
            send = (not conn.backlog or conn.sock.fileno() in writable) and (
                time.perf_counter() < deadline)  # fmt: skip
            try:
                self._serve(conn, state, now, tick, period, packed, send)
            except Exception as exc:  # this connection only
                self.publish_errors += 1
                log.warning("rtde: closing %s: its data package cannot be sent: %s",
                            conn.peer, exc)  # fmt: skip
                conn.close()

    def _serve(
        self,
        conn: RTDEConnection,
        state: Mapping[str, object],
        now: float,
        tick: int,
        period: float,
        packed: dict[RecipeKey, bytes | Exception],
        send: bool,
    ) -> None:
        recipe = conn.output
        if conn.started and recipe is not None and due(tick, recipe.frequency * period):
            data = packed.get(recipe.key)
            if data is None:
                try:
                    data = recipe.pack(state)
                except Exception as exc:
                    data = exc
                packed[recipe.key] = data
            if isinstance(data, Exception):
                raise data
            conn.stats.packages += 1
            conn.stats.bytes += len(data)
            if self.delay > 0.0 or conn.delayed:
                jit = self._rng.uniform(0.0, self.jitter) if self.jitter > 0 else 0.0
                conn.delayed.append((now + self.delay + jit, data))
            else:
                conn.push(data, self.max_backlog, send)
        while conn.delayed and conn.delayed[0][0] <= now:
            conn.push(conn.delayed.popleft()[1], self.max_backlog, send)
        if conn.backlog and send:
            conn.flush()

    def set_delay(self, delay: float, jitter: float = 0.0) -> None:
        """Slow-controller fault: hold data packages back by ``delay`` (+ up to ``jitter``) s."""
        self.delay = max(0.0, float(delay))
        self.jitter = max(0.0, float(jitter))

