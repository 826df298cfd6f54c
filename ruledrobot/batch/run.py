"""A batch from start to end: find the jobs, keep the results a rerun may keep, plan the
others on the engine, write each folder and the manifest as its result comes back.

:func:`run_batch` never lets one job stop the others: a job's bad input, failing
checks, exception or dead worker become its record (``batch.json``).  Ctrl-C
cancels the jobs in flight, closes the cluster and returns with the manifest true:
the jobs not planned are ``pending`` and a rerun of the same command plans them.
"""

from __future__ import annotations

import dataclasses
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

#: seconds between looks for finished jobs, and for newly joined workers while jobs wait
_POLL_S = 0.1
_REFILL_S = 2.0
#: seconds a local cluster may have no worker before the batch stops (workers that cannot
#: start: out of memory, a broken installation); a cluster's scheduler may wait for its
#: workers as long as it takes
NO_WORKER_S = 120.0


@dataclass(frozen=True)
class BatchProgress:
    """Where a batch stands.

    ``total`` jobs, ``kept`` (earlier results kept), ``to_plan`` (planned by this run), of
    which ``done`` have a result (``failed``: infeasible, bad input or crashed) and ``running``
    are on workers; ``elapsed_s`` since the run started; ``last`` the record that just came
    back; ``workers`` the worker threads the scheduler has (None: not started)."""

    total: int
    kept: int
    to_plan: int
    done: int
    failed: int
    running: int
    elapsed_s: float
    last: JobRecord | None = None
    workers: int | None = None

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
    """What :func:`run_batch` did.

    The records of the batch's jobs in order, how many it planned and kept, whether Ctrl-C
    stopped it, the engine it ran on, and why it stopped early if it did (``error``: the local
    cluster lost its workers)."""

    out: Path
    records: tuple[JobRecord, ...]
    planned: int
    kept: int
    interrupted: bool
    elapsed_s: float
    engine: dict[str, Any] | None = None
    error: str | None = None

    @property
    def manifest(self) -> Path:
        """The batch manifest ``batch.json`` in the output folder ``out``."""
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
    """The task of a job whose content was read with its input files' bytes."""
    inputs = tuple((str(f.path), f.data) for f in content.inputs if f.data is not None)
    return JobTask(content.entry.name, content.entry.label, str(content.job_path),
                   str(content.entry.path), content.text or b"", inputs, code)  # fmt: skip


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


def _record(content: JobContent, res: TaskResult, out: Path, code: str, wall_s: float,
            attempts: int) -> JobRecord:  # fmt: skip
    entry = content.entry
    base = JobRecord(entry.name, entry.label, res.status, content.digest, res.message,
                     res.failed_checks, now(), res.plan_s, max(0.0, wall_s - res.plan_s),
                     res.worker or None, code=code, attempts=attempts)  # fmt: skip
    if res.status not in ("feasible", "infeasible"):
        return base
    try:
        files = _write_folder(out, res)
    except (ValueError, OSError) as exc:
        return JobRecord(entry.name, entry.label, "bad_input", content.digest,
                         f"the plan could not be written: {exc}", (), base.planned_at,
                         base.plan_s, base.wait_s, base.worker, code=code,
                         attempts=attempts)  # fmt: skip
    report = next((json.loads(d) for rel, d in res.files if rel == "report.json"), {})
    figures, margins = figures_of(report)
    return JobRecord(entry.name, entry.label, res.status, content.digest, res.message,
                     res.failed_checks, base.planned_at, base.plan_s, base.wait_s,
                     base.worker, figures, margins, files, code, attempts)  # fmt: skip


def _crashed(content: JobContent, exc: BaseException, code: str, wall_s: float,
             attempts: int) -> JobRecord:  # fmt: skip
    """The record of a job whose task did not return: its worker died (KilledWorker), or
    the task raised (a result that could not be sent back, a cancelled task)."""
    entry = content.entry
    if type(exc).__name__ == "KilledWorker":
        times = "twice" if attempts > 1 else "while planning it"
        msg = (f"the worker planning it died {times}: killed, or out of memory? ({exc})")
    else:
        msg = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    return JobRecord(entry.name, entry.label, "crashed", content.digest, msg, (), now(), None,
                     wall_s, None, code=code, attempts=attempts)  # fmt: skip


