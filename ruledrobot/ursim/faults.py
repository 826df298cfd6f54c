"""Faults on a timer or on a signal, for ``ruledrobot ursim --fault`` and scripts.

A fault is written ``KIND@WHEN[:ARG]``:

* ``KIND``: ``protective_stop``, ``emergency_stop``, ``drop`` (close every
  connection; ARG: refuse new ones for ARG s, default 0), ``freeze`` (a frozen
  controller: sockets stay open, nothing answers, nothing is sent, the
  controller time stands still; ARG: for ARG s, default until ``clear``),
  ``slow`` (every data package ARG s late, default 0.2 s), ``clear`` (back to
  normal: faults cleared, e-stop released, no delay, unfrozen);
* ``WHEN``: seconds after start (``5``, ``5s``, ``500ms``) or a signal
  (``SIGUSR1``, ``SIGUSR2``; ``USR1``, ``USR2``): the fault fires each time
  the process receives it;
* ``ARG``: seconds (``3``, ``3s``, ``250ms``).

Examples: ``protective_stop@5s``, ``freeze@10s:3s``, ``drop@2:1``,
``emergency_stop@SIGUSR1``, ``clear@SIGUSR2``.
"""

from __future__ import annotations

import re
import signal
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

__all__ = ["FAULT_KINDS", "FaultSchedule", "FaultSpec", "apply_fault", "parse_fault"]

#: fault kinds and what their ARG means (None: no argument)
FAULT_KINDS: dict[str, str | None] = {
    "protective_stop": None,
    "emergency_stop": None,
    "drop": "seconds during which new connections are refused (default 0)",
    "freeze": "seconds the controller stays frozen (default: until a 'clear')",
    "slow": "delay of every data package in seconds (default 0.2)",
    "clear": None,
}
_SIGNALS = {"SIGUSR1": "SIGUSR1", "USR1": "SIGUSR1", "SIGUSR2": "SIGUSR2", "USR2": "SIGUSR2"}
_SECONDS = re.compile(r"^(\d+(?:\.\d*)?|\.\d+)(ms|s)?$")


class FaultTarget(Protocol):
    """What a fault acts on (:class:`~.server.ThreadedEmulator`, :class:`~.process.Emulator`)."""

    def protective_stop(self, reason: str = ...) -> None:
        """Protective stop: the arm brakes, the program stops; ``reason`` is logged."""
        ...

    def emergency_stop(self, reason: str = ...) -> None:
        """Robot emergency stop: the arm brakes, then power goes off; ``reason`` is logged."""
        ...

    def release_emergency_stop(self) -> None:
        """Release the emergency stop (safety NORMAL; power on and brake release follow)."""
        ...

    def drop_connections(self, refuse_for: float = ...) -> int:
        """Close every client connection; refuse new ones for ``refuse_for`` [s].

        Returns how many connections were closed.
        """
        ...

    def freeze(self, duration: float | None = ...) -> None:
        """Freeze the controller for ``duration`` [s] (None: until :meth:`unfreeze`)."""
        ...

    def unfreeze(self) -> None:
        """End the frozen-controller fault."""
        ...

    def set_slow(self, delay: float, jitter: float = ...) -> None:
        """Hold every RTDE data package back by ``delay`` [s] (plus up to ``jitter`` [s])."""
        ...

    def clear_faults(self) -> None:
        """Back to safety NORMAL and robot RUNNING at once, the stream without delay."""
        ...


@dataclass(frozen=True)
class FaultSpec:
    """One fault: ``kind``, when (``at`` seconds after start, or on ``signal``), ``arg``."""

    kind: str
    at: float | None = None
    signal: str | None = None
    arg: float | None = None
    text: str = ""

    def describe(self) -> str:
        """One line for people: kind, argument and when, e.g. ``freeze (3 s) 10 s after start``."""
        when = f"{self.at:g} s after start" if self.signal is None else f"on {self.signal}"
        arg = f" ({self.arg:g} s)" if self.arg is not None else ""
        return f"{self.kind}{arg} {when}"


def _seconds(text: str, what: str, spec: str) -> float:
    m = _SECONDS.match(text.strip())
    if m is None:
        raise ValueError(f"fault {spec!r}: {what} {text!r} is not a time (e.g. 5, 5s, 500ms)")
    value = float(m.group(1))
    return value / 1000.0 if m.group(2) == "ms" else value


