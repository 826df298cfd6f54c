"""Benchmark of the robot layer: analytic IK, FK, Jacobian, path IK; MuJoCo playback.

Run:  .venv/bin/python scripts/bench_robot.py [--model ur5e] [--n 100000] [--repeat 5]
      [--sim-duration 60] [--no-sim] [--no-render] [--no-calibrated] [--calibration-seed 1]
      [--only-calibrated]

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


def best_alternating(fns: list[Callable[[], object]], repeat: int) -> list[float]:
    """Best wall time [s] of each function over ``repeat`` rounds that call them in turn
    (one warm-up round first), so that load from other processes hits both alike."""
    for fn in fns:
        fn()
    best = [np.inf] * len(fns)
    for _ in range(repeat):
        for k, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            best[k] = min(best[k], time.perf_counter() - t0)
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
    parser.add_argument("--sim-duration", type=float, default=60.0, help="s of playback")
    parser.add_argument("--render-frames", type=int, default=200)
    parser.add_argument("--no-sim", action="store_true", help="skip MuJoCo playback/render")
    parser.add_argument("--no-render", action="store_true", help="skip rendering")
    parser.add_argument("--no-calibrated", action="store_true", help="skip the calibrated IK")
    parser.add_argument("--calibration-seed", type=int, default=1)
    parser.add_argument(
        "--only-calibrated", action="store_true", help="only the calibrated/nominal IK ratio"
    )
    args = parser.parse_args()

    robot = load(args.model)
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, size=(args.n, 6))
    T = robot.fk(q)
    n = args.n
    print(f"robot layer benchmark: {robot.name}, {n} random configurations, best of {args.repeat}")
    if args.only_calibrated:
        bench_calibrated(args, robot, best_time(lambda: robot.ik(T), args.repeat))
        return

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

    # --- calibrated arm: compiled nominal seeds + damped Newton on the calibrated chain --
    if not args.no_calibrated:
        bench_calibrated(args, robot, t_ik)

    # --- MuJoCo playback and rendering (ruledrobot.sim) -----------------------------
    if not args.no_sim:
        bench_sim(args)


def bench_calibrated(args: argparse.Namespace, robot, t_ik: float) -> None:
    """All 8 branches of a calibrated arm on the same poses: time, ratio, residuals, rates."""
    from ruledrobot.robot import random_calibration
    from ruledrobot.robot.ik import calibrated as calibrated_ik

    n = args.n
    cal = random_calibration(robot.name, args.calibration_seed)
    arm = robot.with_calibration(cal)
    rng = np.random.default_rng(1)
    q = rng.uniform(-np.pi, np.pi, size=(n, 6))
    T = arm.fk(q)
    # alternate the two (the machine is shared): best of ``repeat`` each, after a warm-up
    # call that also compiles (or loads) the numba kernels
    arm.ik(T[:10])
    t_nom, t_cal = best_alternating([lambda: robot.ik(T), lambda: arm.ik(T)], args.repeat)
    info = arm.ik(T, return_info=True)
    v = info.valid
    F = arm.fk(np.where(v[..., None], info.q, 0.0))
    dp = np.linalg.norm(F[..., :3, 3] - T[:, None, :3, 3], axis=-1)[v]
    R = np.einsum(
        "...ji,...jk->...ik",
        F[..., :3, :3],
        np.broadcast_to(T[:, None, :3, :3], F[..., :3, :3].shape),
    )
    w = 0.5 * np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                        R[..., 1, 0] - R[..., 0, 1]], axis=-1)[v]  # fmt: skip
    rot = np.arcsin(np.minimum(np.linalg.norm(w, axis=-1), 1.0))
    _, exact = calibrated_ik.nominal_seeds(robot.ur_geometry, arm.flange_poses(T), np.zeros(n))
    seeded = info.seeded
    print(
        f"\ncalibrated {robot.name} ({cal.source}; FK up to "
        f"{np.linalg.norm(T[:, :3, 3] - robot.fk(q)[:, :3, 3], axis=-1).max() * 1e3:.1f} mm "
        f"from nominal), {n} random configurations"
    )
    print(
        f"IK nominal (8 sol.)     {t_nom * 1e3:8.2f} ms  {t_nom / n * 1e6:.3f} us/pose  "
        f"(first run above: {t_ik * 1e3:.2f} ms; alternated with the calibrated IK)"
    )
    print(
        f"IK calibrated (8 sol.)  {t_cal * 1e3:8.2f} ms  {t_cal / n * 1e6:.3f} us/pose  "
        f"ratio {t_cal / t_nom:.2f} x nominal (target 5 x); residual max {dp.max():.1e} m, "
        f"{rot.max():.1e} rad"
    )
    print(
        f"  {v.sum()} solutions (residuals above: FK of each against its pose); "
        f"poses solved {v.any(axis=1).mean() * 100:.2f} %"
    )
    print(
        f"  converged: {(v & exact).sum() / exact.sum() * 100:.3f} % of the nominal closed "
        f"form's branches, {(v & ~exact).sum() / max(1, (seeded & ~exact).sum()) * 100:.1f} % "
        f"of the fallback seeds; not converged (NaN, flagged) {(seeded & ~v).sum()}"
    )
    its = info.iterations[v]
    print(
        f"  Newton iterations: mean {its.mean():.2f}, "
        + ", ".join(
            f"{k}: {c / its.size * 100:.1f} %"
            for k, c in enumerate(np.bincount(its))
            if c / its.size > 0.001
        )
    )


def cell_trajectory(
    duration: float, dt: float = 0.002
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A smooth 6-joint trajectory of the example hot-wire cell, clear of table and stock.

    Sinusoids about ``[0, -1.9, 1.4, -1.3, -pi/2, 0]``, amplitudes
    ``[0.8, 0.3, 0.4, 0.3, 0.25, 0.5]`` rad, periods 5.3-10 s: peak speeds
    0.23-0.50 rad/s (<= 0.16 of the UR5e limits), accelerations <= 0.44 rad/s^2.
    """
    t = np.arange(round(duration / dt) + 1) * dt
    q0 = np.array([0.0, -1.9, 1.4, -1.3, -1.57, 0.0])
    amp = np.array([0.8, 0.3, 0.4, 0.3, 0.25, 0.5])
    w = 2 * np.pi / np.array([10.0, 7.7, 6.1, 8.3, 5.3, 6.7])
    return t, q0 + amp * np.sin(np.outer(t, w)), amp * w * np.cos(np.outer(t, w))