def _outcome(future: Any) -> TaskResult | BaseException:
    """The task's result, fetched now (a result left on a worker dies with it), or the
    exception that stands for it."""
    try:
        return future.result()
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # KilledWorker, a cancelled task, an unpicklable result
        return exc


class _Batch:
    """The state of one run: the jobs' contents and records, what is left to plan, the
    counters.  Made without writing anything; :meth:`write` writes the manifest (after
    every result)."""

    def __init__(self, contents: list[JobContent], out: Path, prior: dict[str, JobRecord],
                 force: bool, progress: Callable[[BatchProgress], None] | None) -> None:
        self.t0 = time.perf_counter()
        self.contents, self.out, self.progress = contents, out, progress
        self.code = code_identity()
        self.records: list[JobRecord] = []
        self.todo: deque[int] = deque()
        self.attempts = [0] * len(contents)
        self.kept = self.done = self.failed = 0
        self.threads: int | None = None
        self.found: list[int] = []  # jobs found to be bad input without planning
        for i, c in enumerate(contents):
            e, old = c.entry, prior.get(c.entry.name)
            if not force and resumable(old, c.digest, out):
                self.records.append(old)  # type: ignore[arg-type]
                self.kept += 1
            elif c.error is not None:  # found without planning: unreadable, not TOML
                self.found.append(i)
                self.records.append(JobRecord(e.name, e.label, "bad_input", c.digest, c.error,
                                              planned_at=now(), code=self.code.id))  # fmt: skip
                self.done += 1
                self.failed += 1
            else:
                self.records.append(pending(e.name, e.label, c.digest, self.code.id))
                self.todo.append(i)
        self.to_plan = len(self.todo) + self.done
        names = {r.name for r in self.records}
        self.earlier = [r for n, r in prior.items() if n not in names]
        self.run: dict[str, Any] = {"started": now(), "finished": None, "interrupted": False,
                                    "error": None, "engine": None, "code": self.code.as_dict(),
                                    "jobs": len(self.records), "kept": self.kept,
                                    "planned": self.done}  # fmt: skip

    def write(self) -> None:
        self.run["planned"] = self.done
        write_manifest(self.out, self.records, self.earlier, self.run)

    def say(self, running: int, last: JobRecord | None = None) -> None:
        if self.progress is not None:
            self.progress(BatchProgress(len(self.records), self.kept, self.to_plan, self.done,
                                        self.failed, running, time.perf_counter() - self.t0,
                                        last, self.threads))  # fmt: skip

    def task(self, i: int) -> JobTask | None:
        """Job ``i``'s task, its files read now: a job or input file changed since the run
        started is planned as it is now, under its new hash; None: the job file is gone
        or broken now (recorded as bad input)."""
        self.attempts[i] += 1
        c = read_content(self.contents[i].entry, self.code.id, keep=True)
        self.contents[i] = dataclasses.replace(c, inputs=tuple(
            dataclasses.replace(f, data=None) for f in c.inputs))  # fmt: skip
        if c.digest != self.records[i].hash:
            self.records[i] = pending(c.entry.name, c.entry.label, c.digest, self.code.id)
        if c.error is None:
            return _task(c, self.code.id)
        e = c.entry
        self.add(i, JobRecord(e.name, e.label, "bad_input", c.digest, c.error,
                              planned_at=now(), code=self.code.id))  # fmt: skip
        return None

    def add(self, i: int, rec: JobRecord) -> None:
        """Job ``i``'s result: recorded, counted, written."""
        self.records[i] = rec
        self.done += 1
        self.failed += rec.failed
        self.write()

    def finish(self, i: int, outcome: TaskResult | BaseException, wall_s: float,
               retries: int) -> JobRecord | None:  # fmt: skip
        """Record job ``i``'s outcome (None: dispatched again after its worker died)."""
        c = self.contents[i]
        if isinstance(outcome, TaskResult):
            rec = _record(c, outcome, self.out, self.code.id, wall_s, self.attempts[i])
        elif type(outcome).__name__ == "KilledWorker" and self.attempts[i] <= retries:
            self.todo.appendleft(i)  # again, when a worker is free
            return None
        else:
            rec = _crashed(c, outcome, self.code.id, wall_s, self.attempts[i])
        self.add(i, rec)
        return rec


