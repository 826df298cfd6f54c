"""The emulator under abuse (issue 9): what one client does can never reach another.

Each test starts its servers on its own loopback address and stops them.
"""

from __future__ import annotations

import contextlib
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from ruledrobot.ursim import Emulator, ThreadedEmulator
from ruledrobot.ursim.faults import FaultSpec, parse_fault
from ruledrobot.ursim.ports.tcp import try_realtime_priority
from ruledrobot.ursim.script.functions import bind
from ruledrobot.ursim.script.program import (
    MAX_LINE_BYTES,
    MAX_PROGRAM_BYTES,
    ProgramSplitter,
    ScriptSyntaxError,
    parse_call,
)
from tests.support.emulators import _address, start_emulator
from tests.support.processes import popen_as_from_a_terminal
from tests.support.rawclient import UR_RTDE_RECEIVE_RECIPE, RawRTDEClient


def _local(nodeid: str, realtime: bool) -> ThreadedEmulator:
    """A threaded emulator in this process on the test's address, ports picked freely."""
    for attempt in range(5):
        try:
            return ThreadedEmulator(_address(nodeid, attempt), "ur5e",
                                    realtime=realtime).start()  # fmt: skip
        except OSError:
            continue
    raise RuntimeError("no free loopback address")


@pytest.fixture
def local(request: pytest.FixtureRequest) -> Iterator[ThreadedEmulator]:
    """A threaded emulator in this process (raw-socket clients only), ports picked freely."""
    emu = _local(request.node.nodeid, realtime=False)
    try:
        yield emu
    finally:
        emu.close()


@pytest.fixture
def local_rt(request: pytest.FixtureRequest) -> Iterator[ThreadedEmulator]:
    """:func:`local` with its threads real-time where the system allows it (``SCHED_FIFO``,
    as ``ursim`` runs them): a thread that holds the interpreter's lock is then not
    preempted by the machine's other processes while the clock waits for it."""
    emu = _local(request.node.nodeid, realtime=True)
    try:
        yield emu
    finally:
        emu.close()


class Reader:
    """A raw RTDE client that reads every package in a thread; records arrival gaps."""

    def __init__(
        self,
        host: str,
        names: list[str] | tuple[str, ...] = ("timestamp",),
        frequency: float = 500.0,
        port: int = 30004,
    ) -> None:
        self.cli = RawRTDEClient(host, port)
        assert self.cli.negotiate()
        assert "NOT_FOUND" not in self.cli.setup_outputs(list(names), frequency)
        assert self.cli.start()
        self.gaps: list[float] = []
        self.timestamps: list[float] = []
        self.error: BaseException | None = None
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)
        self._t.start()

    def _run(self) -> None:
        try_realtime_priority(5)  # the instrument: its own waits for the CPU are not the emulator's
        last = time.monotonic()
        try:
            while not self._stop.is_set():
                d = self.cli.read_data(timeout=2.0)
                now = time.monotonic()
                self.gaps.append(now - last)
                last = now
                if "timestamp" in d:
                    self.timestamps.append(d["timestamp"])
        except BaseException as exc:
            if not self._stop.is_set():
                self.error = exc

    def stop(self) -> None:
        self._stop.set()
        self._t.join(3.0)
        self.cli.close()


def _send_script(host: str, port: int, text: bytes) -> None:
    with socket.create_connection((host, port), timeout=2.0) as s:
        s.sendall(text)


# ---------------------------------------------------------------- 3: one line, one client


@pytest.mark.parametrize(
    "line",
    [
        b"set_standard_digital_out(64, True)",
        b"set_configurable_digital_out(100, True)",
        b"set_standard_digital_out(1e7, True)",
    ],
)
def test_a_bad_io_line_does_not_stop_any_stream(line: bytes, emulator: Emulator) -> None:
    host = emulator.host
    readers = [Reader(host, UR_RTDE_RECEIVE_RECIPE), Reader(host, ["timestamp"], 125.0)]
    try:
        time.sleep(0.3)
        _send_script(host, emulator.ports["script"], line + b"\n")
        _send_script(host, emulator.ports["script"], b"def p():\n  " + line + b"\nend\n")
        time.sleep(0.7)
        for r in readers:
            assert r.error is None
            assert len(r.gaps) > 60 and max(r.gaps[5:]) < 0.1
    finally:
        for r in readers:
            r.stop()
    errors = [m for _, lv, m in emulator.events if lv <= 1]
    assert len(errors) == 2 and all("compile error" in m for m in errors)
    stats = emulator.stats()
    assert stats["tick_errors"] == 0 and stats["publish_errors"] == 0


