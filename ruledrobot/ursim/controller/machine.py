"""The emulated controller: robot/safety/program state machine, registers, I/O, motion.

One :class:`Controller` owns the state a UR controller publishes over RTDE.  :meth:`Controller.tick`
advances it by one control period (2 ms e-Series, 8 ms CB3): the running program (ur_rtde's
control script, via :class:`~..script.handshake.ControlScript`, or any other program, via the
URScript interpreter :class:`~..script.interpreter.Interpreter`) reads its inputs, the trajectory
generator produces a setpoint, the arm backend steps, and the published variables (``values``,
keyed by RTDE name) are refreshed.

State machine (the parts clients see):

* ``robot_mode``: RUNNING after start-up; ``power off`` -> POWER_OFF, ``power on`` -> IDLE,
  ``brake release`` -> RUNNING (dashboard).  Programs only start while RUNNING with safety NORMAL.
* ``safety_mode``: NORMAL; :meth:`protective_stop` -> PROTECTIVE_STOP (the arm brakes, the program
  stops; ``unlock protective stop`` after ``unlock_delay`` s); :meth:`emergency_stop` ->
  ROBOT_EMERGENCY_STOP (the arm brakes, power goes off; :meth:`release_emergency_stop`, then power
  on and brake release).
* ``runtime_state``: STOPPED / PLAYING / PAUSED of the current program.
* programs are compiled before they start (:mod:`..script.interpreter`): one line the emulator
  cannot run refuses the whole program, nothing of it runs, the running program is stopped, the
  compile error is logged at error level and shown as the pendant's popup
  (:attr:`Controller.popup`, closed by the dashboard's ``close popup``).

Thread safety: every public method takes ``lock`` (re-entrant); the RTDE, dashboard and
script-port threads call in concurrently with the clock thread."""

from __future__ import annotations

import logging
import math
import re
import time
from collections import deque
from collections.abc import Sequence
from pathlib import Path
from threading import RLock

import numpy as np
from numpy.typing import ArrayLike

from ...protocol.modes import JointMode, RobotMode, RuntimeState, SafetyMode
from ...robot import RobotModel
from ...robot.motion.arm_kinematics import ArmKinematics
from ...robot.motion.ur_motion import MotionError, PathMotion, Segment, StopMotion
from ..arm.backend import ArmBackend, ArmState, KinematicBackend
from ..script.handshake import ControlScript
from ..script.interpreter import Interpreter, load_program
from ..script.program import CompileError, PathWaypoint, Program
from ..script.runner import move_segment
from ..script.syntax import warm_up
from .programs import program_in
from .registers import IN_DOUBLE, IN_INT, OUT_DOUBLE, OUT_INT, IOMixin
from .safety import SAFETY_BITS, SafetyMixin

__all__ = ["DEFAULT_Q", "Controller", "Event"]

log = logging.getLogger("ruledrobot.ursim")

#: Start configuration [rad]: elbow up, tool pointing down, away from singularities.
DEFAULT_Q = (0.0, -1.5707963267948966, 1.5707963267948966, -1.5707963267948966,
             -1.5707963267948966, 0.0)  # fmt: skip


_ZERO6 = np.zeros(6)


Event = tuple[float, int, str]

#: the most control periods a secondary program may take (it may not wait)
SECONDARY_PERIODS = 8

#: the longest message the controller log keeps [characters]
MAX_LOG_MESSAGE = 1000


class _IdleProgram:
    """A program loaded from the dashboard (``.urp``) that the emulator cannot run: it idles."""

    program = Program("", "", "idle")

    def step(self) -> None:
        return None


