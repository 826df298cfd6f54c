"""A loopback TCP proxy that can freeze or drop a controller's connections, for fault tests.

The runner and ur_rtde connect to fixed ports (RTDE 30004, dashboard 29999, script 30003,
primary 30001)
on one host, so the proxy listens on another loopback address with the same
ports and forwards to the controller's (an :class:`~.emulator.Emulator`, or
URSim on loopback)::

    emu = Emulator("127.0.0.2").start()
    with FaultProxy("127.0.0.77", "127.0.0.2") as proxy:
        ... run_trajectory(traj, "127.0.0.77") ...   # through the proxy
        proxy.freeze()      # sockets stay open, nothing is forwarded (a frozen controller)
        proxy.drop()        # both sides of every connection closed (a dropped connection)

* :meth:`FaultProxy.freeze` — stop forwarding in both directions; existing
  connections stay open and new ones are accepted and held, unanswered.
* :meth:`FaultProxy.drop` — close both sides of every connection; new
  connections are accepted and closed at once for ``refuse_for`` seconds.
* :meth:`FaultProxy.resume` — forward again.

The proxy runs in a child process (one selector thread: no client and no
server in the calling process shares its GIL), binds loopback addresses only,
and :meth:`FaultProxy.close` is bounded in time.
"""

from __future__ import annotations

import contextlib
import ipaddress
import os
import selectors
import socket
import subprocess
import sys
import time
from multiprocessing.connection import Connection

__all__ = ["UR_PORTS", "FaultProxy"]

#: the ports ur_rtde uses: RTDE, dashboard, script
UR_PORTS = (30004, 29999, 30003, 30001)  # + primary interface (KinematicsInfo)
_BUF = 1 << 16


def _loopback(host: str) -> None:
    if not ipaddress.ip_address(socket.gethostbyname(host)).is_loopback:
        raise ValueError(f"fault proxy: {host!r} is not a loopback address")


class _Pair:
    def __init__(self, a: socket.socket, b: socket.socket | None) -> None:
        self.a, self.b = a, b
        self.out = {a: bytearray(), b: bytearray()} if b is not None else {a: bytearray()}

    def other(self, s: socket.socket) -> socket.socket | None:
        return self.b if s is self.a else self.a

    def close(self) -> None:
        for s in (self.a, self.b):
            if s is not None:
                with contextlib.suppress(OSError):
                    s.shutdown(socket.SHUT_RDWR)
                with contextlib.suppress(OSError):
                    s.close()


class _Proxy:  # pragma: no cover - runs in the child process
    def __init__(self, listen: str, target: str, ports: tuple[int, ...], ctl: Connection) -> None:
        self.sel = selectors.DefaultSelector()
        self.target = target
        self.ctl = ctl
        self.mode = "pass"
        self.refuse_until = 0.0
        self.pairs: dict[socket.socket, _Pair] = {}
        self.listeners = []
        for port in ports:
            ls = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            ls.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            ls.bind((listen, port))
            ls.listen(16)
            ls.setblocking(False)
            self.listeners.append(ls)
            self.sel.register(ls, selectors.EVENT_READ, ("listen", port))
        self.sel.register(ctl.fileno(), selectors.EVENT_READ, ("ctl", 0))
        self.counts = {"accepted": 0, "dropped": 0, "held": 0}

    def _watch(self, pair: _Pair) -> None:
        for s in (pair.a, pair.b):
            if s is None:
                continue
            ev = selectors.EVENT_READ | (selectors.EVENT_WRITE if pair.out[s] else 0)
            with contextlib.suppress(KeyError, ValueError):
                self.sel.unregister(s)
            if self.mode == "pass":
                self.sel.register(s, ev, ("conn", 0))

    def _accept(self, ls: socket.socket, port: int) -> None:
        try:
            cs, _ = ls.accept()
        except OSError:
            return
        self.counts["accepted"] += 1
        if time.monotonic() < self.refuse_until:
            with contextlib.suppress(OSError):
                cs.close()
            return
        up = None
        if self.mode == "pass":
            try:
                up = socket.create_connection((self.target, port), timeout=1.0)
            except OSError:
                cs.close()
                return
            up.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            up.setblocking(False)
        else:
            self.counts["held"] += 1
        cs.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        cs.setblocking(False)
        pair = _Pair(cs, up)
        self.pairs[cs] = pair
        if up is not None:
            self.pairs[up] = pair
            self._watch(pair)

    def _close_pair(self, pair: _Pair) -> None:
        for s in (pair.a, pair.b):
            if s is not None:
                self.pairs.pop(s, None)
                with contextlib.suppress(KeyError, ValueError):
                    self.sel.unregister(s)
        pair.close()

    def _io(self, s: socket.socket, events: int) -> None:
        pair = self.pairs.get(s)
        if pair is None:
            return
        dst = pair.other(s)
        if events & selectors.EVENT_READ and dst is not None:
            try:
                data = s.recv(_BUF)
            except BlockingIOError:
                data = None
            except OSError:
                data = b""
            if data == b"":
                self._close_pair(pair)
                return
            if data:
                pair.out[dst].extend(data)
        for d in (pair.a, pair.b):
            if d is not None and pair.out[d]:
                try:
                    k = d.send(pair.out[d])
                    del pair.out[d][:k]
                except BlockingIOError:
                    pass
                except OSError:
                    self._close_pair(pair)
                    return
        self._watch(pair)

    def _command(self) -> bool:
        try:
            cmd, arg = self.ctl.recv()
        except (EOFError, OSError):
            return False
        if cmd == "close":
            self.ctl.send(("ok", None))
            return False
        if cmd == "freeze":
            self.mode = "frozen"
        elif cmd == "resume":
            self.mode = "pass"
        elif cmd == "drop":
            pairs = {id(p): p for p in self.pairs.values()}
            for p in pairs.values():
                self._close_pair(p)
            self.counts["dropped"] += len(pairs)
            self.refuse_until = time.monotonic() + float(arg)
        for p in {id(p): p for p in self.pairs.values()}.values():
            if p.b is not None:
                self._watch(p)
        self.ctl.send(("ok", dict(self.counts, connections=len(self.pairs))))
        return True

    def serve(self) -> None:
        while True:
            for key, events in self.sel.select(0.5):
                kind, port = key.data
                if kind == "ctl":
                    if not self._command():
                        return
                elif kind == "listen":
                    self._accept(key.fileobj, port)  # type: ignore[arg-type]
                else:
                    self._io(key.fileobj, events)  # type: ignore[arg-type]


