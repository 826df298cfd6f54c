"""Benchmark of the time law (ruledrobot.wirecut.motion.timing) against plain toppra.

Run:  .venv/bin/python scripts/bench_timing.py [--n 2000] [--repeat 7] [--dt 0.002]

The path is the one of docs/anchors (§6): 6 joints,
q_k(s) = 0.8 sin(2π(k+1)·0.7 s + k) + 0.3 sin(10π s + k), s ∈ [0, 1], limits
|q̇| ≤ π rad/s, |q̈| ≤ 2π rad/s². Prints plain numbers (best and median wall time
of ``--repeat`` runs after one warm-up call, so toppra's ~1 s import is not
counted); asserts nothing.
"""

from __future__ import annotations

import argparse
import logging
import time
from collections.abc import Callable

import numpy as np

from ruledrobot.wirecut.motion.timing import (
    concatenate,
    joint_move,
    time_path,
    trajectory_limits_report,
)


def timed(fn: Callable[[], object], repeat: int) -> tuple[float, float, object]:
    """(best, median) wall time [s] of ``repeat`` calls after a warm-up, and a result."""
    out = fn()
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return min(ts), float(np.median(ts)), out


def anchor_path(n: int) -> tuple[np.ndarray, np.ndarray]:
    s = np.linspace(0.0, 1.0, n)
    q = np.stack(
        [0.8 * np.sin(2 * np.pi * (k + 1) * 0.7 * s + k) + 0.3 * np.sin(10 * np.pi * s + k)
         for k in range(6)],
        axis=1,
    )  # fmt: skip
    return s, q


def toppra_alone(s: np.ndarray, q: np.ndarray, vl: np.ndarray, al: np.ndarray, dt: float):
    """The anchor measurement: spline + TOPP-RA (seidel) + const-accel output at 1/dt."""
    import toppra
    from toppra.algorithm import TOPPRA
    from toppra.constraint import JointAccelerationConstraint, JointVelocityConstraint

    path = toppra.SplineInterpolator(s, q)
    inst = TOPPRA(
        [JointVelocityConstraint(vl), JointAccelerationConstraint(al)], path,
        gridpoints=s, solver_wrapper="seidel", parametrizer="ParametrizeConstAccel",
    )  # fmt: skip
    traj = inst.compute_trajectory()
    ts = np.arange(0.0, traj.duration, dt)
    return ts, traj(ts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=2000, help="path samples")
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--dt", type=float, default=0.002, help="controller period [s]")
    args = parser.parse_args()
    logging.getLogger("toppra").setLevel(logging.ERROR)
    n, dt, rep = args.n, args.dt, args.repeat
    vl = np.full(6, np.pi)
    al = np.full(6, 2 * np.pi)
    s, q = anchor_path(n)

    t0 = time.perf_counter()
    import toppra  # noqa: F401

    print(f"import toppra: {time.perf_counter() - t0:.2f} s (paid once, on the first call)")
    print(f"path: 6 joints, {n} samples, |qd| <= pi, |qdd| <= 2 pi, dt = {dt} s; "
          f"best / median of {rep}")  # fmt: skip

    b, m, (ts, Q) = timed(lambda: toppra_alone(s, q, vl, al, dt), rep)
    r = trajectory_limits_report(ts, Q, vl, al)
    print(f"  toppra alone (vel+acc, no feed) : {b:.3f} / {m:.3f} s   T = {ts[-1]:.3f} s, "
          f"{len(ts)} samples, speed ratio {r['max_speed_ratio']:.4f}, "
          f"acc ratio {r['max_acc_ratio']:.4f}")  # fmt: skip

    cases = [
        ("time_path, no feed bound", np.zeros(n), 0.1, "toppra"),
        ("time_path, feed binding", np.full(n, 0.4), 0.03, "toppra"),
        ("time_path, feed, reachability", np.full(n, 0.4), 0.03, "reachability"),
    ]
    for name, sf, feed, solver in cases:
        b, m, tp = timed(lambda sf=sf, feed=feed, solver=solver: time_path(
            s, q, sf, feed, vl, al, dt, solver=solver), rep)  # fmt: skip
        print(f"  {name:32s}: {b:.3f} / {m:.3f} s   T = {tp.duration:.3f} s, "
              f"{tp.n_samples} samples, speed {tp.max_speed_ratio:.4f}, "
              f"acc {tp.max_acc_ratio:.4f}, feed {tp.max_feed_ratio:.4f}, "
              f"feed-limited {tp.feed_limited.mean():.1%}, {tp.method}")  # fmt: skip

    print("grid size sweep (time_path, feed binding):")
    for k in (500, 1000, 2000, 5000, 20000):
        sk, qk = anchor_path(k)
        b, m, tp = timed(lambda sk=sk, qk=qk, k=k: time_path(
            sk, qk, np.full(k, 0.4), 0.03, vl, al, dt), max(3, rep // 2))  # fmt: skip
        print(f"  N = {k:5d}: {b:.3f} / {m:.3f} s   T = {tp.duration:.3f} s, "
              f"acc ratio {tp.max_acc_ratio:.4f}, {tp.method}")  # fmt: skip

    q0 = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
    b, m, mv = timed(lambda: joint_move(q0, q[0], vl, al, dt), rep)
    print(f"  joint_move                      : {b * 1e3:.2f} / {m * 1e3:.2f} ms  "
          f"T = {mv.duration:.3f} s, speed {mv.max_speed_ratio:.4f}, "
          f"acc {mv.max_acc_ratio:.4f}")  # fmt: skip
    cut = time_path(s, q, np.full(n, 0.4), 0.03, vl, al, dt)
    back = joint_move(q[-1], q0, vl, al, dt)
    b, m, whole = timed(lambda: concatenate([mv, cut, back], dt), rep)
    print(f"  concatenate (move, cut, move)   : {b * 1e3:.2f} / {m * 1e3:.2f} ms  "
          f"{whole.n_samples} samples, T = {whole.duration:.3f} s")  # fmt: skip
    b, m, _ = timed(lambda: trajectory_limits_report(whole.t, whole.q, vl, al), rep)
    print(f"  trajectory_limits_report        : {b * 1e3:.2f} / {m * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