class Controller(IOMixin, SafetyMixin):
    """The controller state machine behind the emulator's three servers.

    Parameters
    ----------
    model : the arm (DH, limits, control period; its ``tool`` is the initial TCP).
    backend : the arm backend (default :class:`KinematicBackend`).
    q0 : initial joint positions [rad] (default :data:`DEFAULT_Q`).
    unlock_delay : seconds after a protective stop before ``unlock protective
        stop`` is accepted (5 s on a real controller).
    fault_deceleration : joint deceleration [rad/s^2] of the braking after a
        protective or emergency stop.
    programs_dir : the folder the dashboard's ``load`` serves programs from
        (PolyScope serves ``/programs``); nothing outside it can be loaded.
    """

    def __init__(
        self,
        model: RobotModel,
        backend: ArmBackend | None = None,
        *,
        q0: ArrayLike | None = None,
        unlock_delay: float = 5.0,
        fault_deceleration: float = 20.0,
        programs_dir: str | Path | None = None,
    ) -> None:
        self.model = model
        #: the folder ``load`` serves programs from (PolyScope's /programs); None: none
        self.programs_dir = Path(programs_dir).resolve() if programs_dir is not None else None
        self.period = float(model.control_period)
        self.lock = RLock()
        self.kin = ArmKinematics(model)
        self.backend: ArmBackend = backend if backend is not None else KinematicBackend(model)
        q = np.asarray(DEFAULT_Q if q0 is None else q0, dtype=float).reshape(6)
        self.backend.reset(q)
        self.unlock_delay = float(unlock_delay)
        self.fault_deceleration = float(fault_deceleration)
        self.robot_mode = RobotMode.RUNNING
        self.safety_mode = SafetyMode.NORMAL
        self.runtime_state = RuntimeState.STOPPED
        self.program: Program | None = None
        self.runner: ControlScript | Interpreter | _IdleProgram | None = None
        self.loaded_program: str | None = None
        self._loaded_script: Program | None = None
        self.motion: PathMotion | StopMotion | None = None
        self.mode = "idle"  # idle | move | servo | speed
        self._hold_q: np.ndarray | None = None  # where an idle arm rests
        self.time = 0.0
        self.ticks = 0
        self.speed_fraction = 1.0
        self.std_do = 0
        self.conf_do = 0
        self.tool_do = 0
        self.analog_out = [0.0, 0.0]
        #: every change of the outputs: (controller time [s], standard, configurable and
        #: tool digital output bits, standard analog outputs 0 and 1 [fraction])
        self.io_log: deque[tuple[float, int, int, int, float, float]] = deque(maxlen=100_000)
        self._io_last: tuple[int, int, int, float, float] = (0, 0, 0, 0.0, 0.0)
        self.popup: str | None = None  # the pendant's popup (compile errors, popup())
        self.compile_error: CompileError | None = None  # the last program refused
        self.last_input_names: frozenset[str] = frozenset()
        self.history: deque[list[float]] = deque(maxlen=1024)
        self.events: deque[Event] = deque(maxlen=2000)
        self.limit_events = 0
        self._fault_time = -math.inf
        self._watch_name: str | None = None  # RTDE watchdog (rtde_set_watchdog)
        self._watch_timeout = 0.0
        self._watch_action = "stop"
        self._watch_last = 0.0
        self._power_off_when_stopped = False
        self.values: dict[str, object] = {}
        self._kin_memo: dict[str, tuple] = {}  # _kin_state: the last state of each
        warm_up()  # the URScript parser, before any clock runs
        self._init_values()
        self._update_values()

    # ------------------------------------------------------------ values

    def _init_values(self) -> None:
        v = self.values
        z6 = (0.0,) * 6
        for names, zero in ((IN_INT, 0), (OUT_INT, 0), (IN_DOUBLE, 0.0), (OUT_DOUBLE, 0.0)):
            for n in names:
                v[n] = zero
        for i in range(64, 128):
            v[f"input_bit_register_{i}"] = 0
            v[f"output_bit_register_{i}"] = 0
        v.update(
            {
                "input_bit_registers0_to_31": 0,
                "input_bit_registers32_to_63": 0,
                "output_bit_registers0_to_31": 0,
                "output_bit_registers32_to_63": 0,
                "target_current": z6,
                "target_moment": z6,
                "actual_current_window": z6,
                "actual_current_as_torque": z6,
                "joint_control_output": z6,
                "actual_TCP_force": z6,
                "ft_raw_wrench": z6,
                "actual_digital_input_bits": 0,
                "joint_temperatures": (32.0, 33.5, 33.0, 35.0, 35.5, 36.0),
                "actual_tool_accelerometer": (0.0, 0.0, 9.81),
                "actual_momentum": 0.0,
                "actual_main_voltage": 48.0,
                "actual_robot_voltage": 48.0,
                "actual_robot_current": 0.8,
                "actual_joint_voltage": (47.5,) * 6,
                "standard_analog_input0": 0.0,
                "standard_analog_input1": 0.0,
                "analog_io_types": 0,
                "io_current": 0.05,
                "tool_mode": 0,
                "tool_analog_input_types": 0,
                "tool_analog_input0": 0.0,
                "tool_analog_input1": 0.0,
                "tool_output_voltage": 0,
                "tool_output_current": 0.0,
                "tool_temperature": 30.0,
                "tcp_force_scalar": 0.0,
                "payload": 0.0,
                "payload_cog": (0.0, 0.0, 0.0),
                "payload_inertia": z6,
                "joint_position_deviation_ratio": 0.0,
                "collision_detection_ratio": 0.0,
                "time_scale_source": 0,
                "euromap67_input_bits": 0,
                "euromap67_output_bits": 0,
                "euromap67_24V_voltage": 0.0,
                "euromap67_24V_current": 0.0,
                # no encoders on the tool flange / configurable inputs, the default
                # tool I/O set-up of a UR installation (set_tool_output_mode(0),
                # set_tool_digital_output_mode(n, 1))
                "actual_configurable_digital_input_bits": 0,
                "encoder0_raw": 0,
                "encoder1_raw": 0,
                "tool_output_mode": 0,
                "tool_digital_output0_mode": 1,
                "tool_digital_output1_mode": 1,
            }
        )

    def _update_values(self, exec_time: float = 0.0) -> None:
        st = self.backend.state()
        v = self.values
        q = st.q.tolist()
        qd = st.qd.tolist()
        tq = st.target_q.tolist()
        tqd = st.target_qd.tolist()
        pose, speed, elbow = self._kin_state("actual", q, qd)
        if tq == q and tqd == qd:
            tpose, tspeed = pose, speed
        else:
            tpose, tspeed, _ = self._kin_state("target", tq, tqd)
        self.history.append(q)
        running = self.robot_mode == RobotMode.RUNNING
        if running:
            jm = JointMode.RUNNING
        elif self.robot_mode in (RobotMode.IDLE, RobotMode.POWER_ON):
            jm = JointMode.IDLE
        else:
            jm = JointMode.POWER_OFF
        powered = self.robot_mode >= RobotMode.POWER_ON
        playing = self.runtime_state == RuntimeState.PLAYING
        v.update(
            {
                "timestamp": self.time,
                "target_q": tq,
                "target_qd": tqd,
                "target_qdd": st.target_qdd.tolist(),
                "actual_q": q,
                "actual_qd": qd,
                "actual_current": st.current.tolist(),
                "actual_TCP_pose": pose,
                "actual_TCP_speed": speed,
                "target_TCP_pose": tpose,
                "target_TCP_speed": tspeed,
                "elbow_position": elbow,
                "elbow_velocity": (0.0, 0.0, 0.0),
                "actual_execution_time": exec_time * 1000.0,
                "robot_mode": int(self.robot_mode),
                "joint_mode": (int(jm),) * 6,
                "safety_mode": int(self.safety_mode),
                "safety_status": int(self.safety_mode),
                "safety_status_bits": SAFETY_BITS.get(self.safety_mode, 0),
                "robot_status_bits": int(powered) | (int(playing) << 1),
                "runtime_state": int(self.runtime_state),
                "speed_scaling": self.speed_fraction if running else 0.0,
                "target_speed_fraction": self.speed_fraction,
                "actual_digital_output_bits": self.std_do
                | (self.conf_do << 8)
                | (self.tool_do << 16),
                "actual_configurable_digital_output_bits": self.conf_do,
                "standard_analog_output0": self.analog_out[0],
                "standard_analog_output1": self.analog_out[1],
                "tcp_offset": self.kin.tcp_offset,
                "script_control_line": self._script_line(),
            }
        )

    def _kin_state(self, which: str, q: list, qd: list) -> tuple:
        """:meth:`ArmKinematics.state` of ``(q, qd)``, computed only when they or the TCP change.

        ``which`` (``"actual"``, ``"target"``) keeps its last result: an arm at rest costs no
        kinematics per period (60 % of an idle emulator's tick)."""
        model = self.kin.model  # a new TCP is a new model (ArmKinematics.set_model)
        last = self._kin_memo.get(which)
        if last is not None and last[0] is model and last[1] == q and last[2] == qd:
            return last[3]
        out = self.kin.state(q, qd)
        self._kin_memo[which] = (model, q, qd, out)
        return out

    def _script_line(self) -> int:
        r = self.runner
        return r.line if isinstance(r, Interpreter) else 0

    def arm_state(self) -> ArmState:
        """Return the arm's state after the last period.

        The :class:`~ruledrobot.ursim.script.host.ProgramHost` interface.
        """
        return self.backend.state()

    # ------------------------------------------------------------ log

    def log(self, message: str, level: int = 3) -> None:
        """Record an event (level 0 exception, 1 error, 2 warning, 3 info).

        Messages are cut at :data:`MAX_LOG_MESSAGE` characters (the log keeps the
        last 2,000 events: bounded memory whatever clients send)."""
        if len(message) > MAX_LOG_MESSAGE:
            message = message[: MAX_LOG_MESSAGE - 3] + "..."
        self.events.append((self.time, level, message))
        log.log({0: logging.ERROR, 1: logging.ERROR, 2: logging.WARNING}.get(level, logging.INFO),
                "emulator: %s", message)  # fmt: skip

    # ------------------------------------------------------------ motion

    def start_motion(self, motion: PathMotion | StopMotion) -> None:
        """Run ``motion`` (a path or a stop) from the next period; no check that it may move."""
        with self.lock:
            self.motion = motion
            self.mode = "move"

    def stop_motion(self, deceleration: float) -> StopMotion:
        """Brake from the current setpoint to rest (``stopj``); returns the stop motion."""
        with self.lock:
            st = self.backend.state()
            stop = StopMotion(st.target_q, st.target_qd, deceleration)
            self.motion = stop
            self.mode = "move"
            return stop

    def set_servo(self, q: ArrayLike, lookahead_time: float, gain: float) -> None:
        """Servo mode (servoj) towards ``q`` [rad], (6,); ignored unless the robot may move."""
        with self.lock:
            if not self._can_move():
                return
            self.motion = None
            self.mode = "servo"
            self._hold_q = None
            self.backend.servo(q, lookahead_time, gain)

    def set_speed(self, qd: ArrayLike, acceleration: float) -> None:
        """Speed mode (speedj): joint speeds ``qd`` [rad/s]; ignored unless the robot may move."""
        with self.lock:
            if not self._can_move():
                return
            self.motion = None
            self.mode = "speed"
            self._hold_q = None
            self.backend.speed(qd, acceleration)

    def _can_move(self) -> bool:
        return self.robot_mode == RobotMode.RUNNING and self.safety_mode in (
            SafetyMode.NORMAL,
            SafetyMode.REDUCED,
        )

    def build_path(self, waypoints: Sequence[PathWaypoint]) -> PathMotion:
        """A blended path from injected or programmed waypoints, starting at the setpoint."""
        q = self.backend.state().target_q.copy()
        q0 = q.copy()
        segs: list[Segment] = []
        for wp in waypoints:
            target = np.asarray(wp.target, dtype=float)
            seg = move_segment(self.kin, q, wp.kind, target, wp.pose, wp.v, wp.a, wp.r,
                               f"path: movej pose p{list(wp.target)} out of reach")  # fmt: skip
            segs.append(seg)
            q = seg.q_end
        return PathMotion(q0, segs)

    # ------------------------------------------------------------ programs

    def compile(self, text: str) -> Program:
        """Parse and check a program as the controller compiles it (CompileError if not)."""
        return load_program(text, max_payload=self.model.payload)

    def refuse(self, error: CompileError, name: str = "") -> None:
        """A program failed to compile: it does not run; the running one stops; log and popup."""
        with self.lock:
            self.compile_error = error
            if self.runner is not None:
                self.stop_program("a new program arrived", decelerate=True)
            what = f"program {name}" if name else "program"
            self.log(f"compile error: {what} refused, nothing of it runs: {error}", level=1)
            self.show_popup(f"Compile error in line {error.line}: {error.text}: {error.reason}")

    def load_script(self, text: str) -> bool:
        """A program arrived on the script port: compiled, then it replaces the running one.

        A ``sec`` (secondary) program runs at once beside the primary program.
        Returns False when the program was refused (compile error) or cannot start."""
        try:
            prog = self.compile(text)
        except CompileError as exc:
            first = next((ln for ln in text.splitlines() if ln.strip()), "")
            m = re.match(r"\s*(?:def|sec)\s+([A-Za-z_]\w*)", first)
            self.refuse(exc, m.group(1) if m else "")
            return False
        if prog.kind == "sec":
            return self.run_secondary(prog)
        return self.start_program(prog)

    def run_secondary(self, prog: Program) -> bool:
        """A secondary program: it runs now, beside the primary one (which goes on).

        It may not move or wait (refused when it compiles); one that still has not ended
        after :data:`SECONDARY_PERIODS` steps (a socket read that waits) is ended and
        logged.  A runtime error is logged; the primary program is not stopped."""
        with self.lock:
            done: list[bool] = []
            runner = Interpreter(self, prog, on_finish=lambda: done.append(True))
            try:
                for _ in range(SECONDARY_PERIODS):
                    runner.step()
                    if done:
                        break
            except MotionError as exc:
                self.log(f"secondary program {prog.name}: runtime error: {exc}", level=1)
                return False
            finally:
                runner.close()
            if not done:
                self.log(f"secondary program {prog.name} ended: it waited, which a secondary "
                         "program may not", level=1)  # fmt: skip
                return False
            self.log(f"secondary program {prog.name} finished")
            return True

    def start_program(self, prog: Program) -> bool:
        """Start ``prog`` as the primary program (PLAYING), replacing the running one, or False."""
        with self.lock:
            if self.robot_mode != RobotMode.RUNNING:
                self.log(f"cannot start program {prog.name!r}: robot mode "
                         f"{self.robot_mode.name}", level=1)  # fmt: skip
                return False
            if self.safety_mode not in (SafetyMode.NORMAL, SafetyMode.REDUCED):
                self.log(f"cannot start program {prog.name!r}: safety mode "
                         f"{self.safety_mode.name}", level=1)  # fmt: skip
                return False
            if self.runner is not None:
                self.stop_program(f"replaced by {prog.name or 'a new program'}", decelerate=True)
            self.program = prog
            if prog.kind == "rtde_control":
                self.runner = ControlScript(self, prog)
                self.log(f"rtde_control started (register offset {prog.register_offset}, "
                         f"{len(prog.path)} path waypoints)")  # fmt: skip
            elif prog.kind == "idle":
                self.runner = _IdleProgram()
            else:
                self.runner = Interpreter(self, prog)
                self.log(f"program {prog.name or '<line>'} started")
            self.runtime_state = RuntimeState.PLAYING
            return True

    def stop_program(self, reason: str = "", *, decelerate: bool = True) -> None:
        """End the running program (runtime state STOPPED); brake servo/speed/moves."""
        with self.lock:
            if self.runner is None and self.runtime_state == RuntimeState.STOPPED:
                return
            name = self.program.name if self.program else ""
            if isinstance(self.runner, Interpreter):
                self.runner.close()  # its threads end, its sockets close
            self.runner = None
            self.runtime_state = RuntimeState.STOPPED
            self._watch_name = None
            if reason:
                self.log(f"program {name or '<none>'} stopped: {reason}")
            if decelerate and self.mode != "idle" and not isinstance(self.motion, StopMotion):
                self.stop_motion(4.0)

    def program_finished(self) -> None:
        """The program reached its end: logged, then stopped (:meth:`stop_program`)."""
        with self.lock:
            name = self.program.name if self.program else ""
            self.log(f"program {name or '<line>'} finished")
            self.stop_program("", decelerate=True)

    def program_error(self, message: str) -> None:
        """A runtime error in the program: it stops, as on the controller (popup + log)."""
        with self.lock:
            self.log(f"runtime error: {message}", level=1)
            self.stop_program("runtime error", decelerate=True)

    def pause_program(self) -> bool:
        """Dashboard ``pause``: PLAYING -> PAUSED, a moving arm brakes; False when none plays."""
        with self.lock:
            if self.runtime_state != RuntimeState.PLAYING:
                return False
            self.runtime_state = RuntimeState.PAUSED
            if self.mode != "idle":
                self.stop_motion(4.0)
            return True

    def play(self) -> bool:
        """Dashboard ``play``: resume a paused program or start the loaded one."""
        with self.lock:
            if self.runtime_state == RuntimeState.PAUSED and self.runner is not None:
                if not self._can_move():
                    return False
                self.runtime_state = RuntimeState.PLAYING
                return True
            if self.loaded_program is None:
                return False
            prog = self._loaded_script or Program(Path(self.loaded_program).stem, "", "idle")
            return self.start_program(prog)

    def program_path(self, path: str) -> Path | None:
        """Return the file ``path`` names inside :attr:`programs_dir`, or None."""
        return program_in(self.programs_dir, path)

    def load(self, path: str) -> str:
        """Answer the dashboard's ``load``: ``"ok"``, ``"not found"`` or ``"error"``.

        ``"error"``: a ``.script`` that does not compile (logged and shown as a popup).
        Only files inside :attr:`programs_dir` (:meth:`program_path`).  A ``.script`` is run
        by ``play``; a ``.urp`` idles (the emulator cannot run PolyScope programs).
        """
        found = self.program_path(path)
        if found is None:
            return "not found"
        p = found
        script: Program | None = None
        if p.suffix == ".script":
            try:
                text = p.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                self.log(f"load {p}: {exc}", level=1)
                return "error"
            try:
                script = self.compile(text)
            except CompileError as exc:
                with self.lock:
                    self.compile_error = exc
                    self.log(f"compile error: {p.name} not loaded: {exc}", level=1)
                    self.show_popup(f"Compile error in line {exc.line}: {exc.text}: {exc.reason}")
                return "error"
        with self.lock:
            self.loaded_program = str(p)
            self._loaded_script = script
        return "ok"

    # ------------------------------------------------------------ tick

    def tick(self) -> dict[str, object]:
        """Advance one control period; returns ``values`` (do not modify)."""
        t0 = time.perf_counter()
        with self.lock:
            self.ticks += 1
            self.time = self.ticks * self.period
            self._check_watchdog()
            runner = self.runner
            if runner is not None and self.runtime_state == RuntimeState.PLAYING:
                try:
                    runner.step()
                except MotionError as exc:
                    self.program_error(str(exc))
                except Exception as exc:  # never let a program kill the controller
                    log.exception("emulator: program step failed")
                    self.program_error(f"internal error: {exc!r}")
            m = self.motion
            if m is not None:
                scale = self.speed_fraction if isinstance(m, PathMotion) else 1.0
                sp = m.next(self.period, scale)
                if sp is None:
                    self.motion = None
                    self.mode = "idle"
                    if self._power_off_when_stopped:
                        self._power_off_when_stopped = False
                        self.robot_mode = RobotMode.POWER_OFF
                else:
                    self._hold_q = sp[0]
                    self.backend.track(*sp)
            if self.mode == "idle":
                # at rest on the last setpoint (an arm that lags behind still gets there)
                if self._hold_q is not None and self.robot_mode != RobotMode.POWER_OFF:
                    self.backend.track(self._hold_q, _ZERO6, _ZERO6)
                else:
                    self.backend.hold()
            self.backend.step(self.period)
            st = self.backend.state()
            if st.limited:
                self.limit_events += 1
            if self._can_move():
                out = (st.q <= self.model.lower) | (st.q >= self.model.upper)
                if out.any():
                    self.protective_stop(f"joint {int(np.argmax(out))} position limit")
            self._update_values(time.perf_counter() - t0)
            return self.values