def _dispatch(b: _Batch, eng: Engine) -> str | None:
    """Plan ``b``'s jobs on ``eng``, at most one per worker thread in flight, each result
    recorded as it comes; returns why it stopped early (None: every job has a result).
    KeyboardInterrupt cancels the jobs in flight and goes on up."""
    inflight: dict[Any, tuple[int, float]] = {}
    ac = eng.as_completed()
    refill_at, staffed = 0.0, time.perf_counter()
    try:
        while b.todo or inflight:
            if time.perf_counter() >= refill_at:  # workers come and go: look again
                b.threads = threads = eng.threads()
                if threads:
                    staffed = time.perf_counter()
                elif eng.cluster is not None and time.perf_counter() - staffed > NO_WORKER_S:
                    eng.cancel(list(inflight))
                    return (f"the local cluster has had no worker for {NO_WORKER_S:g} s "
                            "(workers that cannot start: out of memory?); the jobs not "
                            "planned are pending")  # fmt: skip
                eng.heal(threads)
                while b.todo and len(inflight) < eng.slots(threads):
                    i = b.todo.popleft()
                    task = b.task(i)
                    if task is None:
                        b.say(len(inflight), b.records[i])
                        continue
                    key = f"ruledrobot-plan-{task.name}-{uuid.uuid4().hex[:8]}"
                    fut = eng.submit(run_task, task, key)
                    inflight[fut] = (i, time.perf_counter())
                    ac.add(fut)
                refill_at = time.perf_counter() + _REFILL_S
                b.say(len(inflight))
            if not ac.has_ready():
                time.sleep(_POLL_S)
                continue
            for fut in ac.next_batch(block=False):
                i, t_sub = inflight.pop(fut)
                outcome = _outcome(fut)
                fut.release()
                rec = b.finish(i, outcome, time.perf_counter() - t_sub, eng.client_retries)
                if rec is not None:
                    b.say(len(inflight), rec)
            refill_at = 0.0
    except KeyboardInterrupt:
        eng.cancel(list(inflight))
        raise
    return None


def run_batch(
    jobs: Sequence[str | Path] | Sequence[JobEntry],
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    progress: Callable[[BatchProgress], None] | None = None,
    timeout: float | None = None,
    quiet: bool = True,
) -> BatchResult:
    """Plan every job of ``jobs`` into ``out/<name>/`` and write the batch's summaries.

    ``jobs``: arguments for :func:`~.jobs.find_jobs`, or entries; the summaries are
    ``out/batch.json`` and ``out/batch.csv``.

    ``workers``: processes of the local cluster (default: sized to the machine);
    ``scheduler``: the address of a Dask scheduler to use instead; ``force``: replan
    jobs whose results a rerun would keep; ``progress``: called with a
    :class:`BatchProgress` whenever a job starts or ends; ``timeout``: seconds to
    reach the scheduler (default :data:`~.engine.TIMEOUT_S`); ``quiet``: silence Dask's
    log.  BatchInputError (and EngineUnavailable) for bad input to the batch itself;
    everything about a job goes into its record.
    """
    out = Path(out)
    entries = tuple(jobs) if jobs and all(isinstance(j, JobEntry) for j in jobs) else \
        find_jobs([str(j) for j in jobs], exclude=out)  # type: ignore[arg-type]  # fmt: skip
    eng = Engine(workers, scheduler, timeout=timeout, quiet=quiet)  # checks the options
    if out.exists() and not out.is_dir():
        raise BatchInputError(f"--out {out}: exists and is not a folder")
    prior = load_records(out) if out.is_dir() else {}
    code = code_identity().id
    b = _Batch([read_content(e, code) for e in entries], out, prior, force, progress)  # type: ignore[arg-type]
    interrupted, error = False, None
    try:
        if b.todo:
            with eng:  # started before anything is written: no scheduler is bad input
                out.mkdir(parents=True, exist_ok=True)
                b.run["engine"] = eng.describe()
                b.write()
                b.say(0)
                for i in b.found:  # bad input found without planning: shown with the others
                    b.say(0, b.records[i])
                error = _dispatch(b, eng)
    except KeyboardInterrupt:
        interrupted = True
    b.run.update(finished=now(), interrupted=interrupted, error=error)
    out.mkdir(parents=True, exist_ok=True)
    b.write()
    return BatchResult(out, tuple(b.records), b.done, b.kept, interrupted,
                       time.perf_counter() - b.t0, b.run["engine"], error)  # fmt: skip
