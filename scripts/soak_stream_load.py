"""Run the demos to the end beside busy processes: does the run hold its feed?

By default it measures what a user gets: each trial runs the whole ``ruledrobot demo``
(``demo``: the hyperbolic paraboloid; ``part``: the part demo, three cuts, the heat
switched) in its default mode, **forwarded** (the controller plays the samples on its
own clock from a buffer the runner keeps full), with ``--load`` busy processes beside
it (plain ``while True: pass`` loops at nice 0, each ending by itself after the trial's
time bound at the latest, and killed by its pid when the trial ends).

``--mode servoj`` (streaming, one servoJ per period on this computer's clock) or
``--mode path``, or ``--run-only``: the plan is made once (``ruledrobot demo [--part]
--no-video --no-stream --out DIR``) and each trial runs ``ruledrobot run
DIR/trajectory.csv --yes --mode MODE`` (``demo`` has no ``--mode``), the same code (the
embedded MuJoCo-backed emulator, the runner, the run's verdict).

Per trial: the exit code, the run's status and verdict, the feed of the actual wire in
the block (lowest where it is held, highest) against the set feed, the wire's distance
from the plan, samples skipped, the longest slip — from the recording's sidecar
(``trajectory.run-NNN.json``, ``"run"``) — and the emulator's complaints from the
output; then a summary per demo.  Everything is bounded in time (``--timeout`` per
trial).

    python scripts/soak_stream_load.py                      # 10 + 10 demos, load 2
    python scripts/soak_stream_load.py --trials 2           # a quick look
    python scripts/soak_stream_load.py --demos part --mode servoj --trials 5 --json soak.json
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CLI = [sys.executable, "-m", "ruledrobot.cli"]


def _nice0() -> None:
    """In a busy process before it runs: nice 0, whatever this script's."""
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, 0)


def busy(n: int, limit: float) -> list[subprocess.Popen]:
    """``n`` busy-looping processes at nice 0 (``while True: pass``, one CPU each), each
    ending by itself after ``limit`` s (a bound should this script die)."""
    code = (f"import signal\nsignal.alarm({max(1, math.ceil(limit))})\n"
            "while True:\n    pass")  # fmt: skip
    return [subprocess.Popen([sys.executable, "-c", code], preexec_fn=_nice0)
            for _ in range(n)]  # fmt: skip


def stop(procs: list[subprocess.Popen]) -> None:
    """Kill the busy processes by their pids and reap them."""
    for p in procs:
        if p.poll() is None:
            os.kill(p.pid, signal.SIGKILL)
        p.wait()


def demo_command(demo: str, out: Path, *extra: str) -> list[str]:
    """``ruledrobot demo [--part] --no-video [extra] --out OUT``."""
    return [*CLI, "demo", *(["--part"] if demo == "part" else []), "--no-video", *extra,
            "--out", str(out)]  # fmt: skip


def plan(demo: str, out: Path, timeout: float) -> Path:
    """Plan ``demo`` into ``out`` (no video, no run); the trajectory CSV."""
    cmd = demo_command(demo, out, "--no-stream")
    t0 = time.monotonic()
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    if res.returncode != 0:
        raise SystemExit(f"planning {demo} failed ({res.returncode}):\n{res.stdout}\n{res.stderr}")
    print(f"planned {demo} in {time.monotonic() - t0:.0f} s: {out / 'trajectory.csv'}", flush=True)
    return out / "trajectory.csv"


def newest_run(folder: Path, before: set[Path]) -> dict | None:
    """The ``"run"`` section of the newest recording's sidecar not in ``before`` (the
    recordings themselves are deleted: large)."""
    new = sorted(set(folder.glob("trajectory.run-*.json")) - before)
    if not new:
        return None
    doc = json.loads(new[-1].read_text())
    for p in new:  # the recordings are large: keep only their sidecars
        p.with_suffix(".csv").unlink(missing_ok=True)
    return doc.get("run")


def _check(run: dict, name: str) -> str | None:
    """The value of check ``name`` of the run's verdict, in words (None when absent)."""
    for c in (run.get("verdict") or {}).get("checks", []):
        if c.get("name") == name:
            return f"{c.get('value')} {c.get('unit', '')}".strip()
    return None


