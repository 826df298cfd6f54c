"""Emulator child processes forked from a warm process (a zygote): :func:`fork_child`.

A fresh interpreter per emulator imports the package anew: 0.4-1.5 s of CPU and
seconds of wall time on a busy machine, and the tests start hundreds of emulators.
The zygote (one per parent process, started on first use: ``python -c`` and a socket
pair) imports :mod:`.process` and builds the URScript parser once, then forks a child
per request; a child is serving in about 0.1 s.  The zygote is told which function a
child runs (``"module:function"``, :data:`EMULATOR_CHILD`), not importing it by name: the
emulator's process module imports this one.  (multiprocessing's ``forkserver``
does the same, but re-runs the parent's ``__main__`` in every child.)

Each child gets the parent's standard output and error and working directory as they
are when it starts (as a child the parent started itself would), and the child's end
of the parent's socket pair; it runs :func:`.process._child_entry` on it and exits.
The zygote ignores SIGINT (as the children do; the parent stops them), reaps its
children (so their CPU time counts in the parent's children), and exits when the
parent does (its socket closes); a child exits when its pipe closes.  The parent
watches a child through a pidfd (:class:`Child`): it is not the child's parent, so
the exit code is the zygote's to reap, not known here.
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import importlib
import os
import select
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
import traceback

__all__ = ["EMULATOR_CHILD", "Child", "fork_child"]

#: what a child runs: the emulator served to the parent over one socket (its fd)
EMULATOR_CHILD = "ruledrobot.ursim.process:_child_entry"

#: s: the longest a request may wait for the zygote (its start imports the package)
ZYGOTE_TIMEOUT = 60.0

_lock = threading.Lock()
#: the zygote of this process per entry point: (owner pid, socket, process); replaced
#: after a fork
_zygotes: dict[str, tuple[int, socket.socket, subprocess.Popen]] = {}


class Child:
    """A child the zygote forked: its :attr:`pid`, watched through a pidfd.

    A pidfd needs Linux 5.3+; elsewhere the child is probed by signal 0 every 10 ms."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self._fd: int | None = None
        self._gone = False
        try:
            self._fd = os.pidfd_open(pid)
        except ProcessLookupError:  # already gone (and reaped by the zygote)
            self._gone = True
        except (AttributeError, OSError):  # no pidfd here: _alive() polls
            pass

    def _alive(self) -> bool:
        try:
            os.kill(self.pid, 0)
            return True
        except ProcessLookupError:
            self._gone = True
            return False

    def wait(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for the child to end; whether it has."""
        if self._gone:
            return True
        if self._fd is None:
            deadline = time.monotonic() + timeout
            while self._alive() and time.monotonic() < deadline:
                time.sleep(0.01)
            return self._gone
        p = select.poll()
        p.register(self._fd, select.POLLIN)
        return bool(p.poll(max(0.0, timeout) * 1e3))

    @property
    def running(self) -> bool:
        """True while the child lives."""
        return not self.wait(0.0)

    def kill(self) -> None:
        """SIGKILL the child (nothing when it is gone)."""
        with contextlib.suppress(ProcessLookupError):
            if self._fd is not None:
                signal.pidfd_send_signal(self._fd, signal.SIGKILL)
            elif not self._gone:
                os.kill(self.pid, signal.SIGKILL)

    def close(self) -> None:
        """Release the pidfd (after the child ended)."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


def fork_child(fd: int, entry: str = EMULATOR_CHILD) -> Child:
    """Fork an emulator child that serves this process on socket ``fd``.

    The child runs ``entry`` (``"module:function"``, called with ``fd``); the caller closes
    its copy of ``fd``.  RuntimeError when the zygote cannot start or fork."""
    with _lock:
        for attempt in (0, 1):  # a dead zygote (killed, crashed) is started again, once
            sock = _zygote_socket(entry, fresh=attempt > 0)
            try:
                return Child(_request(sock, fd))
            except OSError as exc:
                error = exc
        raise RuntimeError(f"emulator: the zygote process cannot fork a child: {error}")


def _request(sock: socket.socket, fd: int) -> int:
    """One fork: send ``fd`` with stdout, stderr and the working directory; the pid back."""
    std = [f if _is_open(f) else os.open(os.devnull, os.O_WRONLY) for f in (1, 2)]
    try:
        socket.send_fds(sock, [os.fsencode(os.getcwd())], [fd, *std])
    finally:
        for new, f in zip(std, (1, 2), strict=True):
            if new != f:
                os.close(new)
    reply = b""
    while len(reply) < 8:
        part = sock.recv(8 - len(reply))
        if not part:
            raise ConnectionError("the zygote process ended")
        reply += part
    pid = struct.unpack("<q", reply)[0]
    if pid < 0:
        raise OSError(-pid, os.strerror(-pid))
    return pid


def _is_open(fd: int) -> bool:
    try:
        os.fstat(fd)
        return True
    except OSError:
        return False


def _zygote_socket(entry: str, fresh: bool) -> socket.socket:
    """The socket to this process's zygote for ``entry``, started first when needed.

    Started when there is none, when it belongs to the process this one was forked from,
    or when ``fresh``."""
    zygote = _zygotes.get(entry)
    if zygote is not None and zygote[0] == os.getpid() and not fresh:
        return zygote[1]
    if zygote is not None and zygote[0] == os.getpid():
        _stop(zygote)
    ours, theirs = socket.socketpair()
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
    code = f"from {__name__} import _serve; _serve({theirs.fileno()}, {entry!r})"
    proc = subprocess.Popen([sys.executable, "-c", code], pass_fds=(theirs.fileno(),), env=env,
                            stdin=subprocess.DEVNULL)  # fmt: skip
    theirs.close()
    ours.settimeout(ZYGOTE_TIMEOUT)
    _zygotes[entry] = (os.getpid(), ours, proc)
    return ours


def _stop(zygote: tuple[int, socket.socket, subprocess.Popen]) -> None:
    """Close the socket of a zygote (it exits) and reap it."""
    _, sock, proc = zygote
    sock.close()
    try:
        proc.wait(2.0)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


@atexit.register
def _at_exit() -> None:
    for zygote in _zygotes.values():
        if zygote[0] == os.getpid():
            _stop(zygote)


def _serve(fd: int, entry: str) -> None:  # pragma: no cover - runs in the zygote
    """The zygote: import, then fork a child per request until the parent's socket closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # reaped here (not SIG_IGN, which lets the kernel reap them) so that their CPU time
    # counts in the zygote's children, and so in its parent's (``time make test``)
    signal.signal(signal.SIGCHLD, _reap)
    from .script.syntax import warm_up

    module, name = entry.split(":")
    target = getattr(importlib.import_module(module), name)

    warm_up()
    gc.collect()
    gc.freeze()  # what the children inherit stays out of their collections
    sock = socket.socket(fileno=fd)
    while True:
        try:
            msg, fds, _, _ = socket.recv_fds(sock, 8192, 3)
        except OSError:
            return
        if not msg:
            return
        if len(fds) != 3:
            for f in fds:
                os.close(f)
            sock.sendall(struct.pack("<q", -22))  # EINVAL
            continue
        try:
            pid = os.fork()
        except OSError as exc:
            pid = -(exc.errno or 11)
        if pid == 0:
            _run_child(sock, fds, msg, target)
        for f in fds:
            os.close(f)
        sock.sendall(struct.pack("<q", pid))


def _reap(_signum: int, _frame: object) -> None:  # pragma: no cover - runs in the zygote
    """SIGCHLD: wait for every child that ended."""
    with contextlib.suppress(ChildProcessError):
        while os.waitpid(-1, os.WNOHANG)[0] > 0:
            pass


def _run_child(sock: socket.socket, fds: list[int], cwd: bytes, entry) -> None:  # pragma: no cover
    """In a forked child: take the parent's stdout, stderr and directory; serve; exit."""
    code = 1
    try:
        sock.close()
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        conn, out, err = fds
        os.dup2(out, 1)
        os.dup2(err, 2)
        os.close(out)
        os.close(err)
        with contextlib.suppress(OSError):
            os.chdir(cwd)
        entry(conn)
        code = 0
    except BaseException:
        traceback.print_exc()
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)
