"""Several emulators on one machine: a taken address moves to the next free loopback
address (demo, run, ursim without --host); an address the user gave is never moved
(issue 31)."""

from __future__ import annotations

import contextlib
import errno
import re
import socket
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ruledrobot.ursim import (
    DEFAULT_Q,
    EMBEDDED_HOST,
    Emulator,
    ThreadedEmulator,
    embedded_emulator,
)
from ruledrobot.ursim.address import address_in_use, loopback_hosts, start_on_free_host
from tests.support.emulators import _address
from tests.support.rawclient import RawRTDEClient


@contextlib.contextmanager
def taken(host: str, port: int = 30004) -> Iterator[socket.socket]:
    """``host:port`` held by a plain listening socket (as another emulator would)."""
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        s.bind((host, port))
        s.listen(1)
        yield s
    finally:
        s.close()


def dashboard(host: str, command: str) -> str:
    """One dashboard command on a new connection (3 s bound); the reply line."""
    with socket.create_connection((host, 29999), timeout=3.0) as s:
        f = s.makefile("rw")
        assert f.readline().startswith("Connected")
        f.write(command + "\n")
        f.flush()
        return f.readline().strip()


def serves(emu: Emulator) -> None:
    """The emulator answers on its own address: the dashboard, and an RTDE stream."""
    assert dashboard(emu.host, "robotmode") == "Robotmode: RUNNING"
    with RawRTDEClient(emu.host, timeout=3.0) as cli:
        assert cli.negotiate(2)
        cli.setup_outputs(["timestamp"], frequency=125.0)
        assert cli.start()
        assert cli.read_data(timeout=3.0)["timestamp"] >= 0.0


def test_loopback_hosts_follow_the_first() -> None:
    assert loopback_hosts("127.0.0.42", 4) == ["127.0.0.42", "127.0.0.43", "127.0.0.44",
                                               "127.0.0.45"]  # fmt: skip
    assert loopback_hosts("127.0.0.253", 4) == ["127.0.0.253", "127.0.0.254", "127.0.1.1",
                                                "127.0.1.2"]  # fmt: skip
    assert loopback_hosts("127.255.255.254", 3) == ["127.255.255.254", "127.0.0.1", "127.0.0.2"]
    hosts = loopback_hosts(EMBEDDED_HOST)
    assert len(hosts) == len(set(hosts)) == 32
    for fixed in ("localhost", "10.0.0.7", "::1"):  # nothing to move to
        assert loopback_hosts(fixed, 5) == [fixed]


def _in_use(host: str) -> OSError:
    exc = OSError(f"rtde server: cannot listen on {host}:30004: [Errno 98] Address already in use")
    exc.errno = errno.EADDRINUSE
    return exc


def test_start_on_free_host_moves_on_only_from_a_taken_address() -> None:
    busy = {"127.0.0.42", "127.0.0.43"}
    tried: list[str] = []

    def start(host: str) -> str:
        tried.append(host)
        if host in busy:
            raise _in_use(host)
        return host

    assert start_on_free_host("127.0.0.42", start) == "127.0.0.44"
    assert tried == ["127.0.0.42", "127.0.0.43", "127.0.0.44"]
    with pytest.raises(OSError, match=r"127\.0\.0\.42:30004") as info:  # the user's address
        start_on_free_host("127.0.0.42", start, find_free_host=False)
    assert address_in_use(info.value)

    def unavailable(host: str) -> str:
        raise OSError(errno.EADDRNOTAVAIL, "Cannot assign requested address")

    with pytest.raises(OSError) as info:  # another error: no other address would do better
        start_on_free_host("127.0.0.42", unavailable)
    assert info.value.errno == errno.EADDRNOTAVAIL
    busy.update(loopback_hosts("127.0.0.42", 5))
    with pytest.raises(OSError, match=r"127\.0\.0\.42 and the 4 addresses after it "
                       r"\(to 127\.0\.0\.46\) are taken") as info:  # fmt: skip
        start_on_free_host("127.0.0.42", start, count=5)
    assert address_in_use(info.value)


def test_two_embedded_emulators_come_up_on_two_addresses_and_both_serve() -> None:
    """What a second ``ruledrobot demo`` does while the first one streams."""
    with embedded_emulator("ur5e", DEFAULT_Q) as first:
        with embedded_emulator("ur5e", DEFAULT_Q) as second:
            assert first.host != second.host
            for emu in (first, second):
                assert emu.host in loopback_hosts(EMBEDDED_HOST)
                serves(emu)
            assert second.robot_mode == first.robot_mode


