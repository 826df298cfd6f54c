"""Benchmark of the cut planner: time vs number of rulings, stage by stage, and the
placement search.

Prints figures; asserts nothing.  Targets (issue "Wire-cutting planner"): for
2,000 refined rulings, planning (redundancy + IK + timing) < 1 s and the whole
``ruledrobot plan`` without video < 5 s on this 2-core machine.  Issue 13: at least
1,000 candidate placements scored per minute for a 2,000-ruling job.

    .venv/bin/python scripts/bench_plan.py            # both
    .venv/bin/python scripts/bench_plan.py place      # the placement search only
"""

from __future__ import annotations

import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from ruledrobot.robot import load
from ruledrobot.wirecut.demo import DEMO_JOB
from ruledrobot.wirecut.job import load_job
from ruledrobot.wirecut.path import chord_ends_in_flange, cut_path, refine_for_job
from ruledrobot.wirecut.planner import plan
from ruledrobot.wirecut.timing import time_path
from ruledrobot.wirecut.toolpath import speed_factor


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "job.toml"
        p.write_text(DEMO_JOB)
        base = load_job(p)
        model = load(base.robot.model)
        print("demo job (hyperbolic paraboloid, UR5e), 9 input rulings, feed 10 mm/s\n")
        print(
            f"{'steps':>5} {'path rulings':>12} {'refine':>8} {'redundancy+IK':>14} "
            f"{'timing':>8} {'planning':>9} {'whole plan':>11}"
        )
        for steps in (6, 8, 10):
            job = replace(base, cuts=(replace(base.cut, surface=replace(base.surface,
                                                                        steps=steps)),))
            t0 = time.perf_counter()
            refine_for_job(job)
            t_ref = time.perf_counter() - t0
            t0 = time.perf_counter()
            cp = cut_path(job, model)
            t_path = time.perf_counter() - t0
            m = cp.motion
            s = np.arange(len(cp.frames), dtype=float)
            t0 = time.perf_counter()
            sf = speed_factor(m.flange, s, chord_ends_in_flange(cp), m.hit)
            time_path(
                s,
                m.q,
                sf,
                job.cut.feed_speed,
                model.max_velocity,
                model.max_acceleration,
                model.control_period,
            )
            t_time = time.perf_counter() - t0
            t0 = time.perf_counter()
            plan(job, Path(tmp) / f"out{steps}")
            t_plan = time.perf_counter() - t0
            print(
                f"{steps:>5} {len(cp.frames):>12} {t_ref:>7.3f}s {t_path - t_ref:>13.3f}s "
                f"{t_time:>7.3f}s {t_path + t_time:>8.3f}s {t_plan:>10.3f}s"
            )
        print(
            "\nplanning = refine + redundancy + IK + timing; whole plan adds sampling at the "
            "controller period, the MuJoCo verification (playback with collision checks), "
            "measurements and writing the files (CSV, JSON, STL, PNG); no video"
        )


def bench_place() -> None:
    """Candidates scored per minute (issue 13): the demo surface refined to 2,051 rulings,
    a 9 x 9 x 9 grid over a region that holds good, marginal and unreachable places."""
    from ruledrobot.wirecut.place import job_passes
    from ruledrobot.wirecut.place_eval import Evaluator
    from ruledrobot.wirecut.placement import Region, transforms

    print("\nplacement search (ruledrobot place): candidates scored per minute")
    print(f"{'bow':>10} {'rulings':>8} {'per cand.':>22} {'candidates':>10} {'time':>8} "
          f"{'per minute':>10} {'feasible':>8}")
    for bow, w in (("symmetric", "0.0"), ("offset", "0.05")):
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / "job.toml"
            p.write_text(DEMO_JOB.replace("steps = 4", "steps = 8")
                         .replace("wire_start = [-0.2, 0.0,", f"wire_start = [-0.2, {w},")
                         .replace("wire_end = [0.2, 0.0,", f"wire_end = [0.2, {w},"))
            job = load_job(p)
            passes = job_passes(job)
            ev = Evaluator(job, passes)
            region = Region((0.2, 1.1), (-0.5, 0.5), (-np.pi / 2, np.pi / 2))
            T = transforms(job, region.grid((9, 9, 9)), "stock")
            ev(T[:8])  # warm up
            t0 = time.perf_counter()
            sc = ev(T)
            dt = time.perf_counter() - t0
            each = f"{ev.rulings_checked} x {len(ev.rolls)} rolls x {len(ev.directions)} dir"
            print(f"{bow:>10} {len(passes[0].frames):>8} {each:>22} {len(T):>10} {dt:>7.1f}s "
                  f"{60 * len(T) / dt:>10.0f} {(sc.margin >= 0).mean():>8.0%}")
    print("each candidate: every sampled ruling x roll x wire direction x 8 IK branches through "
          "the batched IK and the kinematic margins; the planner's clearance rules on the "
          "columns (direction, roll, branch) that can still be the best (branch and bound)")


if __name__ == "__main__":
    if sys.argv[1:] != ["place"]:
        main()
    bench_place()