def test_a_connection_that_cannot_be_served_is_closed_alone(local: ThreadedEmulator) -> None:
    """A value no package can carry (a 65-bit integer) in one client's recipe: that
    client is closed with one log line; the others keep their stream; the clock goes on."""
    host = local.host
    port = local.ports["rtde"]
    good = Reader(host, ["timestamp", "actual_q"], port=port)
    victim = Reader(host, ["timestamp", "actual_digital_output_bits"], port=port)
    try:
        time.sleep(0.2)
        ctrl = local.controller
        with ctrl.lock:
            ctrl.std_do = 1 << 64  # bypasses every check: the packing must fail
        time.sleep(0.5)
        with ctrl.lock:
            ctrl.std_do = 0
        assert victim.error is not None  # closed
        assert good.error is None and max(good.gaps[5:]) < 0.1
        n = len(good.timestamps)
        time.sleep(0.2)
        assert len(good.timestamps) > n + 50
    finally:
        good.stop()
        victim.stop()
    s = local.stats_summary()
    assert s["publish_errors"] >= 1 and s["tick_errors"] == 0
    assert local.running


def test_a_failing_tick_does_not_stop_publishing(
    local: ThreadedEmulator, monkeypatch: pytest.MonkeyPatch
) -> None:
    reader = Reader(local.host, ["timestamp"], port=local.ports["rtde"])
    try:
        time.sleep(0.1)
        ctrl = local.controller
        real = ctrl.backend.step
        calls = {"n": 0}

        def broken(dt: float) -> None:
            calls["n"] += 1
            if calls["n"] < 200:
                raise RuntimeError("backend exploded")
            real(dt)

        monkeypatch.setattr(ctrl.backend, "step", broken)
        time.sleep(0.6)
        assert reader.error is None and max(reader.gaps[5:]) < 0.1
    finally:
        reader.stop()
    assert local.stats_summary()["tick_errors"] >= 100


# ---------------------------------------------------------------- 4: recipes RTDE cannot carry


def test_an_output_recipe_beyond_the_16_bit_size_is_refused(local: ThreadedEmulator) -> None:
    """2,000 VECTOR6D outputs = 96 KB per package: no RTDE packet can carry it (its size
    field is 16 bits).  The setup fails (recipe id 0), the stream cannot start, and the
    other clients never notice."""
    host, port = local.host, local.ports["rtde"]
    good = Reader(host, ["timestamp"], port=port)
    try:
        with RawRTDEClient(host, port) as cli:
            assert cli.negotiate()
            names = ["actual_q"] * 2000
            payload = struct.pack(">d", 500.0) + ",".join(names).encode()
            reply = cli.request(ord("O"), payload)
            assert reply[0] == 0  # failed
            assert not cli.start()
            # a recipe just below the limit is accepted and streams
            n = (65535 - 4) // 48
            assert "NOT_FOUND" not in cli.setup_outputs(["actual_q"] * n, 125.0)
            assert cli.start()
            assert len(cli.read_data()) == 1
        # an input recipe whose data package could never be sent is refused too
        with RawRTDEClient(host, port) as cli:
            assert cli.negotiate()
            rid, _ = cli.setup_inputs(["external_force_torque"] * 2000)  # 96 KB
            assert rid == 0
        time.sleep(0.2)
        assert good.error is None and max(good.gaps[5:]) < 0.1
    finally:
        good.stop()
    s = local.stats_summary()
    assert s["publish_errors"] == 0 and s["tick_errors"] == 0


# ---------------------------------------------------------------- 5: clients that do not read


@pytest.fixture
def roomy(request: pytest.FixtureRequest) -> Iterator[Emulator]:
    """An emulator that takes up to 128 connections per server (the default is 32)."""
    emu = start_emulator(request.node.nodeid, model="ur5e", max_connections=128)
    try:
        yield emu
    finally:
        emu.close()


