"""The runner under faults between ur_rtde and the controller: a frozen controller
(sockets open, nothing answers) and a dropped one (both sides closed), made by a
loopback fault proxy (:mod:`tests.support.faultproxy`) between the runner's ur_rtde
client and the emulator.

Before the ur_rtde session ran in a supervised child process, the first hung forever
(ur_rtde's ``servoStop`` has no timeout) and the second crashed the process in 7 of 16
runs.  Now both end with exit status 1 (not completed) within :data:`BOUND` seconds of
the fault, with the recording so far written and the place to resume from; the
controller's RTDE watchdog (2 Hz) stops the program by itself.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from ruledrobot.export import run_trajectory
from ruledrobot.io.trajectory import read_trajectory, write_trajectory
from ruledrobot.ursim import Emulator
from tests.support.emulators import _address, smooth_trajectory, start_emulator
from tests.support.faultproxy import FaultProxy

pytest.importorskip("rtde_control")

#: the runner's bound from a fault to its return [s]: heartbeat (1 s) + stop budget (1 s)
#: + settling (<= 1.5 s) + 0.5 s; soak: 1.11-1.13 s (frozen), 0.02-0.15 s (dropped)
BOUND = 4.0
#: samples the session may be ahead of the progress callback that injects the fault
LATE = 60


@pytest.fixture
def rig(request: pytest.FixtureRequest) -> Iterator[tuple[Emulator, FaultProxy]]:
    """An emulator and a fault proxy in front of it, on two loopback addresses."""
    emu = start_emulator(request.node.nodeid, model="ur5e", unlock_delay=0.0)
    proxy = None
    try:
        for attempt in range(5):
            addr = _address(request.node.nodeid + "#proxy", attempt)
            if addr == emu.host:
                continue
            try:
                proxy = FaultProxy(addr, emu.host).start()
                break
            except OSError:
                continue
        assert proxy is not None, "no free loopback address for the fault proxy"
        yield emu, proxy
    finally:
        if proxy is not None:
            proxy.close()
        emu.close()


def _run_with(fault: str, emu: Emulator, proxy: FaultProxy, tmp_path: Path):
    traj = smooth_trajectory(duration=2.0)
    src = write_trajectory(tmp_path / "cut.csv", traj)
    fired: list[tuple[int, float]] = []

    def progress(done: int, total: int) -> None:
        if not fired and done >= total // 3:
            fired.append((done, time.monotonic()))
            proxy.freeze() if fault == "freeze" else proxy.drop(refuse_for=1.0)

    # servoj: ur_rtde's hangs in the stream's safe stop and the watchdog (a forwarded run's
    # program talks to the runner directly and stops along the path: test_forward.py)
    res = run_trajectory(src, proxy.listen, progress=progress, lookahead=0.05, mode="servoj")
    assert fired, f"the fault was never injected: the run ended first ({res.status}: {res.message})"
    elapsed = time.monotonic() - fired[0][1]
    # the runner returned in time, not completed (the CLI's exit status 1), and says where
    assert not res.completed and res.moved, res
    assert elapsed < BOUND, f"{elapsed:.2f} s from the fault to the runner's return: {res}"
    assert 0 < res.stop_index <= fired[0][0] + LATE
    assert res.stop is not None and res.resume_index == res.stop_index
    # the recording so far is written and readable
    assert res.actual_path == tmp_path / "cut.run-001.csv"
    rec = read_trajectory(res.actual_path)
    assert rec.n > 100
    # the controller stopped the program by itself (watchdog), the arm rests
    assert emu.wait_for(lambda: emu.runtime_state != 2, timeout=2.0)
    assert any("RTDE watchdog" in e[2] for e in emu.events)
    return res, elapsed


@pytest.mark.parametrize("trial", range(2))
def test_frozen_controller(rig, tmp_path: Path, trial: int) -> None:
    emu, proxy = rig
    res, elapsed = _run_with("freeze", emu, proxy, tmp_path)
    # the data stops: controller_slow after max_latency; the safe stop hangs in
    # servoStop (no timeout in ur_rtde) and the runner kills the client after 1 s
    assert res.status in ("controller_slow", "client_hung"), res
    assert "killed" in res.message and "watchdog" in res.message
    print(f"frozen: {elapsed:.3f} s from the fault to the return: {res.status}")


@pytest.mark.parametrize("trial", range(2))
def test_dropped_controller(rig, tmp_path: Path, trial: int) -> None:
    emu, proxy = rig
    res, elapsed = _run_with("drop", emu, proxy, tmp_path)
    # ur_rtde sees the connection closed, or crashes (its native reconnect race):
    # the runner survives both
    assert res.status in ("connection_lost", "client_died", "program_stopped"), res
    print(f"dropped: {elapsed:.3f} s from the fault to the return: {res.status}")
