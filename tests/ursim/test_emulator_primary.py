"""The emulator's primary and secondary client interfaces (30001, 30002).

Version message first, then robot-state messages at 10 Hz with robot mode data (0) and
KinematicsInfo (5); several clients at once; the connection cap; URScript taken as on
the script port; hostile primary clients never disturb the RTDE stream.
"""

from __future__ import annotations

import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest

from ruledrobot.protocol.primary import (
    KINEMATICS_INFO,
    ROBOT_MESSAGE,
    ROBOT_MODE_DATA,
    ROBOT_STATE,
    PrimaryProtocolError,
    RobotModeData,
    parse_kinematics_info,
    parse_robot_mode_data,
    parse_robot_state,
    parse_version,
    read_kinematics_info,
    robot_mode_subpackage,
    split_messages,
)
from ruledrobot.robot import load
from ruledrobot.ursim import ThreadedEmulator
from ruledrobot.ursim.ports.tcp import try_realtime_priority
from ruledrobot.ursim.server import CB3_VERSION, E_SERIES_VERSION
from tests.support.emulators import _address
from tests.support.rawclient import UR_RTDE_RECEIVE_RECIPE, RawRTDEClient


def _emulator(nodeid: str, model: str = "ur5e", realtime: bool = False,
              **kwargs) -> ThreadedEmulator:  # fmt: skip
    """A threaded emulator in this process (raw-socket clients only) on the test's address."""
    last: Exception | None = None
    for attempt in range(5):
        try:
            return ThreadedEmulator(_address(nodeid, attempt), model, realtime=realtime,
                                    **kwargs).start()  # fmt: skip
        except OSError as exc:
            last = exc
    raise RuntimeError(f"no free loopback address: {last}")


@pytest.fixture
def local(request: pytest.FixtureRequest) -> Iterator[ThreadedEmulator]:
    emu = _emulator(request.node.nodeid)
    try:
        yield emu
    finally:
        emu.close()


class PrimaryReader:
    """Reads one primary/secondary connection in a thread: every message with its arrival
    time (``messages``: (time, type, body))."""

    def __init__(self, host: str, port: int) -> None:
        self.sock = socket.create_connection((host, port), timeout=3.0)
        self.messages: list[tuple[float, int, bytes]] = []
        self.error: Exception | None = None
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)
        self._t.start()

    def _run(self) -> None:
        try_realtime_priority(5)  # the instrument: its own stalls are not the emulator's
        buf = b""
        self.sock.settimeout(0.2)
        try:
            while not self._stop.is_set():
                try:
                    chunk = self.sock.recv(65536)
                except TimeoutError:
                    continue
                if not chunk:
                    return
                now = time.monotonic()
                msgs, buf = split_messages(buf + chunk)
                self.messages.extend((now, k, b) for k, b in msgs)
        except Exception as exc:  # the test looks at it
            self.error = exc

    def states(self) -> list[tuple[float, dict[int, bytes]]]:
        return [(t, parse_robot_state(b)) for t, k, b in self.messages if k == ROBOT_STATE]

    def close(self) -> None:
        self._stop.set()
        self._t.join(2.0)
        self.sock.close()


def _mode(reader: PrimaryReader) -> RobotModeData:
    return parse_robot_mode_data(reader.states()[-1][1][ROBOT_MODE_DATA])


