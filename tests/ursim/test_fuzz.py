"""Malformed input never takes the emulator down: it closes that connection and serves the rest."""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
import time

import numpy as np

from ruledrobot.protocol.rtde import pack_packet
from ruledrobot.ursim import DEFAULT_Q, Emulator
from tests.support import fuzz as fuzz_mod
from tests.support.emulators import UR
from tests.support.rawclient import UR_RTDE_RECEIVE_RECIPE, RawRTDEClient


def _blast(host: str, port: int, payload: bytes, read: bool = True) -> None:
    """Connect, send ``payload``, read whatever comes back for a moment, close."""
    with contextlib.suppress(OSError), socket.create_connection((host, port), timeout=1.0) as s:
        s.sendall(payload)
        if read:
            s.settimeout(0.02)
            with contextlib.suppress(OSError):
                s.recv(65536)


def _handshake() -> bytes:
    return (pack_packet(ord("V"), struct.pack(">H", 2)) + pack_packet(ord("v"))
            + pack_packet(ord("I"), b"input_int_register_0,input_double_register_0,"))  # fmt: skip


def test_malformed_packets_fuzz(emulator: Emulator, ur: UR) -> None:
    host = emulator.host
    rng = np.random.default_rng(2024)
    # a well-behaved client streams the whole time and must not notice
    gaps: list[float] = []
    stop = threading.Event()

    def watch() -> None:
        with RawRTDEClient(host) as cli:
            assert cli.negotiate()
            cli.setup_outputs(list(UR_RTDE_RECEIVE_RECIPE), 500.0)
            assert cli.start()
            last = time.monotonic()
            while not stop.is_set():
                cli.read_data(timeout=2.0)
                now = time.monotonic()
                gaps.append(now - last)
                last = now

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    t_min = time.monotonic() + 1.5  # fuzz for at least 1.5 s, at most 4 s
    t_end = time.monotonic() + 4.0
    cases = 0
    rtde, dash, script = (emulator.ports[k] for k in ("rtde", "dashboard", "script"))
    fixed = [
        b"\x00",  # truncated header
        b"\x00\x01",
        b"\x00\x01V",  # size below the header size
        b"\x00\x02V\x00",
        b"\xff\xffV" + b"x" * 50,  # announces 64 KiB, sends 50 bytes, closes
        b"\x00\x05Zab",  # unknown packet type
        pack_packet(ord("V"), b"\x00\x02\x00"),  # wrong payload size
        pack_packet(ord("v"), b"junk"),
        pack_packet(ord("O"), struct.pack(">d", float("nan")) + b"timestamp"),
        pack_packet(ord("O"), b"\x01"),  # shorter than the frequency
        pack_packet(ord("I"), b"\xff\xfe\x00,,"),  # non-ASCII names
        pack_packet(ord("U"), b""),  # no recipe id
        pack_packet(ord("U"), b"\x07" + b"\x00" * 12),  # unknown recipe
        _handshake() + pack_packet(ord("U"), b"\x01" + b"\x00" * 5),  # wrong data size
        _handshake() + pack_packet(ord("U"), b"\x01" + struct.pack(">id", 1, float("inf"))),
        pack_packet(ord("S")) + pack_packet(ord("P")) * 3,  # start without a recipe
    ]
    for payload in fixed:
        _blast(host, rtde, payload)
        cases += 1
    while time.monotonic() < t_end and (cases < 400 or time.monotonic() < t_min):
        kind = cases % 4
        n = int(rng.integers(1, 700))
        junk = rng.bytes(n)
        if kind == 0:
            _blast(host, rtde, junk)
        elif kind == 1:  # a valid start, then garbage
            _blast(host, rtde, _handshake() + junk)
        elif kind == 2:
            _blast(host, dash, junk + (b"x" * 5000 if cases % 8 == 2 else b"\n"))
        else:
            _blast(host, script, b"def f():\n" + junk if cases % 8 == 3 else junk, read=False)
        cases += 1
    stop.set()
    watcher.join(5.0)
    assert not watcher.is_alive()
    assert cases >= 100
    stats = emulator.stats()
    assert stats["rtde_protocol_errors"] >= len(fixed) - 3  # closed as protocol errors
    # the stream never stalled for the good client
    assert len(gaps) > 500 and max(gaps[10:]) < 0.1
    # the emulator still serves ur_rtde as if nothing happened
    r, c = ur.r, ur.c
    np.testing.assert_allclose(r.getActualQ(), DEFAULT_Q, atol=1e-12)
    target = (np.array(DEFAULT_Q) + 0.05).tolist()
    assert c.moveJ(target, 1.0, 4.0)
    np.testing.assert_allclose(r.getActualQ(), target, atol=1e-9)
    assert emulator.runtime_state == 2


def test_semantic_fuzz_of_the_three_ports(emulator: Emulator, ur: UR) -> None:
    """Hostile but well-formed input (emulator.fuzz): programs with bad arguments, control
    flow, huge numbers, over-long lines; dashboard commands with paths outside the
    programs folder; random RTDE recipes and frequencies.  For 3 s, loopback only, while a
    client streams: the stream never stalls, no controller period and no publish fails,
    the outputs never take a value a controller could not have, nothing outside the
    programs folder loads, and ur_rtde works afterwards."""
    host = emulator.host
    fuzz_mod.check_loopback(host)
    gaps: list[float] = []
    bits: list[int] = []
    stop = threading.Event()

    def watch() -> None:
        with RawRTDEClient(host) as cli:
            assert cli.negotiate()
            cli.setup_outputs(["timestamp", "actual_digital_output_bits",
                               "standard_analog_output0"], 500.0)  # fmt: skip
            assert cli.start()
            last = time.monotonic()
            while not stop.is_set():
                d = cli.read_data(timeout=2.0)
                now = time.monotonic()
                gaps.append(now - last)
                last = now
                bits.append(d["actual_digital_output_bits"])
                assert 0.0 <= d["standard_analog_output0"] <= 1.0

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    time.sleep(0.2)
    report = fuzz_mod.fuzz(host, emulator.ports, duration=3.0, seed=7)
    stop.set()
    watcher.join(5.0)
    assert not watcher.is_alive()
    assert sum(report.cases.values()) > 150, report
    stats = emulator.stats()
    assert stats["tick_errors"] == 0 and stats["publish_errors"] == 0, stats
    assert len(gaps) > 1000 and max(gaps[10:]) < 0.1
    assert max(bits) < 1 << 18  # 8 standard + 8 configurable + 2 tool outputs
    events = emulator.events
    assert not any("Loading program" in m for _, _, m in events)
    assert not any("program step failed" in m or "internal error" in m for _, _, m in events)
    # back to a known state, as an operator would: then ur_rtde as if nothing happened
    emulator.release_emergency_stop()
    emulator.clear_faults()
    emulator.reset(DEFAULT_Q)
    r, c = ur.r, ur.c
    assert c.isConnected()
    target = (np.array(DEFAULT_Q) + 0.05).tolist()
    assert c.moveJ(target, 1.0, 4.0)
    np.testing.assert_allclose(r.getActualQ(), target, atol=1e-9)
