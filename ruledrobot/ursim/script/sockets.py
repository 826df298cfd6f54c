"""URScript's client sockets in the emulator: ``socket_open``, the binary and text reads,
the sends, ``socket_close``.

A program's socket is a TCP connection from the controller to a server (the PC); UR's
client library and ruledrobot's forwarded runs feed trajectory points through one.  The
connection is made and read by a thread of its own, so the controller's clock never waits
on the network: received bytes collect in a buffer that the reads take from.  The reads
wait in *controller time* (whole control periods, ``yield``), as the program would wait on
the controller; a read that times out returns UR's answer for it
(``socket_read_binary_integer``: ``[0, -1, ..., -1]``; ``socket_read_ascii_float``:
``[0, ...]``; ``socket_read_string`` and ``socket_read_line``: ``""``).

Integers on the wire are big-endian signed 32-bit (as UR's).  The emulator connects where
the program asks, as a controller does.
"""

from __future__ import annotations

import math
import socket
import struct
import threading
from collections.abc import Callable, Generator
from typing import Any

from ..ports.tcp import try_realtime_priority
from .program import ScriptRuntimeError

__all__ = ["ScriptSockets"]

Gen = Generator[None, None, Any]

#: the longest a ``socket_open`` waits for the connection [s]
OPEN_TIMEOUT = 2.0
#: the most a socket's receive buffer holds before the reader stops reading (the TCP window
#: then holds the sender) [bytes]
MAX_BUFFER = 4 << 20


class _Conn:
    """One open socket: its connection thread, its receive buffer.  ``realtime``: the
    thread asks for the emulator's server threads' real-time priority (it takes the GIL
    to store what it read: at normal priority, preempted while holding it, it would hold
    up the controller's clock thread behind it)."""

    def __init__(self, host: str, port: int, realtime: bool = False) -> None:
        self.host, self.port = host, int(port)
        self.realtime = realtime
        self.sock: socket.socket | None = None
        self.buf = bytearray()
        self.lock = threading.Lock()
        self.ready = threading.Event()  # the connection attempt ended
        self.ok = False
        self.closed = False
        self.thread = threading.Thread(target=self._run, name=f"urscript socket {host}:{port}",
                                       daemon=True)  # fmt: skip
        self.thread.start()

    def _run(self) -> None:
        if self.realtime:
            try_realtime_priority(5)
        try:
            s = socket.create_connection((self.host, self.port), timeout=OPEN_TIMEOUT)
        except OSError:
            self.ready.set()
            return
        s.settimeout(0.2)
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock, self.ok = s, True
        self.ready.set()
        while not self.closed:
            if len(self.buf) > MAX_BUFFER:
                threading.Event().wait(0.005)
                continue
            try:
                data = s.recv(65536)
            except TimeoutError:
                continue
            except OSError:
                break
            if not data:
                break
            with self.lock:
                self.buf += data
        self.closed = True

    def take(self, n: int) -> bytes | None:
        with self.lock:
            if len(self.buf) < n:
                return None
            out = bytes(self.buf[:n])
            del self.buf[:n]
            return out

    def take_until(self, stop: bytes) -> bytes | None:
        with self.lock:
            k = self.buf.find(stop)
            if k < 0:
                return None
            out = bytes(self.buf[: k + len(stop)])
            del self.buf[: k + len(stop)]
            return out

    def send(self, data: bytes) -> bool:
        s = self.sock
        if s is None or self.closed:
            return False
        try:
            s.sendall(data)
            return True
        except OSError:
            return False

    def close(self) -> None:
        self.closed = True
        if self.sock is not None:
            try:
                self.sock.close()
            except OSError:
                pass


