"""Benchmark of the RTDE emulator's data stream: rate, missed periods and jitter.

Starts an emulator (child process) and 1 or 2 receive clients, each in its
own process, for ``--duration`` seconds:

* ``raw``: a pure-Python RTDE client (``RawRTDEClient``) with ur_rtde's
  58-variable receive recipe (1180-byte packages); it sees every package, so
  it measures the stream itself: packages per second, controller periods
  missing from the timestamps, and the jitter of the arrival intervals.
* ``ur_rtde``: the real ``RTDEReceiveInterface``; a loop polls
  ``getTimestamp()`` and counts distinct timestamps (ur_rtde keeps only the
  newest package, so this is what a user's loop can see).

Usage::

    .venv/bin/python scripts/bench_rtde.py                 # 1 and 2 clients, both kinds, 10 s
    .venv/bin/python scripts/bench_rtde.py --duration 30 --clients 2 --kind raw
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ruledrobot.ursim import Emulator
from tests.support.rawclient import (
    UR_RTDE_RECEIVE_RECIPE,
    RawRTDEClient,
)


def _raw_client(host: str, duration: float, frequency: float, out: mp.Queue) -> None:
    arrivals: list[float] = []
    stamps: list[float] = []
    with RawRTDEClient(host) as cli:
        cli.negotiate(2)
        cli.controller_version()
        types = cli.setup_outputs(UR_RTDE_RECEIVE_RECIPE, frequency)
        assert "NOT_FOUND" not in types, types
        cli.start()
        t_end = time.perf_counter() + duration
        while time.perf_counter() < t_end:
            d = cli.read_data(timeout=3.0)
            arrivals.append(time.perf_counter())
            stamps.append(d["timestamp"])
    out.put(("raw", np.array(arrivals), np.array(stamps)))


def _ur_rtde_client(host: str, duration: float, frequency: float, out: mp.Queue) -> None:
    import rtde_receive

    r = rtde_receive.RTDEReceiveInterface(host, frequency)
    arrivals: list[float] = []
    stamps: list[float] = []
    last = -1.0
    t_end = time.perf_counter() + duration
    while time.perf_counter() < t_end:
        ts = r.getTimestamp()
        if ts != last:
            last = ts
            arrivals.append(time.perf_counter())
            stamps.append(ts)
        time.sleep(0.0005)
    r.disconnect()
    out.put(("ur_rtde", np.array(arrivals), np.array(stamps)))


def _stats(arrivals: np.ndarray, stamps: np.ndarray, period: float) -> dict[str, float]:
    # drop the first 0.5 s (connection set-up)
    keep = arrivals >= arrivals[0] + 0.5
    a, s = arrivals[keep], stamps[keep]
    expected = round((s[-1] - s[0]) / period) + 1
    dt = np.diff(a)
    dev = np.abs(dt - period)
    return {
        "packages": float(a.size),
        "rate_hz": float((a.size - 1) / (a[-1] - a[0])),
        "missed_periods": float(expected - a.size),
        "missed_fraction": float((expected - a.size) / expected),
        "interval_mean_ms": float(dt.mean() * 1e3),
        "jitter_std_ms": float(dt.std() * 1e3),
        "jitter_p99_ms": float(np.percentile(dev, 99) * 1e3),
        "interval_max_ms": float(dt.max() * 1e3),
    }


def _backend(physics: str):
    from ruledrobot.ursim.arm.physics import MujocoBackend

    return MujocoBackend if physics == "mujoco" else None


def run_case(
    host: str,
    n_clients: int,
    kind: str,
    duration: float,
    model: str,
    realtime: bool,
    physics: str = "kinematic",
) -> dict:
    ctx = mp.get_context("spawn")
    with Emulator(host, model, realtime=realtime, backend=_backend(physics)) as emu:
        period = 0.002 if model.endswith("e") else 0.008
        freq = 1.0 / period
        q: mp.Queue = ctx.Queue()
        target = _raw_client if kind == "raw" else _ur_rtde_client
        procs = [
            ctx.Process(target=target, args=(host, duration, freq, q)) for _ in range(n_clients)
        ]
        for p in procs:
            p.start()
        results = [q.get(timeout=duration + 30) for _ in procs]
        for p in procs:
            p.join(10)
        clock = emu.stats()
    per_client = [_stats(a, s, period) for _, a, s in results]
    return {
        "kind": kind,
        "clients": n_clients,
        "duration_s": duration,
        "model": model,
        "realtime_clock": bool(clock["realtime_clock"]),
        "per_client": per_client,
        "emulator_clock": {
            k: clock[k]
            for k in (
                "ticks",
                "missed_fraction",
                "lateness_mean_ms",
                "lateness_p99_ms",
                "lateness_max_ms",
            )
        },
    }


def runner_latency(host: str, model_name: str, physics: str) -> dict:
    """End-to-end latency of the runner: the lag of the recorded actual joints behind the
    planned ones (best-fitting time shift) on a 3 s servoJ stream, and the error left."""
    import tempfile

    from ruledrobot.export import run_trajectory
    from ruledrobot.io.trajectory import read_trajectory, write_trajectory
    from ruledrobot.robot import load
    from ruledrobot.robot.motion.trajectory import Trajectory

    model = load(model_name)
    t = np.arange(0.0, 3.0, model.control_period)
    q0 = np.array([3.0, -1.2, 1.4, -1.8, -1.57, 0.0])
    q = q0 + 0.15 * np.sin(2 * np.pi * t / 3.0)[:, None] * np.array([1, -0.5, 0.5, 1, 0.5, 1])
    with (
        tempfile.TemporaryDirectory() as tmp,
        Emulator(host, model_name, q0=q[0], backend=_backend(physics), unlock_delay=0.0) as emu,
    ):
        src = write_trajectory(Path(tmp) / "cut.csv", Trajectory.from_joints(t, q, model))
        t0 = time.perf_counter()
        res = run_trajectory(src, emu.host, model_name)
        wall = time.perf_counter() - t0
        rec = read_trajectory(res.actual_path)
    best = (np.inf, 0.0)
    for lag in np.arange(0.0, 0.25, model.control_period):
        ref = np.stack([np.interp(rec.t - lag, t, q[:, j]) for j in range(6)], axis=1)
        inside = (rec.t - lag >= 0) & (rec.t - lag <= t[-1])
        err = float(np.abs(rec.q[inside] - ref[inside]).max())
        best = min(best, (err, float(lag)))
    return {
        "physics": physics,
        "status": res.status,
        "lag_s": best[1],
        "error_after_lag_rad": best[0],
        "wall_s": wall,
        "planned_s": float(t[-1]),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--host", default="127.0.0.40")
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--clients", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--kind", choices=["raw", "ur_rtde", "both"], default="both")
    ap.add_argument("--model", default="ur5e")
    ap.add_argument(
        "--no-realtime", action="store_true", help="do not try SCHED_FIFO for the emulator clock"
    )
    ap.add_argument("--json", type=Path, help="also write the results here")
    ap.add_argument(
        "--physics",
        choices=["kinematic", "mujoco"],
        default="kinematic",
        help="the emulator's arm for the stream cases",
    )
    args = ap.parse_args()
    kinds = ["raw", "ur_rtde"] if args.kind == "both" else [args.kind]
    out = []
    for kind in kinds:
        for n in args.clients:
            res = run_case(
                args.host, n, kind, args.duration, args.model, not args.no_realtime, args.physics
            )
            out.append(res)
            for i, c in enumerate(res["per_client"]):
                print(
                    f"{kind:8s} clients={n} #{i}: {c['rate_hz']:7.2f} Hz, missed "
                    f"{100 * c['missed_fraction']:.3f}% ({c['missed_periods']:.0f}), interval "
                    f"{c['interval_mean_ms']:.3f} ms, jitter std {c['jitter_std_ms']:.3f} ms, "
                    f"p99 {c['jitter_p99_ms']:.3f} ms, max {c['interval_max_ms']:.2f} ms"
                )
            e = res["emulator_clock"]
            rt = "SCHED_FIFO" if res["realtime_clock"] else "normal priority"
            print(
                f"{'':8s} emulator clock ({rt}): "
                f"missed {100 * e['missed_fraction']:.3f}%, lateness "
                f"mean {e['lateness_mean_ms']:.3f} ms, p99 {e['lateness_p99_ms']:.3f} ms, "
                f"max {e['lateness_max_ms']:.3f} ms"
            )
    for physics in ("kinematic", "mujoco"):
        lat = runner_latency(args.host, args.model, physics)
        out.append({"runner_latency": lat})
        print(
            f"runner ({physics} arm): {lat['status']}, actual lags the plan by "
            f"{lat['lag_s'] * 1e3:.0f} ms (servoJ lookahead 0.1 s, gain 300), error after the lag "
            f"{lat['error_after_lag_rad']:.2e} rad; {lat['wall_s']:.2f} s wall for "
            f"{lat['planned_s']:.2f} s planned (incl. connect, approach, stop)"
        )
    if args.json:
        args.json.write_text(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