def bench_sim(args: argparse.Namespace) -> None:
    """Playback real-time factor and tracking error on a 60 s trajectory; render fps."""
    import dataclasses
    import os
    import tempfile

    from ruledrobot import sim
    from ruledrobot.sim.scene import example_scene

    cell = example_scene()  # UR5e, 400 mm bow, 200 mm stock, table
    cell = dataclasses.replace(cell, robot=cell.robot.with_tool([0, 0, 0.25, 0, 0, 0]))
    t, q, qd = cell_trajectory(args.sim_duration)
    print(
        f"\nMuJoCo playback: {cell.robot.name} hot-wire cell, {args.sim_duration:g} s smooth "
        f"trajectory ({t.size} samples at 500 Hz), best of {args.repeat}"
    )
    for ff in ("velocity", "torque"):
        for label, kw in (("with collision checks", {}), ("dynamics only", {"collisions": False})):
            best = None
            for _ in range(max(1, args.repeat)):
                res = sim.play(cell, t, q, qd, feedforward=ff, **kw)
                if best is None or res.wall_time < best.wall_time:
                    best = res
            assert best is not None
            rep = best.report()
            rtf, phys = rep["realtime_factor"], rep["physics_realtime_factor"]
            print(
                f"  {ff:8s} feed-forward, {label:21s}: {best.wall_time * 1e3:7.1f} ms  "
                f"{rtf:6.0f}x real time (physics {phys:4.0f}x)"
            )
        pos, rot = rep["tcp_position_error_mm"], rep["tcp_orientation_error_deg"]
        print(
            f"    TCP error max {pos['max']:.3f} mm, rms {pos['rms']:.3f} mm; orientation max "
            f"{rot['max']:.4f} deg; joint max {rep['joint_error_rad']['max']:.2e} rad; "
            f"torque/limit {rep['joint_torque']['max_ratio']:.2f}, "
            f"speed/limit {rep['joint_speed']['max_ratio']:.2f}; "
            f"collisions {rep['collision_count']}"
        )
    if args.no_render:
        return
    try:
        renderer = sim.Renderer(cell, width=640, height=480)
    except sim.RenderUnavailable as exc:
        print(f"rendering               skipped: {exc}")
        return
    with renderer as r:
        qs = q[:: max(1, q.shape[0] // args.render_frames)][: args.render_frames]
        r.frame(qs[0])
        t0 = time.perf_counter()
        for qk in qs:
            r.frame(qk)
        el = time.perf_counter() - t0
    print(
        f"render 640x480 (EGL/OSMesa, fast settings): {len(qs) / el:6.1f} frames/s "
        f"(MUJOCO_GL={os.environ.get('MUJOCO_GL')})"
    )
    res = sim.play(cell, t[:5001], q[:5001], qd[:5001], collisions=False)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        path = sim.render_video(res, f"{tmp}/cell.mp4", fps=25)
        el = time.perf_counter() - t0
        size = path.stat().st_size
    n = int(res.duration * 25) + 1
    print(
        f"video 10 s, 25 fps, 640x480, H.264 (render + encode): {el:5.2f} s, "
        f"{n / el:5.1f} frames/s, {size / 1e6:.2f} MB"
    )


if __name__ == "__main__":
    main()
