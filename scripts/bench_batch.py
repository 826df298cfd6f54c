"""Benchmark of batch planning on Dask: throughput with 1 and 2 local workers, the
speed-up, and the engine's overhead per job against planning the same jobs one after
another in one process.

Twenty jobs (the demo job with two refinement steps, feeds 30 to 49 mm/s: about
1.5-2.5 s each to plan and verify in MuJoCo).  Runs, each into a fresh folder:

* ``serial``: ``planner.plan`` on each job in this process, one after another
  (imports and a first plan done before the clock starts);
* ``batch, 1 worker`` / ``batch, 2 workers``, alternately, ``--repeat`` times each
  (the best is kept: the machine is shared, and other work only slows a run down):
  ``run_batch`` with a new local cluster each time — its start, the workers'
  imports, dispatch, the results' transfer and the files' writing included.  Also
  the steady throughput: jobs per minute from the moment every worker has
  delivered its first job (start and imports left out).

Prints figures and ratios, and the load average at each run (other work on the
machine slows every figure).  Target (issue 16): speed-up 2 workers / 1 worker
>= 1.7 on this 2-core machine.

    .venv/bin/python scripts/bench_batch.py [--jobs 20] [--repeat 2]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from ruledrobot.batch import Engine, run_batch
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
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


def _batch(jobs: list[Path], out: Path, workers: int) -> dict:
    """One run of ``run_batch``: wall time, the steady rate, the worker's plan time."""
    done: list[float] = []
    t0 = time.perf_counter()

    def progress(p) -> None:
        if p.last is not None:
            done.append(time.perf_counter() - t0)

    res = run_batch([str(p) for p in jobs], out, workers=workers, progress=progress)
    wall = time.perf_counter() - t0
    assert res.exit_code == 0 and res.planned == len(jobs), [x.status for x in res.records]
    first = done[workers - 1]  # every worker has delivered a job
    return {"wall": wall, "steady": (len(done) - workers) / (done[-1] - first) * 60,
            "plan_s": sum(x.plan_s for x in res.records) / len(jobs), "load": _load(),
            "mb": sum((out / f).stat().st_size for x in res.records for f in x.files)
            / len(jobs) / 1e6}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=20, help="number of jobs (default 20)")
    ap.add_argument("--repeat", type=int, default=2, help="runs per worker count (best kept)")
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
        print(f"serial, one process      {t_serial:6.1f} s  {t_serial / n:5.2f} s/job  "
              f"{n / t_serial * 60:5.1f} jobs/min   ({_load()})")  # fmt: skip

        t0 = time.perf_counter()
        with Engine(workers=1) as eng:
            eng.describe()
        t_engine = time.perf_counter() - t0
        print(f"local cluster start+stop {t_engine:6.1f} s  (1 worker, no job)")

        runs: dict[int, list[dict]] = {1: [], 2: []}
        for k in range(args.repeat):
            for w in (1, 2):
                r = _batch(jobs, root / f"batch{w}-{k}", w)
                runs[w].append(r)
                print(f"batch, {w} worker{'s' if w > 1 else ' '} (run {k + 1}) {r['wall']:6.1f} s  "
                      f"{r['wall'] / n:5.2f} s/job  {n / r['wall'] * 60:5.1f} jobs/min   steady "
                      f"{r['steady']:5.1f} jobs/min   plan on a worker {r['plan_s']:.2f} s/job   "
                      f"({r['load']})")  # fmt: skip
    best = {w: min(rs, key=lambda r: r["wall"]) for w, rs in runs.items()}
    steady = {w: max(r["steady"] for r in rs) for w, rs in runs.items()}
    t1, t2 = best[1]["wall"], best[2]["wall"]
    overhead = (t1 - t_serial) / n
    print()
    print(f"speed-up, 2 workers / 1 worker, whole run   {t1 / t2:5.2f} x   (target >= 1.7)")
    print(f"speed-up, 2 workers / 1 worker, steady      {steady[2] / steady[1]:5.2f} x")
    print(f"speed-up, 2 workers / serial                {t_serial / t2:5.2f} x")
    print(f"engine overhead per job, (1 worker - serial) / {n}   {overhead:+.2f} s "
          f"({overhead / (t_serial / n) * 100:+.0f} % of a job; of it once: cluster "
          f"start+stop {t_engine:.1f} s and the worker's imports)")  # fmt: skip
    print(f"files per job returned by the worker        {best[1]['mb']:.2f} MB")


if __name__ == "__main__":
    main()
