"""Benchmark of the cut planner: time vs number of rulings, stage by stage.

Prints figures; asserts nothing.  Targets (issue "Wire-cutting planner"): for
2,000 refined rulings, planning (redundancy + IK + timing) < 1 s and the whole
``ruledrobot plan`` without video < 5 s on this 2-core machine.

    .venv/bin/python scripts/bench_plan.py
"""

from __future__ import annotations

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
            job = replace(base, surface=replace(base.surface, steps=steps))
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


if __name__ == "__main__":
    main()
