"""Hostile input for the emulator's three ports: for ``tests/ursim/test_fuzz.py`` and
``scripts/fuzz_emulator.py``.

:func:`fuzz` sends, for a bounded time, round-robin cases on short-lived
connections: URScript programs with bad arguments, control flow, huge and
non-finite numbers, over-long lines, secondary programs that move; dashboard
commands with random arguments (paths outside the programs folder included);
RTDE sessions with random recipes, frequencies and input packages.  It only
ever connects to loopback addresses (127.0.0.0/8): :func:`check_loopback`.
"""

from __future__ import annotations

import contextlib
import ipaddress
import socket
import struct
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ruledrobot.protocol.rtde import pack_packet
from ruledrobot.protocol.rtde_types import INPUT_TYPES, OUTPUT_TYPES

__all__ = ["FuzzReport", "check_loopback", "dashboard_case", "fuzz", "rtde_case", "script_case"]

_OUTPUTS = sorted(OUTPUT_TYPES)
_INPUTS = sorted(INPUT_TYPES)
_IO = ("set_standard_digital_out", "set_configurable_digital_out", "set_tool_digital_out",
       "set_digital_out", "set_standard_analog_out", "write_output_integer_register",
       "write_output_float_register", "write_output_boolean_register")  # fmt: skip
_NUMBERS = ("0", "1", "7", "8", "64", "100", "-1", "1e7", "1.5", "1e999", "-1e308", "0.5",
            "2147483648", "3000000000", "nan", "inf", "True", "False", '"x"',
            "[1, 2]")  # fmt: skip
_LINES = ("while True:", "if 1:", "end", "x = 1", "thread t():", "movej(q)", "sync(",
          "movej([0,0,0,0,0,0]", "p[0,0,0,0,0,0]", "set_tcp(p[0, 0])",
          'popup("x", blocking=True)',
          "force_mode(p[0,0,0,0,0,0], [0,0,1,0,0,0], [0,0,5,0,0,0], 2, [1,1,1,1,1,1])",
          "servoj([0, 0, 0, 0, 0, 0], t=0.002, lookahead_time=1, gain=1)",
          "movej([0, -1.57, 1.57, -1.57, -1.57, 0], a=1.4, v=1.05, t=3)",
          "set_payload(1e9, [0, 0, 0])", "textmsg(\"" + "z" * 300 + "\")",
          "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]")  # fmt: skip
_DASHBOARD = ("PolyscopeVersion", "robotmode", "safetymode", "safetystatus", "programState",
              "running", "get loaded program", "power on", "power off", "brake release",
              "unlock protective stop", "close popup", "close safety popup", "popup {}",
              "addToLog {}", "load {}", "play", "pause", "stop", "restart safety",
              "isProgramSaved", "get serial number", "is in remote control", "quit")  # fmt: skip
_PATHS = ("/etc/shadow", "/etc/passwd", "../../etc/hostname", "cut.urp", "x.script",
          "/programs/../etc", "\x00", "a" * 3000, "sub/../../x.urp", "")  # fmt: skip


def check_loopback(host: str) -> None:
    """ValueError unless ``host`` is an IPv4 loopback address (127.0.0.0/8)."""
    try:
        ok = ipaddress.ip_address(host) in ipaddress.ip_network("127.0.0.0/8")
    except ValueError:
        ok = False
    if not ok:
        raise ValueError(f"fuzz: {host!r} is not a loopback address (127.0.0.0/8)")


