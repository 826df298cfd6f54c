"""The runner's side of a forwarded run (:mod:`.program`), in the child process.

:func:`forward` listens on the address the controller reaches this computer at, sends
the forwarding program to the controller's script port, accepts the program's connection
and keeps it :attr:`~.program.ForwardSettings.ahead` samples ahead of the sample the
controller reports playing (output int register ``REG_SAMPLE``).  Meanwhile it records
and watches as a stream does (deviation, faults); a stop request (Ctrl-C) or a fault is
sent as a ``STOP`` message, and the program stops along the path.  When the program
reports ``DRY`` (this computer stalled longer than the buffer) the run ends with status
``buffer_dry`` and the resume point; ``DONE`` ends it completed.
"""

from __future__ import annotations

import contextlib
import socket
import time

import numpy as np

from ...protocol.primary import SCRIPT_PORT
from ..run_session import Session, Stop
from .program import (
    REG_SAMPLE,
    REG_STATE,
    ForwardSettings,
    State,
    end_message,
    forward_program,
    sample_messages,
    stop_message,
)

__all__ = ["forward", "local_address"]


def local_address(host: str) -> str:
    """The address of this computer as the controller at ``host`` reaches it."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.connect((host, SCRIPT_PORT))  # no packet is sent: the route is looked up
        return str(probe.getsockname()[0])


def _send_program(host: str, text: str, timeout: float) -> None:
    with socket.create_connection((host, SCRIPT_PORT), timeout=timeout) as sock:
        sock.sendall(text.encode())


def forward(s: Session, q_grid: np.ndarray, hot: np.ndarray | None, settings: ForwardSettings,
            heat: object, heartbeat: float, connect_timeout: float,
            levels: np.ndarray | None = None) -> None:  # fmt: skip
    """Play ``q_grid`` (K, 6) on the controller's clock (module doc).

    ``hot`` (K,) the heat per sample or None; ``levels`` (K,) the analog set-points as
    written (a scheduled power, :func:`~..heat.written_levels`) or None.  Returns when the
    program reports ``DONE``; raises :class:`Stop` otherwise (after the program's controlled
    stop when it still runs)."""
    K = q_grid.shape[0]
    me = local_address(s.host)
    server = socket.create_server((me, 0))
    server.settimeout(connect_timeout)
    port = server.getsockname()[1]
    program = forward_program(me, port, settings, heat, connect_timeout,  # type: ignore[arg-type]
                              levels is not None)
    s.link.stage("forwarding: program", connect_timeout + 1.0)
    if s.c is not None:
        with contextlib.suppress(Exception):
            s.c.stopScript()  # ur_rtde's control script ends; ours takes the controller
    try:
        _send_program(s.host, program, connect_timeout)
        s.link.stage("forwarding: connect", connect_timeout + 1.0)
        try:
            conn, _ = server.accept()
        except TimeoutError:
            raise Stop("command_failed", f"the forwarding program did not connect back to "
                       f"{me}:{port} within {connect_timeout:g} s") from None  # fmt: skip
    finally:
        server.close()
    with conn:
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        conn.settimeout(2.0)
        _play(s, conn, q_grid, hot, levels, settings, heartbeat, K)


def _play(s: Session, conn: socket.socket, q_grid: np.ndarray, hot: np.ndarray | None,
          levels: np.ndarray | None, settings: ForwardSettings, heartbeat: float,
          K: int) -> None:  # fmt: skip

    def part(a: int, b: int) -> bytes:
        return sample_messages(q_grid[a:b], None if hot is None else hot[a:b], a,
                               None if levels is None else levels[a:b])  # fmt: skip

    r = s.r
    ahead = settings.ahead
    sent = min(K, ahead)
    conn.sendall(part(0, sent))
    if sent == K:
        conn.sendall(end_message(K))
    # the program connected: wait for the controller's data to say it runs (the newest
    # package may predate its start by a period or two)
    deadline = time.monotonic() + 2.0
    while int(r.getRuntimeState()) != 2 and time.monotonic() < deadline:
        time.sleep(0.002)
    s.link.stage("forwarding", heartbeat)
    # the controller plays from its buffer: its data late by less than the buffer endangers
    # nothing (an emulator whose host stalls catches up); a controller silent longer stops
    s.max_latency = max(s.max_latency, settings.buffer)
    s.start_recording()
    s.start_clock()
    s.watch_registers = (REG_SAMPLE,)  # the sample playing, from the joints' own package
    stop: Stop | None = None
    dt = 1.0 / s.frequency
    while True:
        state = int(r.getOutputIntRegister(REG_STATE))
        playing = int(r.getOutputIntRegister(REG_SAMPLE))
        if state in (State.DONE, State.DRY, State.STOPPED, State.FAILED):
            break
        try:
            qa = s.poll()
            # the deviation match anchored at the sample the controller played when it
            # measured qa (read apart, the two came from packages up to 0.1 s apart after
            # a stall of this process, and the match was put that far ahead of the arm)
            at = s.registers[REG_SAMPLE]
            s.check_deviation(q_grid, qa, max(at, 0), timed=at >= 0, anchored=at >= 0)
            s.service()
        except Stop as st:
            if st.status == "program_stopped" and int(r.getOutputIntRegister(REG_STATE)) in (
                    State.DONE, State.DRY, State.STOPPED, State.FAILED):
                break  # it ended between the two reads (found: a completed run said stopped)
            stop = st
            with contextlib.suppress(OSError):
                conn.sendall(stop_message())
            s.link.stage("forwarding: stopping", settings.stop_time + 12.0 * settings.lookahead
                         + 2.0)  # fmt: skip
            _wait_stopped(s, settings)
            break
        if playing >= 0 and sent < K:
            upto = min(K, playing + 1 + ahead)
            if upto > sent:
                try:
                    conn.sendall(part(sent, upto))
                    if upto == K:
                        conn.sendall(end_message(K))
                except OSError:
                    # the program closed its end: it ended (ran dry and stopped, or was
                    # stopped) while this process was held past its buffer; the state it
                    # reports says which (found: a 1 s stall of this process, the dry
                    # stop and its settle over in 0.8 s, reported as a dead client)
                    _wait_stopped(s, settings)
                    break
                s.sent = upto - 1
                sent = upto
        time.sleep(dt)
    s.sent = max(s.sent, int(r.getOutputIntRegister(REG_SAMPLE)))
    s.flush(force=True)
    if stop is not None:
        raise stop
    state = int(r.getOutputIntRegister(REG_STATE))
    if state == State.DONE:
        return
    k = int(r.getOutputIntRegister(REG_SAMPLE))
    if state == State.DRY:
        raise Stop("buffer_dry", f"this computer did not send samples for longer than the "
                   f"{settings.buffer:g} s buffer: the controller stopped along the path near "
                   f"grid sample {k}, heat off (resume from there)")  # fmt: skip
    if state == State.STOPPED:
        raise Stop("command_failed", f"the forwarding program stopped near grid sample {k}")
    raise Stop("command_failed", "the forwarding program could not reach this computer or got "
               "no samples in time")  # fmt: skip


def _wait_stopped(s: Session, settings: ForwardSettings) -> None:
    """Record until the program reports its controlled stop done (or a bound passes)."""
    r = s.r
    deadline = time.monotonic() + settings.stop_time + 12.0 * settings.lookahead + 1.5
    while time.monotonic() < deadline:
        with contextlib.suppress(Exception):
            s.record(*s.snapshot())
            if int(r.getOutputIntRegister(REG_STATE)) in (State.DRY, State.STOPPED,
                                                          State.DONE, State.FAILED):  # fmt: skip
                return
            if int(r.getRuntimeState()) != 2:
                return
        s.flush()
        time.sleep(0.002)
