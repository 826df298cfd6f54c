"""A small threaded TCP server: accept loop, one reader thread per connection, clean shutdown.

Subclasses implement :meth:`TcpServer.handle` (the per-connection loop), or, with
``single_thread`` set, :meth:`TcpServer.on_data`: one selector thread then reads every
connection of the server (for servers that mostly send: no thread per client).  Every
socket has a short timeout so threads notice :meth:`TcpServer.close` within
``POLL`` seconds; ``close`` is bounded in time.  :meth:`TcpServer.drop_all`
closes every connection and refuses new ones for a while (the "dropped
connection" fault).

Bounds: at most ``max_connections`` connections (one thread each).  When the
server is full, a newcomer takes the place of the connection that has been
idle longest, if that one has received nothing for ``idle_timeout`` seconds
(and, for RTDE, streams nothing); otherwise the newcomer is refused (accepted
and closed at once).  Idle connections are not closed otherwise: ur_rtde
keeps its dashboard and script-port connections open and silent for a whole
session.

``frozen`` (an Event, set by the frozen-controller fault): nothing is accepted,
read or answered; connections stay open and the kernel buffers what arrives.
"""

from __future__ import annotations

import contextlib
import logging
import os
import select
import selectors
import socket
import threading
import time
from collections.abc import Callable

__all__ = [
    "IDLE_WAIT",
    "POLL",
    "Connection",
    "QueuedConnection",
    "TcpServer",
    "quick_ack",
    "writable_fds",
]

log = logging.getLogger("ruledrobot.ursim")

#: seconds between checks of the stop flag in blocking socket calls
POLL = 0.1
#: seconds a non-blocking connection's thread waits for data before it looks at its
#: flags again; close() wakes it at once (the shutdown makes the socket readable), so
#: this only bounds how soon a connection the clock marked broken is closed.  Short
#: waits cost: 100 connections x 10 wake-ups/s compete with the clock for the GIL.
IDLE_WAIT = 1.0


class Connection:
    """One accepted client socket with a lock for writes and a closed flag."""

    def __init__(self, sock: socket.socket, addr: tuple) -> None:
        self.sock = sock
        self.addr = addr
        self.closed = False
        self.write_lock = threading.Lock()
        self.last_rx = time.monotonic()  # when bytes last arrived

    def idle_for(self, now: float) -> float:
        """Seconds since the peer last sent anything (0 for a connection in use)."""
        return now - self.last_rx

    @property
    def closing(self) -> bool:
        """True when the connection should be closed by its own thread."""
        return False

    @property
    def peer(self) -> str:
        """The peer's address as ``"host:port"`` (for log lines)."""
        return f"{self.addr[0]}:{self.addr[1]}" if len(self.addr) >= 2 else str(self.addr)

    def sendall(self, data: bytes) -> bool:
        """Blocking send (replies); False when the connection is gone."""
        if self.closed:
            return False
        try:
            with self.write_lock:
                self.sock.sendall(data)
            return True
        except OSError:
            self.close()
            return False

    def close(self) -> None:
        """Shut the socket down and close it; a second call does nothing, errors are ignored."""
        if self.closed:
            return
        self.closed = True
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)
        with contextlib.suppress(OSError):
            self.sock.close()