def feed_text(row: dict) -> str:
    """The feed per cut: ``name lowest-highest mm/s (set S: -a % / +b %)``."""
    parts = []
    for name, lo, hi, *set_tol in row["feed_mm_s"]:
        if not set_tol:  # a --json file from before the set feed was kept
            parts.append(f"{name} {lo}-{hi} mm/s")
            continue
        speed, tol = set_tol
        if lo is None or hi is None:
            parts.append(f"{name}: not measured (set {speed:g} mm/s)")
            continue
        parts.append(f"{name} {lo:.3f}-{hi:.3f} mm/s (set {speed:g} ± {100 * tol:g} %: "
                     f"{100 * (lo / speed - 1):+.2f} % / {100 * (hi / speed - 1):+.2f} %)")
    return "; ".join(parts) or "no feed measured"


def cpu_times() -> list[int]:
    """The machine's CPU counters (/proc/stat: user nice system idle iowait irq softirq
    steal), jiffies."""
    try:
        return [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:9]]
    except OSError:
        return [0] * 8


def whole_demo(args: argparse.Namespace) -> bool:
    """Whether each trial runs the whole ``ruledrobot demo`` (its default mode)."""
    return args.mode == "forward" and not args.run_only


def trial(demo: str, traj: Path, args: argparse.Namespace, normal: bool = False) -> dict:
    """One run of ``demo`` beside ``args.load`` busy processes; its figures (a dict)."""
    before = set(traj.parent.glob("trajectory.run-*.json"))
    cpu0, load0 = cpu_times(), os.getloadavg()[0]
    load = busy(args.load, args.timeout + 30)
    if whole_demo(args):
        cmd = demo_command(demo, traj.parent)
    else:
        cmd = [*CLI, "run", str(traj), "--yes", "--mode", args.mode]
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
        "mode": args.mode,
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
                       f["highest_m_s"] and 1e3 * f["highest_m_s"], 1e3 * f["speed_m_s"],
                       f["tolerance"]] for f in feeds],
        "hot_dwell": _check(run, "hot_dwell"),
        "priority": run.get("priority"),
        "load_before": round(load0, 2),
        "load_after": round(os.getloadavg()[0], 2),
        "idle_pct": round(100 * cpu[3] / total, 1),
        "steal_pct": round(100 * cpu[7] / total, 1),
        "emulator": [ln.strip() for ln in text.splitlines()
                     if ln.strip().startswith(("emulator:", "emulator clock:"))][:3],
        "message": run.get("message", text.strip().splitlines()[-1:] if text else ""),
    }  # fmt: skip
    if code != 0:
        row["tail"] = text.strip().splitlines()[-12:]
    return row


def trial_text(i: int, row: dict) -> str:
    """One line per trial: exit code, status, the feed against the set feed, the wire."""
    wire = row["wire_deviation_mm"]
    text = (f"{row['demo']} #{i}: exit {row['exit']}, {row['status']}, ok {row['ok']}; "
            f"{feed_text(row)}; wire {'-' if wire is None else f'{wire:.3f}'} mm from the "
            f"plan; {row['seconds']:.0f} s")  # fmt: skip
    if row["hot_dwell"] is not None:
        text += f"; hot dwell {row['hot_dwell']}"
    if row["skipped"]:
        text += f"; skipped {row['skipped']} (in the stock {row['skipped_in_stock']})"
    if row["exit"] != 0:
        text += f"\n    {row['failed']} {row['message']!s:.300}"
    for line in row["emulator"]:
        text += f"\n    {line}"
    return text


def summaries(rows: list[dict]) -> None:
    """The summary of ``rows``: per demo, mode and priority (:func:`summarize`)."""
    for demo in dict.fromkeys(r["demo"] for r in rows):
        mine = [r for r in rows if r["demo"] == demo]
        for mode in dict.fromkeys(r.get("mode", "?") for r in mine):
            same = [r for r in mine if r.get("mode", "?") == mode]
            for prio in sorted({r["priority"] or "?" for r in same}):
                summarize(demo, f"{mode}, {prio}",
                          [r for r in same if (r["priority"] or "?") == prio])