def parse_fault(text: str) -> FaultSpec:
    """``KIND@WHEN[:ARG]`` -> :class:`FaultSpec`; ValueError naming what is wrong."""
    spec = text.strip()
    kind, at_sign, rest = spec.partition("@")
    kind = kind.strip().lower().replace("-", "_")
    if not at_sign or not rest.strip():
        raise ValueError(f"fault {spec!r}: expected KIND@WHEN[:ARG], e.g. protective_stop@5s")
    if kind not in FAULT_KINDS:
        raise ValueError(f"fault {spec!r}: unknown kind {kind!r}; expected one of "
                         f"{', '.join(FAULT_KINDS)}")  # fmt: skip
    when, _, arg_text = rest.partition(":")
    arg = None
    if arg_text.strip():
        if FAULT_KINDS[kind] is None:
            raise ValueError(f"fault {spec!r}: {kind} takes no argument")
        arg = _seconds(arg_text, "the argument", spec)
    sig = _SIGNALS.get(when.strip().upper())
    if sig is not None:
        return FaultSpec(kind, None, sig, arg, spec)
    return FaultSpec(kind, _seconds(when, "the time", spec), None, arg, spec)


def apply_fault(emu: FaultTarget, spec: FaultSpec) -> None:
    """Inject ``spec`` now."""
    reason = f"fault {spec.text or spec.kind}"
    if spec.kind == "protective_stop":
        emu.protective_stop(reason)
    elif spec.kind == "emergency_stop":
        emu.emergency_stop(reason)
    elif spec.kind == "drop":
        emu.drop_connections(spec.arg or 0.0)
    elif spec.kind == "freeze":
        emu.freeze(spec.arg)
    elif spec.kind == "slow":
        emu.set_slow(0.2 if spec.arg is None else spec.arg)
    elif spec.kind == "clear":
        emu.unfreeze()
        emu.release_emergency_stop()
        emu.clear_faults()
    else:  # pragma: no cover - parse_fault admits only FAULT_KINDS
        raise ValueError(f"fault kind {spec.kind!r}")


class FaultSchedule:
    """Fires timed faults from a thread and signal faults from signal handlers.

    :meth:`start` must run in the main thread when there are signal faults
    (Python installs signal handlers there only); :meth:`stop` ends the timer
    and restores the previous handlers.  ``on_fire(spec)`` is called after each
    fault (e.g. to print it).
    """

    def __init__(
        self, specs: list[FaultSpec], on_fire: Callable[[FaultSpec], None] | None = None
    ) -> None:
        self.specs = list(specs)
        self.on_fire = on_fire
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._saved: dict[int, object] = {}
        self.fired: list[FaultSpec] = []

    def start(self, emu: FaultTarget) -> FaultSchedule:
        """Arm the faults against ``emu``; returns self.

        Signal faults get their handlers now (the previous ones are kept for :meth:`stop`; call this
        in the main thread).  Timed faults fire from a daemon thread, each ``at`` seconds after this
        call (monotonic clock), in order of ``at``.
        """
        t0 = time.monotonic()
        timed = sorted((s for s in self.specs if s.at is not None), key=lambda s: s.at or 0.0)
        by_signal: dict[str, list[FaultSpec]] = {}
        for s in self.specs:
            if s.signal is not None:
                by_signal.setdefault(s.signal, []).append(s)
        for name, specs in by_signal.items():
            signum = getattr(signal, name)

            def handler(_signum: int, _frame: object, specs: list[FaultSpec] = specs) -> None:
                for s in specs:
                    self._fire(emu, s)

            self._saved[signum] = signal.signal(signum, handler)
        if timed:
            self._thread = threading.Thread(target=self._run, args=(emu, timed, t0),
                                            name="emu-faults", daemon=True)  # fmt: skip
            self._thread.start()
        return self

    def _run(self, emu: FaultTarget, timed: list[FaultSpec], t0: float) -> None:
        for s in timed:
            if self._stop.wait(max(0.0, t0 + (s.at or 0.0) - time.monotonic())):
                return
            self._fire(emu, s)

    def _fire(self, emu: FaultTarget, spec: FaultSpec) -> None:
        apply_fault(emu, spec)
        self.fired.append(spec)
        if self.on_fire is not None:
            self.on_fire(spec)

    def stop(self) -> None:
        """Stop the timer thread (waiting up to 2 s) and restore the saved signal handlers."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)
        for signum, old in self._saved.items():
            signal.signal(signum, old)  # type: ignore[arg-type]
        self._saved.clear()
