"""The runner's side of the child process: start it, watch it, kill it when it hangs or dies.

:class:`Child` starts :mod:`.run_child` (``python -c``, a socket pair, its own
session, output to a log file) and :meth:`Child.supervise` reads its messages
until ``("done", ...)``, with a time bound on every step: each ``("stage",
name, timeout)`` the child announces sets how long it may stay silent; a
silent child is killed (SIGKILL), a dead one is noticed at once (the pipe
closes).  Either way the recording streamed so far is kept: a crash loses at
most one chunk (:data:`~.run_session.CHUNK`).  A Ctrl-C (KeyboardInterrupt,
also SIGTERM and SIGHUP while supervising) asks the child for a safe stop; a
second one kills it.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from typing import Any

import numpy as np

__all__ = ["Child", "ChildGone", "Outcome"]


class ChildGone(RuntimeError):
    """The child died or was killed before it answered."""


@dataclass
class Outcome:
    """What the supervision ended with.

    ``status``/``message``: the child's (``done``) or the supervisor's
    (``client_died``, ``client_hung``, or the stop the child had reported,
    with what happened after); ``info``: the child's last progress
    (``k_match``, ``sent``, ``max_dev``); ``chunks``: the recording, (t, q, tcp, k, outputs)
    arrays in order (``k``: the grid sample each was matched to, -1 for none);
    ``killed``: the supervisor killed the child;
    ``exit``: how the child ended, in words; ``log``: the tail of its output;
    ``timeline``: (``time.monotonic()``, event) of every stage, stop and end.
    """

    status: str = ""
    message: str = ""
    info: dict = field(default_factory=lambda: {"k_match": 0, "sent": 0, "max_dev": 0.0})
    chunks: list[tuple[np.ndarray, ...]] = field(default_factory=list)
    killed: bool = False
    exit: str = ""
    log: str = ""
    timeline: list[tuple[float, str]] = field(default_factory=list)


def _describe_exit(code: int | None) -> str:
    if code is None:
        return "still running"
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"


class Child:
    """The ur_rtde session in a child process."""

    def __init__(self, cfg: dict) -> None:
        ours, theirs = socket.socketpair()
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
        self._log = tempfile.TemporaryFile()
        code = f"from ruledrobot.export.run_child import main; main({theirs.fileno()})"
        self.proc = subprocess.Popen(
            [sys.executable, "-c", code],
            pass_fds=(theirs.fileno(),),
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=self._log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        theirs.close()
        self.conn = Connection(ours.detach())
        self.stage = ("starting", 30.0)
        self.conn.send(cfg)

    # ------------------------------------------------------------ messages

    def send(self, *msg: Any) -> bool:
        """Send the tuple ``msg`` to the child; whether it went (False when the pipe is gone)."""
        try:
            self.conn.send(msg)
            return True
        except OSError:
            return False

    def recv(self, timeout: float) -> tuple | None:
        """The next message, None after ``timeout`` s; ChildGone when the pipe closed."""
        try:
            if not self.conn.poll(max(0.0, timeout)):
                return None
            return self.conn.recv()
        except (EOFError, OSError):
            raise ChildGone(self.exit_text()) from None

    def wait_for(self, kinds: tuple[str, ...]) -> tuple:
        """Messages until one of ``kinds``, under the stage deadlines (kills on a hang)."""
        last = time.monotonic()
        while True:
            left = last + self.stage[1] - time.monotonic()
            if left <= 0:
                self.kill()
                raise ChildGone(f"no answer for {self.stage[1]:g} s ({self.stage[0]}): killed")
            msg = self.recv(min(left, 0.1))
            if msg is None:
                continue
            last = time.monotonic()
            if msg[0] == "stage":
                self.stage = (msg[1], msg[2])
            elif msg[0] in kinds:
                return msg

    # ------------------------------------------------------------ lifecycle

    def exit_text(self) -> str:
        """Return how the child ended, in words, after waiting up to 0.5 s for it.

        ``"exit code 0"``, ``"killed by SIGSEGV"``, ``"still running"``.
        """
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(0.5)
        return _describe_exit(self.proc.poll())

    def kill(self) -> None:
        """Kill the child if it still runs and wait up to 2 s for it."""
        if self.proc.poll() is None:
            with contextlib.suppress(OSError):
                self.proc.kill()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(2.0)

    def close(self, grace: float = 1.0) -> None:
        """Ask the child to leave, kill it after ``grace`` s; close the pipe."""
        self.send("exit")
        try:
            self.proc.wait(grace)
        except subprocess.TimeoutExpired:
            self.kill()
        with contextlib.suppress(OSError):
            self.conn.close()

    def log_tail(self, lines: int = 12) -> str:
        """Return the last ``lines`` lines of the child's output.

        Of its last 4 KiB; empty when unreadable.
        """
        try:
            self._log.seek(0, os.SEEK_END)
            size = self._log.tell()
            self._log.seek(max(0, size - 4096))
            text = self._log.read().decode("utf-8", "replace")
        except OSError:
            return ""
        return "\n".join(text.strip().splitlines()[-lines:])

    # ------------------------------------------------------------ the run

    def supervise(
        self,
        on_progress: Callable[[dict], Any] | None,
        *,
        stop_bound: float,
    ) -> Outcome:
        """Read the run's messages until ``done``; kill on a hang; survive a crash.

        ``on_progress(info)`` is called with every chunk (it may raise
        KeyboardInterrupt).  ``stop_bound``: seconds from a stop request (or a
        stop the child reports) to ``done`` before the child is killed.
        """
        out = Outcome()
        reported: tuple[str, str] | None = None  # a stop the child reported
        asked: tuple[str, str] | None = None  # a stop we asked for
        stop_deadline = float("inf")
        last = time.monotonic()
        restore = _trap_termination()
        try:
            while True:
                try:
                    now = time.monotonic()
                    silent_left = last + self.stage[1] - now
                    if silent_left <= 0 or now > stop_deadline:
                        why = (
                            f"no answer for {self.stage[1]:g} s ({self.stage[0]})"
                            if silent_left <= 0
                            else f"the stop did not finish within {stop_bound:g} s"
                        )
                        self.kill()
                        out.killed = True
                        return self._end(
                            out,
                            reported or asked,
                            f"the ur_rtde client hung: {why}; the runner killed it",
                            "client_hung",
                        )
                    msg = self.recv(min(silent_left, stop_deadline - now, 0.1))
                    if msg is None:
                        continue
                    last = time.monotonic()
                    kind = msg[0]
                    if kind == "stage":
                        self.stage = (msg[1], msg[2])
                        out.timeline.append((last, f"stage {msg[1]}"))
                    elif kind in ("rec", "beat"):
                        if kind == "rec":
                            out.chunks.append(tuple(msg[1:-1]))
                        out.info = msg[-1]
                        if on_progress is not None and reported is None and asked is None:
                            on_progress(out.info)
                    elif kind == "stopping":
                        reported = (msg[1], msg[2])
                        out.timeline.append((last, f"stop reported: {msg[1]}"))
                        stop_deadline = min(stop_deadline, last + stop_bound)
                    elif kind == "done":
                        d = msg[1]
                        out.status, out.message = d["status"], d["message"]
                        out.info = {k: v for k, v in d.items() if k not in ("status", "message")}
                        out.timeline.append((last, "done"))
                        return out
                except ChildGone as gone:
                    return self._end(
                        out,
                        reported or asked,
                        f"the ur_rtde client process died ({gone})",
                        "client_died",
                    )
                except KeyboardInterrupt as exc:
                    if asked is not None:  # the second one
                        self.kill()
                        out.killed = True
                        return self._end(
                            out,
                            asked,
                            "stopped again: the runner killed the ur_rtde client",
                            "interrupted",
                        )
                    text = str(exc) or "Ctrl-C"
                    asked = ("interrupted", f"interrupted by the user ({text})")
                    self.send("stop", *asked)
                    out.timeline.append((time.monotonic(), "stop asked: interrupted"))
                    stop_deadline = time.monotonic() + stop_bound
        finally:
            restore()

    def _end(self, out: Outcome, stop: tuple[str, str] | None, what: str, status: str) -> Outcome:
        out.timeline.append((time.monotonic(), status))
        out.exit = self.exit_text()
        out.log = self.log_tail()
        if stop is not None:
            out.status = stop[0]
            out.message = f"{stop[1]}; then {what}"
        else:
            out.status = status
            out.message = what
        return out


def _trap_termination() -> Callable[[], None]:
    """While supervising: SIGTERM and SIGHUP stop the run like Ctrl-C (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt(signal.Signals(signum).name)

    saved = {}
    for sig in (signal.SIGTERM, signal.SIGHUP):
        with contextlib.suppress(ValueError, OSError):
            saved[sig] = signal.signal(sig, handler)

    def restore() -> None:
        for sig, h in saved.items():
            with contextlib.suppress(ValueError, OSError):
                signal.signal(sig, h)

    return restore