def main() -> None:
    """The trials (module doc), or ``--summarize`` a ``--json`` file written before."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--demos", default="demo,part", help="demo, part or both (comma)")
    ap.add_argument("--trials", type=int, default=10, help="runs of each demo")
    ap.add_argument("--load", type=int, default=2, help="busy processes beside each run")
    ap.add_argument("--timeout", type=float, default=600.0, help="per trial [s]")
    ap.add_argument("--mode", default="forward", choices=("forward", "servoj", "path"),
                    help="the run's mode; other than forward (the demo's), each trial runs "
                    "'ruledrobot run --mode MODE' on a plan made once")  # fmt: skip
    ap.add_argument("--run-only", action="store_true",
                    help="plan once, each trial 'ruledrobot run' (not the whole demo)")
    ap.add_argument("--out", type=Path, default=None, help="demo folders (default: a temp dir)")
    ap.add_argument("--json", type=Path, default=None, help="write every trial here")
    ap.add_argument("--compare-priority", action="store_true",
                    help="every other trial with the run's child at normal priority "
                    "(RULEDROBOT_RUN_PRIORITY=normal), to measure what the priority does")
    ap.add_argument("--summarize", type=Path, default=None,
                    help="only print the summary of a --json file written before")
    args = ap.parse_args()
    if args.summarize is not None:
        summaries(json.loads(args.summarize.read_text()))
        return
    base = args.out or Path(tempfile.mkdtemp(prefix="soak_stream_"))
    how = ("the whole 'ruledrobot demo' (forwarded)" if whole_demo(args)
           else f"'ruledrobot run --mode {args.mode}'")  # fmt: skip
    print(f"{args.trials} trials of each of {args.demos}: {how}, beside {args.load} busy "
          f"processes; folders in {base}", flush=True)  # fmt: skip
    rows = []
    for demo in args.demos.split(","):
        if whole_demo(args):
            (base / demo).mkdir(parents=True, exist_ok=True)
            traj = base / demo / "trajectory.csv"
        else:
            traj = plan(demo, base / demo, 1200.0)
        for i in range(args.trials):
            row = trial(demo, traj, args, normal=args.compare_priority and i % 2 == 1)
            rows.append(row)
            print(trial_text(i + 1, row), flush=True)
            if args.json:
                args.json.parent.mkdir(parents=True, exist_ok=True)
                args.json.write_text(json.dumps(rows, indent=1))
    print(f"\nsummary (load {args.load}):")
    summaries(rows)


def summarize(demo: str, what: str, rs: list[dict]) -> None:
    """One line per demo, mode and priority: completed, exit 0, the feed over all trials
    against the set feed, the wire, skips; then the trials that did not exit 0."""
    done = sum(r["status"] == "completed" for r in rs)
    ok = sum(r["exit"] == 0 for r in rs)
    sk = sorted(r["skipped"] for r in rs if r["skipped"] is not None)
    sl = [r["max_slip_ms"] for r in rs if r["max_slip_ms"] is not None]
    wires = [r["wire_deviation_mm"] for r in rs if r["wire_deviation_mm"] is not None]
    codes = sorted({str(r["exit"]) for r in rs})
    print(f"  {demo} ({what}): {done}/{len(rs)} completed, {ok} exit 0 (codes "
          f"{', '.join(codes)}); wire from the plan max {max(wires, default=float('nan')):.3f} "
          f"mm; skipped samples {sk} (in the stock max "
          f"{max((r['skipped_in_stock'] or 0) for r in rs)}); longest slip max "
          f"{max(sl, default=0):.1f} ms")  # fmt: skip
    cuts: dict[str, list] = {}
    for r in rs:
        for name, lo, hi, *set_tol in r["feed_mm_s"]:
            if set_tol:  # files from before the set feed was kept: no summary
                cuts.setdefault(name, []).append((lo, hi, set_tol[0]))
    for name, fs in cuts.items():
        los = [lo for lo, _, _ in fs if lo is not None]
        his = [hi for _, hi, _ in fs if hi is not None]
        speed = fs[0][2]
        if los and his:
            print(f"    feed {name}: {min(los):.3f}-{max(his):.3f} mm/s over {len(fs)} runs "
                  f"(set {speed:g}: {100 * (min(los) / speed - 1):+.2f} % / "
                  f"{100 * (max(his) / speed - 1):+.2f} %)")  # fmt: skip
    for r in rs:
        if r["exit"] != 0:
            print(f"    exit {r['exit']}: {r['status']} {r['failed']} {r['message']!s:.200}")


if __name__ == "__main__":
    main()
