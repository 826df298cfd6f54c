"""The emulator in a child process, driven from this one: :class:`Emulator`.

ur_rtde's Python bindings keep the GIL while they wait for the controller
(the interface constructors, ``moveJ``, ...).  An emulator on threads of the
same process can then never answer: the client deadlocks.  :class:`Emulator`
therefore runs the :class:`~.server.ThreadedEmulator` in a child process
(forked from a warm process, :mod:`.zygote`, talking over a socket pair) and
forwards fault injection and state queries to it.  With
``in_process=True`` it runs the threaded emulator here instead (for clients
in other processes, or raw-socket clients).

The child exits when :meth:`Emulator.close` is called or when this process
dies (its pipe closes).
"""

from __future__ import annotations

import contextlib
import gc
import os
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterator
from multiprocessing.connection import Connection
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..protocol.modes import RobotMode, RuntimeState, SafetyMode
from ..protocol.primary import KinematicsInfo
from ..robot import Calibration, RobotModel
from .address import start_on_free_host
from .arm.backend import ArmBackend
from .arm.emulated import emulated_model
from .ports.tcp import try_realtime_priority
from .server import ThreadedEmulator
from .zygote import Child, fork_child

__all__ = ["EMBEDDED_HOST", "Emulator", "embedded_emulator"]

#: Where the embedded emulator listens when a command is given no robot address.
EMBEDDED_HOST = "127.0.0.42"

#: methods and properties of ThreadedEmulator the parent may call
_CALLS = frozenset(
    {
        "protective_stop",
        "emergency_stop",
        "release_emergency_stop",
        "drop_connections",
        "set_slow",
        "clear_faults",
        "stats_summary",
        "reset_stats",
        "freeze",
        "unfreeze",
        "reset",
    }
)
_PROPS = frozenset(
    {
        "io_log",
        "actual_q",
        "tcp_pose",
        "robot_mode",
        "safety_mode",
        "runtime_state",
        "events",
        "ports",
        "popup",
        "programs_dir",
        "calibration",
        "kinematics_info",
    }
)


def _kill(proc: Child) -> None:
    proc.kill()
    proc.wait(2.0)
    proc.close()


def _child_entry(fd: int) -> None:  # pragma: no cover - runs in the child
    """Entry point of the child process: run the emulator, serve the parent's requests."""
    with contextlib.suppress(ValueError, OSError):
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    conn = Connection(fd)
    try:
        kwargs = conn.recv()
        find_free_host = kwargs.pop("find_free_host", False)
        emu = start_on_free_host(
            kwargs["host"], lambda h: ThreadedEmulator(**dict(kwargs, host=h)).start(),
            find_free_host=find_free_host,
        )  # fmt: skip
        # everything allocated so far lives as long as the process: keep it out of
        # the cyclic collector so that full collections stay short (no clock stalls)
        gc.collect()
        gc.freeze()
        if emu.realtime:  # this thread answers the parent (stats, events) holding the GIL:
            try_realtime_priority(5)  # preempted at normal priority, it stalls the clock
    except BaseException as exc:
        text = str(exc) if type(exc) is OSError else f"{type(exc).__name__}: {exc}"
        with contextlib.suppress(OSError):
            conn.send(("error", (text, getattr(exc, "errno", None))))
        return
    conn.send(("ready", (emu.host, emu.ports)))
    try:
        while True:
            try:
                name, args, kw = conn.recv()
            except (EOFError, OSError):
                break
            if name == "close":
                break
            try:
                if name in _CALLS:
                    result = getattr(emu, name)(*args, **kw)
                elif name in _PROPS:
                    result = getattr(emu, name)
                else:
                    raise AttributeError(f"emulator has no remote method {name!r}")
                conn.send(("ok", result))
            except Exception as exc:
                conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        emu.close()
        with contextlib.suppress(OSError):
            conn.send(("closed", None))


