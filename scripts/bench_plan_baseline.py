"""Planning time of this tree against a baseline commit, measured in the same run.

Each of the demo jobs (the built-in cut and the part) is planned by ``make_plan`` (no
MuJoCo, no files) in a fresh subprocess, alternately by this tree and by a ``git
worktree`` of the baseline commit, best of ``--repeat`` runs each (the machine is
shared: alternating and taking the best keeps load spikes out of the ratio).  Prints
seconds, the ratio this / baseline and each one's planning time over its motion's
duration (issue 25: at most 0.05; here with the first plan's imports and compiled kernels
loaded, which ``scripts/bench_plan.py ratio`` leaves out); asserts nothing.

    .venv/bin/python scripts/bench_plan_baseline.py --baseline 240fa83 --repeat 3
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

CHILD = r"""
import sys, time, tempfile, pathlib
from ruledrobot.wirecut.job.demo import DEMO_JOB, PART_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
text = {"demo": DEMO_JOB, "part": PART_JOB}[sys.argv[1]]
with tempfile.TemporaryDirectory() as tmp:
    p = pathlib.Path(tmp) / "job.toml"
    p.write_text(text)
    job = load_job(p)
    t0 = time.perf_counter()
    plan = make_plan(job)
    dt = time.perf_counter() - t0
print(f"{dt:.4f} {plan.motion.timed.t[-1]:.3f}")
"""


def _time(src: Path, job: str) -> tuple[float, float]:
    env = dict(os.environ, PYTHONPATH=str(src))
    out = subprocess.run([sys.executable, "-c", CHILD, job], env=env, capture_output=True,
                         text=True, check=True, cwd=src)  # fmt: skip
    dt, motion = out.stdout.split()
    return float(dt), float(motion)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", required=True, help="a commit of this repository")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "baseline"
        subprocess.run(["git", "worktree", "add", "-q", "--detach", str(base), args.baseline],
                       cwd=ROOT, check=True)  # fmt: skip
        try:
            print(f"make_plan, best of {args.repeat} (alternating), this tree vs {args.baseline}")
            print(f"{'job':>6} {'this (s)':>9} {'baseline (s)':>13} {'ratio':>6} "
                  f"{'motion this / base (s)':>24} {'plan/motion this / base':>24}")
            for job in ("demo", "part"):
                this, old = [], []
                for _ in range(args.repeat):
                    this.append(_time(ROOT, job))
                    old.append(_time(base, job))
                a, b = min(this), min(old)
                print(f"{job:>6} {a[0]:9.2f} {b[0]:13.2f} {a[0] / b[0]:6.2f} "
                      f"{a[1]:12.1f} / {b[1]:<10.1f} {a[0] / a[1]:13.3f} / {b[0] / b[1]:.3f}")
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT,
                           check=False)  # fmt: skip


if __name__ == "__main__":
    main()
