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
from enum import IntEnum

import numpy as np

from ..protocol.modes import RobotMode, SafetyMode
from ..protocol.primary import DASHBOARD_PORT
from ..robot.arm.ur_tables import nominal_dh
from ..robot.motion.trajectory import KinematicsRef, TrajectoryMeta
from ..robot.verdict import Check

__all__ = [
    "DASHBOARD_PORT",
    "ControllerInfo",
    "controller_checks",
    "query_dashboard",
    "readiness_check",
]


_VERSION_RE = re.compile(r"(\d+)\.(\d+)\.(\d+)(?:\.(\d+))?")


@dataclass(frozen=True)
class ControllerInfo:
    """What the dashboard said.

    ``model_reply`` (``"UR5"``), ``version_reply`` (``"URSoftware 5.11.1.108318 (...)"``),
    ``version`` (major, minor, bugfix)."""

    host: str
    model_reply: str
    version_reply: str
    version: tuple[int, int, int] | None

    @property
    def generation(self) -> str | None:
        """``"CB3"`` (major version below 4) or ``"e-Series"``, None when the version is unknown."""
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
        """The version as ``"5.11.1"``, or ``"unknown"``."""
        return "unknown" if self.version is None else ".".join(map(str, self.version))


#: m, rad: a controller's DH table read over the primary interface equals another table
#: (the planned one, the catalogue's) when no entry differs by more than this
DH_TOL = 1e-12


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
    """Check the controller's robot model and control period against the trajectory's.

    The kinematics: :func:`kinematics_check`.
    """
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
    return checks


def kinematics_check(meta: TrajectoryMeta, host: str, *, timeout: float = 3.0,
                     force: bool = False) -> tuple[Check, KinematicsRef | None]:  # fmt: skip
    """Check the controller's kinematics against the ones the trajectory was planned with.

    The controller's KinematicsInfo (primary interface): the same DH table (to
    :data:`DH_TOL`) and, when the trajectory knows them, the same per-joint checksums.
    ``force`` turns a mismatch into information (a conscious choice, shown as such).  Also
    returns the controller's kinematics (None when not read): a recording is in *its* frame.
    """
    check, info = _kinematics_check(meta, host, timeout, force)
    if info is None:
        return check, None
    nominal = _is_nominal(info.dh(), meta.robot)
    ref = KinematicsRef(info.dh(), "nominal" if nominal else f"controller {host}", "",
                        None if nominal else tuple(int(c) for c in info.checksum))  # fmt: skip
    return check, ref


def _kinematics_check(meta: TrajectoryMeta, host: str, timeout: float, force: bool):
    from ..protocol.primary import PrimaryProtocolError, read_kinematics_info

    label = f"kinematics (planned with: {meta.kinematics.source})"
    try:
        info, _ = read_kinematics_info(host, timeout=timeout)
    except (OSError, PrimaryProtocolError) as exc:
        detail = f"the controller's kinematics could not be read: {exc}"
        if force:
            return Check.info("kinematics", label, "not read (--force)", detail=detail), None
        failed = Check("kinematics", label, "not read", "the trajectory's", relation="==",
                       ok=False, detail=detail + "; --force runs without this check")  # fmt: skip
        return failed, None
    planned = meta.kinematics.dh
    diff = info.dh() - planned
    names = ("theta_offset", "a", "d", "alpha")
    off = np.argwhere(np.abs(diff) > DH_TOL)[:4]
    problems = [f"joint {j + 1} {names[c]}: controller {info.dh()[j, c]:.9g}, planned "
                f"{planned[j, c]:.9g}" for j, c in off]  # fmt: skip
    want = meta.kinematics.controller_checksum
    if want is not None and tuple(info.checksum) != tuple(want):
        bad = [j + 1 for j in range(6) if info.checksum[j] != want[j]]
        problems.append(f"checksums of joints {bad} differ (controller {list(info.checksum)}, "
                        f"planned {list(want)})")  # fmt: skip
    source = "nominal" if _is_nominal(info.dh(), meta.robot) else "calibrated"
    value = f"{source}, checksums {list(info.checksum)}"
    if not problems:
        return Check("kinematics", label, value, "the trajectory's", relation="==", ok=True), info
    detail = ("the trajectory was planned for other kinematics than the controller's: "
              + "; ".join(problems) + ". Fetch the calibration (ruledrobot calibration fetch) "
              "and plan again")  # fmt: skip
    if force:
        return Check.info("kinematics", label, value + " — MISMATCH ignored (--force)",
                          detail=detail), info  # fmt: skip
    return Check("kinematics", label, value, "the trajectory's", relation="==", ok=False,
                 detail=detail), info  # fmt: skip


def _is_nominal(dh: np.ndarray, robot: str) -> bool:
    """Whether a controller's DH table (6, 4) is the catalogue's of ``robot`` (to
    :data:`DH_TOL`)."""
    return not np.any(np.abs(dh - _nominal_dh(robot)) > DH_TOL)


def _nominal_dh(robot: str) -> np.ndarray:
    m = nominal_dh(robot)
    return np.stack([m.theta_offset, m.a, m.d, m.alpha], axis=1)


def _named(enum: type[IntEnum], value: int) -> str:
    """``5 (IDLE)``: a mode's number and, when the protocol knows it, its name."""
    try:
        return f"{value} ({enum(value).name})"
    except ValueError:
        return str(value)


def readiness_check(host: str, state: dict) -> Check:
    """Robot mode RUNNING and safety NORMAL (from the RTDE state the session read)."""
    mode, safety = int(state["robot_mode"]), int(state["safety_mode"])
    stopped = state.get("protective") or state.get("emergency")
    ok = mode == RobotMode.RUNNING and safety == SafetyMode.NORMAL and not stopped
    detail = ""
    if mode != RobotMode.RUNNING:
        detail = (
            f"controller at {host}: robot mode {_named(RobotMode, mode)}, expected 7 (RUNNING): "
            "power on and release the brakes first"
        )
    elif not ok:
        detail = (
            f"controller at {host}: safety mode {_named(SafetyMode, safety)}, expected 1 "
            "(NORMAL): clear the protective or emergency stop first"
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
