"""Fuzz the controller emulator for longer than the test does (loopback only).

    python scripts/fuzz_emulator.py --duration 60 --seed 3 --host 127.0.0.50

Starts an emulator (child process) on a loopback address, streams a 500 Hz
client beside the fuzzer (``tests.support.fuzz``), and prints the
cases sent, the stream's worst gap, the clock's statistics and the controller
log's errors.  Exit status 1 when a controller period or a publish failed or
the stream stalled for more than 100 ms.  The emulator is always stopped.
"""

from __future__ import annotations

import argparse
import threading
import time

from ruledrobot.ursim import Emulator
from tests.support.fuzz import check_loopback, fuzz
from tests.support.rawclient import RawRTDEClient


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--host", default="127.0.0.50", help="loopback address (127.0.0.0/8)")
    ap.add_argument("--duration", type=float, default=30.0, help="seconds of fuzzing")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    check_loopback(args.host)
    gaps: list[float] = []
    stop = threading.Event()
    with Emulator(args.host, "ur5e") as emu:

        def watch() -> None:
            with RawRTDEClient(args.host) as cli:
                cli.negotiate()
                cli.setup_outputs(["timestamp"], 500.0)
                cli.start()
                last = time.monotonic()
                while not stop.is_set():
                    cli.read_data(timeout=3.0)
                    now = time.monotonic()
                    gaps.append(now - last)
                    last = now

        t = threading.Thread(target=watch, daemon=True)
        t.start()
        time.sleep(0.2)
        report = fuzz(args.host, emu.ports, args.duration, args.seed)
        stop.set()
        t.join(5.0)
        stats = emu.stats()
        errors = [m for _, lv, m in emu.events if lv <= 1]
    worst = max(gaps[10:], default=float("nan"))
    print(f"cases {report.cases}, refused or closed early {report.refused}")
    print(f"stream: {len(gaps)} packages, worst gap {worst * 1e3:.1f} ms")
    print({k: round(v, 3) for k, v in stats.items()})
    print(f"controller log: {len(errors)} errors (last kept), e.g. {errors[-3:]}")
    bad = stats["tick_errors"] or stats["publish_errors"] or not worst < 0.1
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