class Emulator:
    """A UR controller emulator on ``host``.

    RTDE 30004, dashboard 29999, script 30003, primary 30001, secondary 30002.

    The real ur_rtde client (RTDEReceiveInterface, RTDEControlInterface,
    RTDEIOInterface, DashboardClient) connects to it as to a robot.

    Parameters
    ----------
    host : loopback address to bind, e.g. ``"127.0.0.2"`` (see ``allow_remote``).
    model : robot model name (``"ur5e"``, ...) or a :class:`RobotModel`.
    find_free_host : when ``host`` is taken (another emulator listens there), listen on
        the next free loopback address instead (:func:`~.address.start_on_free_host`);
        :attr:`host` says where once started.  False: a taken ``host`` is an
        ``OSError`` (``errno.EADDRINUSE``).
    calibration : the robot's factory calibration (a :class:`~ruledrobot.robot.Calibration`
        or a ``ruledrobot.calibration/1`` file) or None (nominal kinematics).  Checked
        here: a calibration of another model raises ValueError before anything starts.
    in_process : run on threads of this process instead of a child process
        (never with a ur_rtde client in this process: it would deadlock).
    start_timeout : seconds to wait for the child to listen.
    **options : passed to :class:`~.server.ThreadedEmulator`: ``backend`` (an
        :class:`ArmBackend`, or a picklable factory ``model -> backend`` for the
        child process), ``q0``, ``rtde_port``, ``dashboard_port``,
        ``script_port``, ``primary_port``, ``secondary_port``, ``version``,
        ``serial_number``, ``unlock_delay``, ``allow_remote``.

    Use as a context manager, or call :meth:`start` / :meth:`close`.
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        model: str | RobotModel = "ur5e",
        *,
        find_free_host: bool = False,
        in_process: bool = False,
        start_timeout: float = 20.0,
        backend: ArmBackend | Callable[[RobotModel], ArmBackend] | None = None,
        q0: ArrayLike | None = None,
        calibration: Calibration | str | os.PathLike | None = None,
        **options: Any,
    ) -> None:
        self.host = host
        self.model_name = model if isinstance(model, str) else model.name
        self.in_process = in_process
        self.start_timeout = float(start_timeout)
        self.find_free_host = bool(find_free_host)
        self._kwargs: dict[str, Any] = dict(options, host=host, model=model, backend=backend)
        if calibration is not None:  # refused here, before a child process starts
            self._kwargs["calibration"] = emulated_model(model, calibration).calibration
        if q0 is not None:
            self._kwargs["q0"] = np.asarray(q0, dtype=float).tolist()
        self._local: ThreadedEmulator | None = None
        self._proc: Any = None
        self._conn: Any = None
        self._lock = threading.Lock()
        self._ports: dict[str, int] = {}
        if in_process:
            self._local = ThreadedEmulator(**self._kwargs)

    # ------------------------------------------------------------ lifecycle

    def start(self) -> Emulator:
        """Start serving (in the child process unless ``in_process``); returns self."""
        if self._local is not None:
            if not self._local.running:
                first = self._local
                self._local = start_on_free_host(
                    self.host, lambda h: (first if h == first.host else
                                          ThreadedEmulator(**dict(self._kwargs, host=h))).start(),
                    find_free_host=self.find_free_host,
                )  # fmt: skip
                self.host = self._local.host
            self._ports = self._local.ports
            return self
        if self._proc is not None:
            return self
        ours, theirs = socket.socketpair()
        try:
            proc = fork_child(theirs.fileno())
        finally:
            theirs.close()
        conn = Connection(ours.detach())
        try:
            conn.send(dict(self._kwargs, find_free_host=self.find_free_host))
            if not conn.poll(self.start_timeout):
                raise RuntimeError(
                    f"emulator on {self.host}: did not start in {self.start_timeout} s"
                )
            status, payload = conn.recv()
        except (EOFError, OSError) as exc:
            _kill(proc)
            conn.close()
            raise RuntimeError(
                f"emulator on {self.host}: the child process died ({exc or 'it exited'})"
            ) from None
        except BaseException:
            _kill(proc)
            conn.close()
            raise
        if status != "ready":
            _kill(proc)
            conn.close()
            text, code = payload
            error = OSError(f"emulator on {self.host}: {text}")
            error.errno = code  # EADDRINUSE: the address is taken
            raise error
        self._proc, self._conn = proc, conn
        self.host, self._ports = payload
        return self

    def close(self, timeout: float = 5.0) -> None:
        """Stop the emulator; bounded by ``timeout`` seconds (the child is killed after it)."""
        if self._local is not None:
            self._local.close(timeout)
            return
        proc, conn = self._proc, self._conn
        if proc is None:
            return
        self._proc = self._conn = None
        deadline = time.monotonic() + timeout
        with contextlib.suppress(OSError, BrokenPipeError, EOFError):
            with self._lock:
                conn.send(("close", (), {}))
                while conn.poll(max(0.0, deadline - time.monotonic())):
                    if conn.recv()[0] == "closed":
                        break
        if proc.wait(max(0.1, deadline - time.monotonic())):
            proc.close()
        else:
            _kill(proc)
        with contextlib.suppress(OSError):
            conn.close()

    def __enter__(self) -> Emulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def running(self) -> bool:
        """True while the emulator serves: the child process lives, or the in-process clock runs."""
        if self._local is not None:
            return self._local.running
        return self._proc is not None and self._proc.running

    @property
    def pid(self) -> int | None:
        """Process id of the child (None in-process or when not started)."""
        return None if self._proc is None else self._proc.pid

    # ------------------------------------------------------------ remote calls

    def _call(self, name: str, *args: Any, timeout: float = 10.0, **kw: Any) -> Any:
        if self._local is not None:
            attr = getattr(self._local, name)
            return attr(*args, **kw) if name in _CALLS else attr
        if self._conn is None:
            raise RuntimeError(f"emulator on {self.host} is not running")
        with self._lock:
            self._conn.send((name, args, kw))
            if not self._conn.poll(timeout):
                raise TimeoutError(f"emulator on {self.host}: no answer to {name} in {timeout} s")
            status, payload = self._conn.recv()
        if status != "ok":
            raise RuntimeError(f"emulator on {self.host}: {name}: {payload}")
        return payload

    # faults
    def protective_stop(self, reason: str = "protective stop injected") -> None:
        """Fault: protective stop (the arm brakes, the program stops; dashboard unlock)."""
        self._call("protective_stop", reason)

    def emergency_stop(self, reason: str = "emergency stop injected") -> None:
        """Fault: emergency stop (the arm brakes, power goes off)."""
        self._call("emergency_stop", reason)

    def release_emergency_stop(self) -> None:
        """Release the e-stop; then dashboard ``power on`` and ``brake release``."""
        self._call("release_emergency_stop")

    def drop_connections(self, refuse_for: float = 0.0) -> int:
        """Fault: close every client connection; refuse new ones for ``refuse_for`` s."""
        return int(self._call("drop_connections", refuse_for))

    def freeze(self, duration: float | None = None) -> None:
        """Freeze the controller (a fault) for ``duration`` s, or until :meth:`unfreeze`.

        A frozen controller: sockets open, nothing answers or is sent, the time stands
        still.
        """
        self._call("freeze", duration)

    def unfreeze(self) -> None:
        """End the frozen-controller fault."""
        self._call("unfreeze")

    def set_slow(self, delay: float, jitter: float = 0.0) -> None:
        """Fault: slow controller; data packages arrive ``delay`` (+ up to ``jitter``) s late."""
        self._call("set_slow", delay, jitter)

    def clear_faults(self) -> None:
        """Safety NORMAL, robot RUNNING, normal stream (test helper)."""
        self._call("clear_faults")

    def reset(self, q: ArrayLike) -> None:
        """Put the arm at rest at joint positions ``q``."""
        self._call("reset", np.asarray(q, dtype=float).tolist())

    # state
    @property
    def ports(self) -> dict[str, int]:
        """The bound ports, keyed by server name; empty before :meth:`start`.

        Keys ``rtde``, ``dashboard``, ``script``, ``primary`` and ``secondary``; where port 0 was
        asked for, the port the system picked.
        """
        return dict(self._ports)

    @property
    def actual_q(self) -> np.ndarray:
        """Actual joint positions [rad]."""
        return np.asarray(self._call("actual_q"), dtype=float)

    @property
    def tcp_pose(self) -> np.ndarray:
        """Actual TCP pose (UR vector)."""
        return np.asarray(self._call("tcp_pose"), dtype=float)

    @property
    def robot_mode(self) -> RobotMode:
        """The controller's robot mode (RUNNING, IDLE, POWER_OFF, ...)."""
        return RobotMode(self._call("robot_mode"))

    @property
    def safety_mode(self) -> SafetyMode:
        """The controller's safety mode (NORMAL, PROTECTIVE_STOP, ROBOT_EMERGENCY_STOP, ...)."""
        return SafetyMode(self._call("safety_mode"))

    @property
    def runtime_state(self) -> RuntimeState:
        """The runtime state of the controller's program (STOPPED, PLAYING, PAUSED)."""
        return RuntimeState(self._call("runtime_state"))

    @property
    def programs_dir(self) -> str:
        """The folder the dashboard's ``load`` serves programs from."""
        return str(self._call("programs_dir"))

    @property
    def calibration(self) -> Calibration | None:
        """The calibration the emulator runs with (None: nominal kinematics)."""
        return self._call("calibration")

    @property
    def kinematics_info(self) -> KinematicsInfo:
        """The KinematicsInfo the primary interface serves."""
        return self._call("kinematics_info")

    @property
    def popup(self) -> str | None:
        """The popup the pendant shows (a compile error, URScript ``popup``), or None."""
        return self._call("popup")

    @property
    def events(self) -> list[tuple[float, int, str]]:
        """The controller's log: (controller time, level, message)."""
        return list(self._call("events"))

    @property
    def io_log(self) -> list[tuple[float, int, int, int, float, float]]:
        """Every change of the outputs.

        (controller time [s], standard, configurable and tool digital output bits, standard
        analog outputs 0 and 1 [fraction]) — what a test reads to see when the wire was hot."""
        return list(self._call("io_log"))

    def reset_stats(self) -> None:
        """Forget the clock's timing so far (measure one phase of a test)."""
        self._call("reset_stats")

    def stats(self) -> dict[str, float]:
        """Clock timing and counters (see :meth:`ThreadedEmulator.stats_summary`)."""
        return dict(self._call("stats_summary"))

    def wait_for(self, predicate: Callable[[], bool], timeout: float = 5.0) -> bool:
        """Poll ``predicate`` every 10 ms until it holds or ``timeout`` passes."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(0.01)
        return bool(predicate())

    def __repr__(self) -> str:
        where = "in-process" if self.in_process else f"pid {self.pid}"
        return f"Emulator({self.model_name!r} on {self.host}, {where})"


@contextlib.contextmanager
def embedded_emulator(
    model: str | RobotModel,
    q0: ArrayLike,
    host: str = EMBEDDED_HOST,
    *,
    find_free_host: bool = True,
) -> Iterator[Emulator]:
    """The default target of ``ruledrobot run`` and ``demo`` without a robot address.

    A MuJoCo-backed emulator of ``model`` with the arm at ``q0`` (rad), on loopback, closed on
    exit.

    It listens on ``host`` or, when that is taken (another emulator runs there) and
    ``find_free_host``, on the next free loopback address: ``emulator.host`` says where.
    An ``OSError`` (``errno.EADDRINUSE`` when every address tried is taken) when it
    cannot listen.
    """
    from .arm.physics import MujocoBackend

    emu = Emulator(host, model, q0=q0, backend=MujocoBackend,
                   find_free_host=find_free_host).start()  # fmt: skip
    try:
        yield emu
    finally:
        emu.close()
