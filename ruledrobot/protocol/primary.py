"""The primary client interface of a UR controller (ports 30001 and 30002), as far as we use it.

The controller sends, on connection, a *version message* and then, at 10 Hz, a
*robot-state message*.  Every message (big-endian)::

    int32  size           # of the whole message, header included
    uint8  type           # 16 robot state, 20 robot message, 25 program state, ...
    ...    body

A robot-state message (type 16) is a sequence of sub-packages, each::

    uint32 size           # of the sub-package, header included
    uint8  type           # 0 robot mode, 1 joint data, ..., 5 KinematicsInfo, 6 configuration
    ...    body

KinematicsInfo (sub-package 5, 225 bytes) holds the controller's *effective*
kinematics — the nominal DH table with the robot's factory calibration::

    uint32[6] checksum    # one per joint
    double[6] dh_theta    # theta offsets (rad)
    double[6] dh_a        # m
    double[6] dh_d        # m
    double[6] dh_alpha    # rad
    uint32    calibration_status

Robot mode data (sub-package 0; UR's "Client Interface" documentation for 3.x and
5.x, and the Universal Robots Client Library's ``RobotModeData``)::

    uint64    timestamp
    bool      isRealRobotConnected, isRealRobotEnabled, isRobotPowerOn,
              isEmergencyStopped, isProtectiveStopped, isProgramRunning, isProgramPaused
    int8      robotMode         # the RTDE robot modes: -1 no controller ... 7 running
    uint8     controlMode       # 0 position, 1 teach, 2 force, 3 torque
    double    targetSpeedFraction, speedScaling, targetSpeedFractionLimit
    uint8     reserved          # 5.x only (47 bytes in all; 46 on 3.x)

(bools are one byte each).  UR documents the timestamp's type, not its unit.

A robot message (type 20) starts with ``uint64 timestamp, int8 source, uint8
message type``; the version message (type 3) then holds ``uint8 n, char[n]
project name, uint8 major, uint8 minor, int32 bugfix, int32 build, string
build date``.

Parsers here are strict: a truncated, oversized or wrong-type packet raises
:class:`PrimaryProtocolError` naming what was wrong; the reader never waits
longer than its deadline.
"""

from __future__ import annotations

import socket
import struct
import time
from dataclasses import dataclass

import numpy as np

__all__ = [
    "DASHBOARD_PORT",
    "KINEMATICS_INFO",
    "KINEMATICS_INFO_SIZE",
    "MAX_MESSAGE_SIZE",
    "PRIMARY_PORT",
    "ROBOT_MESSAGE",
    "ROBOT_MODE_DATA",
    "ROBOT_STATE",
    "SCRIPT_PORT",
    "SECONDARY_PORT",
    "KinematicsInfo",
    "PrimaryProtocolError",
    "RobotModeData",
    "Version",
    "kinematics_info_subpackage",
    "parse_kinematics_info",
    "parse_robot_mode_data",
    "parse_robot_state",
    "parse_version",
    "read_kinematics_info",
    "robot_mode_subpackage",
    "robot_state_message",
    "split_messages",
    "version_message",
]

PRIMARY_PORT = 30001
SECONDARY_PORT = 30002
#: the real-time client interface, where ur_rtde and forwarded runs send their programs
SCRIPT_PORT = 30003
#: the dashboard server
DASHBOARD_PORT = 29999
#: message types
ROBOT_STATE = 16
ROBOT_MESSAGE = 20
PROGRAM_STATE_MESSAGE = 25
#: robot-state sub-package types
ROBOT_MODE_DATA = 0
JOINT_DATA = 1
KINEMATICS_INFO = 5
CONFIGURATION_DATA = 6
#: robot-message types
ROBOT_MESSAGE_VERSION = 3
#: robot-message source of the version message
VERSION_SOURCE = -2

_KIN_BODY = struct.Struct(">6I6d6d6d6dI")
_MODE_BODY = struct.Struct(">Q7?bBddd")  # 41 bytes; 5.x appends one reserved byte
#: robot mode data sub-package size (header included): 3.x, 5.x
ROBOT_MODE_DATA_SIZE_V3 = 5 + _MODE_BODY.size  # 46
ROBOT_MODE_DATA_SIZE_V5 = ROBOT_MODE_DATA_SIZE_V3 + 1  # 47
KINEMATICS_INFO_SIZE = 5 + _KIN_BODY.size  # 225
#: Largest message accepted (a robot-state message is about 1.5 kB).
MAX_MESSAGE_SIZE = 1 << 20
_HEADER = struct.Struct(">iB")
_SUB_HEADER = struct.Struct(">IB")


class PrimaryProtocolError(ValueError):
    """A primary-interface packet that is truncated, oversized or of the wrong type."""