@pytest.mark.parametrize("n", [20, 100])
def test_clients_that_do_not_read_cost_only_themselves(n: int, roomy: Emulator) -> None:
    """n clients set up ur_rtde's 58-variable stream at 500 Hz, then never read.  Before:
    with 20 of them the clock stalled for 300-500 ms at a time and lost 1.4 s of 6.  Now
    sends never wait, stuck sockets are not even tried, and a client whose queue passes
    256 KiB is disconnected: the reading client keeps its 500 Hz stream and the clock's
    worst gap between two publishes stays under 10 ms (see the bounds below)."""
    emulator = roomy
    host = emulator.host
    reader = Reader(host, UR_RTDE_RECEIVE_RECIPE)
    idle = []
    try:
        time.sleep(0.3)
        emulator.reset_stats()  # the machine's own noise: the reader alone for 1.5 s
        time.sleep(1.5)
        base = emulator.stats()
        for _ in range(n):
            cli = RawRTDEClient(host)
            assert cli.negotiate()
            cli.setup_outputs(list(UR_RTDE_RECEIVE_RECIPE), 500.0)
            assert cli.start()
            idle.append(cli)  # ... and never read again
        emulator.reset_stats()
        t0, k0 = time.monotonic(), len(reader.timestamps)
        ts0 = reader.timestamps[-1]
        time.sleep(3.0)  # no polling: every stats() call takes the emulator's GIL a while
        stats = emulator.stats()
        wall = time.monotonic() - t0
        rate = (len(reader.timestamps) - k0) / wall
        controller_time = reader.timestamps[-1] - ts0
    finally:
        reader.stop()
        for cli in idle:
            cli.close()
    assert reader.error is None
    # On a quiet machine the clock's worst gap stays under 10 ms (measured 2.3-5.8 ms with
    # 20 or 100 slow clients; 2.1-9.6 ms with both cores loaded by busy processes).  This
    # VM's own noise, one reader and no slow client, reaches 16-48 ms gaps and a p99 of
    # 7.7 ms at times, so the test bounds what the fix guarantees, against the noise
    # measured just before: nothing near the 300-500 ms stalls of before, no more long
    # gaps than the noise explains, p99 within 3 ms of the noise's.  One gap of 101 ms
    # happens in about one run in ten with 100 slow clients beside two busy processes
    # (measured 6 Dec 2026: 3 of 30 runs, each 101.1-101.4 ms, when the slow clients'
    # sockets are closed; with the clock not real-time, single gaps of 40-220 ms); it
    # failed CI at the old 100 ms bound.  250 ms still tells the old stalls apart.
    noise = base["gaps_over_10ms"] * 2.0  # the baseline lasted half as long
    assert stats["gap_max_ms"] < 250.0, (base, stats)
    assert stats["gaps_over_10ms"] <= max(10.0, 3.0 * noise), (base, stats)
    assert stats["gap_p99_ms"] < min(10.0, max(5.0, base["gap_p99_ms"] + 3.0)), (base, stats)
    # while the slow clients' kernel buffers fill (a fraction of a second) every period
    # sends to all of them: a few publishes are skipped (measured 0-9 %)
    assert stats["resyncs"] == 0 and stats["missed_fraction"] < 0.15
    assert rate > 450.0  # the reader's 500 Hz stream (it was 357 Hz)
    assert controller_time == pytest.approx(wall, abs=0.2)  # real time (it lost 0.7 s in 3)
    assert stats["rtde_connections"] == 1  # the n slow ones were disconnected


# ---------------------------------------------------------------- 6: the script port is linear


