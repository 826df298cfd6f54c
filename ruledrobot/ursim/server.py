"""The emulator core: a controller, its clock, and the servers clients talk to.

Ports default to the controller's (RTDE 30004, dashboard 29999, script
30003, primary 30001, secondary 30002).  ur_rtde's Python bindings cannot
change them, so parallel emulators use distinct loopback addresses
(127.0.0.2, 127.0.0.3, ...; all of 127.0.0.0/8 is loopback on Linux).  The
emulator binds to loopback only unless ``allow_remote=True``.
"""

from __future__ import annotations

import contextlib
import gc
import ipaddress
import logging
import math
import os
import shutil
import socket
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..protocol.modes import RobotMode, RuntimeState, SafetyMode
from ..robot import Calibration, RobotModel
from .address import start_on_free_host
from .arm.backend import ArmBackend, KinematicBackend
from .arm.emulated import emulated_model, kinematics_info_of
from .clock import ClockStats
from .controller.machine import Controller
from .ports.dashboard import DashboardServer
from .ports.primary import PrimaryPublisher, PrimaryServer
from .ports.rtde import RTDEServer
from .ports.script import ScriptPortServer
from .ports.tcp import try_realtime_priority

__all__ = [
    "CB3_VERSION",
    "E_SERIES_VERSION",
    "ClockStats",
    "ThreadedEmulator",
    "emulated_model",
    "kinematics_info_of",
    "serve",
]

log = logging.getLogger("ruledrobot.ursim")

#: controller versions reported to ``v``: e-Series (500 Hz) and CB3 (125 Hz)
E_SERIES_VERSION = (5, 11, 1, 108318)
CB3_VERSION = (3, 15, 7, 106331)

_switch_lock = threading.Lock()
_switch_users = 0
_switch_saved = 0.005


#: s: the longest stall of the emulator's host the clock catches up on (it runs the missed
#: periods, as the controller would have); a longer one makes the controller's time jump
MAX_CATCH_UP = 10.0


def _check_host(host: str, allow_remote: bool) -> None:
    try:
        addr = ipaddress.ip_address(socket.gethostbyname(host))
    except (OSError, ValueError):
        raise ValueError(f"host: cannot resolve {host!r}") from None
    if not addr.is_loopback and not allow_remote:
        raise ValueError(
            f"host: {host!r} is not a loopback address; pass allow_remote=True to serve "
            "a network interface"
        )