@dataclass(frozen=True, eq=False)
class KinematicsInfo:
    """A controller's effective kinematics: DH per joint (6,) each, checksums, status."""

    checksum: tuple[int, ...]
    theta: np.ndarray
    a: np.ndarray
    d: np.ndarray
    alpha: np.ndarray
    calibration_status: int

    def dh(self) -> np.ndarray:
        """(6, 4) per joint ``[theta_offset, a, d, alpha]`` (ruledrobot's DH column order)."""
        return np.stack([self.theta, self.a, self.d, self.alpha], axis=1)


@dataclass(frozen=True)
class RobotModeData:
    """Robot mode data (sub-package 0): power, stops, program state, modes, speed slider."""

    timestamp: int
    real_robot_connected: bool
    real_robot_enabled: bool
    power_on: bool
    emergency_stopped: bool
    protective_stopped: bool
    program_running: bool
    program_paused: bool
    robot_mode: int
    control_mode: int
    target_speed_fraction: float
    speed_scaling: float
    target_speed_fraction_limit: float


@dataclass(frozen=True)
class Version:
    """The controller software version (``major.minor.bugfix.build``)."""

    project: str
    major: int
    minor: int
    bugfix: int
    build: int
    date: str = ""

    @property
    def text(self) -> str:
        """The version as ``"major.minor.bugfix.build"``."""
        return f"{self.major}.{self.minor}.{self.bugfix}.{self.build}"


# --------------------------------------------------------------------------- building


def kinematics_info_subpackage(info: KinematicsInfo) -> bytes:
    """The KinematicsInfo sub-package (225 bytes, header included)."""
    body = _KIN_BODY.pack(*[int(c) for c in info.checksum], *map(float, info.theta),
                          *map(float, info.a), *map(float, info.d), *map(float, info.alpha),
                          int(info.calibration_status))  # fmt: skip
    return _SUB_HEADER.pack(KINEMATICS_INFO_SIZE, KINEMATICS_INFO) + body


def robot_mode_subpackage(data: RobotModeData, *, reserved: bool = True) -> bytes:
    """The robot mode data sub-package.

    47 bytes with the reserved byte of 5.x (``reserved=True``), 46 bytes as 3.x sends it."""
    body = _MODE_BODY.pack(int(data.timestamp), bool(data.real_robot_connected),
                           bool(data.real_robot_enabled), bool(data.power_on),
                           bool(data.emergency_stopped), bool(data.protective_stopped),
                           bool(data.program_running), bool(data.program_paused),
                           int(data.robot_mode), int(data.control_mode),
                           float(data.target_speed_fraction), float(data.speed_scaling),
                           float(data.target_speed_fraction_limit))  # fmt: skip
    if reserved:
        body += b"\x00"
    return _SUB_HEADER.pack(_SUB_HEADER.size + len(body), ROBOT_MODE_DATA) + body


def robot_state_message(subpackages: list[bytes]) -> bytes:
    """A robot-state message (type 16) holding the given sub-packages."""
    body = b"".join(subpackages)
    return _HEADER.pack(_HEADER.size + len(body), ROBOT_STATE) + body


def version_message(version: Version, timestamp: int = 0) -> bytes:
    """The version message a controller sends first on every connection."""
    name = version.project.encode()
    date = version.date.encode()
    body = (struct.pack(">QbB", timestamp, VERSION_SOURCE, ROBOT_MESSAGE_VERSION)
            + struct.pack(">B", len(name)) + name
            + struct.pack(">BBii", version.major, version.minor, version.bugfix, version.build)
            + date)  # fmt: skip
    return _HEADER.pack(_HEADER.size + len(body), ROBOT_MESSAGE) + body


# --------------------------------------------------------------------------- parsing


def split_messages(buffer: bytes) -> tuple[list[tuple[int, bytes]], bytes]:
    """Split the complete messages ``(type, body)`` off the start of ``buffer``.

    Returns them and the rest (an incomplete message).  Raises on a size field below the
    header or above :data:`MAX_MESSAGE_SIZE`.
    """
    out: list[tuple[int, bytes]] = []
    pos = 0
    view = memoryview(buffer)
    while len(buffer) - pos >= _HEADER.size:
        size, kind = _HEADER.unpack_from(view, pos)
        if size < _HEADER.size or size > MAX_MESSAGE_SIZE:
            raise PrimaryProtocolError(f"primary message at byte {pos}: size field {size} outside "
                                       f"[{_HEADER.size}, {MAX_MESSAGE_SIZE}]")  # fmt: skip
        if len(buffer) - pos < size:
            break
        out.append((kind, bytes(view[pos + _HEADER.size : pos + size])))
        pos += size
    return out, bytes(view[pos:])


