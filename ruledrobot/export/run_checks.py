"""The runner's checks of the controller before motion: robot model, control period,
kinematics (a marked hook), readiness.

The robot model and the software version come from the **dashboard server**
(port 29999: ``get robot model`` -> ``UR5``, ``PolyscopeVersion`` ->
``URSoftware 5.11.1.108318 (...)``), read with a plain socket and a time bound
(ur_rtde is not involved, so this cannot hang or crash the runner).  The
generation follows from the major version: 3.x is a CB3 (125 Hz, names without
``e``), 5.x an e-Series (500 Hz): ``UR5`` + 5.x is ``ur5e``.  The control period
is the generation's; it must equal the trajectory's ``control_period``.
"""

from __future__ import annotations

import re
import socket
import time
from dataclasses import dataclass

from ..robot.trajectory import TrajectoryMeta
from ..robot.verdict import Check

__all__ = [
    "DASHBOARD_PORT",
    "ControllerInfo",
    "controller_checks",
    "query_dashboard",
    "readiness_check",
]

DASHBOARD_PORT = 29999
ROBOT_MODE_RUNNING = 7
SAFETY_MODE_NORMAL = 1

_VERSION_RE = re.compile(r"(\d+)\.(\d+)\.(\d+)(?:\.(\d+))?")


@dataclass(frozen=True)
class ControllerInfo:
    """What the dashboard said: ``model_reply`` (``"UR5"``), ``version_reply``
    (``"URSoftware 5.11.1.108318 (...)"``), ``version`` (major, minor, bugfix)."""

    host: str
    model_reply: str
    version_reply: str
    version: tuple[int, int, int] | None

    @property
    def generation(self) -> str | None:
        if self.version is None:
            return None
        return "CB3" if self.version[0] < 4 else "e-Series"

    @property
    def control_period(self) -> float | None:
        """The generation's controller period [s]: 8 ms (CB3), 2 ms (e-Series and later)."""
        if self.version is None:
            return None
        return 0.008 if self.version[0] < 4 else 0.002

    @property
    def robot(self) -> str | None:
        """The catalogue name (``"ur5e"``), or None when the replies do not say."""
        m = re.fullmatch(r"UR(\d+)E?", self.model_reply.strip().upper())
        if m is None or self.version is None:
            return None
        size = int(m.group(1))
        if self.version[0] < 4:
            return f"ur{size}"
        return f"ur{size}" if size >= 20 else f"ur{size}e"

    @property
    def version_text(self) -> str:
        return "unknown" if self.version is None else ".".join(map(str, self.version))


def _read_line(sock: socket.socket, buf: bytearray, deadline: float) -> str:
    while b"\n" not in buf:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError("no answer")
        sock.settimeout(left)
        data = sock.recv(4096)
        if not data:
            raise ConnectionError("connection closed")
        buf.extend(data)
        if len(buf) > 65536:
            raise ConnectionError("answer too long")
    nl = buf.index(b"\n")
    line = bytes(buf[:nl]).decode("utf-8", "replace").strip()
    del buf[: nl + 1]
    return line


def query_dashboard(
    host: str, *, timeout: float = 3.0, port: int = DASHBOARD_PORT
) -> ControllerInfo:
    """Ask the dashboard server for the robot model and the software version.

    Raises ``ConnectionError`` (with the reason) when it cannot be reached or does
    not answer within ``timeout`` seconds in all.
    """
    deadline = time.monotonic() + timeout
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            buf = bytearray()
            _read_line(sock, buf, deadline)  # the greeting
            sock.sendall(b"PolyscopeVersion\n")
            version_reply = _read_line(sock, buf, deadline)
            sock.sendall(b"get robot model\n")
            model_reply = _read_line(sock, buf, deadline)
            sock.sendall(b"quit\n")
    except TimeoutError:
        raise ConnectionError(f"dashboard server {host}:{port}: no answer within {timeout:g} s"
                              ) from None  # fmt: skip
    except OSError as exc:
        raise ConnectionError(
            f"dashboard server {host}:{port}: {exc or type(exc).__name__}"
        ) from None
    m = _VERSION_RE.search(version_reply)
    version = (int(m.group(1)), int(m.group(2)), int(m.group(3))) if m else None
    return ControllerInfo(host, model_reply, version_reply, version)


def controller_checks(meta: TrajectoryMeta, info: ControllerInfo) -> list[Check]:
    """Robot model and control period against the trajectory's; kinematics (hook)."""
    checks = []
    said = f"dashboard said {info.model_reply!r} and {info.version_reply!r}"
    robot = info.robot
    if robot is None:
        value = f"unknown ({info.model_reply or 'no answer'})"
        detail = (
            f"the controller at {info.host} did not say which robot it is ({said}); the "
            f"trajectory is for a {meta.robot}: not run"
        )
    else:
        value = f"{robot} ({info.generation}, software {info.version_text})"
        detail = (
            f"the trajectory was planned for a {meta.robot}, the controller at {info.host} "
            f"is a {robot} ({said}): refused; plan the job for the {robot}"
        )
    checks.append(
        Check(
            "robot_model",
            "robot model (dashboard)",
            value,
            meta.robot,
            "",
            "==",
            robot == meta.robot,
            True,
            "" if robot == meta.robot else detail,
        )
    )
    period = info.control_period
    ok = period is not None and abs(period - meta.control_period) < 1e-9
    if period is None:
        value_p: float | str = "unknown"
        detail = f"the controller's software version is unknown ({said})"
    else:
        value_p = 1e3 * period
        detail = (
            f"the controller runs at {1 / period:.0f} Hz ({info.generation}), the trajectory "
            f"is sampled at {1 / meta.control_period:.0f} Hz: refused"
        )
    checks.append(
        Check(
            "control_period",
            "control period (from the software version)",
            value_p,
            1e3 * meta.control_period,
            "ms",
            "==",
            ok,
            True,
            "" if ok else detail,
        )
    )
    # HOOK(kinematics): compare the controller's calibrated kinematics with
    # meta.kinematics.checksum once the primary interface's KinematicsInfo
    # package (port 30001) is read; until then this is information, not a pass.
    checks.append(
        Check.info(
            "kinematics",
            f"kinematics (trajectory's: {meta.kinematics.source}, "
            f"{meta.kinematics.checksum[:15]}...)",
            "not checked (controller kinematics not read yet)",
        )
    )
    return checks


def readiness_check(host: str, state: dict) -> Check:
    """Robot mode RUNNING and safety NORMAL (from the RTDE state the session read)."""
    mode, safety = int(state["robot_mode"]), int(state["safety_mode"])
    stopped = state.get("protective") or state.get("emergency")
    ok = mode == ROBOT_MODE_RUNNING and safety == SAFETY_MODE_NORMAL and not stopped
    detail = ""
    if mode != ROBOT_MODE_RUNNING:
        detail = (
            f"controller at {host}: robot mode {mode}, expected 7 (RUNNING): power on and "
            "release the brakes first"
        )
    elif not ok:
        detail = (
            f"controller at {host}: safety mode {safety}, expected 1 (NORMAL): clear the "
            "protective or emergency stop first"
        )
    return Check(
        "controller_ready",
        "controller ready (robot mode, safety)",
        f"mode {mode}, safety {safety}",
        "mode 7 (RUNNING), safety 1 (NORMAL)",
        "",
        "",
        ok,
        True,
        detail,
    )
