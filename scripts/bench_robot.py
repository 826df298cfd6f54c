"""Benchmark of the robot layer: analytic IK, FK, Jacobian, path IK.

Run:  .venv/bin/python scripts/bench_robot.py [--model ur5e] [--n 100000] [--repeat 5]

Prints plain numbers (best of ``--repeat`` runs); no assertions on time.
The comparison uses ``ur_analytic_ik`` (C++/Eigen, one pose per call) when
it is installed (``pip install ur-analytic-ik``, the ``bench`` extra).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from ruledrobot.robot import load


def best_time(fn: Callable[[], object], repeat: int) -> float:
    """Best wall time [s] of ``repeat`` calls (after one warm-up call)."""
    fn()
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def smooth_path(n: int) -> np.ndarray:
    """A smooth 6-joint path that passes 1e-3 rad from the wrist singularity."""
    t = np.linspace(0.0, 1.0, n)
    return np.stack(
        [0.3 + 0.5 * t, -1.2 + 0.3 * t, 1.4 - 0.2 * t, -1.0 + 0.5 * t, 0.3 - 0.6 * t + 1e-3,
         0.5 + 4.0 * t],
        axis=-1,
    )  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="ur5e")
    parser.add_argument("--n", type=int, default=100_000, help="poses for IK/FK")
    parser.add_argument("--oracle-n", type=int, default=5_000, help="poses for ur_analytic_ik")
    parser.add_argument("--path-n", type=int, default=2_000, help="poses for path IK")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()

    robot = load(args.model)
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, size=(args.n, 6))
    T = robot.fk(q)
    n = args.n
    print(f"robot layer benchmark: {robot.name}, {n} random configurations, best of {args.repeat}")

    # --- forward kinematics ------------------------------------------------------
    t_fk = best_time(lambda: robot.fk(q), args.repeat)
    print(
        f"FK                      {t_fk * 1e3:8.2f} ms  {n / t_fk / 1e6:6.2f} M poses/s  "
        f"{t_fk / n * 1e6:.3f} us/pose"
    )
    t_jac = best_time(lambda: robot.jacobian(q), args.repeat)
    print(
        f"Jacobian                {t_jac * 1e3:8.2f} ms  {n / t_jac / 1e6:6.2f} M poses/s  "
        f"{t_jac / n * 1e6:.3f} us/pose"
    )

    # --- analytic IK, all 8 solutions ---------------------------------------------
    t_ik = best_time(lambda: robot.ik(T), args.repeat)
    t_ik_nc = best_time(lambda: robot.ik(T, check=False), args.repeat)
    t_ik_info = best_time(lambda: robot.ik(T, return_info=True), args.repeat)
    print(
        f"IK (8 sol., checked)    {t_ik * 1e3:8.2f} ms  {n / t_ik / 1e6:6.2f} M poses/s  "
        f"{t_ik / n * 1e6:.3f} us/pose"
    )
    print(
        f"IK (8 sol., no check)   {t_ik_nc * 1e3:8.2f} ms  {n / t_ik_nc / 1e6:6.2f} M poses/s  "
        f"{t_ik_nc / n * 1e6:.3f} us/pose"
    )
    print(
        f"IK (+ singularity info) {t_ik_info * 1e3:8.2f} ms  {n / t_ik_info / 1e6:6.2f} M poses/s  "
        f"{t_ik_info / n * 1e6:.3f} us/pose"
    )

    try:
        import ur_analytic_ik
    except ImportError:
        print("ur_analytic_ik           not installed: comparison skipped")
    else:
        oracle = getattr(ur_analytic_ik, robot.name)
        m = min(args.oracle_n, n)
        Ts = [np.ascontiguousarray(T[k]) for k in range(m)]

        def run_oracle() -> None:
            for Tk in Ts:
                oracle.inverse_kinematics(Tk)

        t_or = best_time(run_oracle, max(1, args.repeat // 2))
        per = t_or / m
        print(
            f"ur_analytic_ik (loop)   {per * n * 1e3:8.2f} ms  {1 / per / 1e6:6.2f} M poses/s  "
            f"{per * 1e6:.3f} us/pose  (measured on {m} poses, scaled to {n})"
        )
        print(
            f"speed-up of ours        {per / (t_ik / n):8.1f} x (checked), "
            f"{per / (t_ik_nc / n):.1f} x (no check)"
        )

    # --- path IK ------------------------------------------------------------------
    qp = smooth_path(args.path_n)
    P = robot.fk(qp)
    t_path = best_time(lambda: robot.path_ik(P, q_start=qp[0]), args.repeat)
    res = robot.path_ik(P, q_start=qp[0])
    print(
        f"path IK ({args.path_n} poses)     {t_path * 1e3:8.2f} ms  "
        f"{t_path / args.path_n * 1e6:.2f} us/pose  (all ok: {res.all_ok}, "
        f"max step {res.max_step:.2e} rad, max |q - q_ref| {np.abs(res.q - qp).max():.1e})"
    )

    # --- MuJoCo playback / rendering: to be added with ruledrobot.sim --------------


if __name__ == "__main__":
    main()
