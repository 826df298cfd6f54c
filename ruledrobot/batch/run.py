"""A batch from start to end: find the jobs, keep the results a rerun may keep, plan the
others on the engine, write each folder and the manifest as its result comes back.

:func:`run_batch` never lets one job stop the others: a job's bad input, failing
checks, exception or dead worker become its record (``batch.json``).  Ctrl-C
cancels the jobs in flight, closes the cluster and returns with the manifest true:
the jobs not planned are ``pending`` and a rerun of the same command plans them.
"""

from __future__ import annotations

import json
import time
import traceback
import uuid
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..io.outdir import StagedFolder
from .content import JobContent, code_identity, read_content
from .engine import Engine
from .jobs import BatchInputError, JobEntry, find_jobs
from .manifest import (
    JobRecord,
    figures_of,
    load_records,
    now,
    pending,
    resumable,
    write_manifest,
)
from .task import JobTask, TaskResult, run_task

__all__ = ["BatchProgress", "BatchResult", "run_batch"]

#: seconds between looks for newly joined workers while jobs wait
_POLL_S = 0.1
_REFILL_S = 2.0


@dataclass(frozen=True)
class BatchProgress:
    """Where a batch stands: ``total`` jobs, ``kept`` (earlier results kept),
    ``to_plan`` (planned by this run), of which ``done`` have a result (``failed``:
    infeasible, bad input or crashed) and ``running`` are on workers; ``elapsed_s``
    since the run started; ``last`` the record that just came back."""

    total: int
    kept: int
    to_plan: int
    done: int
    failed: int
    running: int
    elapsed_s: float
    last: JobRecord | None = None

    @property
    def throughput(self) -> float | None:
        """Jobs per second this run has planned (None before the first)."""
        return self.done / self.elapsed_s if self.done and self.elapsed_s > 0 else None

    @property
    def eta_s(self) -> float | None:
        """Seconds left at the throughput so far (None before the first result)."""
        rate = self.throughput
        return None if rate is None else (self.to_plan - self.done) / rate


@dataclass(frozen=True)
class BatchResult:
    """What :func:`run_batch` did: the records of the batch's jobs in order, how many it
    planned and kept, whether Ctrl-C stopped it, the engine it ran on."""

    out: Path
    records: tuple[JobRecord, ...]
    planned: int
    kept: int
    interrupted: bool
    elapsed_s: float
    engine: dict[str, Any] | None = None

    @property
    def manifest(self) -> Path:
        return self.out / "batch.json"

    @property
    def not_feasible(self) -> tuple[JobRecord, ...]:
        """Jobs that are not feasible: infeasible, bad input, crashed, or not planned."""
        return tuple(r for r in self.records if r.status != "feasible")

    @property
    def exit_code(self) -> int:
        """0 every job feasible; 1 some job is not; 130 stopped by Ctrl-C."""
        if self.interrupted:
            return 130
        return 1 if self.not_feasible else 0


def _task(content: JobContent, code: str) -> JobTask:
    inputs = tuple((str(f.path), f.data) for f in content.inputs if f.data is not None)
    return JobTask(content.entry.name, content.entry.label, str(content.job_path),
                   content.text or b"", inputs, code)  # fmt: skip


def _write_folder(out: Path, res: TaskResult) -> tuple[str, ...]:
    """The plan folder's files written to ``out/<name>`` as a whole (staged, swapped in,
    ``manifest.json`` rebuilt); their paths relative to ``out``."""
    with StagedFolder(out / res.name) as stage:
        for rel, data in res.files:
            p = stage.path / rel
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(data)
        stage.commit(res.info)
    names = sorted([rel for rel, _ in res.files] + ["manifest.json"])
    return tuple(f"{res.name}/{rel}" for rel in names)


def _record(content: JobContent, res: TaskResult, out: Path, code: str,
            wall_s: float) -> JobRecord:  # fmt: skip
    entry = content.entry
    base = JobRecord(entry.name, entry.label, res.status, content.digest, res.message,
                     res.failed_checks, now(), res.plan_s, max(0.0, wall_s - res.plan_s),
                     res.worker or None, code=code)  # fmt: skip
    if res.status not in ("feasible", "infeasible"):
        return base
    try:
        files = _write_folder(out, res)
    except (ValueError, OSError) as exc:
        return JobRecord(entry.name, entry.label, "bad_input", content.digest,
                         f"the plan could not be written: {exc}", (), base.planned_at,
                         base.plan_s, base.wait_s, base.worker, code=code)  # fmt: skip
    report = next((json.loads(d) for rel, d in res.files if rel == "report.json"), {})
    figures, margins = figures_of(report)
    return JobRecord(entry.name, entry.label, res.status, content.digest, res.message,
                     res.failed_checks, base.planned_at, base.plan_s, base.wait_s,
                     base.worker, figures, margins, files, code)  # fmt: skip


