"""The ur_rtde side of a run, in the child process: interfaces, monitoring, recording,
safe stop.

Everything here runs in the process :mod:`.run_child` starts; ur_rtde may hang
(its ``servoStop`` has no timeout) or crash (SIGSEGV in its native reconnect)
there without taking the runner with it.  The session talks to the supervisor
through a :class:`Link`:

* ``("stage", name, timeout)`` before every step: the supervisor kills the
  child when no message follows within ``timeout`` seconds;
* ``("rec", t, q, tcp, k, outs, info)`` every ``CHUNK`` seconds while recording: the
  recording so far (controller time, actual joints, actual TCP, the grid sample
  the deviation match put each at, -1 where none was made: the settling after a
  stop, and the outputs the heat is switched on: digital bits, analog 0 and 1), plus
  the progress (``info``: matched grid sample, samples sent, largest
  deviation, samples skipped);
  it doubles as the heartbeat; ``("beat", info)`` when not recording;
* ``("stopping", status, message)`` when the session stops on a fault.

The supervisor may send ``("stop", status, message)`` (Ctrl-C) at any time;
:meth:`Link.check` raises it as :class:`Stop` in the next period.
"""

from __future__ import annotations

import math
import socket
import time
from typing import Any

import numpy as np

from ..protocol.primary import DASHBOARD_PORT
from ..robot.motion.trajectory import Heat
from .heat import set_heat_rtde

__all__ = ["CHUNK", "Link", "Session", "SessionError", "Stop"]

#: seconds between recording chunks / heartbeats
CHUNK = 0.05
RUNTIME_PLAYING = 2
_NO_OUTPUTS = [float("nan")] * 3


