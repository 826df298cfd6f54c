"""Soak the runner under faults: many runs through a loopback fault proxy, each faulted.

Each trial streams a 2 s trajectory with ``run_trajectory`` to an emulator behind a
:class:`~tests.support.faultproxy.FaultProxy` and injects one fault a third of the
way in; it measures the time from the fault to the runner's return and counts how the
ur_rtde client ended (crashed: ``client_died``, killed after a hang: ``client_hung`` or
a reported stop after which the client was killed) and whether the runner itself hung
(no return within ``--bound``) or raised.

Fault kinds: ``frozen`` (the proxy stops forwarding, sockets open), ``dropped`` (the
proxy closes both sides), ``pstop`` / ``estop`` (the emulator's protective / emergency
stop), ``ctrlc`` (KeyboardInterrupt in the runner, as a terminal's Ctrl-C).

Everything runs on loopback (127.0.0.0/8) and is bounded in time: a trial that does
not return within ``--hard-limit`` seconds ends the script with a stack dump
(faulthandler).  ``--load N`` adds N busy-looping processes (a loaded machine).

    python scripts/soak_runner.py                       # 20 frozen + 20 dropped
    python scripts/soak_runner.py --kinds pstop,estop,ctrlc --trials 10 --load 2
"""

from __future__ import annotations

import argparse
import faulthandler
import multiprocessing as mp
import re
import statistics
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

KINDS = ("frozen", "dropped", "pstop", "estop", "ctrlc")


def _busy(stop_at: float) -> None:  # pragma: no cover - load process
    x = 0
    while time.time() < stop_at:
        x = (x * 31 + 7) % 1000003


def _watchdog_silence(emu, seen: int) -> float | None:
    """The silence the emulator's RTDE watchdog reported in events after index ``seen``."""
    found = None
    for e in emu.events[seen:]:
        m = re.search(r"RTDE watchdog: .* not updated for ([\d.]+) s", e[2])
        if m:
            found = float(m.group(1))
    return found


def trial(kind: str, emu, proxy, src: Path, traj, bound: float) -> dict:
    from ruledrobot.export import run_trajectory

    fired: list[float] = []
    seen = len(emu.events)

    def progress(done: int, total: int) -> None:
        if not fired and done >= total // 3:
            fired.append(time.monotonic())
            if kind == "frozen":
                proxy.freeze()
            elif kind == "dropped":
                proxy.drop(refuse_for=1.0)
            elif kind == "pstop":
                emu.protective_stop("soak")
            elif kind == "estop":
                emu.emergency_stop("soak")
            elif kind == "ctrlc":
                raise KeyboardInterrupt

    t0 = time.monotonic()
    try:
        res = run_trajectory(src, proxy.listen, progress=progress, lookahead=0.05)
    except Exception as exc:  # the runner itself failed: counted
        return {"kind": kind, "outcome": f"runner raised {type(exc).__name__}: {exc}"}
    end = time.monotonic()
    out = {"kind": kind, "status": res.status, "total": end - t0, "client": res.client,
           "recorded": 0 if res.actual is None else res.actual.n,
           "file": res.actual_path is not None}  # fmt: skip
    if not fired:
        out["outcome"] = f"stopped before the fault: {res.message}"
        return out
    out["fault_to_exit"] = end - fired[0]
    if res.status == "client_died" or "process died" in res.message:
        how = (res.client.splitlines() or ["?"])[0]
        out["outcome"] = f"client crashed ({how}), survived"
    elif res.status == "client_hung" or "killed" in res.message:
        out["outcome"] = "client hung (killed)"
    else:
        out["outcome"] = "clean stop"
    if out["fault_to_exit"] > bound:
        out["outcome"] += f", runner beyond {bound:g} s"
    emu.wait_for(lambda: emu.runtime_state != 2, timeout=3.0)
    out["watchdog"] = _watchdog_silence(emu, seen)
    return out


