"""Benchmark of the geometry core: SE(3) geodesics, refinement steps, common normals.

Prints figures and ratios against peers; asserts nothing.  Run:

    make bench            # or: .venv/bin/python scripts/bench_geometry.py

Targets (issue "Geometry core"): >= 5 M SE(3) geodesic evaluations/s from 4x4
matrices; one dh/four_point step on 100,000 lines < 0.08 s.  Issue 25: the geodesic at
least 12x pytransform3d's batch ScLERP, both from and to 4x4 matrices on the same pairs,
timed in interleaved rounds (best of ``--repeat``), one thread each.
"""

from __future__ import annotations

import argparse
import platform
import time
from collections.abc import Callable

import numpy as np

import ruledrobot as rr
from ruledrobot.geometry import lines as L
from ruledrobot.geometry import se3
from ruledrobot.subdivision import get_scheme
from ruledrobot.subdivision.engine import refine_sequence
from ruledrobot.subdivision.spaces import SE3Space


def best_of(fn: Callable[[], object], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def interleaved(
    ours: Callable[[], object], peers: list[Callable[[], object]], repeat: int
) -> tuple[float, list[float]]:
    """Best times of ``ours`` and of each peer over ``repeat`` interleaved rounds."""
    t_ours, t_peers = [], [[] for _ in peers]
    for _ in range(repeat):
        for fn, times in [(ours, t_ours), *zip(peers, t_peers, strict=True)]:
            t0 = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t0)
    return min(t_ours), [min(t) for t in t_peers]


def random_poses(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return se3.pose_from_quaternion(q, rng.normal(size=(n, 3)))


def smooth_lines(n: int) -> rr.Lines:
    """n rulings of a smooth non-helical surface (dense, like refined data)."""
    u = np.linspace(0.0, 6.0, n)
    pts = np.stack([np.cos(u), np.sin(1.3 * u), 0.2 * u], 1)
    dirs = np.stack([np.cos(0.7 * u), np.sin(0.7 * u), 1.0 + 0.3 * np.sin(u)], 1)
    return rr.Lines.from_point_direction(pts, dirs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000, help="batch size (default 100000)")
    ap.add_argument("--repeat", type=int, default=7, help="best of this many runs")
    ap.add_argument(
        "--only-geodesic", action="store_true", help="the SE(3) geodesic comparison alone"
    )
    args = ap.parse_args()
    n, rep = args.n, args.repeat
    rng = np.random.default_rng(0)
    print(
        f"ruledrobot {rr.__version__}, numpy {np.__version__}, Python {platform.python_version()}"
    )
    print(f"batch n = {n:,}, best of {rep}\n")

    # 1. SE(3) geodesic from 4x4 matrices: ours and the peers on the same inputs, each
    # returning (n, 4, 4) matrices, timed in interleaved rounds (ours, peer, ours, peer,
    # ...) so that a slow spell of the shared machine hits both; best of the rounds
    A, B = random_poses(rng, n), random_poses(rng, n)
    print("SE(3) geodesic A exp(t log(A^-1 B)) from 4x4 matrices (random pairs, t = 0.5)")
    t0 = time.perf_counter()
    ours_out = se3.geodesic(A, B, 0.5)  # the first call loads the compiled kernel
    t_first = time.perf_counter() - t0
    peers: dict[str, Callable[[], np.ndarray]] = {}
    try:
        import pytransform3d.trajectories as ptr

        def p3d() -> np.ndarray:
            da = ptr.dual_quaternions_from_transforms(A)
            db = ptr.dual_quaternions_from_transforms(B)
            return ptr.transforms_from_dual_quaternions(
                ptr.dual_quaternions_sclerp(da, db, np.full(n, 0.5))
            )

        peers["pytransform3d batch ScLERP    "] = p3d
    except ImportError:
        print("  pytransform3d not installed: pip install -e '.[bench]' for the comparison")
    try:
        from scipy.spatial.transform import RigidTransform

        def scipy_geo() -> np.ndarray:
            ta, tb = RigidTransform.from_matrix(A), RigidTransform.from_matrix(B)
            rel = (ta.inv() * tb).as_exp_coords()
            return (ta * RigidTransform.from_exp_coords(0.5 * rel)).as_matrix()

        peers["scipy RigidTransform log/exp  "] = scipy_geo
    except ImportError:
        pass
    t_ours, t_peer = interleaved(lambda: se3.geodesic(A, B, 0.5), list(peers.values()), rep)
    print(
        f"  ruledrobot.se3.geodesic          {t_ours * 1e3:8.1f} ms  {n / t_ours / 1e6:6.2f} M/s"
        f"   (target >= 5 M/s; first call {t_first * 1e3:.0f} ms, kernel load included)"
    )
    for (name, fn), t_p in zip(peers.items(), t_peer, strict=True):
        err = np.abs(fn() - ours_out).max()
        print(
            f"  {name}   {t_p * 1e3:8.1f} ms  {n / t_p / 1e6:6.2f} M/s"
            f"   ours is {t_p / t_ours:4.1f}x faster (max difference {err:.1e})"
        )

    if args.only_geodesic:
        return

    # 2. one refinement step of each algorithm on n lines
    lines = smooth_lines(n)
    print(f"\nOne refinement step on {n:,} lines (scheme four_point)")
    for alg in ("projection", "combined", "dh"):
        t = best_of(lambda alg=alg: rr.refine(lines, alg, "four_point", 1), rep)
        print(f"  {alg:10s} whole refine()      {t * 1e3:8.1f} ms  {n / t / 1e6:6.2f} M lines/s")
    space = SE3Space()
    frames = rr.RuledSurface(lines).dh_frames()
    x = space.encode(frames)
    sch = get_scheme("four_point")
    t_step = best_of(lambda: refine_sequence(space, x, sch, 1, False), rep)
    t_frames = best_of(lambda: rr.RuledSurface(lines).dh_frames(), rep)
    print(f"  dh: frame extraction              {t_frames * 1e3:8.1f} ms")
    print(f"  dh: SE(3) four_point step alone   {t_step * 1e3:8.1f} ms   (target < 80 ms)")
    chaikin = get_scheme("chaikin")
    t_ch = best_of(lambda: refine_sequence(space, x, chaikin, 1, False), rep)
    print(
        f"  dh: chaikin step alone            {t_ch * 1e3:8.1f} ms"
        "   (pytransform3d-based baseline in the notes: 261 ms; four_point 345 ms)"
    )

    # 3. common normals
    a = lines.plucker[:-1]
    b = lines.plucker[1:]
    t_cn = best_of(lambda: L.common_normal(a, b), rep)
    print(f"\nCommon normals of consecutive lines ({n - 1:,} pairs, robust: parallel/intersecting)")
    print(
        f"  ruledrobot common_normal          {t_cn * 1e3:8.1f} ms  "
        f"{(n - 1) / t_cn / 1e6:6.2f} M pairs/s  ({t_cn / (n - 1) * 1e6:.3f} us/pair; "
        "spatialmath Line3.closest_to_line: 280 us/pair)"
    )


if __name__ == "__main__":
    main()
