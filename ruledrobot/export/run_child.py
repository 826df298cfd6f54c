"""The child process of a run: the only process that loads ur_rtde.

Started by :mod:`.run_supervisor` as ``python -c "...; main(fd)"`` with one end
of a socket pair.  Protocol (pickled tuples, see :mod:`.run_session`):

1. receives the session config (dict); connects the receive interface; sends
   ``("state", {...})`` (modes, actual joints) or ``("error", message)``;
2. waits for ``("go", motion)`` or ``("cancel",)``;
3. on go: control interface, TCP, payload, watchdog, approach, motion,
   streaming the recording; on any stop the safe stop; then
   ``("done", {...})``;
4. on ``("exit",)`` (or the pipe closing) leaves with ``os._exit`` — the
   interfaces are not disconnected one by one (ur_rtde's ``disconnect``
   sleeps 0.5 s each and races with its reconnect thread; the kernel closes
   the sockets).

The child ignores SIGINT and runs in its own session (the terminal's Ctrl-C
goes to the supervisor, which asks for a safe stop), and is killed when the
supervisor dies (``PR_SET_PDEATHSIG``; the controller's watchdog then stops
the program).

It raises its scheduling priority first (:func:`raise_priority`, before ur_rtde
starts its threads, which inherit it): a stream that must send every 2 ms cannot
wait behind whatever else the machine runs.  The ``state`` message says what it got
(``"priority"``), and the runner says so when it is not real-time.
"""

from __future__ import annotations

import os
import signal
import sys
from multiprocessing.connection import Connection

import numpy as np

from ..robot.motion.trajectory import Heat
from .forward import ForwardSettings
from .forward.client import forward
from .run_motion import approach, preheat, run_program, stream
from .run_session import Link, Session, SessionError, Stop

__all__ = ["NICE", "RT_PRIORITY", "client_defect", "main", "raise_priority"]

#: SCHED_RR priority of the streaming process: low (1-99), below the emulator's clock
#: (10) and servers (5), so that a controller emulated on the same machine goes first
RT_PRIORITY = 4
#: the nice value tried when real-time scheduling is refused
NICE = -10


def raise_priority(rt_priority: int = RT_PRIORITY, nice: int = NICE) -> tuple[bool, str]:
    """Raise the calling thread's scheduling priority.

    Threads it starts later inherit it: ``SCHED_RR`` ``rt_priority`` where the OS allows
    (Linux, root or CAP_SYS_NICE), else nice ``nice``; nothing when the environment says
    ``RULEDROBOT_RUN_PRIORITY=normal`` (to measure what the priority does).  Returns
    (real-time, what it got in words)."""
    if os.environ.get("RULEDROBOT_RUN_PRIORITY") == "normal":  # measurements (scripts/)
        return False, "normal priority (RULEDROBOT_RUN_PRIORITY=normal)"
    why = "not supported on this OS"
    setter = getattr(os, "sched_setscheduler", None)
    if setter is not None:
        try:
            setter(0, os.SCHED_RR, os.sched_param(rt_priority))
            return True, f"SCHED_RR {rt_priority}"
        except (OSError, AttributeError) as exc:
            why = getattr(exc, "strerror", None) or str(exc)
    try:
        os.setpriority(os.PRIO_PROCESS, 0, nice)
        return False, f"nice {nice} (real-time scheduling refused: {why})"
    except (OSError, AttributeError) as exc:
        now = os.getpriority(os.PRIO_PROCESS, 0) if hasattr(os, "getpriority") else 0
        refused = getattr(exc, "strerror", None) or exc
        return False, (f"normal priority, nice {now} (real-time scheduling refused: {why}; "
                       f"nice {nice} refused: {refused})")  # fmt: skip


def _die_with_parent() -> None:
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        if os.getppid() == 1:  # the parent died before prctl
            os._exit(3)
    except Exception:
        pass