class ThreadedEmulator:
    """A UR controller on ``host`` in this process.

    RTDE, dashboard, script port, primary and secondary interfaces, simulated arm.

    Runs on threads of the calling process.  ur_rtde's Python bindings hold
    the GIL while they wait for the controller, so a ur_rtde client in the
    same process would deadlock it: use :class:`~.process.Emulator` (a child
    process, the default) there; this class is what the child runs, and what
    :func:`serve` runs.

    Parameters
    ----------
    host : address to bind (loopback, e.g. ``"127.0.0.2"``, unless ``allow_remote``).
    model : robot model name or :class:`RobotModel` (its control period sets the
        clock: 500 Hz e-Series, 125 Hz CB3; its tool is the initial TCP).
    calibration : the robot's factory calibration (:class:`~ruledrobot.robot.Calibration`
        or a ``ruledrobot.calibration/1`` file), or None: the emulator is then that
        robot (its KinematicsInfo, its FK and IK in everything it reports and does).
        A calibration of another model is refused (ValueError).
    backend : arm backend, or a factory called with the model (default: kinematic).
        It simulates the joints of the nominal arm (its dynamics).
    q0 : initial joint positions [rad].
    rtde_port, dashboard_port, script_port, primary_port, secondary_port : ports (0
        picks free ones).
    version : controller version reported to clients (default 5.11.1 for
        e-Series models, 3.15.7 for CB3).
    serial_number : digits, reported by ``get serial number``.
    unlock_delay : seconds before a protective stop can be unlocked (5 on a robot).
    allow_remote : allow a non-loopback ``host``.
    max_connections, idle_timeout : per server, at most ``max_connections``
        connections; when full, a newcomer replaces the connection idle longest if
        it has received nothing (and streams nothing) for ``idle_timeout`` s,
        else it is refused.
    programs_dir : the folder the dashboard's ``load`` serves programs from (as
        PolyScope serves ``/programs``); default: an empty temporary folder,
        removed by :meth:`close` (:attr:`programs_dir` says where).
    realtime : try to run the clock thread with real-time priority
        (``SCHED_FIFO`` 10, the server threads 5; needs CAP_SYS_NICE, silently
        skipped otherwise): fewer missed periods when clients load the CPU.
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        model: str | RobotModel = "ur5e",
        *,
        backend: ArmBackend | Callable[[RobotModel], ArmBackend] | None = None,
        q0: ArrayLike | None = None,
        calibration: Calibration | str | os.PathLike | None = None,
        rtde_port: int = 30004,
        dashboard_port: int = 29999,
        script_port: int = 30003,
        primary_port: int = 30001,
        secondary_port: int = 30002,
        version: tuple[int, int, int, int] | None = None,
        serial_number: str = "20235500001",
        unlock_delay: float = 5.0,
        allow_remote: bool = False,
        realtime: bool = True,
        max_connections: int = 32,
        idle_timeout: float = 10.0,
        programs_dir: str | None = None,
    ) -> None:
        _check_host(host, allow_remote)
        self.realtime = realtime
        self.realtime_clock = False
        self.model = emulated_model(model, calibration)
        self.calibration: Calibration | None = self.model.calibration
        self.kinematics_info = kinematics_info_of(self.model)
        if not serial_number.isdigit():
            raise ValueError(f"serial_number: digits only, got {serial_number!r}")
        if version is None:
            version = E_SERIES_VERSION if self.model.control_period < 0.005 else CB3_VERSION
        self.version = tuple(int(x) for x in version)
        self.host = host
        if isinstance(backend, type) or (callable(backend) and not hasattr(backend, "state")):
            backend = backend(self.model.nominal)  # a factory: called with the (nominal) model
        self._own_programs = programs_dir is None
        if programs_dir is None:
            programs_dir = tempfile.mkdtemp(prefix="ruledrobot-programs-")
        elif not Path(programs_dir).is_dir():
            raise ValueError(f"programs_dir: {programs_dir!r} is not a folder")
        self.programs_dir = str(programs_dir)
        if backend is None:
            backend = KinematicBackend(self.model.nominal)
        self.controller = Controller(self.model, backend, q0=q0, unlock_delay=unlock_delay,
                                     programs_dir=self.programs_dir)  # fmt: skip
        limits = {"max_connections": max_connections, "idle_timeout": idle_timeout}
        self.rtde = RTDEServer(host, rtde_port, self.controller, self.version, **limits)  # type: ignore[arg-type]
        self.dashboard = DashboardServer(
            host, dashboard_port, self.controller, version=self.version,  # type: ignore[arg-type]
            serial_number=serial_number, **limits,
        )  # fmt: skip
        self.script = ScriptPortServer(host, script_port, self.controller, **limits)
        self.frozen = threading.Event()  # the frozen-controller fault
        self._thaw: threading.Timer | None = None
        self.primary = PrimaryServer(host, primary_port, self.controller, self._hello,
                                     name="primary", **limits)  # fmt: skip
        self.secondary = PrimaryServer(host, secondary_port, self.controller, self._hello,
                                       name="secondary", **limits)  # fmt: skip
        major, minor, bugfix, build = self.version
        self.publisher = PrimaryPublisher(self.controller, (self.primary, self.secondary),
                                          self.kinematics_info, (major, minor, bugfix, build),
                                          self.frozen)  # fmt: skip
        self._servers = (self.rtde, self.dashboard, self.script, self.primary, self.secondary)
        self.controller.realtime = realtime  # the threads its programs start (sockets)
        for srv in self._servers:
            srv.realtime = realtime
            srv.frozen = self.frozen
        self.stats = ClockStats()
        #: periods the clock runs late to catch up after a stall of its host (MAX_CATCH_UP s)
        self.max_catch_up_ticks = math.ceil(MAX_CATCH_UP / self.controller.period)
        self._stop = threading.Event()
        self._clock: threading.Thread | None = None
        self._started = False

    # ------------------------------------------------------------ lifecycle

    def start(self) -> ThreadedEmulator:
        """Bind the three ports and start the clock; returns self."""
        if self._started:
            return self
        started = []
        try:
            for srv in self._servers:
                srv.start()
                started.append(srv)
        except OSError:
            for srv in started:
                srv.close(timeout=1.0)
            if self._own_programs:  # nothing started: close() will not run
                shutil.rmtree(self.programs_dir, ignore_errors=True)
            raise
        self.publisher.start()
        _acquire_switch_interval()
        gc.callbacks.append(self._gc_timer)
        self._started = True
        self._clock = threading.Thread(target=self._run_clock, name="emu-clock", daemon=True)
        self._clock.start()
        log.info("emulator %s on %s: rtde %d, dashboard %d, script %d, primary %d, secondary %d",
                 self.model.name, self.host, self.rtde.port, self.dashboard.port,
                 self.script.port, self.primary.port, self.secondary.port)  # fmt: skip
        return self

    def close(self, timeout: float = 3.0) -> None:
        """Stop the clock and the servers; bounded by ``timeout`` seconds."""
        if not self._started:
            return
        self._started = False
        deadline = time.monotonic() + timeout
        self.unfreeze()
        self._stop.set()
        if self._clock is not None:
            self._clock.join(max(0.1, deadline - time.monotonic()))
        self.publisher.close(timeout=max(0.1, (deadline - time.monotonic()) / 6))
        for srv in self._servers:
            srv.close(timeout=max(0.1, (deadline - time.monotonic()) / 6))
        with contextlib.suppress(ValueError):
            gc.callbacks.remove(self._gc_timer)
        _release_switch_interval()
        if self._own_programs:
            shutil.rmtree(self.programs_dir, ignore_errors=True)

    def __enter__(self) -> ThreadedEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def running(self) -> bool:
        """True between :meth:`start` and :meth:`close` while the clock thread lives."""
        return self._started and self._clock is not None and self._clock.is_alive()

    def _hello(self) -> bytes:
        return self.publisher.hello()

    # ------------------------------------------------------------ clock

    def _run_clock(self) -> None:
        if self.realtime:
            self.realtime_clock = try_realtime_priority(10)
        ctrl = self.controller
        period = ctrl.period
        stats = self.stats
        lateness, gaps = stats.lateness, stats.gaps
        assert lateness is not None and gaps is not None
        next_t = time.perf_counter() + period
        last_publish: float | None = None
        while not self._stop.is_set():
            if self.frozen.is_set():  # frozen: no tick, no data, the time stands still
                self._stop.wait(0.01)
                next_t = time.perf_counter() + period
                last_publish = None
                continue
            now = time.perf_counter()
            wait = next_t - now
            if wait > 0:
                time.sleep(wait)
            now = time.perf_counter()
            late = now - next_t
            if late > period:
                # the host woke us late: the controller does not pause, so run the periods
                # it would have run (and publish them, with their controller time), then
                # this one; only a stall beyond MAX_CATCH_UP s resynchronises (the
                # controller's time then jumps: logged and counted)
                missed = int(late // period)
                if missed > self.max_catch_up_ticks:
                    stats.resyncs += 1
                    self._log_error(f"emulator: its host stalled {1e3 * late:.0f} ms: "
                                    "controller time jumped", stats.resyncs)  # fmt: skip
                    next_t = now
                    missed = 0
                stats.stall_max = max(stats.stall_max, late)
                for _ in range(missed):
                    self._publish(self._tick(), now)
                    stats.ticks += 1
                stats.missed += missed
                next_t += missed * period
                late = now - next_t
            state = self._tick()
            if last_publish is not None:
                gaps.append(now - last_publish)
            last_publish = now
            self._publish(state, now)
            stats.ticks += 1
            lateness.append(late)
            next_t += period

    def _publish(self, state: dict[str, object], now: float) -> None:
        try:
            self.rtde.publish(state, now, self.controller.ticks)
        except Exception:  # publish isolates connections; this is a bug, keep the clock
            self.stats.publish_errors += 1
            self._log_error("emulator: publishing failed", self.stats.publish_errors)

    def _gc_timer(self, phase: str, info: dict) -> None:
        """gc callback: the longest collector pause (``stats.gc_max``)."""
        if phase == "start":
            self._gc_t0 = time.perf_counter()
        else:
            pause = time.perf_counter() - getattr(self, "_gc_t0", time.perf_counter())
            self.stats.gc_max = max(self.stats.gc_max, pause)

    def _tick(self) -> dict[str, object]:
        """One controller period; a failure is counted and logged (rate-limited), and the
        last published values go out again: the clock and the streams go on."""
        try:
            return self.controller.tick()
        except Exception:
            self.stats.tick_errors += 1
            self._log_error("emulator: controller tick failed", self.stats.tick_errors)
            return self.controller.values

    @staticmethod
    def _log_error(message: str, count: int) -> None:
        """Log the 1st, 2nd, 4th, 8th, ... occurrence (a traceback per tick floods the log)."""
        if count & (count - 1) == 0:
            log.exception("%s (%d times so far)", message, count)

    # ------------------------------------------------------------ faults

    def protective_stop(self, reason: str = "protective stop injected") -> None:
        """Fault: protective stop (arm brakes, program stops; unlock via dashboard)."""
        self.controller.protective_stop(reason)

    def emergency_stop(self, reason: str = "emergency stop injected") -> None:
        """Fault: emergency stop (arm brakes, power off)."""
        self.controller.emergency_stop(reason)

    def release_emergency_stop(self) -> None:
        """Release the e-stop (then dashboard ``power on`` and ``brake release``)."""
        self.controller.release_emergency_stop()

    def drop_connections(self, refuse_for: float = 0.0) -> int:
        """Fault: close every client connection; refuse new ones for ``refuse_for`` s."""
        n = 0
        for srv in self._servers:
            n += srv.drop_all(refuse_for)
        self.controller.log(f"dropped {n} connections (refusing for {refuse_for:g} s)", level=2)
        return n

    def freeze(self, duration: float | None = None) -> None:
        """Fault: a frozen controller, for ``duration`` s (None: until :meth:`unfreeze`).

        Sockets stay open, nothing is accepted, read, answered or sent, and the
        controller time stands still (the kernel buffers what clients send; it is
        read and answered after the freeze).
        """
        if duration is not None and not duration > 0.0:
            raise ValueError(f"freeze: duration must be > 0 s, got {duration}")
        self.controller.log("controller frozen" + (f" for {duration:g} s" if duration else ""),
                            level=2)  # fmt: skip
        self.frozen.set()
        if self._thaw is not None:
            self._thaw.cancel()
            self._thaw = None
        if duration is not None:
            self._thaw = threading.Timer(duration, self.unfreeze)
            self._thaw.daemon = True
            self._thaw.start()

    def unfreeze(self) -> None:
        """End the frozen-controller fault (no-op when not frozen)."""
        if self._thaw is not None:
            self._thaw.cancel()
            self._thaw = None
        if self.frozen.is_set():
            self.frozen.clear()
            self.controller.log("controller answers again (frozen fault over)", level=2)

    def set_slow(self, delay: float, jitter: float = 0.0) -> None:
        """Fault: a slow controller; every data package arrives ``delay`` (+ jitter) s late.

        ``set_slow(0)`` restores the normal stream.
        """
        self.rtde.set_delay(delay, jitter)
        self.controller.log(f"slow controller: delay {delay:g} s, jitter {jitter:g} s", level=2)

    def clear_faults(self) -> None:
        """Back to safety NORMAL, robot RUNNING, no delay (test helper)."""
        self.rtde.set_delay(0.0)
        self.controller.clear_faults()

    # ------------------------------------------------------------ observation

    @property
    def actual_q(self) -> np.ndarray:
        """Actual joint positions [rad], shape (6,), base to wrist 3 (a copy)."""
        with self.controller.lock:
            return self.controller.backend.state().q.copy()

    @property
    def tcp_pose(self) -> np.ndarray:
        """Actual TCP pose as a UR vector."""
        with self.controller.lock:
            return np.asarray(self.controller.values["actual_TCP_pose"], dtype=float)

    @property
    def robot_mode(self) -> RobotMode:
        """The controller's robot mode (RUNNING, IDLE, POWER_OFF, ...)."""
        return self.controller.robot_mode

    @property
    def safety_mode(self) -> SafetyMode:
        """The controller's safety mode (NORMAL, PROTECTIVE_STOP, ROBOT_EMERGENCY_STOP, ...)."""
        return self.controller.safety_mode

    @property
    def runtime_state(self) -> RuntimeState:
        """The runtime state of the controller's program (STOPPED, PLAYING, PAUSED)."""
        return self.controller.runtime_state

    @property
    def popup(self) -> str | None:
        """The popup the pendant shows (a compile error, URScript ``popup``), or None."""
        return self.controller.popup

    @property
    def events(self) -> list[tuple[float, int, str]]:
        """Controller log: (controller time, level, message)."""
        with self.controller.lock:
            return list(self.controller.events)

    @property
    def io_log(self) -> list[tuple[float, int, int, int, float, float]]:
        """Every change of the outputs.

        (controller time [s], standard, configurable and tool digital output bits, standard
        analog outputs 0 and 1 [fraction])."""
        with self.controller.lock:
            return list(self.controller.io_log)

    @property
    def ports(self) -> dict[str, int]:
        """The bound ports.

        ``{"rtde": ..., "dashboard": ..., "script": ..., "primary": ..., "secondary": ...}``."""
        return {
            "rtde": self.rtde.port,
            "dashboard": self.dashboard.port,
            "script": self.script.port,
            "primary": self.primary.port,
            "secondary": self.secondary.port,
        }

    def stats_summary(self) -> dict[str, float]:
        """Clock timing (:meth:`ClockStats.summary`) plus RTDE counters."""
        out = self.stats.summary()
        out["rtde_protocol_errors"] = float(self.rtde.protocol_errors)
        out["publish_errors"] = float(self.rtde.publish_errors + self.stats.publish_errors)
        out["rtde_connections"] = float(len(self.rtde.connections()))
        out["programs_received"] = float(self.script.programs_received
                                         + self.primary.programs_received
                                         + self.secondary.programs_received)  # fmt: skip
        out["primary_connections"] = float(len(self.primary.connections())
                                           + len(self.secondary.connections()))  # fmt: skip
        out["primary_messages"] = float(self.publisher.sent)
        out["primary_dropped"] = float(self.primary.dropped + self.secondary.dropped)
        out["primary_errors"] = float(self.publisher.errors)
        servers = self._servers
        out["refused_connections"] = float(sum(s.refused for s in servers))
        out["evicted_connections"] = float(sum(s.evicted for s in servers))
        out["limit_events"] = float(self.controller.limit_events)
        out["realtime_clock"] = float(self.realtime_clock)
        return out

    def reset_stats(self) -> None:
        """Forget the clock's timing so far (measure one phase of a test)."""
        self.stats.lateness.clear()
        self.stats.gaps.clear()
        self.stats.ticks = self.stats.missed = self.stats.resyncs = 0
        self.stats.gc_max = 0.0

    def reset(self, q: ArrayLike) -> None:
        """Put the arm at rest at ``q`` (no motion, no program change)."""
        with self.controller.lock:
            self.controller.motion = None
            self.controller.mode = "idle"
            self.controller._hold_q = None
            self.controller.backend.reset(np.asarray(q, dtype=float))

    def wait_for(self, predicate: Callable[[], bool], timeout: float = 5.0) -> bool:
        """Poll ``predicate`` every 5 ms until it holds or ``timeout`` passes."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(0.005)
        return bool(predicate())

    def __repr__(self) -> str:
        return (f"ThreadedEmulator({self.model.name!r} on {self.host}, rtde {self.rtde.port}, "
                f"{'running' if self.running else 'stopped'})")  # fmt: skip


def _acquire_switch_interval() -> None:
    """Shorten the GIL switch interval while an emulator runs (500 Hz needs < 1 ms)."""
    global _switch_users, _switch_saved
    with _switch_lock:
        if _switch_users == 0:
            _switch_saved = sys.getswitchinterval()
            sys.setswitchinterval(min(_switch_saved, 0.0005))
        _switch_users += 1


def _release_switch_interval() -> None:
    global _switch_users
    with _switch_lock:
        _switch_users = max(0, _switch_users - 1)
        if _switch_users == 0:
            with contextlib.suppress(ValueError):
                sys.setswitchinterval(_switch_saved)


def serve(
    host: str = "127.0.0.1",
    model: str | RobotModel = "ur5e",
    *,
    duration: float | None = None,
    ready: Callable[[ThreadedEmulator], None] | None = None,
    find_free_host: bool = False,
    **kwargs: object,
) -> None:
    """Run an emulator until Ctrl-C (or for ``duration`` seconds); blocking.

    ``ready(emulator)`` is called once it listens (e.g. to print the address:
    ``emulator.host``); with ``find_free_host`` a taken ``host`` is replaced by the
    next free loopback address (:func:`~.address.start_on_free_host`); other keyword
    arguments go to :class:`ThreadedEmulator`.  The emulator runs in this process:
    connect clients from another process.
    """
    emu = start_on_free_host(
        host, lambda h: ThreadedEmulator(h, model, **kwargs).start(),  # type: ignore[arg-type]
        find_free_host=find_free_host,
    )  # fmt: skip
    with emu:
        if ready is not None:
            ready(emu)
        t0 = time.monotonic()
        try:
            while duration is None or time.monotonic() - t0 < duration:
                time.sleep(0.1)
        except KeyboardInterrupt:
            log.info("emulator: interrupted, shutting down")
