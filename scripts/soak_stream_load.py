"""Stream the demos to the end beside busy processes: does the runner keep its schedule?

For each demo (``demo``: the hyperbolic paraboloid, ~26 s of streaming; ``part``: the
part demo, three cuts, ~130 s) the plan is made once (``ruledrobot demo [--part]
--no-video --no-stream --out DIR``), then each trial starts ``--load`` busy processes
(``python -c "while ...: pass"``, each ending by itself after ``--load-limit`` s at the
latest, and killed by its pid when the trial ends) and streams the plan with
``ruledrobot run DIR/trajectory.csv --yes`` — the demo's own streaming step, the same
code (``cli.robot.stream``: the embedded MuJoCo-backed emulator, the runner, the run's
verdict).  With ``--full`` each trial runs the whole ``ruledrobot demo`` instead
(planning under load too).

Per trial: the exit code, the run's status and verdict, samples skipped (all, and with
the wire in the block), the longest slip, the feed and wire figures — from the
recording's sidecar (``trajectory.run-NNN.json``, ``"run"``) — and the emulator's
complaints from the output.  Everything is bounded in time (``--timeout`` per trial).

    python scripts/soak_stream_load.py                      # 10 + 10 trials, load 2
    python scripts/soak_stream_load.py --demos part --trials 5 --json out/soak.json
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CLI = [sys.executable, "-m", "ruledrobot.cli"]


def busy(n: int, limit: float) -> list[subprocess.Popen]:
    """``n`` busy-looping processes that end by themselves after ``limit`` s."""
    code = f"import time\nend = time.monotonic() + {limit}\nwhile time.monotonic() < end: pass"
    return [subprocess.Popen([sys.executable, "-c", code]) for _ in range(n)]


def stop(procs: list[subprocess.Popen]) -> None:
    for p in procs:
        if p.poll() is None:
            os.kill(p.pid, signal.SIGKILL)
        p.wait()


def plan(demo: str, out: Path, timeout: float) -> Path:
    cmd = [*CLI, "demo", "--no-video", "--no-stream", "--out", str(out)]
    if demo == "part":
        cmd.insert(len(CLI) + 1, "--part")
    t0 = time.monotonic()
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    if res.returncode != 0:
        raise SystemExit(f"planning {demo} failed ({res.returncode}):\n{res.stdout}\n{res.stderr}")
    print(f"planned {demo} in {time.monotonic() - t0:.0f} s: {out / 'trajectory.csv'}", flush=True)
    return out / "trajectory.csv"


def newest_run(folder: Path, before: set[Path]) -> dict | None:
    new = sorted(set(folder.glob("trajectory.run-*.json")) - before)
    if not new:
        return None
    doc = json.loads(new[-1].read_text())
    for p in new:  # the recordings are large: keep only their sidecars
        p.with_suffix(".csv").unlink(missing_ok=True)
    return doc.get("run")


def cpu_times() -> list[int]:
    """The machine's CPU counters (/proc/stat: user nice system idle iowait irq softirq
    steal), jiffies."""
    try:
        return [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:9]]
    except OSError:
        return [0] * 8


def trial(demo: str, traj: Path, args: argparse.Namespace, normal: bool = False) -> dict:
    before = set(traj.parent.glob("trajectory.run-*.json"))
    cpu0, load0 = cpu_times(), os.getloadavg()[0]
    load = busy(args.load, args.timeout + 30)
    if args.full:
        cmd = [*CLI, "demo", "--no-video", "--out", str(traj.parent)]
        if demo == "part":
            cmd.insert(len(CLI) + 1, "--part")
    else:
        cmd = [*CLI, "run", str(traj), "--yes"]
    t0 = time.monotonic()
    try:
        env = dict(os.environ, RULEDROBOT_RUN_PRIORITY="normal") if normal else None
        res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,
                             timeout=args.timeout, env=env)  # fmt: skip
        code, text = res.returncode, res.stdout + res.stderr
    except subprocess.TimeoutExpired as exc:
        code, text = "timeout", f"{exc.stdout or ''}{exc.stderr or ''}"
    finally:
        stop(load)
    took = time.monotonic() - t0
    cpu = [b - a for a, b in zip(cpu0, cpu_times(), strict=True)]
    total = max(1, sum(cpu))
    run = newest_run(traj.parent, before) or {}
    feeds = run.get("feeds") or []
    row = {
        "demo": demo,
        "exit": code,
        "seconds": round(took, 1),
        "status": run.get("status", "?"),
        "ok": run.get("ok"),
        "failed": (run.get("verdict") or {}).get("failed"),
        "skipped": run.get("skipped_samples"),
        "skipped_in_stock": run.get("skipped_in_stock"),
        "max_slip_ms": None if run.get("max_slip_s") is None else 1e3 * run["max_slip_s"],
        "max_deviation_rad": run.get("max_deviation_rad"),
        "wire_deviation_mm": None if run.get("wire_deviation_m") is None
        else 1e3 * run["wire_deviation_m"],
        "feed_mm_s": [[f["name"], f["lowest_m_s"] and 1e3 * f["lowest_m_s"],
                       f["highest_m_s"] and 1e3 * f["highest_m_s"]] for f in feeds],
        "priority": run.get("priority"),
        "load_before": round(load0, 2),
        "load_after": round(os.getloadavg()[0], 2),
        "idle_pct": round(100 * cpu[3] / total, 1),
        "steal_pct": round(100 * cpu[7] / total, 1),
        "emulator": [ln.strip() for ln in text.splitlines() if "emulator:" in ln][:3],
        "message": run.get("message", text.strip().splitlines()[-1:] if text else ""),
    }  # fmt: skip
    if code != 0:
        row["tail"] = text.strip().splitlines()[-12:]
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--demos", default="demo,part", help="demo, part or both (comma)")
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--load", type=int, default=2, help="busy processes beside each run")
    ap.add_argument("--timeout", type=float, default=400.0, help="per trial [s]")
    ap.add_argument("--full", action="store_true", help="run the whole demo in each trial")
    ap.add_argument("--out", type=Path, default=None, help="plan folders (default: a temp dir)")
    ap.add_argument("--json", type=Path, default=None, help="write every trial here")
    ap.add_argument("--compare-priority", action="store_true",
                    help="every other trial with the streaming process at normal priority "
                    "(RULEDROBOT_RUN_PRIORITY=normal), to measure what the priority does")
    ap.add_argument("--summarize", type=Path, default=None,
                    help="only print the summary of a --json file written before")
    args = ap.parse_args()
    if args.summarize is not None:
        rows = json.loads(args.summarize.read_text())
        for demo in dict.fromkeys(r["demo"] for r in rows):
            for prio in sorted({r["priority"] or "?" for r in rows if r["demo"] == demo}):
                summarize(demo, prio, [r for r in rows if r["demo"] == demo
                                       and (r["priority"] or "?") == prio])  # fmt: skip
        return
    base = args.out or Path(tempfile.mkdtemp(prefix="soak_stream_"))
    rows = []
    for demo in args.demos.split(","):
        traj = plan(demo, base / demo, 1200.0)
        for i in range(args.trials):
            row = trial(demo, traj, args, normal=args.compare_priority and i % 2 == 1)
            rows.append(row)
            print(json.dumps({"trial": i + 1, **row}), flush=True)
            if args.json:
                args.json.parent.mkdir(parents=True, exist_ok=True)
                args.json.write_text(json.dumps(rows, indent=1))
    print(f"\nsummary (load {args.load}):")
    for demo in args.demos.split(","):
        for prio in sorted({r["priority"] or "?" for r in rows if r["demo"] == demo}):
            summarize(demo, prio, [r for r in rows if r["demo"] == demo
                                   and (r["priority"] or "?") == prio])  # fmt: skip


def summarize(demo: str, prio: str, rs: list[dict]) -> None:
    """One line per demo and priority: completed, exit 0, skips, slip, feed."""
    done = sum(r["status"] == "completed" for r in rs)
    ok = sum(r["exit"] == 0 for r in rs)
    sk = sorted(r["skipped"] for r in rs if r["skipped"] is not None)
    sl = [r["max_slip_ms"] for r in rs if r["max_slip_ms"] is not None]
    codes = sorted({str(r["exit"]) for r in rs})
    print(f"  {demo} ({prio}): {done}/{len(rs)} completed, {ok} exit 0 (codes "
          f"{', '.join(codes)}); skipped samples {sk} (in the stock max "
          f"{max((r['skipped_in_stock'] or 0) for r in rs)}); longest slip max "
          f"{max(sl, default=0):.1f} ms")
    for r in rs:
        if r["exit"] != 0:
            print(f"    exit {r['exit']}: {r['status']} {r['failed']} {r['message']!s:.200}")


if __name__ == "__main__":
    main()
