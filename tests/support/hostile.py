"""Hostile primary/secondary clients in a process of their own (``python -m``).

``python -m tests.support.hostile HOST SECONDS SEED PORT [PORT ...]``: one thread per
port connects and closes, closes mid-message, sends truncated programs or garbage, or
stays and never reads (at most six such sockets a thread), 50 connections a second a
thread, for SECONDS; prints ``ready`` on its first connection.  A process apart from
the test's, at the lowest priority: the test's own threads (the emulator under test, its
readers) then share neither their interpreter's lock nor, when the machine is busy, their
CPU with the attackers, as a controller's hostile clients are other machines.
"""

from __future__ import annotations

import os
import socket
import struct
import sys
import threading
import time

import numpy as np

__all__ = ["hostile"]


def hostile(host: str, port: int, until: float, rng: np.random.Generator,
            ready: threading.Event) -> None:  # fmt: skip
    """Attack ``host:port`` until ``time.monotonic()`` passes ``until``."""
    silent: list[socket.socket] = []
    try:
        while time.monotonic() < until:
            kind = int(rng.integers(5))
            try:
                s = socket.create_connection((host, port), timeout=1.0)
            except OSError:
                time.sleep(0.01)
                continue
            ready.set()
            if kind == 0:  # connect, close
                s.close()
            elif kind == 1:  # read a few bytes of the version message, close mid-message
                s.recv(7)
                s.close()
            elif kind == 2:  # a truncated program, then close
                s.sendall(b"def cut():\n  movej([0, -1.57, 1.5")
                s.close()
            elif kind == 3:  # garbage, then an abortive close (RST)
                s.sendall(bytes(rng.integers(0, 256, 300, dtype=np.uint8)))
                s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
                s.close()
            elif len(silent) < 6:  # never reads, stays
                s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
                silent.append(s)
            else:
                s.close()
            time.sleep(0.02)
    finally:
        for s in silent:
            s.close()


def main(argv: list[str]) -> None:
    """Run one attacking thread per port (see the module doc)."""
    host, seconds, seed, ports = argv[0], float(argv[1]), int(argv[2]), argv[3:]
    # the lowest priority: on a 2-core machine this process would otherwise take the CPU
    # from the emulator (in the test's process, not real-time) and its readers; what is
    # tested is how the emulator treats these connections, not a CPU they share (in a
    # fresh-clone run beside the other real-time tests, 41 periods over 10 ms at nice 0)
    os.nice(19)
    until = time.monotonic() + seconds
    ready = threading.Event()
    threads = [threading.Thread(target=hostile, args=(host, int(p), until,
                                                      np.random.default_rng(seed + k), ready))
               for k, p in enumerate(ports)]  # fmt: skip
    for t in threads:
        t.start()
    if ready.wait(5.0):
        print("ready", flush=True)
    for t in threads:
        t.join()


if __name__ == "__main__":
    main(sys.argv[1:])