class QueuedConnection(Connection):
    """A connection whose sends never wait: bytes the socket does not take are queued.

    Used by the streaming servers (RTDE, primary interface): the thread that sends
    (the clock, the publisher) must never block on one client.  Beyond a bound the
    connection is marked ``broken`` and its own thread closes it.
    """

    #: the server's name in log lines
    kind = "tcp"

    def __init__(self, sock: socket.socket, addr: tuple) -> None:
        super().__init__(sock, addr)
        self.backlog = bytearray()
        self.broken = False  # a send failed or the backlog overflowed: close
        self.dropped_backlog = 0
        self.last_tx = time.monotonic()  # when the socket last took bytes

    @property
    def closing(self) -> bool:
        """Whether the connection is broken, to be closed by its own thread.

        Broken: the connection's own thread closes it (closing a socket with megabytes
        unsent costs milliseconds, which the sending thread must not pay).
        """
        return self.broken

    def push(self, data: bytes, max_backlog: int, send: bool = True) -> None:
        """Queue bytes and send what the socket takes now, never blocking.

        Beyond ``max_backlog`` queued bytes the connection is marked broken (closed by its
        thread).

        ``send=False``: only queue (the socket is known not to be writable: a send
        attempt would only cost a GIL hand-off)."""
        with self.write_lock:
            if self.closed or self.broken:
                return
            self.backlog += data
            if send:
                self._flush_locked()
            if len(self.backlog) > max_backlog:
                self.dropped_backlog += 1
                log.warning("%s: client %s does not read its data (%d bytes queued): closing",
                            self.kind, self.peer, len(self.backlog))  # fmt: skip
                self.backlog = bytearray()
                self.broken = True

    def flush(self) -> None:
        """Send what of the queue the socket takes now, never blocking."""
        with self.write_lock:
            if not self.closed and not self.broken and self.backlog:
                self._flush_locked()

    def _flush_locked(self) -> None:
        try:
            n = self.sock.send(self.backlog, socket.MSG_DONTWAIT)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self.backlog = bytearray()
            self.broken = True
            return
        if n:
            self.last_tx = time.monotonic()
        del self.backlog[:n]


def writable_fds(conns: list[QueuedConnection]) -> set[int]:
    """File descriptors of ``conns`` whose socket takes data now (one system call)."""
    if not conns:
        return set()
    fds = [c.sock.fileno() for c in conns]
    fds = [fd for fd in fds if fd >= 0]
    poll = getattr(select, "poll", None)
    try:
        if poll is None:  # pragma: no cover - not Linux
            return set(select.select([], fds, [], 0.0)[1])
        p = poll()
        for fd in fds:
            p.register(fd, select.POLLOUT)
        return {fd for fd, ev in p.poll(0) if ev & select.POLLOUT}
    except (OSError, ValueError):
        return set()


def quick_ack(sock: socket.socket) -> None:
    """Acknowledge what ``sock`` received at once, not after Linux's delayed-ACK timer.

    The timer waits up to 40 ms; call it after each ``recv``.

    A peer that sends small packets with Nagle's algorithm on (ur_rtde's sockets: their
    no-delay option is lost when boost::asio's connect reopens the socket) holds its next
    packet until the previous one is acknowledged.  A connection that sends nothing back
    to carry the ACK (ur_rtde's IO interface: inputs without replies, after the
    request-reply set-up that put the socket into delayed-ACK mode) would get it 40 ms
    late.  ``TCP_QUICKACK`` sends a pending ACK now and leaves that mode; it does not
    stick, hence once per ``recv``.  No effect where the option does not exist.
    """
    option = getattr(socket, "TCP_QUICKACK", None)
    if option is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.IPPROTO_TCP, option, 1)


#: the nice value a thread asks for when real-time scheduling is refused
FALLBACK_NICE = -10


def try_realtime_priority(priority: int) -> bool:
    """Give the calling thread ``SCHED_FIFO`` ``priority`` if allowed (Linux, CAP_SYS_NICE).

    When refused, nice :data:`FALLBACK_NICE` if allowed (Linux nice values are per thread).
    Returns whether the thread is real-time."""
    setter = getattr(os, "sched_setscheduler", None)
    if setter is not None:
        try:
            setter(0, os.SCHED_FIFO, os.sched_param(priority))
            return True
        except (OSError, AttributeError):
            pass
    try:
        os.setpriority(os.PRIO_PROCESS, 0, FALLBACK_NICE)
    except (OSError, AttributeError):
        pass
    return False