def test_program_text_is_cut_and_parsed_in_linear_time() -> None:
    # a 320 KB line of 100,000 tokens: 8 s of CPU before (the tokenizer re-stripped the
    # rest of the line at every token), milliseconds now
    cost = {}
    for n in (32_000, 320_000):
        line = "write_output_integer_register(1" + ", 1" * ((n - 32) // 3) + ")"
        t = time.process_time()
        with pytest.raises(ScriptSyntaxError, match="at most 2 arguments"):
            bind(parse_call(line))
        cost[n] = time.process_time() - t
    # linear: 10 times the text, about 10 times the time (measured 0.05 s and 0.46 s)
    assert cost[320_000] < 2.0 and cost[320_000] < 25 * cost[32_000] + 0.05, cost
    # 20 MiB without a newline (before: the whole buffer scanned again at every chunk,
    # 1 s of CPU for 20 MiB, 4 times that for twice the size): refused at MAX_LINE_BYTES
    sp = ProgramSplitter()
    chunk = "x" * (256 << 10)
    t = time.process_time()
    with pytest.raises(ValueError, match="line longer than"):
        for _ in range(80):
            list(sp.feed(chunk))
    assert time.process_time() - t < 0.1
    # 20 MiB of short lines and no 'end': refused at MAX_PROGRAM_BYTES, each byte seen once
    sp = ProgramSplitter()
    chunk = "def p():\n" + "  sync()\n" * (1 << 15)
    t = time.process_time()
    with pytest.raises(ValueError, match="larger than 8 MiB"):
        for _ in range(80):
            list(sp.feed(chunk))
    assert time.process_time() - t < 1.0
    # a line longer than MAX_LINE_BYTES is refused as soon as it is
    sp = ProgramSplitter()
    with pytest.raises(ValueError, match="line longer than"):
        list(sp.feed('def p():\n  textmsg("' + "y" * (MAX_LINE_BYTES + 10)))


def test_splitter_keeps_its_cuts() -> None:
    """The linear splitter cuts exactly where the old one did, for any fragmentation."""
    a = "def a():\n  if True:\n    sleep(1)\n  end\nend\n"
    b = "\n\n  \ndef b():\n  sync()\nend   \n"
    c = "textmsg(1)\n"
    d = "sec s():\n  set_standard_digital_out(1, True)\nend\n"
    text = a + b + c + d
    for step in (1, 3, 7, 64, len(text)):
        sp = ProgramSplitter()
        got = []
        for i in range(0, len(text), step):
            got.extend(sp.feed(text[i : i + step]))
        assert got == [a, "def b():\n  sync()\nend   \n", c, d], step
    sp = ProgramSplitter()
    assert list(sp.feed("def e():\n  sync()\nend")) == []  # 'end' without its newline yet
    assert list(sp.feed("\n")) == ["def e():\n  sync()\nend\n"]


def test_a_servoj_program_of_some_megabytes_runs(local_rt: ThreadedEmulator) -> None:
    """Limits: MAX_PROGRAM_BYTES per program, MAX_LINE_BYTES per line.  A 2.5 MB program
    (the size urscript_program refuses by default) is parsed by lark and compiled in a few
    seconds (2.6-4.6 s measured on 2 cores) and runs; one beyond the limit is refused,
    logged, and its connection closed.  The emulator's threads real-time, as ``ursim``
    runs them: at normal priority, beside the other real-time tests, the compiling thread
    was preempted while it held the interpreter's lock and the stream stalled 0.75 s."""
    local = local_rt
    q = "[0.0, -1.5707963, 1.5707963, -1.5707963, -1.5707963, 0.0]"
    line = f"  servoj({q}, t=0.002, lookahead_time=0.1, gain=300)\n"
    n = 2_500_000 // len(line)
    text = ("def big():\n" + line * n + "end\n").encode()
    reader = Reader(local.host, ["timestamp"], port=local.ports["rtde"])
    try:
        t = time.monotonic()
        _send_script(local.host, local.ports["script"], text)
        assert local.wait_for(lambda: local.runtime_state == 2, 20.0)
        compile_s = time.monotonic() - t
        too_big = b"def huge():\n" + line.encode() * (MAX_PROGRAM_BYTES // len(line) + 1)
        with socket.create_connection((local.host, local.ports["script"]), timeout=5.0) as s:
            with contextlib.suppress(OSError):
                s.sendall(too_big)
            s.settimeout(5.0)
            with contextlib.suppress(OSError):
                assert s.recv(10) == b""  # closed by the emulator
        assert local.wait_for(
            lambda: any("larger than" in m for _, lv, m in local.events if lv <= 1), 5.0
        )
        assert local.runtime_state == 2  # the big program still runs
        # compiling 2.5 MB in this (in-process) emulator holds the GIL in stretches: the
        # stream goes on, with gaps measured up to 0.24 s on 2 cores (a known limit:
        # parsing costs ~1.5 s of CPU per MB); a stall of seconds would fail here
        assert reader.error is None and max(reader.gaps[5:]) < 0.5
    finally:
        reader.stop()
    assert compile_s < 12.0


# ---------------------------------------------------------------- 7: memory, caps, idle


def _proc_status(pid: int) -> dict[str, int]:
    out = {}
    with open(f"/proc/{pid}/status") as f:
        for ln in f:
            if ln.startswith(("VmRSS:", "Threads:")):
                out[ln.split(":")[0]] = int(ln.split()[1])
    return out


def test_the_dashboard_keeps_bounded_memory(emulator: Emulator) -> None:
    """50,000 lines of 4 KB (unknown commands and addToLog): +207 MiB never freed before
    (every command was kept); now the emulator keeps the last 100 commands, log
    messages are cut at 1,000 characters, and the memory stays put."""
    pytest.importorskip("resource")
    host = emulator.host
    time.sleep(0.3)
    rss0 = _proc_status(emulator.pid)["VmRSS"]
    n = 50_000
    with socket.create_connection((host, emulator.ports["dashboard"]), timeout=10.0) as s:
        f = s.makefile("rb")
        assert f.readline().startswith(b"Connected")
        replies = []
        reader = threading.Thread(target=lambda: replies.extend(f.readline() for _ in range(n)))
        reader.start()
        junk = b"x" * 4000 + b"\n"
        log = b"addToLog " + b"y" * 3990 + b"\n"
        for _ in range(n // 100):
            s.sendall((junk + log) * 50)
        reader.join(30.0)
    assert len(replies) == n and replies[-1] == b"Added log message\n"
    assert replies[0].startswith(b"could not understand")
    time.sleep(0.3)
    grown = (_proc_status(emulator.pid)["VmRSS"] - rss0) / 1024
    assert grown < 20.0, f"{grown:.0f} MiB kept"
    assert all(len(m) <= 1000 for _, _, m in emulator.events)


def test_connection_cap_and_idle_eviction(request: pytest.FixtureRequest) -> None:
    """600 connections that send nothing: 607 threads before.  Now each server holds at
    most max_connections; beyond that a newcomer takes the place of a connection idle
    for idle_timeout s, or is refused.  Clients that talk are never evicted for it."""
    emu = start_emulator(request.node.nodeid, model="ur5e", max_connections=16, idle_timeout=1.0)
    host = emu.host
    idle: list[socket.socket] = []
    try:
        threads0 = _proc_status(emu.pid)["Threads"]
        with RawRTDEClient(host) as streaming:  # a client in use: it keeps its place
            assert streaming.negotiate()
            streaming.setup_outputs(["timestamp"], 125.0)
            assert streaming.start()
            for port in emu.ports.values():
                for _ in range(200):
                    with contextlib.suppress(OSError):
                        idle.append(socket.create_connection((host, port), timeout=0.5))
            time.sleep(0.5)
            threads = _proc_status(emu.pid)["Threads"]
            assert threads - threads0 <= 3 * 16, threads
            stats = emu.stats()
            assert stats["refused_connections"] >= 3 * 16  # (the rest wait in listen queues)
            time.sleep(1.0)  # the silent ones are now idle for more than idle_timeout
            d = dashboard_line(host, emu.ports["dashboard"], "PolyscopeVersion")
            assert d.startswith("URSoftware")
            for _ in range(50):
                streaming.read_data(timeout=1.0)  # never evicted: it receives its stream
        assert emu.stats()["evicted_connections"] >= 1
    finally:
        for s in idle:
            s.close()
        emu.close()


def dashboard_line(host: str, port: int, command: str) -> str:
    """One dashboard command on a new connection; the reply line."""
    with socket.create_connection((host, port), timeout=3.0) as s:
        f = s.makefile("rw")
        assert f.readline().startswith("Connected")
        f.write(command + "\n")
        f.flush()
        return f.readline().strip()


# ---------------------------------------------------------------- 8: what the network may do


def test_restart_safety_does_not_release_an_emergency_stop(emulator: Emulator) -> None:
    """An e-stop is released on the robot (the button), never from the network."""
    host, port = emulator.host, emulator.ports["dashboard"]
    emulator.emergency_stop("test")
    assert emulator.wait_for(lambda: emulator.robot_mode == 3, 3.0)  # braked, power off
    assert dashboard_line(host, port, "restart safety") == "Restarting safety"
    time.sleep(0.1)
    assert emulator.safety_mode == 7  # ROBOT_EMERGENCY_STOP, still
    assert dashboard_line(host, port, "power on").startswith("Failed")
    assert any(
        "emergency stop" in m and "released on the robot" in m
        for _, lv, m in emulator.events
        if lv <= 2
    )
    emulator.release_emergency_stop()  # the button
    assert emulator.safety_mode == 1
    assert dashboard_line(host, port, "power on") == "Powering on"
    assert dashboard_line(host, port, "brake release") == "Brake releasing"
    assert emulator.wait_for(lambda: emulator.robot_mode == 7, 2.0)


def test_programs_are_loaded_from_the_programs_folder_only(
    request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    """As PolyScope serves /programs: anything outside the folder, or missing, is
    "File not found" (the answer reveals nothing about other files)."""
    programs = tmp_path / "programs"
    programs.mkdir()
    (programs / "cut.urp").write_text("placeholder")
    (programs / "sub").mkdir()
    (programs / "sub" / "heat.script").write_text(
        "def heat():\n  set_standard_digital_out(2, True)\nend\n"
    )
    secret = tmp_path / "secret.urp"
    secret.write_text("outside")
    (programs / "link.urp").symlink_to(secret)
    emu = start_emulator(request.node.nodeid, model="ur5e", programs_dir=str(programs))
    host, port = emu.host, emu.ports["dashboard"]
    try:
        assert emu.programs_dir == str(programs)
        for path in (
            "/etc/shadow",
            "/etc/hostname",
            "/etc/passwd",
            "../secret.urp",
            str(secret),
            "link.urp",
            "sub/../../secret.urp",
            "missing.urp",
            "",
        ):
            reply = dashboard_line(host, port, f"load {path}")
            assert reply == f"File not found: {path}".strip(), reply
        assert dashboard_line(host, port, "get loaded program") == "No program loaded"
        assert dashboard_line(host, port, "load cut.urp") == "Loading program: cut.urp"
        assert dashboard_line(host, port, "get loaded program") == (
            f"Loaded program: {programs / 'cut.urp'}"
        )
        full = str(programs / "sub" / "heat.script")
        assert dashboard_line(host, port, f"load {full}") == f"Loading program: {full}"
        assert dashboard_line(host, port, "play") == "Starting program"
        assert emu.wait_for(lambda: any("heat finished" in m for _, _, m in emu.events), 3.0)
    finally:
        emu.close()


def test_ursim_binds_before_it_says_it_listens() -> None:
    from typer.testing import CliRunner

    from ruledrobot.cli import app

    runner = CliRunner()
    refused = runner.invoke(app, ["ursim", "--host", "10.255.255.1", "--duration", "0.5"])
    assert refused.exit_code == 2, refused.output
    assert "listening" not in refused.output and "not a loopback" in refused.output
    host = _address("test_ursim_binds_before_it_says_it_listens", 0)
    ok = runner.invoke(app, ["ursim", "--host", host, "--duration", "0.5"])
    assert ok.exit_code == 0, ok.output
    assert f"listening on {host}" in ok.output


# ---------------------------------------------------------------- 9: faults, frozen controller


def test_fault_specs_parse_or_say_what_is_wrong() -> None:
    assert parse_fault("protective_stop@5s") == FaultSpec(
        "protective_stop", 5.0, None, None, "protective_stop@5s"
    )
    assert parse_fault("freeze@500ms:3s").at == 0.5 and parse_fault("freeze@1:3").arg == 3.0
    assert parse_fault("emergency-stop@SIGUSR1").signal == "SIGUSR1"
    assert parse_fault("clear@usr2").signal == "SIGUSR2"
    assert parse_fault("drop@2:250ms").arg == 0.25
    for bad, why in [("protective_stop", "KIND@WHEN"), ("explode@5s", "unknown kind"),
                     ("freeze@soon", "not a time"), ("slow@1:fast", "not a time"),
                     ("emergency_stop@1:2", "takes no argument")]:  # fmt: skip
        with pytest.raises(ValueError, match=why):
            parse_fault(bad)


def test_a_frozen_controller_keeps_its_sockets_and_answers_nothing(emulator: Emulator) -> None:
    host, ports = emulator.host, emulator.ports
    with (
        RawRTDEClient(host) as cli,
        socket.create_connection((host, ports["dashboard"]), timeout=2.0) as dash,
    ):
        assert cli.negotiate()
        cli.setup_outputs(["timestamp"], 125.0)
        assert cli.start()
        f = dash.makefile("rb")
        assert f.readline().startswith(b"Connected")
        t_before = cli.read_data()["timestamp"]
        emulator.freeze()
        time.sleep(0.05)
        # drain what was sent before the freeze, then: nothing, but the socket is open
        t_last = t_before
        with contextlib.suppress(TimeoutError):
            while True:
                t_last = cli.read_data(timeout=0.2)["timestamp"]
        dash.sendall(b"robotmode\n")
        dash.settimeout(0.5)
        with pytest.raises(TimeoutError):
            dash.recv(100)  # no reply, no EOF
        late = socket.create_connection((host, ports["dashboard"]), timeout=2.0)  # queued
        late.settimeout(0.3)
        with pytest.raises(TimeoutError):
            late.recv(100)  # no greeting while frozen
        assert emulator.runtime_state in (1, 2)  # the emulator itself is alive
        emulator.unfreeze()
        dash.settimeout(2.0)
        assert f.readline() == b"Robotmode: RUNNING\n"  # the queued request, answered now
        late.settimeout(2.0)
        assert late.recv(100).startswith(b"Connected")
        late.close()
        t_after = cli.read_data(timeout=2.0)["timestamp"]
        assert t_after - t_last < 0.1  # the controller time stood still (frozen > 1 s)
        assert t_last >= t_before
    assert any("frozen" in m for _, _, m in emulator.events)


def test_ursim_injects_faults_on_a_timer_and_on_a_signal(tmp_path: Path) -> None:
    host = _address("test_ursim_injects_faults_on_a_timer_and_on_a_signal", 0)
    cmd = [sys.executable, "-c", "from ruledrobot.cli import app; app()", "ursim",
           "--host", host, "--duration", "20", "--programs", str(tmp_path),
           "--fault", "protective_stop@1s", "--fault", "emergency_stop@SIGUSR1",
           "--fault", "clear@SIGUSR2"]  # fmt: skip
    proc = popen_as_from_a_terminal(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                    text=True)  # stopped by SIGINT below
    try:
        assert proc.stdout is not None
        lines = []
        for line in proc.stdout:  # the banner comes once the ports are bound
            lines.append(line)
            if "listening on" in line:
                break
        assert any("listening on" in ln for ln in lines), lines
        dash = emulator_dashboard(host)
        assert dash("safetymode") == "Safetymode: NORMAL"
        deadline = time.monotonic() + 5.0
        while dash("safetymode") != "Safetymode: PROTECTIVE_STOP":
            assert time.monotonic() < deadline, "no protective stop after 1 s"
            time.sleep(0.05)
        proc.send_signal(signal.SIGUSR1)
        deadline = time.monotonic() + 3.0
        while dash("safetymode") != "Safetymode: ROBOT_EMERGENCY_STOP":
            assert time.monotonic() < deadline, "SIGUSR1 did not trigger the e-stop"
            time.sleep(0.05)
        proc.send_signal(signal.SIGUSR2)
        deadline = time.monotonic() + 3.0
        while dash("safetymode") != "Safetymode: NORMAL":
            assert time.monotonic() < deadline, "SIGUSR2 did not clear"
            time.sleep(0.05)
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            out, _ = proc.communicate(timeout=10.0)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
    assert "fault: emergency_stop on SIGUSR1" in out and proc.returncode == 0, out


def emulator_dashboard(host: str) -> Callable[[str], str]:
    """A dashboard query function on one connection."""
    s = socket.create_connection((host, 29999), timeout=3.0)
    f = s.makefile("rw")
    assert f.readline().startswith("Connected")

    def ask(cmd: str) -> str:
        f.write(cmd + "\n")
        f.flush()
        return f.readline().strip()

    return ask