def reset(kind: str, emu, proxy, traj) -> None:
    if kind == "frozen":
        proxy.drop(refuse_for=0.0)
        proxy.resume()
    if kind == "dropped":
        time.sleep(1.1)  # the proxy refused new connections for 1 s
    emu.wait_for(lambda: emu.runtime_state != 2, timeout=3.0)
    emu.clear_faults()
    emu.reset(traj.q[0])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kinds", default="frozen,dropped", help=f"comma list of {', '.join(KINDS)}")
    ap.add_argument("--trials", type=int, default=20, help="trials per fault kind")
    ap.add_argument("--load", type=int, default=0, help="busy processes beside the soak")
    ap.add_argument("--bound", type=float, default=4.0, help="fault-to-exit bound [s]")
    ap.add_argument("--hard-limit", type=float, default=60.0, help="per trial [s]")
    ap.add_argument("--emulator", default="127.0.91.2")
    ap.add_argument("--proxy", default="127.0.91.77")
    args = ap.parse_args()
    kinds = [k.strip() for k in args.kinds.split(",") if k.strip()]
    for k in kinds:
        if k not in KINDS:
            ap.error(f"unknown fault kind {k!r}")

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    import numpy as np

    from ruledrobot.io.trajectory import write_trajectory
    from ruledrobot.robot import load
    from ruledrobot.robot.motion.trajectory import Trajectory
    from ruledrobot.ursim import DEFAULT_Q, Emulator
    from tests.support.faultproxy import FaultProxy

    t = np.arange(0.0, 2.0 + 1e-9, 0.002)
    s = np.sin(np.pi * t / 2.0) ** 2
    q = np.asarray(DEFAULT_Q) + np.array([0.09, -0.07, 0.09, 0.07, 0.09, -0.09]) * s[:, None]
    traj = Trajectory.from_joints(t, q, load("ur5e"), source="soak trajectory")
    loaders = [mp.get_context("spawn").Process(target=_busy, args=(time.time() + 3600,),
                                               daemon=True) for _ in range(args.load)]  # fmt: skip
    for p in loaders:
        p.start()
    results: list[dict] = []
    try:
        with (
            tempfile.TemporaryDirectory() as tmp,
            Emulator(args.emulator, "ur5e", unlock_delay=0.0, q0=traj.q[0]) as emu,
            FaultProxy(args.proxy, args.emulator) as proxy,
        ):
            src = write_trajectory(Path(tmp) / "cut.csv", traj)
            for kind in kinds:
                for i in range(args.trials):
                    faulthandler.dump_traceback_later(args.hard_limit, exit=True)
                    r = trial(kind, emu, proxy, src, traj, args.bound)
                    faulthandler.cancel_dump_traceback_later()
                    results.append(r)
                    fte = r.get("fault_to_exit")
                    print(f"{kind:8s} {i + 1:3d}: {r.get('status', '-'):16s} "
                          f"{'-' if fte is None else f'{fte:6.3f} s'}  {r['outcome']}",
                          flush=True)  # fmt: skip
                    reset(kind, emu, proxy, traj)
    finally:
        for p in loaders:
            p.kill()
    print(f"\nsummary ({args.trials} trials per kind, load {args.load}, bound {args.bound:g} s)")
    print(f"{'fault':8s} {'trials':>6s} {'clean':>6s} {'crashed':>8s} {'hung':>5s} "
          f"{'runner>bound':>12s} {'median [s]':>10s} {'max [s]':>8s} {'watchdog [s]':>13s}"
          "  statuses")  # fmt: skip
    for kind in kinds:
        rs = [r for r in results if r["kind"] == kind]
        times = [r["fault_to_exit"] for r in rs if "fault_to_exit" in r]
        oc = Counter(r["outcome"] for r in rs)
        st = Counter(r.get("status", "raised") for r in rs)
        w = [r["watchdog"] for r in rs if r.get("watchdog") is not None]
        wd = f"{len(w)}x {min(w):.3f}-{max(w):.3f}" if w else "-"
        print(f"{kind:8s} {len(rs):6d} {sum('clean' in o for o in oc.elements()):6d} "
              f"{sum('crashed' in o for o in oc.elements()):8d} "
              f"{sum('hung' in o for o in oc.elements()):5d} "
              f"{sum('beyond' in o or 'raised' in o for o in oc.elements()):12d} "
              f"{statistics.median(times) if times else float('nan'):10.3f} "
              f"{max(times) if times else float('nan'):8.3f} {wd:>13s}  {dict(st)}")  # fmt: skip
    bad = [r for r in results if "beyond" in r["outcome"] or "raised" in r["outcome"]
           or "before the fault" in r["outcome"] or not r.get("file")]  # fmt: skip
    if bad:
        print(f"{len(bad)} trials beyond the bound, raising, or without a recording")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