def script_case(rng: np.random.Generator) -> bytes:
    """One hostile program (or line) for the script port."""
    kind = int(rng.integers(0, 6))
    if kind == 0:  # an I/O setter with arguments from the edge of the ranges
        fn = _IO[int(rng.integers(len(_IO)))]
        a, b = (_NUMBERS[int(rng.integers(len(_NUMBERS)))] for _ in range(2))
        body = [f"{fn}({a}, {b})"]
    elif kind == 1:  # lines the emulator cannot run, among good ones
        body = ["set_standard_digital_out(1, True)", _LINES[int(rng.integers(len(_LINES)))],
                "set_standard_digital_out(2, True)"]  # fmt: skip
    elif kind == 2:  # random bytes
        return b"def f():\n" + rng.bytes(int(rng.integers(1, 400))) + b"\nend\n"
    elif kind == 3:  # an over-long line (the connection is closed)
        return b'textmsg("' + b"w" * 70_000 + b'")\n'
    elif kind == 4:  # a secondary program that tries to move
        return b"sec s():\n  set_standard_digital_out(3, True)\n  movej([0,0,0,0,0,0])\nend\n"
    else:  # a valid program: small moves and I/O
        q = np.round(np.array([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0])
                     + rng.uniform(-0.05, 0.05, 6), 5).tolist()  # fmt: skip
        body = [f"movej({q}, a=3, v=2)", f"set_standard_digital_out({int(rng.integers(8))}, True)",
                f"set_standard_analog_out(0, {float(rng.uniform()):.3f})"]  # fmt: skip
    if rng.uniform() < 0.3:
        return (body[0] + "\n").encode("utf-8", "replace")  # a bare line
    return ("def fz():\n" + "".join(f"  {ln}\n" for ln in body) + "end\n").encode()


def dashboard_case(rng: np.random.Generator) -> bytes:
    """A few dashboard lines with random arguments."""
    out = []
    for _ in range(int(rng.integers(1, 6))):
        cmd = _DASHBOARD[int(rng.integers(len(_DASHBOARD)))]
        if "{}" in cmd:
            arg = _PATHS[int(rng.integers(len(_PATHS)))] if cmd.startswith("load") else (
                rng.bytes(int(rng.integers(0, 60))).decode("latin-1"))  # fmt: skip
            cmd = cmd.format(arg)
        out.append(cmd.encode("utf-8", "replace").replace(b"\n", b" ") + b"\n")
    return b"".join(out)


def rtde_case(rng: np.random.Generator) -> bytes:
    """An RTDE session: random recipes, frequency, start, input packages (sent blind)."""
    n = int(rng.integers(1, 400))
    names = ",".join(_OUTPUTS[int(i)] for i in rng.integers(0, len(_OUTPUTS), n)).encode()
    freq = float(rng.choice([0.5, 1.0, 100.0, 125.0, 333.3, 500.0, 1000.0, 1e-9, 5000.0]))
    inputs = [_INPUTS[int(i)] for i in rng.integers(0, len(_INPUTS), int(rng.integers(1, 8)))]
    pkt = pack_packet(ord("V"), struct.pack(">H", 2))
    pkt += pack_packet(ord("O"), struct.pack(">d", freq) + names[:60_000])
    pkt += pack_packet(ord("I"), ",".join(inputs).encode())
    pkt += pack_packet(ord("S"))
    # a data package of random bytes of the right size may or may not decode
    pkt += pack_packet(ord("U"), b"\x01" + rng.bytes(int(rng.integers(0, 64))))
    return pkt


@dataclass
class FuzzReport:
    """Cases sent per port, and connections the emulator refused or closed early."""

    cases: dict[str, int] = field(default_factory=lambda: {"script": 0, "dashboard": 0,
                                                            "rtde": 0})  # fmt: skip
    refused: int = 0


def _send(host: str, port: int, payload: bytes, read_for: float) -> bool:
    try:
        with socket.create_connection((host, port), timeout=1.0) as s:
            s.sendall(payload)
            if read_for > 0:
                s.settimeout(read_for)
                with contextlib.suppress(OSError):
                    s.recv(65536)
        return True
    except OSError:
        return False


def fuzz(
    host: str,
    ports: dict[str, int],
    duration: float,
    seed: int = 0,
    *,
    stop: Callable[[], bool] | None = None,
) -> FuzzReport:
    """Send hostile cases to the three ports for ``duration`` s (loopback only)."""
    check_loopback(host)
    rng = np.random.default_rng(seed)
    report = FuzzReport()
    makers = (("script", script_case, 0.0), ("dashboard", dashboard_case, 0.02),
              ("rtde", rtde_case, 0.02))  # fmt: skip
    t_end = time.monotonic() + float(duration)
    k = 0
    while time.monotonic() < t_end and not (stop is not None and stop()):
        name, make, read_for = makers[k % 3]
        k += 1
        if not _send(host, ports[name], make(rng), read_for):
            report.refused += 1
        report.cases[name] += 1
    return report
