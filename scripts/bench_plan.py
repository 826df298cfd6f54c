"""Benchmark of the cut planner: time vs number of rulings, stage by stage, a part,
and the placement search.

Prints figures; asserts nothing.  Targets: for 2,000 refined rulings, planning
(redundancy + IK + timing) < 1 s and the whole ``ruledrobot plan`` without video
< 5 s on this 2-core machine (issue "Wire-cutting planner"); for the built-in demo and
part (three cuts, one closed), planned in at most 0.05 of the time their motion takes
on the robot (issue 25; a tenth for the whole plan in issue "Real parts"); at least
1,000 candidate placements scored per minute for a 2,000-ruling job (issue 13).

    .venv/bin/python scripts/bench_plan.py            # all
    .venv/bin/python scripts/bench_plan.py ratio      # the demo and the part against their motion
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
from ruledrobot.wirecut.cut.passes import cut_path, refine_for_job
from ruledrobot.wirecut.cut.wire_geometry import speed_factor
from ruledrobot.wirecut.job.demo import DEMO_JOB, PART_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.motion.timing import time_path
from ruledrobot.wirecut.planner import plan


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
            sf = speed_factor(m.flange, s, job.tool, job.stock, 0.002)
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
        _part(Path(tmp))


def _part(tmp: Path, repeat: int = 3) -> None:
    """The built-in demo and part: the stages of a plan against the duration of its motion
    (issue 25: each planned in at most 0.05 of it), best of ``repeat`` warm runs."""
    for name, text in (("demo", DEMO_JOB), ("part", PART_JOB)):
        _stages(tmp, name, text, repeat)


def _stages(tmp: Path, name: str, text: str, repeat: int) -> None:
    import os

    from ruledrobot.wirecut.plan import make_plan
    from ruledrobot.wirecut.report.outcome import plan_outcome
    from ruledrobot.wirecut.verify import verify_plan

    p = tmp / f"{name}.toml"
    p.write_text(text)
    job = load_job(p)
    plan(job, tmp / f"{name}_warm")  # imports and compiled kernels loaded: warm runs below
    best = {"planning": np.inf, "verification": np.inf, "outcome": np.inf, "whole": np.inf}
    for _ in range(repeat):
        t0 = time.perf_counter()
        planned = make_plan(job)
        t1 = time.perf_counter()
        ver = verify_plan(planned)
        t2 = time.perf_counter()
        plan_outcome(planned, ver)
        t3 = time.perf_counter()
        result = plan(job, tmp / f"{name}_out")
        t4 = time.perf_counter()
        for key, dt in (("planning", t1 - t0), ("verification", t2 - t1),
                        ("outcome", t3 - t2), ("whole", t4 - t3)):  # fmt: skip
            best[key] = min(best[key], dt)
    motion = planned.motion.timed.t[-1]
    cutting = float(np.sum(planned.motion.surface) * planned.model.control_period)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"\n{name}: {len(job.cuts)} cut(s) ({', '.join(c.name for c in job.cuts)}), "
          f"{len(planned.passes)} passes, {sum(len(cp.frames) for cp in planned.passes)} "
          f"rulings, verdict {'PASS' if result.feasible else 'FAIL'}; best of {repeat} warm "
          f"runs, load average {load:.1f} on {os.cpu_count()} cores")  # fmt: skip
    print(f"  planning (rulings, passes, transits, timing, measurement): {best['planning']:7.2f} s")
    print(f"  MuJoCo verification:                                       "
          f"{best['verification']:7.2f} s")  # fmt: skip
    print(f"  report and verdict:                                        {best['outcome']:7.2f} s")
    print(f"  whole plan with files, part mesh, no video:                {best['whole']:7.2f} s")
    print(f"  the motion on the robot: {motion:.1f} s, of which the wire on the surfaces "
          f"{cutting:.1f} s")
    print(f"  planning / motion on the robot:   {best['planning'] / motion:.3f} (target <= 0.05)")
    print(f"  whole plan / motion on the robot: {best['whole'] / motion:.3f} (target <= 0.05)")


def bench_place() -> None:
    """Candidates scored per minute (issue 13): the demo surface refined to 2,051 rulings,
    a 9 x 9 x 9 grid over a region that holds good, marginal and unreachable places."""
    from ruledrobot.place.regions import Region, transforms
    from ruledrobot.place.search import job_passes
    from ruledrobot.wirecut.reach.evaluate import Evaluator

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
    _place_on_workers()


def _place_on_workers() -> None:
    """The symmetric-bow case scored in this process and on a local Dask cluster of 2
    workers (``ruledrobot place --workers 2``; issue 16), scores compared."""
    try:
        from ruledrobot.batch.engine import Engine
        from ruledrobot.batch.place import DistributedEvaluator
    except ImportError:
        print("dask not installed: the cluster comparison is skipped (the batch extra)")
        return
    from ruledrobot.place.regions import Region, transforms
    from ruledrobot.place.search import job_passes
    from ruledrobot.wirecut.reach.evaluate import Evaluator

    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "job.toml"
        p.write_text(DEMO_JOB.replace("steps = 4", "steps = 8"))
        job = load_job(p)
        ev = Evaluator(job, job_passes(job))
        region = Region((0.2, 1.1), (-0.5, 0.5), (-np.pi / 2, np.pi / 2))
        T = transforms(job, region.grid((9, 9, 9)), "stock")
        t0 = time.perf_counter()
        here = ev(T)
        t_here = time.perf_counter() - t0
        t0 = time.perf_counter()
        with Engine(2) as eng:
            t_start = time.perf_counter() - t0
            d = DistributedEvaluator(ev, eng)
            t1 = time.perf_counter()
            there = d(T)
            t_there = time.perf_counter() - t1
    same = all(np.array_equal(getattr(here, f), getattr(there, f))
               for f in ("margin", "score", "pass_margin", "column", "exact"))  # fmt: skip
    print(f"\n{len(T)} candidates, symmetric bow: in this process {t_here:.1f} s "
          f"({60 * len(T) / t_here:.0f} per minute); on 2 local Dask workers {t_there:.1f} s "
          f"({60 * len(T) / t_there:.0f} per minute, speed-up {t_here / t_there:.2f} x; "
          f"cluster start {t_start:.1f} s more); the same scores: {same}")


if __name__ == "__main__":
    if sys.argv[1:] == ["ratio"]:
        with tempfile.TemporaryDirectory() as tmp:
            _part(Path(tmp))
    else:
        if sys.argv[1:] != ["place"]:
            main()
        bench_place()