class TcpServer:
    """Listens on (host, port); runs :meth:`handle` in a thread per connection.

    With ``realtime`` set, the server's threads ask for ``SCHED_FIFO`` priority 5
    (below the clock's 10): a thread holding the GIL is then never preempted by
    ordinary processes while the clock waits for the GIL.
    """

    name = "tcp"
    realtime = False
    #: non-blocking sockets (no send ever waits; :meth:`recv_loop` waits in a selector)
    nonblocking = False
    #: one selector thread reads every connection (:meth:`on_data`) instead of a thread
    #: each running :meth:`handle`; the sockets are non-blocking
    single_thread = False

    def __init__(
        self, host: str, port: int, *, max_connections: int = 32, idle_timeout: float = 10.0
    ) -> None:
        if max_connections < 1:
            raise ValueError(f"max_connections: expected >= 1, got {max_connections}")
        if not idle_timeout > 0.0:
            raise ValueError(f"idle_timeout: expected > 0 s, got {idle_timeout}")
        self.max_connections = int(max_connections)
        self.idle_timeout = float(idle_timeout)
        self.refused = 0
        self.evicted = 0
        self.host = host
        self.port = int(port)
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._conns: dict[int, Connection] = {}
        self._threads: list[threading.Thread] = []
        self._refuse_until = 0.0
        self._listener: socket.socket | None = None
        self._accept_thread: threading.Thread | None = None
        self._select_thread: threading.Thread | None = None
        self._new: list[Connection] = []  # accepted, to be registered by the selector thread
        self._wake: tuple[socket.socket, socket.socket] | None = None
        #: set: a frozen controller (nothing accepted, read or answered; sockets stay open)
        self.frozen = threading.Event()
        self.accepted = 0
        self.errors = 0

    # ------------------------------------------------------------ lifecycle

    def start(self) -> None:
        """Listen on (``host``, ``port``) and start the accept thread.

        With ``single_thread`` also the selector thread that reads every connection.  Port 0 picks a
        free port (:attr:`port` says which).  OSError, with the bind's ``errno`` (EADDRINUSE: the
        address is taken), when the address cannot be bound.
        """
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((self.host, self.port))
        except OSError as exc:
            s.close()
            error = OSError(f"{self.name} server: cannot listen on {self.host}:{self.port}: {exc}")
            error.errno = exc.errno  # EADDRINUSE: the address is taken (address.py moves on)
            raise error from None
        s.listen(16)
        s.settimeout(POLL)
        self.port = s.getsockname()[1]
        self._listener = s
        if self.single_thread:
            self._wake = socket.socketpair()
            for w in self._wake:
                w.setblocking(False)
            self._select_thread = threading.Thread(
                target=self._select_loop, name=f"emu-{self.name}-read", daemon=True
            )
            self._select_thread.start()
        self._accept_thread = threading.Thread(
            target=self._accept_loop, name=f"emu-{self.name}-accept", daemon=True
        )
        self._accept_thread.start()

    @property
    def stopping(self) -> bool:
        """True once :meth:`close` was called."""
        return self._stop.is_set()

    def close(self, timeout: float = 2.0) -> None:
        """Stop accepting, close every connection, join the threads (bounded by ``timeout``)."""
        self._stop.set()
        if self._listener is not None:
            with contextlib.suppress(OSError):  # wakes the accept() at once (Linux; a close
                self._listener.shutdown(socket.SHUT_RDWR)  # alone waits out its POLL timeout)
            with contextlib.suppress(OSError):
                self._listener.close()
        for c in self.connections():
            c.close()
        self._wakeup()
        deadline = time.monotonic() + timeout
        threads = [self._accept_thread, self._select_thread, *self._threads]
        for t in threads:
            if t is not None and t is not threading.current_thread():
                t.join(max(0.0, deadline - time.monotonic()))

    def connections(self) -> list[Connection]:
        """The open connections now (a copy of the list)."""
        with self._lock:
            return list(self._conns.values())

    def drop_all(self, refuse_for: float = 0.0) -> int:
        """Close every connection; refuse new ones for ``refuse_for`` seconds. Returns the count."""
        self._refuse_until = time.monotonic() + max(0.0, refuse_for)
        conns = self.connections()
        for c in conns:
            c.close()
        self._wakeup()
        return len(conns)

    # ------------------------------------------------------------ internals

    def _accept_loop(self) -> None:
        assert self._listener is not None
        if self.realtime:
            try_realtime_priority(5)
        while not self._stop.is_set():
            if self.frozen.is_set():  # the kernel's listen queue holds the newcomers
                self._stop.wait(POLL)
                continue
            try:
                sock, addr = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:
                if self._stop.is_set():
                    return
                time.sleep(POLL)
                continue
            if time.monotonic() < self._refuse_until or not self._make_room():
                with contextlib.suppress(OSError):
                    sock.close()
                continue
            if self.nonblocking or self.single_thread:
                sock.setblocking(False)
            else:
                sock.settimeout(POLL)
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn = self.make_connection(sock, addr)
            self.accepted += 1
            if self.single_thread:
                with self._lock:
                    self._conns[id(conn)] = conn
                    self._new.append(conn)
                self._wakeup()
                continue
            with self._lock:
                self._conns[id(conn)] = conn
                self._threads = [t for t in self._threads if t.is_alive()]
                t = threading.Thread(
                    target=self._run, args=(conn,), name=f"emu-{self.name}-{conn.peer}", daemon=True
                )
                self._threads.append(t)
            t.start()

    def _make_room(self) -> bool:
        """Room for one more connection: True, evicting the idlest one if needed."""
        with self._lock:
            if len(self._conns) < self.max_connections:
                return True
            now = time.monotonic()
            victim = max(self._conns.values(), key=lambda c: c.idle_for(now))
            if victim.idle_for(now) < self.idle_timeout:
                self.refused += 1
                if self.refused & (self.refused - 1) == 0:  # 1st, 2nd, 4th, ... time
                    log.warning("%s server: %d connections, none idle for %g s: refusing "
                                "(%d times so far)", self.name, len(self._conns),
                                self.idle_timeout, self.refused)  # fmt: skip
                return False
            del self._conns[id(victim)]
            self.evicted += 1
        log.info("%s server: full; closing %s, idle for %.1f s", self.name, victim.peer,
                 victim.idle_for(now))  # fmt: skip
        victim.close()
        return True

    def _wakeup(self) -> None:
        """Make the selector thread look at its connections now (new, closed, closing)."""
        if self._wake is not None:
            with contextlib.suppress(OSError):
                self._wake[1].send(b"\0")

    def _select_loop(self) -> None:
        """The ``single_thread`` reader: every connection of this server, one selector."""
        assert self._wake is not None
        if self.realtime:
            try_realtime_priority(5)
        wake = self._wake[0]
        sel = selectors.DefaultSelector()
        sel.register(wake, selectors.EVENT_READ)
        mine: dict[int, Connection] = {}
        try:
            while not self._stop.is_set():
                # first the connections closed elsewhere (their fd numbers may be reused by
                # the newcomers), then the newcomers
                for key in [k for k, c in mine.items() if c.closed or c.closing]:
                    self._finish(sel, mine.pop(key))
                with self._lock:
                    new, self._new = self._new, []
                for conn in new:
                    for attempt in range(2):
                        try:
                            sel.register(conn.sock, selectors.EVENT_READ, conn)
                        except KeyError:  # its fd number is a connection closed just now
                            for key in [k for k, c in mine.items() if c.closed]:
                                self._finish(sel, mine.pop(key))
                            if attempt == 0:
                                continue
                            self._finish(sel, conn)
                        except (OSError, ValueError):
                            self._finish(sel, conn)
                        else:
                            mine[id(conn)] = conn
                        break
                if self.frozen.is_set():  # nothing read; the kernel buffers what arrives
                    self._stop.wait(POLL)
                    continue
                for key, _ in sel.select(IDLE_WAIT):
                    if key.fileobj is wake:
                        with contextlib.suppress(OSError):
                            while wake.recv(4096):
                                pass
                        continue
                    conn = key.data
                    try:
                        data = conn.sock.recv(65536)
                    except (BlockingIOError, InterruptedError):
                        continue
                    except OSError:
                        data = b""
                    if not data:
                        conn.close()
                        continue
                    conn.last_rx = time.monotonic()
                    try:
                        self.on_data(conn, data)
                    except Exception as exc:
                        self.errors += 1
                        log.warning("%s server: connection %s closed after an error: %s",
                                    self.name, conn.peer, exc)  # fmt: skip
                        conn.close()
        finally:
            for conn in mine.values():
                self._finish(sel, conn)
            sel.close()
            for w in self._wake:
                with contextlib.suppress(OSError):
                    w.close()

    def _finish(self, sel: selectors.BaseSelector, conn: Connection) -> None:
        with contextlib.suppress(KeyError, ValueError, OSError):
            sel.unregister(conn.sock)
        conn.close()
        with self._lock:
            self._conns.pop(id(conn), None)
        self.on_close(conn)

    def _run(self, conn: Connection) -> None:
        if self.realtime:
            try_realtime_priority(5)
        try:
            self.handle(conn)
        except Exception as exc:
            self.errors += 1
            log.warning(
                "%s server: connection %s closed after an error: %s", self.name, conn.peer, exc
            )
        finally:
            conn.close()
            with self._lock:
                self._conns.pop(id(conn), None)
            self.on_close(conn)

    def recv_loop(
        self, conn: Connection, on_data: Callable[[bytes], None], bufsize: int = 65536
    ) -> None:
        """Read until the peer closes, the server stops or ``on_data`` raises.

        A non-blocking socket: also when the connection is closing.
        """
        if conn.sock.gettimeout() != 0.0:  # recv waits up to the socket's timeout
            self._recv(conn, on_data, bufsize, None, (TimeoutError,))
            return
        with selectors.DefaultSelector() as sel:
            try:
                sel.register(conn.sock, selectors.EVENT_READ)
            except (OSError, ValueError):
                return
            self._recv(conn, on_data, bufsize, lambda: bool(sel.select(IDLE_WAIT)),
                       (BlockingIOError, InterruptedError))  # fmt: skip

    def _recv(
        self,
        conn: Connection,
        on_data: Callable[[bytes], None],
        bufsize: int,
        ready: Callable[[], bool] | None,
        again: tuple[type[OSError], ...],
    ) -> None:
        """The receive loop: ``ready`` (non-blocking sockets) waits for data, ``again`` are
        the errors of a ``recv`` that found none."""
        while not self._stop.is_set() and not conn.closed:
            if ready is not None and conn.closing:
                return
            if self.frozen.is_set():
                self._stop.wait(POLL)
                continue
            if ready is not None and not ready():
                continue
            try:
                data = conn.sock.recv(bufsize)
            except again:
                continue
            except OSError:
                return
            if not data:
                return
            conn.last_rx = time.monotonic()
            on_data(data)

    # ------------------------------------------------------------ for subclasses

    def make_connection(self, sock: socket.socket, addr: tuple) -> Connection:
        """Wrap an accepted socket; servers that need more per client return a subclass."""
        return Connection(sock, addr)

    def handle(self, conn: Connection) -> None:
        """The per-connection loop (a thread each unless ``single_thread``).

        It returns, or raises (logged), when the connection is to close; :meth:`recv_loop` is the
        usual body.
        """
        raise NotImplementedError

    def on_data(self, conn: Connection, data: bytes) -> None:
        """``single_thread`` servers: bytes arrived on ``conn`` (raise to close it)."""
        raise NotImplementedError

    def on_close(self, conn: Connection) -> None:
        """Called after a connection is closed and removed."""