def parse_robot_state(body: bytes) -> dict[int, bytes]:
    """The sub-packages ``{type: body}`` of a robot-state message body."""
    subs: dict[int, bytes] = {}
    pos = 0
    while pos < len(body):
        if len(body) - pos < _SUB_HEADER.size:
            raise PrimaryProtocolError(f"robot state: truncated sub-package header at byte {pos}")
        size, kind = _SUB_HEADER.unpack_from(body, pos)
        if size < _SUB_HEADER.size or pos + size > len(body):
            raise PrimaryProtocolError(f"robot state: sub-package type {kind} at byte {pos} has "
                                       f"size {size}, {len(body) - pos} bytes left")  # fmt: skip
        subs[kind] = body[pos + _SUB_HEADER.size : pos + size]
        pos += size
    return subs


def parse_kinematics_info(body: bytes) -> KinematicsInfo:
    """A KinematicsInfo sub-package body (220 bytes, without its 5-byte header)."""
    if len(body) != _KIN_BODY.size:
        raise PrimaryProtocolError(f"KinematicsInfo: {len(body) + 5} bytes, expected "
                                   f"{KINEMATICS_INFO_SIZE}")  # fmt: skip
    v = _KIN_BODY.unpack(body)
    arr = np.asarray(v[6:30], dtype=np.float64).reshape(4, 6)
    if not np.isfinite(arr).all():
        raise PrimaryProtocolError("KinematicsInfo: DH values contain NaN or infinity")
    return KinematicsInfo(tuple(v[:6]), arr[0], arr[1], arr[2], arr[3], int(v[30]))


def parse_robot_mode_data(body: bytes) -> RobotModeData:
    """A robot mode data sub-package body (without its header).

    The 41 bytes of the documented fields; what follows (5.x's reserved byte, fields a later
    version adds) is ignored, as UR asks clients to do."""
    if len(body) < _MODE_BODY.size:
        raise PrimaryProtocolError(f"robot mode data: {len(body) + 5} bytes, expected at least "
                                   f"{ROBOT_MODE_DATA_SIZE_V3}")  # fmt: skip
    v = _MODE_BODY.unpack_from(body, 0)
    if not all(np.isfinite(v[10:13])):
        raise PrimaryProtocolError("robot mode data: speed fractions contain NaN or infinity")
    return RobotModeData(int(v[0]), *(bool(b) for b in v[1:8]), int(v[8]), int(v[9]),
                         float(v[10]), float(v[11]), float(v[12]))  # fmt: skip


def parse_version(body: bytes) -> Version | None:
    """The version of a robot-message body, or None if it is another robot message."""
    if len(body) < 10:
        raise PrimaryProtocolError(f"robot message: {len(body)} bytes, shorter than its header")
    _, _source, kind = struct.unpack_from(">QbB", body, 0)
    if kind != ROBOT_MESSAGE_VERSION:
        return None
    try:
        n = body[10]
        name = body[11 : 11 + n].decode("utf-8", "replace")
        major, minor, bugfix, build = struct.unpack_from(">BBii", body, 11 + n)
    except (IndexError, struct.error):
        raise PrimaryProtocolError("version message: truncated") from None
    return Version(name, major, minor, bugfix, build, body[21 + n :].decode("utf-8", "replace"))


def read_kinematics_info(
    host: str, port: int = PRIMARY_PORT, timeout: float = 3.0
) -> tuple[KinematicsInfo, Version | None]:
    """Connect to a controller's primary interface and return its KinematicsInfo.

    And its version, when it came first.  Gives up after ``timeout`` s in all (OSError /
    TimeoutError naming the host), raises :class:`PrimaryProtocolError` on bad packets.
    """
    deadline = time.monotonic() + timeout
    version: Version | None = None
    buf = b""
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except OSError as exc:
        raise OSError(f"controller {host}:{port}: cannot connect ({exc})") from None
    with sock:
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"controller {host}:{port}: no KinematicsInfo within "
                                   f"{timeout:g} s")  # fmt: skip
            sock.settimeout(left)
            try:
                chunk = sock.recv(65536)
            except TimeoutError:
                continue
            if not chunk:
                raise PrimaryProtocolError(f"controller {host}:{port}: closed the connection "
                                           "before sending KinematicsInfo")  # fmt: skip
            buf += chunk
            messages, buf = split_messages(buf)
            for kind, body in messages:
                if kind == ROBOT_MESSAGE and version is None:
                    version = parse_version(body)
                elif kind == ROBOT_STATE:
                    subs = parse_robot_state(body)
                    if KINEMATICS_INFO in subs:
                        return parse_kinematics_info(subs[KINEMATICS_INFO]), version
