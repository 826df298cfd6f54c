"""Benchmark of the pictures every plan writes: ``plots.png`` (``plot_plan``) and the
playback's ``tracking.png`` + ``limits.png`` (``PlaybackResult.plot``), on the built-in
demo and part jobs.

Each job is planned and played once; each picture is then drawn ``--reps`` times and the
fastest time is printed (the machine is shared: the minimum is the drawing's own cost).
``--against DIR`` runs the same measurement on another checkout (e.g. a worktree of the
commit before a change) in a child process and prints the ratio; both use only
``plot_plan`` and ``PlaybackResult.plot``, so any version of them is comparable.

    .venv/bin/python scripts/bench_pictures.py
    .venv/bin/python scripts/bench_pictures.py --against /path/to/main --reps 7

Measured on this 2-core machine (shared), best of 7, before the "fastpics" changes
(main at 5a9e241) and after them:

    job   picture        before   after   ratio
    demo  plot_plan      0.27 s   0.22 s   0.84
    demo  sim figures    0.21 s   0.20 s   0.93
    part  plot_plan      0.50 s   0.33 s   0.65
    part  sim figures    0.25 s   0.23 s   0.90

Prints figures; asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def measure(reps: int) -> dict[str, float]:
    """Fastest seconds of each picture ``{"demo plot_plan": s, ...}`` on this checkout."""
    from ruledrobot.wirecut.job.demo import DEMO_JOB, PART_JOB
    from ruledrobot.wirecut.job.load import load_job
    from ruledrobot.wirecut.plan import make_plan
    from ruledrobot.wirecut.report.files import surface_mesh
    from ruledrobot.wirecut.report.part_mesh import part_mesh
    from ruledrobot.wirecut.report.plots import plot_plan
    from ruledrobot.wirecut.verify import verify_plan

    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, text in (("demo", DEMO_JOB), ("part", PART_JOB)):
            (folder / "job.toml").write_text(text)
            plan = make_plan(load_job(folder / "job.toml"))
            playback = verify_plan(plan).playback
            part, surface = part_mesh(plan.job, plan.passes), surface_mesh(plan)
            draws = {"plot_plan": lambda p=plan, m=part, s=surface: plot_plan(
                         folder / "plots.png", p, m, s),
                     "sim figures": lambda pb=playback: pb.plot(folder / "simulation")}  # fmt: skip
            for what, draw in draws.items():
                draw()  # imports, font caches
                best = float("inf")
                for _ in range(reps):
                    t0 = time.perf_counter()
                    draw()
                    best = min(best, time.perf_counter() - t0)
                out[f"{name} {what}"] = best
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reps", type=int, default=5, help="draws per picture (the best counts)")
    ap.add_argument("--against", type=Path, help="another checkout to compare with")
    ap.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # the child's output
    args = ap.parse_args()
    here = measure(args.reps)
    if args.json:
        print(json.dumps(here))
        return
    other = None
    if args.against is not None:
        env = {**os.environ, "PYTHONPATH": str(args.against.resolve())}
        run = subprocess.run([sys.executable, __file__, "--json", "--reps", str(args.reps)],
                             env=env, capture_output=True, text=True, check=True)  # fmt: skip
        other = json.loads(run.stdout.strip().splitlines()[-1])
    head = f"{'picture':<18}{'this (s)':>10}"
    print(head + (f"{'against (s)':>13}{'ratio':>8}" if other else ""))
    for key, s in here.items():
        row = f"{key:<18}{s:>10.3f}"
        if other:
            row += f"{other[key]:>13.3f}{s / other[key]:>8.2f}"
        print(row)


if __name__ == "__main__":
    main()