def _motion(s: Session, m: dict) -> None:
    s.link.stage("connecting control", m["connect_timeout"])
    s.connect_control()
    s.link.stage("setup", 5.0)
    s.c.setTcp([float(x) for x in m["tcp_offset"]])
    s.c.setPayload(float(m["mass"]), [float(x) for x in m["cog"]])
    s.arm_watchdog()
    qa = np.asarray(s.r.getActualQ())
    moved = float(np.max(np.abs(qa - np.asarray(m["checked_q"]))))
    if moved > m["moved_tolerance"]:
        raise Stop("command_failed", f"the arm moved {moved:.4f} rad since the checks: run again")
    q_grid = np.asarray(m["q_grid"])
    heat = m.get("heat")
    hot = None
    if heat is not None:
        s.link.stage("connecting IO", m["connect_timeout"])
        s.connect_io(Heat(heat["kind"], heat["index"], heat["value"]))
        hot = np.asarray(heat["hot"], dtype=bool)
    levels = None if heat is None or heat.get("levels") is None else np.asarray(heat["levels"])
    approach(s, q_grid[0], m["approach_speed"], m["approach_acceleration"], m["heartbeat"])
    if hot is not None and hot[0]:  # entering a cut where it stopped: heat before moving
        preheat(s, float(heat["preheat"]), m["heartbeat"],
                None if levels is None else float(levels[0]))  # fmt: skip
    if m["mode"] == "forward":
        settings = ForwardSettings(1.0 / s.frequency, m["buffer"], m["stop_time"],
                                   m["lookahead"], m["gain"])  # fmt: skip
        hv = None if heat is None else Heat(heat["kind"], heat["index"], heat["value"])
        forward(s, q_grid, hot, settings, hv, m["heartbeat"], m["connect_timeout"], levels)
    elif m["mode"] == "servoj":
        stream(s, q_grid, m["lookahead"], m["gain"], m["heartbeat"], hot, levels)
    else:  # the path program switches the heat where the plan does
        run_program(s, q_grid, m["program"], m["heartbeat"])
        s.set_heat(False)


def client_defect(exc: BaseException) -> str:
    """The words of an error this process did not expect (a defect, not the robot's).

    The exception, the file and line it came from (its traceback also goes to stderr,
    which the supervisor keeps as the client's output) and what was done: it once read as
    a dead client, "exit code 0", when a forwarded run's socket closed under it."""
    import traceback

    traceback.print_exception(exc, file=sys.stderr)
    frames = traceback.extract_tb(exc.__traceback__)
    where = f", at {os.path.basename(frames[-1].filename)}:{frames[-1].lineno}" if frames else ""
    return (f"the run's client failed ({type(exc).__name__}: {exc}{where}): the arm was "
            "stopped as on any stop; this is a defect of ruledrobot, please report it with "
            "this message")


def _run(s: Session, m: dict) -> None:
    link = s.link
    s.window = int(m["window"])
    stop: Stop | None = None
    try:
        _motion(s, m)
    except Stop as st:
        stop = Stop(st.status, st.message)  # without the traceback (it holds the interfaces)
    except SessionError as exc:
        stop = Stop("command_failed", str(exc))
    except RuntimeError as exc:
        stop = s.classify("ur_rtde", exc)
    except Exception as exc:  # a defect of this program: the arm is stopped as on any stop
        stop = Stop("client_error", client_defect(exc))
    if stop is None:
        s.safe_stop(m["mode"], m["stop_deceleration"], m["stop_budget"])  # end of program
    else:
        link.send("stopping", stop.status, stop.message)
        s.safe_stop(m["mode"], m["stop_deceleration"], m["stop_budget"])
    s.settle()
    done = {
        "status": "completed" if stop is None else stop.status,
        "message": "trajectory completed" if stop is None else stop.message,
        **s.info(),
    }
    link.send("done", done)


def main(fd: int) -> None:  # pragma: no cover - runs in the child
    """Run the child's side of the protocol (module doc) on the socket ``fd``; never returns.

    Ignores SIGINT, dies with its parent, raises its priority, then receives the
    session config, connects, sends ``state`` (or ``error``) and on ``go`` runs the
    motion; leaves with ``os._exit(0)`` whatever happened.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with_parent()
    conn = Connection(fd)
    realtime, priority = raise_priority()
    try:
        cfg = conn.recv()
        link = Link(conn)
        s = Session(link, cfg)
        link.stage("connecting", cfg["connect_timeout"])
        try:
            s.connect_receive()
            state = s.state()
        except (SessionError, RuntimeError) as exc:
            link.send("error", str(exc))
            return
        state["priority"] = priority
        state["realtime"] = realtime
        link.send("state", state)
        msg = conn.recv()
        if msg[0] == "go":
            _run(s, msg[1])
            conn.recv()  # ("exit",)
    except (EOFError, OSError):
        pass
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)