def _child_entry(fd: int) -> None:  # pragma: no cover - runs in the child
    ctl = Connection(fd)
    listen, target, ports = ctl.recv()
    try:
        proxy = _Proxy(listen, target, tuple(ports), ctl)
    except OSError as exc:
        ctl.send(("error", str(exc)))
        return
    ctl.send(("ready", None))
    proxy.serve()


class FaultProxy:
    """Forward ``listen``:ports to ``target``:ports (loopback), with faults on demand."""

    def __init__(self, listen: str, target: str, ports: tuple[int, ...] = UR_PORTS) -> None:
        _loopback(listen)
        _loopback(target)
        self.listen, self.target, self.ports = listen, target, tuple(ports)
        self._proc: subprocess.Popen | None = None
        self._conn: Connection | None = None

    def start(self, timeout: float = 10.0) -> FaultProxy:
        ours, theirs = socket.socketpair()
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
        code = f"from {__name__} import _child_entry; _child_entry({theirs.fileno()})"
        self._proc = subprocess.Popen([sys.executable, "-c", code], pass_fds=(theirs.fileno(),),
                                      env=env, stdin=subprocess.DEVNULL)  # fmt: skip
        theirs.close()
        self._conn = Connection(ours.detach())
        self._conn.send((self.listen, self.target, list(self.ports)))
        if not self._conn.poll(timeout):
            self.close()
            raise RuntimeError(f"fault proxy on {self.listen}: did not start in {timeout} s")
        status, payload = self._conn.recv()
        if status != "ready":
            self.close()
            raise OSError(f"fault proxy on {self.listen}: {payload}")
        return self

    def _call(self, cmd: str, arg: float = 0.0) -> dict:
        if self._conn is None:
            raise RuntimeError("fault proxy not started")
        self._conn.send((cmd, arg))
        if not self._conn.poll(5.0):
            raise RuntimeError(f"fault proxy: no answer to {cmd}")
        return self._conn.recv()[1]

    def freeze(self) -> dict:
        """Stop forwarding; keep every socket open (and accept new ones, unanswered)."""
        return self._call("freeze")

    def drop(self, refuse_for: float = 0.0) -> dict:
        """Close both sides of every connection; refuse new ones for ``refuse_for`` s."""
        return self._call("drop", refuse_for)

    def resume(self) -> dict:
        return self._call("resume")

    def close(self, timeout: float = 3.0) -> None:
        proc, conn = self._proc, self._conn
        self._proc = self._conn = None
        if conn is not None:
            with contextlib.suppress(OSError, EOFError):
                conn.send(("close", 0.0))
                conn.poll(timeout)
            with contextlib.suppress(OSError):
                conn.close()
        if proc is not None:
            try:
                proc.wait(timeout)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(2.0)

    def __enter__(self) -> FaultProxy:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()