def test_emulators_starting_at_the_same_moment_end_on_two_addresses(request) -> None:
    """Two processes starting on one address race for its ports: the bind decides,
    the loser moves on."""
    first = _address(request.node.nodeid, 0)
    emus = [Emulator(first, "ur5e", find_free_host=True) for _ in range(2)]
    go = threading.Barrier(2, timeout=10.0)
    errors: list[BaseException] = []

    def start(emu: Emulator) -> None:
        go.wait()
        try:
            emu.start()
        except BaseException as exc:  # reported below
            errors.append(exc)

    threads = [threading.Thread(target=start, args=(e,)) for e in emus]
    try:
        for t in threads:
            t.start()
        for t in threads:
            t.join(30.0)
        assert not errors, errors
        hosts = {e.host for e in emus}
        assert len(hosts) == 2 and hosts <= set(loopback_hosts(first)), hosts
        for emu in emus:
            serves(emu)
    finally:
        for emu in emus:
            emu.close()


def test_a_partly_taken_address_is_released_before_the_next_is_tried(request) -> None:
    """Only the primary port (30001) is taken: the three ports bound before it and the
    programs folder are released, the emulator (in process here) listens on the next
    address."""
    first = _address(request.node.nodeid, 0)
    with taken(first, 30001):
        failed = ThreadedEmulator(first, "ur5e")
        with pytest.raises(OSError, match=re.escape(f"{first}:30001")) as info:
            failed.start()
        assert address_in_use(info.value)
        assert not Path(failed.programs_dir).exists()  # nothing started, nothing left behind
        with taken(first, 30004), taken(first, 29999), taken(first, 30003):
            pass  # bound again: the failed start let them go
        emu = Emulator(first, "ur5e", find_free_host=True, in_process=True).start()
        try:
            assert emu.host == loopback_hosts(first)[1]
            assert dashboard(emu.host, "robotmode") == "Robotmode: RUNNING"
        finally:
            emu.close()


def test_an_emulator_on_a_taken_address_it_was_given_says_so() -> None:
    host = _address("test_an_emulator_on_a_taken_address_it_was_given_says_so", 0)
    said = re.escape(f"cannot listen on {host}:30004")
    with taken(host), pytest.raises(OSError, match=said) as info:
        Emulator(host, "ur5e").start()
    assert address_in_use(info.value)


def test_ursim_moves_from_its_taken_default_and_says_where(monkeypatch, request) -> None:
    from ruledrobot.cli import app
    from ruledrobot.cli import robot as cli_robot

    first = _address(request.node.nodeid, 0)
    monkeypatch.setattr(cli_robot, "DEFAULT_URSIM_HOST", first)
    with taken(first):
        res = CliRunner().invoke(app, ["ursim", "--duration", "0.3"])
    assert res.exit_code == 0, res.output
    second = loopback_hosts(first)[1]
    assert f"{first} is taken (another emulator runs there?): listening on {second} instead" \
        in res.output  # fmt: skip
    assert f"listening on {second}: RTDE 30004" in res.output


def test_ursim_refuses_a_taken_host_it_was_given_in_one_line(request) -> None:
    from ruledrobot.cli import app

    host = _address(request.node.nodeid, 0)
    with taken(host):
        res = CliRunner().invoke(app, ["ursim", "--host", host, "--duration", "0.3"])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: --host {host} is taken"), res.output
    assert "Address already in use" in lines[0] and "listening" not in res.output
    assert res.exception is None or isinstance(res.exception, SystemExit)


def test_run_says_in_one_line_when_its_embedded_emulator_cannot_start(monkeypatch,
                                                                      tmp_path) -> None:
    """Every address taken: one line and exit 2 (was a traceback)."""
    import numpy as np

    import ruledrobot.ursim as ursim
    from ruledrobot.cli import app
    from ruledrobot.io.trajectory import write_trajectory
    from ruledrobot.robot import load
    from ruledrobot.robot.motion.trajectory import Trajectory

    @contextlib.contextmanager
    def nowhere(*args, **kwargs) -> Iterator[Emulator]:
        exc = OSError("no free loopback address: 127.0.0.42 and the 31 addresses after it "
                      "(to 127.0.0.73) are taken")  # fmt: skip
        exc.errno = errno.EADDRINUSE
        raise exc
        yield  # a generator: the context manager's shape

    monkeypatch.setattr(ursim, "embedded_emulator", nowhere)
    t = np.arange(0.0, 0.1, 0.002)
    traj = write_trajectory(tmp_path / "t.csv", Trajectory.from_joints(
        t, np.tile(DEFAULT_Q, (t.size, 1)), load("ur5e")))  # fmt: skip
    res = CliRunner().invoke(app, ["run", str(traj), "--yes"])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert lines == ["error: the embedded controller emulator cannot start: no free loopback "
                     "address: 127.0.0.42 and the 31 addresses after it (to 127.0.0.73) are "
                     "taken"], res.output  # fmt: skip