class Stop(Exception):
    """End the motion: ``status`` and ``message`` go into the run's result."""

    def __init__(self, status: str, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


class SessionError(RuntimeError):
    """The controller cannot be used (not reachable, control interface refused)."""


class Link:
    """The child's end of the pipe to the supervisor."""

    def __init__(self, conn: Any) -> None:
        self.conn = conn
        self.stop: Stop | None = None

    def send(self, *msg: Any) -> None:
        """Send the tuple ``msg``, remembering a lost pipe instead of raising.

        When the pipe is gone, remember a ``supervisor_lost`` :class:`Stop` (raised by the next
        :meth:`check`) instead of raising."""
        try:
            self.conn.send(msg)
        except (OSError, EOFError):
            self.stop = self.stop or Stop("supervisor_lost", "the runner's supervisor went away")

    def stage(self, name: str, timeout: float) -> None:
        """Announce step ``name`` to the supervisor.

        The supervisor kills the child when no message follows within ``timeout`` [s]."""
        self.send("stage", name, float(timeout))

    def check(self) -> None:
        """Raise :class:`Stop` when the supervisor asked to stop (or went away)."""
        if self.stop is None:
            try:
                while self.conn.poll(0):
                    msg = self.conn.recv()
                    if msg and msg[0] == "stop":
                        self.stop = Stop(str(msg[1]), str(msg[2]))
                    elif msg and msg[0] == "exit":
                        self.stop = Stop("supervisor_lost", "the runner ended the session")
            except (OSError, EOFError):
                self.stop = Stop("supervisor_lost", "the runner's supervisor went away")
        if self.stop is not None:
            raise Stop(self.stop.status, self.stop.message)


class Session:
    """The two ur_rtde interfaces of one run, its monitoring and its recording."""

    def __init__(self, link: Link, cfg: dict) -> None:
        self.link = link
        self.host: str = cfg["host"]
        self.frequency = float(cfg["frequency"])
        self.watchdog = float(cfg["watchdog"])
        self.deviation_limit = float(cfg["deviation_limit"])
        self.max_latency = float(cfg["max_latency"])
        self.r: Any = None
        self.c: Any = None
        self.io: Any = None  # rtde_io.RTDEIOInterface when the run switches the wire's heat
        self.heat: Heat | None = None
        self.hot = False
        self.level = 0.0  # the analog set-point last written (a scheduled power)
        self.max_dev = 0.0
        self.k_match = 0
        self.k_high = 0  # the furthest plan sample matched so far
        self.skipped = 0  # samples skipped to keep the schedule (stream)
        #: the grid samples skipped, as half-open ranges (stream)
        self.skipped_ranges: list[tuple[int, int]] = []
        self.max_slip = 0.0  # the longest the stream was behind its schedule [s]
        self.sent = 0
        self.window = 10
        self.recording = False
        self._buf: list[tuple[float, list[float], list[float], int, list[float]]] = []
        self._fresh = False  # the last recorded sample awaits its deviation match
        #: output int registers read with each snapshot, from its data package
        #: (:meth:`snapshot`); ``registers`` holds their values of the last one
        self.watch_registers: tuple[int, ...] = ()
        self.registers: dict[int, int] = {}
        self._last_ts = -math.inf
        self._ts0: float | None = None
        self._last_flush = 0.0
        self._lag_min = math.inf
        self._last_poll = math.inf
        self._wall0 = 0.0
        self._clock_ts0 = 0.0

    # ------------------------------------------------------------ connection

    def connect_receive(self) -> None:
        """Connect the receive interface at ``frequency`` [Hz].

        Raises
        ------
        SessionError
            When the controller is not reachable.
        """
        import rtde_receive

        try:
            self.r = rtde_receive.RTDEReceiveInterface(self.host, self.frequency)
        except RuntimeError as exc:
            raise SessionError(f"controller at {self.host} not reachable: {exc}") from None

    def state(self) -> dict:
        """Return the controller's state before motion.

        ``robot_mode``, ``safety_mode``, ``runtime_state`` (ints), ``protective``,
        ``emergency`` (bools) and ``q``, the actual joint angles [rad] (6 floats)."""
        r = self.r
        return {
            "robot_mode": int(r.getRobotMode()),
            "safety_mode": int(r.getSafetyMode()),
            "protective": bool(r.isProtectiveStopped()),
            "emergency": bool(r.isEmergencyStopped()),
            "runtime_state": int(r.getRuntimeState()),
            "q": [float(x) for x in r.getActualQ()],
        }

    def connect_control(self) -> None:
        """Connect the control interface (it uploads the control script).

        Raises
        ------
        SessionError
            When the controller refuses it.
        """
        import rtde_control

        try:
            self.c = rtde_control.RTDEControlInterface(self.host, self.frequency)
        except RuntimeError as exc:
            raise SessionError(f"controller at {self.host}: control interface: {exc}") from None

    def connect_io(self, heat: Heat) -> None:
        """The IO interface that switches ``heat``; the wire starts cold."""
        import rtde_io

        try:
            self.io = rtde_io.RTDEIOInterface(self.host)
        except RuntimeError as exc:
            raise SessionError(f"controller at {self.host}: IO interface: {exc}") from None
        self.heat = heat
        self.set_heat(False)

    def set_heat(self, on: bool, value: float | None = None) -> None:
        """Switch the wire's heat (no-op without heat); a refusal stops the run.

        An analog output goes to the set-point ``value`` when given (a scheduled power)."""
        if self.heat is None or self.io is None:
            return
        if not set_heat_rtde(self.io, self.heat, on, value):
            what = f"to {value:.4g}" if value is not None else ("on" if on else "off")
            raise Stop("command_failed", f"the controller refused to set the heat "
                       f"({self.heat.output}) {what}")  # fmt: skip
        self.hot = on
        self.level = (value if value is not None else 0.0) if on else 0.0

    def arm_watchdog(self) -> None:
        """The control script stops the program when no command arrives for 1/watchdog s."""
        if self.watchdog > 0:
            self.c.setWatchdog(self.watchdog)

    def kick(self) -> None:
        """Kick the control script's watchdog (no-op when ``watchdog`` is 0)."""
        if self.watchdog > 0:
            self.c.kickWatchdog()

    # ------------------------------------------------------------ recording

    def start_recording(self) -> None:
        """Record from the next data package on; its controller time becomes t = 0."""
        self.recording = True
        self._ts0 = None
        self._last_ts = -math.inf

    def record(self, ts: float, q: list[float], tcp: list[float],
               outputs: list[float] | None = None) -> None:  # fmt: skip
        """Append one data package while recording.

        Packages not newer than the last are skipped.

        Parameters
        ----------
        ts : float
            Controller time [s].
        q : list of float, 6 values
            Actual joint angles [rad].
        tcp : list of float, 6 values
            Actual TCP pose in the base frame as a UR pose vector: position [m],
            rotation vector [rad].
        outputs : list of float, 3 values, optional
            The outputs the wire's heat may be on: ``actual_digital_output_bits``,
            ``standard_analog_output0`` and ``1`` (NaN when not read).
        """
        if self.recording and ts > self._last_ts:
            if self._ts0 is None:
                self._ts0 = ts
            self._last_ts = ts
            outs = _NO_OUTPUTS if outputs is None else outputs
            self._buf.append((ts - self._ts0, q, tcp, -1, outs))
            self._fresh = True

    def snapshot(self) -> tuple[float, list[float], list[float], list[float]]:
        """Return (controller time, actual q, actual TCP, outputs) of one data package.

        Outputs: the digital output bits and the two standard analog outputs, where the wire's
        heat is switched.  ur_rtde's getters each read the newest package, so a package arriving
        between them would mix two; the timestamp read again tells.  The output int registers
        of :attr:`watch_registers` are read in the same package, into :attr:`registers` (a
        forwarded run's sample playing: read apart from the joints, while ur_rtde's receive
        thread caught up on a backlog, it was up to 0.1 s newer than them)."""
        r = self.r
        regs: dict[int, int] = {}
        for _ in range(4):
            ts = r.getTimestamp()
            q, tcp = r.getActualQ(), r.getActualTCPPose()
            outs = [float(r.getActualDigitalOutputBits()), float(r.getStandardAnalogOutput0()),
                    float(r.getStandardAnalogOutput1())]  # fmt: skip
            regs = {i: int(r.getOutputIntRegister(i)) for i in self.watch_registers}
            if r.getTimestamp() == ts:
                break
        self.registers = regs
        return ts, q, tcp, outs

    def info(self) -> dict:
        """Return the progress so far.

        ``k_match`` (matched grid sample), ``sent``, ``max_dev`` (largest joint deviation
        [rad]), ``recording_t0`` (controller time [s] of the recording's first sample, None
        before), ``skipped``, ``skipped_ranges`` (half-open grid sample ranges) and
        ``max_slip`` [s]."""
        return {"k_match": self.k_match, "sent": self.sent, "max_dev": self.max_dev,
                "recording_t0": self._ts0, "skipped": self.skipped,
                "skipped_ranges": list(self.skipped_ranges),
                "max_slip": self.max_slip}  # fmt: skip

    def keep_schedule(self, k: int, elapsed: float, n: int) -> int:
        """Return the sample to send after sample ``k``, ``elapsed`` seconds into the stream.

        In a stream of ``n`` samples: ``k + 1``, or the sample due now when periods overran (the
        ones passed are skipped; the last sample is always sent).  Raises :class:`Stop`
        (``client_slow``) when the stream is more than ``max_latency`` behind."""
        due = int(elapsed * self.frequency)  # the sample whose period has begun
        slip = elapsed - (k + 1) / self.frequency
        self.max_slip = max(self.max_slip, slip)
        if slip > self.max_latency:
            raise Stop(
                "client_slow",
                f"the runner sent grid sample {k + 1} {1e3 * slip:.0f} ms late (limit "
                f"{1e3 * self.max_latency:.0f} ms): this computer could not keep the "
                "controller period; catching up would jump the arm",
            )
        nxt = k + 1
        if due > nxt and nxt < n:
            nxt = min(due, n - 1)
            if nxt > k + 1:
                self.skipped += nxt - (k + 1)
                self.skipped_ranges.append((k + 1, nxt))
        return nxt

    def flush(self, force: bool = False) -> None:
        """Send the recording so far (and the progress) at most every CHUNK seconds."""
        now = time.monotonic()
        if not force and now - self._last_flush < CHUNK:
            return
        self._last_flush = now
        if self._buf:
            t = np.array([b[0] for b in self._buf])
            q = np.array([b[1] for b in self._buf])
            tcp = np.array([b[2] for b in self._buf])
            k = np.array([b[3] for b in self._buf], dtype=np.int64)
            outs = np.array([b[4] for b in self._buf], dtype=float)
            self._buf = []
            self.link.send("rec", t, q, tcp, k, outs, self.info())
        else:
            self.link.send("beat", self.info())

    def service(self) -> None:
        """Once per period: send what is due, obey a stop request."""
        self.flush()
        self.link.check()

    # ------------------------------------------------------------ monitoring

    def start_clock(self) -> None:
        """Start the latency watch: the wall clock and the controller clock from now."""
        self._wall0 = time.monotonic()
        self._clock_ts0 = self.r.getTimestamp()
        self._lag_min = math.inf
        self._last_poll = self._wall0

    def connected(self) -> bool:
        """Whether the receive interface (and the control one, when made) is connected.

        False when asking fails."""
        try:
            return bool(self.r.isConnected() and (self.c is None or self.c.isConnected()))
        except Exception:
            return False

    def poll(self) -> np.ndarray:
        """Read the state, record it, raise :class:`Stop` on a fault; returns actual q."""
        r = self.r
        if not self.connected():
            raise Stop("connection_lost", "the RTDE connection to the controller was lost")
        if r.isEmergencyStopped():
            raise Stop("emergency_stop", "the robot is emergency stopped")
        if r.isProtectiveStopped():
            raise Stop("protective_stop", "the robot is protective stopped")
        ts, qa, tcp, outs = self.snapshot()
        self.record(ts, qa, tcp, outs)
        now = time.monotonic()
        if now - self._last_poll > self.max_latency / 2:
            # this process was not run for a while (the machine busy, a stop signal): its
            # own stall, not the controller's — the newest data may lag behind until
            # ur_rtde's receive thread has caught up, so the watch starts again from here
            self._lag_min = math.inf
        self._last_poll = now
        lag = (now - self._wall0) - (ts - self._clock_ts0)
        self._lag_min = min(self._lag_min, lag)
        if lag - self._lag_min > self.max_latency:
            raise Stop(
                "controller_slow",
                f"controller data {1e3 * (lag - self._lag_min):.0f} ms late (limit "
                f"{1e3 * self.max_latency:.0f} ms): the controller stopped answering "
                "in time",
            )
        if r.getRuntimeState() != RUNTIME_PLAYING:
            raise Stop("program_stopped", "the control script stopped running on the controller")
        return np.asarray(qa)

    def check_deviation(self, plan: np.ndarray, qa: np.ndarray, upto: int,
                        timed: bool = True, anchored: bool = False) -> None:  # fmt: skip
        """Match ``qa`` to the nearest plan sample; raise :class:`Stop` when it deviates.

        The deviation of ``qa`` from the nearest plan sample in ``[k_high - window / 4, upto]``
        (at most ``window`` ahead of ``k_match``), ``k_high`` the furthest sample matched so far;
        moves ``k_match`` there.  ``timed`` (streaming: sample ``upto`` was commanded now): the
        arm must also be at most ``window`` samples behind it.

        The match may step back a little behind the furthest it reached (a quarter of the
        window, about the servo's lag): where the plan creeps (the start of a move from
        rest) a later sample can look nearest for a while, and a match that only moves
        forward would run ahead of the arm and report its lag as a deviation.  Never
        further, and never step by step: a path that leaves the way it came (the lead-in
        after a pre-heat hold, a pass that turns round in its own kerf) looks, to a
        nearest-sample match, like its arrival run backwards, and a match allowed to
        step back from wherever it is would walk back along the arrival while the arm
        goes on (found on the part demo: 0.05 rad reported for an arm 0.001 rad from the
        plan).  ``anchored``: ``upto`` is the sample the controller reports playing (a
        forwarded run), so a match more than a window behind it moves up to the window
        behind it (the gap a stall of this process leaves in the recording)."""
        lo = max(0, self.k_high - self.window // 4)
        hi = max(lo, min(upto, self.k_match + self.window)) + 1
        if anchored and upto - self.window > lo:
            # the controller reports the sample it plays (a forwarded run): after a stall of
            # this process the recording has a gap, and the arm is near ``upto``, further
            # than a window from the last match — search the window behind it
            lo, hi = upto - self.window, upto + 1
        d = np.max(np.abs(plan[lo:hi] - qa), axis=1)
        # the last of the minima (equal to a micro-radian): through a hold longer than
        # the window (the wire heating) the plan repeats one sample, up to rounding of
        # the resampling, and the match must reach its end
        dev = float(d.min())  # the distance to the plan: its nearest sample
        j = int(np.flatnonzero(d <= dev + 1e-6)[-1])
        self.k_match = lo + j
        self.k_high = max(self.k_high, self.k_match)
        if self._fresh and self._buf:  # the sample poll() just recorded: where it is
            b = self._buf[-1]
            self._buf[-1] = (b[0], b[1], b[2], self.k_match, b[4])
            self._fresh = False
        self.max_dev = max(self.max_dev, dev)
        if dev > self.deviation_limit:
            raise Stop(
                "deviation",
                f"joint deviation {dev:.4f} rad from the plan exceeds the "
                f"limit {self.deviation_limit:.4f} rad",
            )
        if timed and self._behind(plan, qa, upto):
            raise Stop(
                "deviation",
                f"the arm is {(upto - self.k_match) / self.frequency:.2f} s behind the plan "
                f"(limit {self.window / self.frequency:.2f} s, three servo look-aheads and "
                "0.1 s): it stopped following the commands",
            )

    def _behind(self, plan: np.ndarray, qa: np.ndarray, upto: int) -> bool:
        """The arm has stopped following: matched more than ``window`` samples behind the
        command ``upto`` *and* further from it than the plan was ``window`` samples ago
        (plus a tenth of the deviation limit).  The distance matters: where the plan
        comes to rest the servo filter closes the last micro-radians slowly, and the
        matched sample then lags far in index while the arm is where it should be."""
        if upto - self.k_match <= self.window:
            return False
        target = plan[upto]
        arm = float(np.max(np.abs(qa - target)))
        plan_then = float(np.max(np.abs(plan[upto - self.window] - target)))
        return arm > plan_then + 0.1 * self.deviation_limit

    def classify(self, what: str, exc: Exception | None = None) -> Stop:
        """Return the :class:`Stop` that says why a command failed or returned False.

        The stream may be a period behind."""
        deadline = time.monotonic() + 0.1
        while time.monotonic() < deadline:
            try:
                self.poll()
            except Stop as stop:
                return Stop(stop.status, f"{what}: {stop.message}")
            except Exception as e:
                return Stop("connection_lost", f"{what}: {e}")
            time.sleep(0.004)
        if not self.connected():
            return Stop("connection_lost", f"{what}: the connection to the controller was lost")
        if exc is not None:
            return Stop("command_failed", f"{what}: ur_rtde: {exc}")
        return Stop("command_failed", f"{what} was refused by the controller")

    # ------------------------------------------------------------ stopping

    def safe_stop(self, mode: str, deceleration: float, budget: float) -> None:
        """Stop the arm: servoStop / stopJ, then stopScript, within ``budget`` seconds.

        Each best effort, the whole within ``budget`` seconds (else the supervisor kills this
        process)."""
        self.link.stage("stopping", budget)
        if self.hot or self.heat is not None:  # the heat first: a still wire burns the foam
            try:
                set_heat_rtde(self.io, self.heat, False)
                self.hot, self.level = False, 0.0
            except Exception:
                pass
        if mode == "forward":  # the program is ours (it stops along the path on request)
            self._dashboard_stop(budget)
            return
        c = self.c
        if c is None:
            return
        try:
            if c.isConnected() and c.isProgramRunning():
                if mode == "servoj":
                    c.servoStop(deceleration)
                else:
                    c.stopJ(deceleration, False)
        except Exception:
            pass
        try:
            if c.isConnected() and c.isProgramRunning():
                c.stopScript()
        except Exception:
            pass

    def _dashboard_stop(self, budget: float) -> None:
        """Stop a program that still runs through the dashboard's ``stop`` (a forwarding
        program ends by itself; this is for one that does not)."""
        try:
            if self.r is None or int(self.r.getRuntimeState()) != RUNTIME_PLAYING:
                return
            with socket.create_connection((self.host, DASHBOARD_PORT), timeout=budget) as d:
                d.settimeout(budget)
                d.recv(256)  # the greeting
                d.sendall(b"stop\n")
                d.recv(256)
        except Exception:
            pass

    def settle(self, timeout: float = 1.5) -> None:
        """Record until the arm rests (speed < 1e-3 rad/s for 50 ms) or ``timeout``."""
        self.link.stage("settling", timeout + 1.0)
        r = self.r
        deadline = time.monotonic() + timeout
        quiet = 0.0
        while time.monotonic() < deadline:
            try:
                if not r.isConnected():
                    break
                self.record(*self.snapshot())
                qd = max(abs(x) for x in r.getActualQd())
            except Exception:
                break
            self.flush()
            quiet = quiet + 0.002 if qd < 1e-3 else 0.0
            if quiet >= 0.05:
                break
            time.sleep(0.002)
        self.flush(force=True)

    def disconnect(self) -> None:
        """Destroy the interfaces (control first).

        ur_rtde's ``disconnect()`` sleeps 0.5 s and its destructor calls it again: dropping the
        last reference is one."""
        self.c = None
        self.r = None