def _wait(pred, timeout: float = 3.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(0.01)
    return bool(pred())


# ---------------------------------------------------------------- the layout


def test_robot_mode_data_is_the_documented_layout() -> None:
    data = RobotModeData(123456789, False, True, True, False, True, True, False, 7, 0,
                         0.5, 0.25, 1.0)  # fmt: skip
    # hand-packed, field by field, as UR's Client Interface documentation lists them
    body = struct.pack(">Q", 123456789) + bytes([0, 1, 1, 0, 1, 1, 0]) + bytes([7, 0])
    body += struct.pack(">ddd", 0.5, 0.25, 1.0)
    v5 = struct.pack(">IB", 47, 0) + body + b"\x00"  # 5.x: a reserved byte
    v3 = struct.pack(">IB", 46, 0) + body
    assert robot_mode_subpackage(data) == v5
    assert robot_mode_subpackage(data, reserved=False) == v3
    assert parse_robot_mode_data(v5[5:]) == data == parse_robot_mode_data(v3[5:])
    assert parse_robot_mode_data(v5[5:] + b"later fields") == data  # ignored, as UR asks
    neg = robot_mode_subpackage(RobotModeData(0, *[False] * 7, -1, 0, 1.0, 1.0, 1.0))
    assert parse_robot_mode_data(neg[5:]).robot_mode == -1  # NO_CONTROLLER: int8
    with pytest.raises(PrimaryProtocolError, match="at least 46"):
        parse_robot_mode_data(v3[5:-1])
    bad = robot_mode_subpackage(RobotModeData(0, *[False] * 7, 7, 0, float("nan"), 1.0, 1.0))
    with pytest.raises(PrimaryProtocolError, match="NaN"):
        parse_robot_mode_data(bad[5:])


# ---------------------------------------------------------------- the stream


def test_version_first_then_state_at_10_hz_on_both_ports(local: ThreadedEmulator) -> None:
    nominal = load("ur5e")
    readers = [PrimaryReader(local.host, local.ports[p]) for p in ("primary", "secondary")]
    try:
        time.sleep(2.5)
    finally:
        for r in readers:
            r.close()
    for r in readers:
        assert r.error is None
        t, kind, body = r.messages[0]
        assert kind == ROBOT_MESSAGE
        version = parse_version(body)
        assert version is not None and version.project == "URControl"
        assert (version.major, version.minor, version.bugfix, version.build) == E_SERIES_VERSION
        assert all(k == ROBOT_STATE for _, k, _ in r.messages[1:])
        states = r.states()
        # one at once, then one every 100 ms on an absolute schedule
        assert states[0][0] - t < 0.05
        times = np.array([t for t, _ in states[1:]])
        gaps = np.diff(times)
        assert len(states) >= 22, len(states)
        assert abs(float(np.mean(gaps)) - 0.1) < 0.005, gaps
        assert float(np.max(gaps)) < 0.3, gaps
        for _, subs in states:
            assert sorted(subs) == [ROBOT_MODE_DATA, KINEMATICS_INFO]
            assert len(subs[ROBOT_MODE_DATA]) == 42  # 47 with the header: 5.x
        info = parse_kinematics_info(states[-1][1][KINEMATICS_INFO])
        # nominal: the catalogue's table bit for bit, checksums 0, status 2 (linearised)
        for got, want in ((info.theta, nominal.theta_offset), (info.a, nominal.a),
                          (info.d, nominal.d), (info.alpha, nominal.alpha)):  # fmt: skip
            assert got.tobytes() == np.asarray(want, dtype=">f8").astype(float).tobytes()
        assert info.checksum == (0,) * 6 and info.calibration_status == 2
        mode = _mode(r)
        assert mode.robot_mode == 7 and mode.power_on and mode.control_mode == 0
        assert not (mode.real_robot_connected or mode.emergency_stopped or mode.program_running)
        assert mode.speed_scaling == 1.0 == mode.target_speed_fraction
        stamps = [parse_robot_mode_data(s[ROBOT_MODE_DATA]).timestamp for _, s in states]
        assert np.all(np.diff(stamps) > 0)  # controller time [us]
        assert 0.05e6 < np.mean(np.diff(stamps[1:])) < 0.15e6


def test_robot_mode_data_follows_the_controller_and_scripts_run(local: ThreadedEmulator) -> None:
    r = PrimaryReader(local.host, local.ports["primary"])
    try:
        assert _wait(lambda: len(r.states()) >= 1)
        # URScript on the secondary port runs as on the script port
        with socket.create_connection((local.host, local.ports["secondary"]), timeout=3) as s:
            s.sendall(b"def waiting():\n  sleep(3.0)\nend\n")
            assert _wait(lambda: _mode(r).program_running, 2.0)
        assert local.stats_summary()["programs_received"] == 1.0
        local.protective_stop("test")
        assert _wait(lambda: _mode(r).protective_stopped and not _mode(r).program_running, 2.0)
        local.clear_faults()
        local.emergency_stop("test")
        assert _wait(lambda: _mode(r).emergency_stopped, 2.0)
        assert _wait(lambda: not _mode(r).power_on and _mode(r).robot_mode == 3, 3.0)
        # frozen: nothing is sent; then the stream goes on
        n0 = len(r.messages)
        local.freeze(0.6)
        time.sleep(0.45)
        assert len(r.messages) - n0 <= 1
        assert _wait(lambda: len(r.messages) - n0 >= 4, 2.0)
    finally:
        r.close()


def test_cb3_sends_3x_version_and_layout(request: pytest.FixtureRequest) -> None:
    emu = _emulator(request.node.nodeid, "ur5")
    try:
        info, version = read_kinematics_info(emu.host, emu.ports["secondary"])
        assert version is not None
        assert (version.major, version.minor, version.bugfix, version.build) == CB3_VERSION
        assert info.d.tolist() == load("ur5").d.tolist()
        r = PrimaryReader(emu.host, emu.ports["primary"])
        try:
            assert _wait(lambda: len(r.states()) >= 1)
            assert len(r.states()[0][1][ROBOT_MODE_DATA]) == 41  # 46 with the header: 3.x
        finally:
            r.close()
    finally:
        emu.close()


def test_many_clients_at_once(local: ThreadedEmulator) -> None:
    streams = [PrimaryReader(local.host, local.ports[p]) for p in ("primary", "secondary") * 5]
    results: list[object] = []

    def read(port: int) -> None:
        try:
            results.append(read_kinematics_info(local.host, port, timeout=5.0))
        except Exception as exc:
            results.append(exc)

    try:
        t0 = time.monotonic()
        threads = [threading.Thread(target=read, args=(local.ports[p],))
                   for p in ("primary", "secondary") * 8]  # fmt: skip
        for t in threads:
            t.start()
        for t in threads:
            t.join(10.0)
        took = time.monotonic() - t0
        time.sleep(1.6)
    finally:
        for s in streams:
            s.close()
    assert len(results) == 16 and not [r for r in results if isinstance(r, Exception)], results
    first = results[0][0]  # type: ignore[index]
    for info, version in results:  # type: ignore[misc]
        assert info.checksum == first.checksum and info.d.tolist() == first.d.tolist()
        assert version is not None and version.major == 5
    assert took < 2.0, took  # the state comes at once, not at the next period
    for s in streams:  # ten streams at once, each at 10 Hz
        assert s.error is None
        times = np.array([t for t, _ in s.states()])
        assert len(times) >= 16, len(times)
        assert abs(float(np.mean(np.diff(times[1:]))) - 0.1) < 0.01


def test_connection_cap_refuses_beyond_the_limit(request: pytest.FixtureRequest) -> None:
    emu = _emulator(request.node.nodeid, max_connections=4, idle_timeout=1.0)
    readers: list[PrimaryReader] = []
    try:
        readers = [PrimaryReader(emu.host, emu.ports["primary"]) for _ in range(4)]
        assert _wait(lambda: all(len(r.states()) >= 1 for r in readers))
        time.sleep(1.3)  # beyond idle_timeout: the readers take data, they are not idle
        with socket.create_connection((emu.host, emu.ports["primary"]), timeout=3) as s:
            assert s.recv(100) == b""  # refused: accepted and closed at once
        assert emu.primary.refused >= 1 and emu.primary.evicted == 0
        # the secondary port has its own cap
        info, _ = read_kinematics_info(emu.host, emu.ports["secondary"])
        assert info.calibration_status == 2
        readers.pop().close()
        assert _wait(lambda: len(emu.primary.connections()) == 3)
        info, _ = read_kinematics_info(emu.host, emu.ports["primary"])
        for r in readers:
            assert r.error is None and len(r.states()) >= 12
    finally:
        for r in readers:
            r.close()
        emu.close()


# ---------------------------------------------------------------- hostile clients


def _rtde_reader(host: str, port: int, stop: threading.Event, times: list[float]) -> None:
    # real-time where allowed, as the emulator's threads: on a busy machine a reader at
    # nice 0 waited up to 0.1 s for the CPU, and its arrival gaps were the scheduler's
    try_realtime_priority(5)
    cli = RawRTDEClient(host, port)
    try:
        assert cli.negotiate()
        assert "NOT_FOUND" not in cli.setup_outputs(list(UR_RTDE_RECEIVE_RECIPE), 500.0)
        assert cli.start()
        while not stop.is_set():
            cli.read_data(timeout=2.0)
            times.append(time.monotonic())
    finally:
        cli.close()


@pytest.fixture
def local_rt(request: pytest.FixtureRequest) -> Iterator[ThreadedEmulator]:
    """:func:`local` with the emulator's threads real-time where the system allows it
    (``SCHED_FIFO``, as ``ursim`` runs them): its clock then keeps its periods on a busy
    machine, and what the test measures is how it treats hostile connections (at nice 0
    it missed 5-13 % of its periods beside two or three busy processes, attackers or not)."""
    emu = _emulator(request.node.nodeid, realtime=True)
    try:
        yield emu
    finally:
        emu.close()


def test_truncated_and_closing_primary_clients_do_not_disturb_rtde(
    local_rt: ThreadedEmulator,
) -> None:
    local = local_rt
    # a stream 50 times denser than a controller's, so that the clients that never read
    # fill their buffers within the test and are dropped
    local.publisher.period = 0.002
    local.primary.max_backlog = local.secondary.max_backlog = 8192
    stop = threading.Event()
    times: list[float] = []
    rtde = threading.Thread(target=_rtde_reader, args=(local.host, local.rtde.port, stop, times))
    rtde.start()
    good = PrimaryReader(local.host, local.ports["primary"])
    try:
        time.sleep(3.0)  # the baseline as long as the hostile phase: the same odds of noise
        base = np.diff(times[1:])
        # the attackers in a process of their own (tests/support/hostile.py): in threads of
        # this one they took the interpreter's lock from the emulator and the readers,
        # and the stream fell to 353 Hz in a fresh-clone run (a test artifact: a
        # controller's hostile clients are other machines)
        ports = [str(local.ports[p]) for p in ("primary", "secondary") * 2]
        attackers = subprocess.Popen([sys.executable, "-m", "tests.support.hostile",
                                      local.host, "3.4", "0", *ports],
                                     stdout=subprocess.PIPE, text=True)  # fmt: skip
        assert attackers.stdout is not None and attackers.stdout.readline().strip() == "ready"
        n_base = len(times)
        local.reset_stats()
        t0 = time.monotonic()
        time.sleep(3.0)
        stats = local.stats_summary()
        n_during = len(times) - n_base
        during = np.diff(times[n_base:])
        took = time.monotonic() - t0
        attackers.wait(10.0)
    finally:
        stop.set()
        rtde.join(5.0)
        good.close()
        if "attackers" in locals() and attackers.poll() is None:
            attackers.kill()
    assert good.error is None
    # the RTDE stream: its rate, no stall beyond what the machine's noise explains
    assert n_during >= 0.95 * 500 * took, (n_during, took)
    # one gap of up to 0.11 s happens beside two busy processes (1 run in 7, measured on
    # 6 Dec 2026: this emulator's threads are not real-time, and the scheduler gives the
    # busy ones their slice); the stalls the rule is about were seconds
    assert float(during.max()) < 0.25, during.max()
    # periods over 10 ms: no more than the machine gave a moment before in as long a
    # time, doubled, plus 4 (0 before and 4 during failed twice in a row on a quiet
    # machine against the old bound of 3 + 3 x the count of a 1 s baseline)
    assert np.count_nonzero(during > 0.010) <= 4 + 2 * np.count_nonzero(base > 0.010)
    assert stats["tick_errors"] == 0 and stats["publish_errors"] == 0
    # missed controller periods: the same bound as the rate above (measured 0-3.3 % while
    # hostile clients connect and close hundreds of times a second on 2 cores)
    assert stats["primary_errors"] == 0 and stats["missed_fraction"] < 0.05, stats
    # the well-behaved primary client kept its (dense) stream while the attackers ran
    # (measured from their start: before it, the publisher waits out its old 100 ms
    # period once after the test changed it, and on a busy machine the reader's first
    # states can come late enough that this gap was the third, not the first)
    gaps = np.diff([t for t, _ in good.states() if t >= t0])
    assert len(gaps) > 500 and float(gaps.max()) < 0.05, float(gaps.max())
    # the clients that never read were dropped while the test ran; now all are gone
    assert stats["primary_dropped"] >= 1, stats
    assert _wait(lambda: stats_now(local)["primary_connections"] == 0, 5.0)
    assert local.rtde.protocol_errors == 0


def stats_now(emu: ThreadedEmulator) -> dict[str, float]:
    return emu.stats_summary()
