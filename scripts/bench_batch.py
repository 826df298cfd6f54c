"""Benchmark of batch planning on Dask: throughput with 1 and 2 local workers, the
speed-up, and the engine's overhead per job against planning the same jobs one after
another in one process.

Twenty jobs (the demo job with two refinement steps, feeds 30 to 49 mm/s: about
3 s each to plan and verify in MuJoCo).  Three runs, each into a fresh folder:

* ``serial``: ``planner.plan`` on each job in this process, one after another
  (imports and a first plan done before the clock starts);
* ``batch, 1 worker`` / ``batch, 2 workers``: ``run_batch`` with a new local
  cluster each time — its start, the workers' imports, dispatch, the results'
  transfer and the files' writing included.

Prints figures and ratios, and the load average before and after (other work on
the machine slows every figure).  Target (issue 16): speed-up 2 workers / 1 worker
>= 1.7 on this 2-core machine.

    .venv/bin/python scripts/bench_batch.py [--jobs 20]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from ruledrobot.batch import Engine, run_batch
from ruledrobot.wirecut.demo import DEMO_JOB
from ruledrobot.wirecut.job import load_job
from ruledrobot.wirecut.planner import plan

FAST = DEMO_JOB.replace("steps = 4", "steps = 2")


def _jobs(folder: Path, n: int) -> list[Path]:
    folder.mkdir(parents=True)
    paths = []
    for k in range(n):
        p = folder / f"piece{k:02d}.toml"
        p.write_text(FAST.replace("feed_speed = 0.01 ", f"feed_speed = {0.030 + k * 0.001:.3f} "))
        paths.append(p)
    return paths


def _load() -> str:
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def _batch(jobs: list[Path], out: Path, workers: int) -> tuple[float, object]:
    t0 = time.perf_counter()
    res = run_batch([str(p) for p in jobs], out, workers=workers)
    return time.perf_counter() - t0, res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=20, help="number of jobs (default 20)")
    args = ap.parse_args()
    n = args.jobs
    print(f"{n} jobs (demo job, 2 refinement steps, feed 30..{29 + n} mm/s), "
          f"{os.cpu_count()} cores; {_load()}\n")  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="bench-batch-") as tmp:
        root = Path(tmp)
        jobs = _jobs(root / "jobs", n)
        plan(load_job(jobs[0]), root / "warm")  # imports and caches, off the clock

        t0 = time.perf_counter()
        for p in jobs:
            assert plan(load_job(p), root / "serial" / p.stem).feasible
        t_serial = time.perf_counter() - t0
        print(f"serial, one process      {t_serial:7.1f} s   {t_serial / n:5.2f} s/job   "
              f"{n / t_serial * 60:5.1f} jobs/min   ({_load()})")  # fmt: skip

        t0 = time.perf_counter()
        with Engine(workers=1) as eng:
            eng.describe()
        t_engine = time.perf_counter() - t0
        print(f"local cluster start+stop {t_engine:7.1f} s   (1 worker, no job)")

        times, results = {}, {}
        for w in (1, 2):
            times[w], results[w] = _batch(jobs, root / f"batch{w}", w)
            r = results[w]
            assert r.exit_code == 0 and r.planned == n, [x.status for x in r.records]
            plan_s = sum(x.plan_s for x in r.records) / n
            print(f"batch, {w} worker{'s' if w > 1 else ' '}        {times[w]:7.1f} s   "
                  f"{times[w] / n:5.2f} s/job   {n / times[w] * 60:5.1f} jobs/min   "
                  f"(plan on a worker {plan_s:.2f} s/job; {_load()})")  # fmt: skip
        mb = sum((root / "batch1" / f).stat().st_size for x in results[1].records
                 for f in x.files) / n / 1e6  # fmt: skip

    speedup = times[1] / times[2]
    overhead = (times[1] - t_serial) / n
    print()
    print(f"speed-up, 2 workers / 1 worker          {speedup:5.2f} x   (target >= 1.7)")
    print(f"speed-up, 2 workers / serial            {t_serial / times[2]:5.2f} x")
    print(f"engine overhead per job (1 worker - serial) / {n}   {overhead:+.2f} s "
          f"({overhead / (t_serial / n) * 100:+.0f} % of a job; cluster start+stop "
          f"{t_engine:.1f} s of it once)")  # fmt: skip
    print(f"files per job returned by the worker    {mb:.2f} MB")


if __name__ == "__main__":
    main()