def _failed_future(content: JobContent, future: Any, code: str, wall_s: float) -> JobRecord:
    """The record of a job whose task did not return: its worker died twice (KilledWorker),
    or the task raised (a result that could not be sent back, a cancelled task)."""
    entry = content.entry
    exc = future.exception() if future.status == "error" else None
    if type(exc).__name__ == "KilledWorker":
        msg = (f"the worker planning it died, and so did the one that tried again: killed, "
               f"or out of memory? ({exc})")  # fmt: skip
    elif exc is not None:
        tb = future.traceback()
        msg = "".join(traceback.format_exception(type(exc), exc, tb))
    else:
        msg = f"the task ended as {future.status!r} without a result"
    return JobRecord(entry.name, entry.label, "crashed", content.digest, msg, (), now(), None,
                     wall_s, None, code=code)  # fmt: skip


def run_batch(
    jobs: Sequence[str | Path] | Sequence[JobEntry],
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    progress: Callable[[BatchProgress], None] | None = None,
    timeout: float = 10.0,
    quiet: bool = True,
) -> BatchResult:
    """Plan every job of ``jobs`` (arguments for :func:`~.jobs.find_jobs`, or entries)
    into ``out/<name>/`` and write ``out/batch.json`` and ``out/batch.csv``.

    ``workers``: processes of the local cluster (default: sized to the machine);
    ``scheduler``: the address of a Dask scheduler to use instead; ``force``: replan
    jobs whose results a rerun would keep; ``progress``: called with a
    :class:`BatchProgress` whenever a job starts or ends; ``timeout``: seconds to
    reach the scheduler.  BatchInputError (and EngineUnavailable) for bad input to the
    batch itself; everything about a job goes into its record.
    """
    t0 = time.perf_counter()
    entries = tuple(jobs) if jobs and all(isinstance(j, JobEntry) for j in jobs) else \
        find_jobs([str(j) for j in jobs])  # type: ignore[arg-type]  # fmt: skip
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise BatchInputError(f"--out {out}: exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    prior = load_records(out)
    code = code_identity()
    contents = [read_content(e, code.id) for e in entries]  # type: ignore[arg-type]
    records: list[JobRecord] = []
    todo: deque[int] = deque()
    kept = done = failed = 0
    for i, c in enumerate(contents):
        e, old = c.entry, prior.get(c.entry.name)
        if not force and resumable(old, c.digest, out):
            records.append(old)  # type: ignore[arg-type]
            kept += 1
        elif c.error is not None:  # found without planning: unreadable, not TOML
            records.append(JobRecord(e.name, e.label, "bad_input", c.digest, c.error,
                                     planned_at=now(), code=code.id))  # fmt: skip
            done += 1
            failed += 1
        else:
            records.append(pending(e.name, e.label, c.digest, code.id))
            todo.append(i)
    names = {r.name for r in records}
    earlier = [r for n, r in prior.items() if n not in names]
    run: dict[str, Any] = {"started": now(), "finished": None, "interrupted": False,
                           "engine": None, "code": code.as_dict(), "jobs": len(records),
                           "kept": kept, "planned": done}  # fmt: skip
    write_manifest(out, records, earlier, run)
    to_plan = len(todo) + done

    def say(running: int, last: JobRecord | None = None) -> None:
        if progress is not None:
            progress(BatchProgress(len(records), kept, to_plan, done, failed, running,
                                   time.perf_counter() - t0, last))  # fmt: skip

    say(0)
    interrupted = False
    engine_info = None
    inflight: dict[Any, tuple[int, float]] = {}
    try:
        if todo:
            with Engine(workers, scheduler, timeout=timeout, quiet=quiet) as eng:
                engine_info = run["engine"] = eng.describe()
                write_manifest(out, records, earlier, run)
                ac = eng.as_completed()
                try:
                    refill_at = 0.0
                    while todo or inflight:
                        if todo and time.perf_counter() >= refill_at:
                            slots = eng.slots()
                            while todo and len(inflight) < slots:
                                i = todo.popleft()
                                key = f"ruledrobot-plan-{contents[i].entry.name}-" \
                                      f"{uuid.uuid4().hex[:8]}"  # fmt: skip
                                fut = eng.submit(run_task, _task(contents[i], code.id), key)
                                inflight[fut] = (i, time.perf_counter())
                                ac.add(fut)
                            refill_at = time.perf_counter() + _REFILL_S
                            say(len(inflight))
                        if not ac.has_ready():
                            time.sleep(_POLL_S)
                            continue
                        for fut in ac.next_batch(block=False):
                            i, t_sub = inflight.pop(fut)
                            wall = time.perf_counter() - t_sub
                            if fut.status == "finished":
                                rec = _record(contents[i], fut.result(), out, code.id, wall)
                            else:
                                rec = _failed_future(contents[i], fut, code.id, wall)
                            fut.release()
                            records[i] = rec
                            done += 1
                            failed += rec.failed
                            run["planned"] = done
                            write_manifest(out, records, earlier, run)
                            say(len(inflight), rec)
                        refill_at = 0.0
                except KeyboardInterrupt:
                    eng.cancel(list(inflight))
                    raise
    except KeyboardInterrupt:
        interrupted = True
    run["finished"], run["interrupted"] = now(), interrupted
    write_manifest(out, records, earlier, run)
    return BatchResult(out, tuple(records), done, kept, interrupted, time.perf_counter() - t0,
                       engine_info)  # fmt: skip