class ScriptSockets:
    """The sockets of one program run.

    ``period`` is the control period [s]; ``realtime``: their threads ask for real-time
    priority (the emulator's setting)."""

    def __init__(self, period: float, realtime: bool = False) -> None:
        self.period = float(period)
        self.realtime = realtime
        self.conns: dict[str, _Conn] = {}

    def close_all(self) -> None:
        """Close every socket of the program (it ended)."""
        for c in self.conns.values():
            c.close()
        self.conns.clear()

    def _conn(self, name: str) -> _Conn | None:
        c = self.conns.get(str(name))
        return c if c is not None and c.ok else None

    def _ticks(self, timeout: float) -> int:
        return max(0, math.ceil(float(timeout) / self.period - 1e-9))

    def _wait(self, socket_name: str, timeout: float, take: Callable[[_Conn], bytes | None]
              ) -> Generator[None, None, bytes | None]:  # fmt: skip
        """What ``take`` finds in the socket's buffer, waiting up to ``timeout`` s of
        controller time (whole periods); None on a timeout or a closed socket."""
        c = self.conns.get(str(socket_name))
        for k in range(self._ticks(timeout) + 1):
            data = take(c) if c is not None else None
            if data is not None or c is None or c.closed:
                return data
            if k < self._ticks(timeout):
                yield
        return None

    # ------------------------------------------------------------ open, close, send
    def socket_open(self, address: str, port: int, socket_name: str = "socket_0") -> Gen:
        """Connect (waiting in controller time); True when connected."""
        old = self.conns.pop(str(socket_name), None)
        if old is not None:
            old.close()
        conn = _Conn(str(address), int(port), self.realtime)
        self.conns[str(socket_name)] = conn
        while not conn.ready.is_set():
            yield
        return conn.ok

    def socket_close(self, socket_name: str = "socket_0") -> None:
        """Close the named socket (nothing when it is not open)."""
        c = self.conns.pop(str(socket_name), None)
        if c is not None:
            c.close()

    def socket_send_int(self, value: int, socket_name: str = "socket_0") -> bool:
        """Send ``value`` as a big-endian signed 32-bit integer."""
        c = self._conn(socket_name)
        return c is not None and c.send(struct.pack(">i", int(value)))

    def socket_send_byte(self, value: int, socket_name: str = "socket_0") -> bool:
        """Send one byte."""
        c = self._conn(socket_name)
        return c is not None and c.send(bytes([int(value) & 0xFF]))

    def socket_send_string(self, str: object, socket_name: str = "socket_0") -> bool:
        """Send a string (or a number's text), no newline."""
        c = self._conn(socket_name)
        return c is not None and c.send(f"{str}".encode("latin-1", "replace"))

    def socket_send_line(self, str: object, socket_name: str = "socket_0") -> bool:
        """Send a string and a newline."""
        c = self._conn(socket_name)
        return c is not None and c.send(f"{str}\n".encode("latin-1", "replace"))

    # ------------------------------------------------------------ reads
    def socket_read_binary_integer(self, number: int, socket_name: str = "socket_0",
                                   timeout: float = 2.0) -> Gen:  # fmt: skip
        """Read ``number`` big-endian int32 values: ``[number, v1, ..., vn]``.

        Waiting up to ``timeout`` s of controller time; ``[0, -1, ..., -1]`` on a timeout.
        """
        n = int(number)
        if n < 1 or n > 30:
            raise ScriptRuntimeError(f"socket_read_binary_integer(): number must be 1..30, got {n}")
        data = yield from self._wait(socket_name, timeout, lambda conn: conn.take(4 * n))
        if data is None:
            return [0] + [-1] * n
        return [n, *struct.unpack(f">{n}i", data)]

    def socket_read_ascii_float(self, number: int, socket_name: str = "socket_0",
                                timeout: float = 2.0) -> Gen:  # fmt: skip
        """``[n, f1, ..., fn]`` from a text ``(f1, ..., fn)``; ``[0, ...]`` on a timeout."""
        n = int(number)
        c = self.conns.get(str(socket_name))
        ticks = self._ticks(timeout)
        k = 0
        while True:
            data = c.take_until(b")") if c is not None else None
            if data is not None:
                text = data.decode("latin-1").strip()
                try:
                    vals = [float(x) for x in text[text.index("(") + 1 : -1].split(",")]
                except ValueError:
                    return [0] + [0.0] * n
                return [len(vals), *vals] if len(vals) == n else [0] + [0.0] * n
            if k >= ticks or c is None or c.closed:
                return [0] + [0.0] * n
            k += 1
            yield

    def socket_read_line(self, socket_name: str = "socket_0", timeout: float = 2.0) -> Gen:
        """One line without its newline; ``""`` on a timeout."""
        data = yield from self._wait(socket_name, timeout, lambda conn: conn.take_until(b"\n"))
        if data is None:
            return ""
        return data.decode("latin-1").rstrip("\r\n")

    def socket_read_string(self, socket_name: str = "socket_0", prefix: str = "",
                           suffix: str = "", timeout: float = 2.0) -> Gen:  # fmt: skip
        """The text between ``prefix`` and ``suffix`` (a line when neither is given)."""
        if not suffix:
            return (yield from self.socket_read_line(socket_name, timeout))
        c = self.conns.get(str(socket_name))
        ticks = self._ticks(timeout)
        k = 0
        while True:
            data = c.take_until(suffix.encode("latin-1")) if c is not None else None
            if data is not None:
                text = data.decode("latin-1")[: -len(suffix)]
                if prefix and prefix in text:
                    text = text[text.index(prefix) + len(prefix) :]
                return text
            if k >= ticks or c is None or c.closed:
                return ""
            k += 1
            yield
