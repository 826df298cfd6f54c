"""Fixtures for tests that talk to the emulator: distinct loopback addresses, hard time limits.

Every test gets its own 127.x.y.z address (derived from its node id, with a
fallback when the address is busy), so tests can run in parallel processes.
ur_rtde's calls hold the GIL and can block, so each test also runs under a
``faulthandler`` deadline that dumps the stacks and exits instead of hanging.
"""

from __future__ import annotations

import contextlib
import faulthandler
import hashlib
import os
import sys
from collections.abc import Iterator

import numpy as np
import pytest

from ruledrobot.robot import load
from ruledrobot.robot.motion.trajectory import Trajectory
from ruledrobot.ursim import DEFAULT_Q, Emulator

#: hard limit per test [s]
TEST_DEADLINE = float(os.environ.get("RULEDROBOT_EXPORT_TEST_DEADLINE", "90"))


@pytest.fixture(autouse=True)
def _deadline() -> Iterator[None]:
    faulthandler.dump_traceback_later(TEST_DEADLINE, exit=True, file=sys.stderr)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()


def _address(nodeid: str, attempt: int) -> str:
    h = hashlib.sha256(f"{nodeid}#{attempt}#{os.getpid()}".encode()).digest()
    return f"127.{1 + h[0] % 250}.{h[1]}.{2 + h[2] % 250}"


@pytest.fixture
def host(request: pytest.FixtureRequest) -> str:
    """A loopback address of this test's own."""
    return _address(request.node.nodeid, 0)


def start_emulator(nodeid: str, **kwargs) -> Emulator:
    """Start an emulator on an address derived from ``nodeid`` (retrying when busy)."""
    last: Exception | None = None
    for attempt in range(5):
        emu = Emulator(_address(nodeid, attempt), **kwargs)
        try:
            return emu.start()
        except OSError as exc:
            last = exc
    raise RuntimeError(f"no free loopback address for the emulator: {last}")


@pytest.fixture
def emulator(request: pytest.FixtureRequest) -> Iterator[Emulator]:
    """A UR5e emulator (child process) with instant protective-stop unlock."""
    emu = start_emulator(request.node.nodeid, model="ur5e", unlock_delay=0.0)
    try:
        yield emu
    finally:
        emu.close()


class UR:
    """The real ur_rtde interfaces to one controller, created on first use.

    ur_rtde's ``disconnect()`` sleeps 0.5 s and its destructor calls it again,
    and a control interface whose controller disappears aborts the process
    (its reconnect thread throws).  :meth:`release` therefore destroys each
    interface nobody else holds (one disconnect) and explicitly disconnects
    one still referenced (e.g. by the frames of a failed test).
    """

    def __init__(self, host: str, frequency: float = -1.0, flags: int | None = None) -> None:
        self.host = host
        self.frequency = frequency
        self.flags = flags
        self._r = None
        self._c = None
        self._io = None

    @property
    def r(self):
        if self._r is None:
            import rtde_receive

            self._r = rtde_receive.RTDEReceiveInterface(self.host, self.frequency)
        return self._r

    @property
    def c(self):
        if self._c is None:
            import rtde_control

            if self.flags is None:
                self._c = rtde_control.RTDEControlInterface(self.host, self.frequency)
            else:
                self._c = rtde_control.RTDEControlInterface(self.host, self.frequency, self.flags)
        return self._c

    @property
    def io(self):
        if self._io is None:
            import rtde_io

            self._io = rtde_io.RTDEIOInterface(self.host)
        return self._io

    def release(self) -> None:
        for name in ("_io", "_c", "_r"):
            obj = getattr(self, name)
            setattr(self, name, None)
            if obj is None:
                continue
            if sys.getrefcount(obj) > 2:
                with contextlib.suppress(Exception):
                    obj.disconnect()
            del obj


@pytest.fixture
def ur(emulator: Emulator) -> Iterator[UR]:
    """ur_rtde interfaces (``ur.r``, ``ur.c``, ``ur.io``) to the test's emulator."""
    u = UR(emulator.host)
    try:
        yield u
    finally:
        u.release()


def smooth_trajectory(
    duration: float = 1.2,
    amplitude: tuple[float, ...] = (0.09, -0.07, 0.09, 0.07, 0.09, -0.09),
    q0: tuple[float, ...] = DEFAULT_Q,
    period: float = 0.002,
    model: str = "ur5e",
) -> Trajectory:
    """q(t) = q0 + A sin^2(pi t / T): rest to rest and back, within the UR5e limits."""
    t = np.arange(0.0, duration + 1e-9, period)
    s = np.sin(np.pi * t / duration) ** 2
    q = np.asarray(q0) + np.asarray(amplitude) * s[:, None]
    return Trajectory.from_joints(t, q, load(model), source="synthetic test trajectory")
