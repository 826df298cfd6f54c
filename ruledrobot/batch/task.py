"""The worker's task: plan one job from its text and its input files' bytes, return the
plan folder's files.

Workers need no shared file system: a :class:`JobTask` carries the job's effective
text and the bytes of every input file it names.  The worker writes the inputs into
a private temporary folder *at their client paths under it* (``<tmp>/in/<absolute
path>``), points the job's file fields there, plans with
:func:`ruledrobot.wirecut.planner.plan` (MuJoCo verification on, no video) into
``<tmp>/out``, and returns every file of the folder (its ``manifest.json`` is
rebuilt where the files land).  The job keeps the path the client names it by
(reports, ``trajectory.json``) and the input files keep the names ``plan`` would
give them (a calibration's source, error messages), so the files equal those of
``ruledrobot plan`` on that path.  Nothing is left in the temporary folder.

A task never raises for a job's sake: bad input (``ValueError`` from the job's
parser or the planner) and any other exception (with its traceback) come back as a
:class:`TaskResult`.  A worker whose ruledrobot differs from the client's (its
:func:`~.content.code_identity`) refuses the job.

**Test hook.**  When the environment variable ``RULEDROBOT_BATCH_TEST_KILL`` holds a
glob that matches the job's name, the worker kills its own process (``SIGKILL``) at
the planner's first progress message — mid-plan, the way the kernel's out-of-memory
killer would — after appending a line to the file named by
``RULEDROBOT_BATCH_TEST_KILL_LOG``, if set.  The tests use it to check that a dead
worker costs only its job; nothing else sets these variables.
"""

from __future__ import annotations

import dataclasses
import os
import signal
import socket
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from fnmatch import fnmatch
from pathlib import Path
from typing import Any

from ..io.outdir import MANIFEST, read_manifest
from ..wirecut.job.load import Job, file_fields, job_document, parse_job
from .content import code_identity, resolve_input

__all__ = ["KILL_HOOK", "KILL_LOG", "JobTask", "TaskResult", "run_task"]

KILL_HOOK = "RULEDROBOT_BATCH_TEST_KILL"
KILL_LOG = "RULEDROBOT_BATCH_TEST_KILL_LOG"


@dataclass(frozen=True)
class JobTask:
    """What a worker needs to plan one job.

    ``label`` the path the reports name, ``job_path`` the job file's absolute path on the
    client (its folder resolves relative paths) and ``named_path`` that path as the client
    names it, ``text`` the effective job's bytes, ``inputs`` ``(absolute client path, bytes)``
    of every input file that exists, ``code`` the client's code id."""

    name: str
    label: str
    job_path: str
    named_path: str
    text: bytes = field(repr=False)
    inputs: tuple[tuple[str, bytes], ...] = field(default=(), repr=False)
    code: str = ""


@dataclass(frozen=True)
class TaskResult:
    """A job's result.

    ``status`` feasible, infeasible, bad_input or crashed; ``message`` the verdict's summary,
    the bad input's message or the traceback; ``files`` ``(relative path, bytes)`` of the plan
    folder without its manifest, and ``info`` what that manifest said beside the files (kind,
    feasible, verdict); ``plan_s`` seconds the worker took; ``worker`` ``host:pid``."""

    name: str
    status: str
    message: str
    failed_checks: tuple[str, ...] = ()
    files: tuple[tuple[str, bytes], ...] = field(default=(), repr=False)
    info: dict[str, Any] = field(default_factory=dict)
    plan_s: float = 0.0
    worker: str = ""


def _where() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def _mirror(root: Path, path: str | Path) -> Path:
    """``path`` (absolute, on the client) inside ``root``."""
    p = Path(path)
    return root.joinpath(*p.parts[1:]) if p.is_absolute() else root / p


def _test_hook(name: str):
    pattern = os.environ.get(KILL_HOOK)
    if not pattern or not fnmatch(name, pattern):
        return None

    def kill(_msg: str) -> None:
        log = os.environ.get(KILL_LOG)
        if log:
            with open(log, "a", encoding="utf-8") as fh:
                fh.write(f"{name} {_where()}\n")
        os.kill(os.getpid(), signal.SIGKILL)

    return kill


def _folder_files(folder: Path) -> tuple[tuple[tuple[str, bytes], ...], dict[str, Any]]:
    paths = [p for p in sorted(folder.rglob("*")) if p.is_file() and p != folder / MANIFEST]
    files = tuple((p.relative_to(folder).as_posix(), p.read_bytes()) for p in paths)
    man = read_manifest(folder) or {}
    info = {k: v for k, v in man.items() if k not in ("format", "complete", "written", "files")}
    return files, info


def _as_named(job: Job, named: dict[str, str]) -> Job:
    """``job`` with the paths it carries into its files named as on the client: a
    calibration file without a ``source`` is known by its path (``trajectory.json``)."""
    cal = job.robot.calibration
    if cal is None or cal.source not in named:
        return job
    cal = dataclasses.replace(cal, source=named[cal.source])
    return dataclasses.replace(job, robot=dataclasses.replace(job.robot, calibration=cal))


def _plan(task: JobTask, tmp: Path, t0: float) -> TaskResult:
    from ..wirecut.planner import plan

    root = tmp / "in"
    for path, data in task.inputs:
        dst = _mirror(root, path)
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_bytes(data)
    job_path = Path(task.job_path)
    named: dict[str, str] = {}  # a path in the mirror -> the path ``plan`` would use

    def unmirror(msg: str) -> str:
        for mine in sorted(named, key=len, reverse=True):
            msg = msg.replace(mine, named[mine])
        return msg.replace(str(root), "")

    def result(status: str, message: str, **kw) -> TaskResult:
        return TaskResult(task.name, status, message, plan_s=time.perf_counter() - t0,
                          worker=_where(), **kw)  # fmt: skip

    try:
        doc = job_document(task.text.decode("utf-8"), task.label)
        for loc, value in file_fields(doc):
            table = doc
            for key in loc[:-1]:
                table = table[key]
            mine = str(_mirror(root, resolve_input(value, job_path)))
            table[loc[-1]] = mine
            named[mine] = str(resolve_input(value, Path(task.named_path)))
        job = parse_job(doc, task.label, base_dir=_mirror(root, job_path.parent))
        job = dataclasses.replace(_as_named(job, named), source=Path(task.label),
                                  source_bytes=task.text)  # fmt: skip
        out = tmp / "out" / task.name
        res = plan(job, out, progress=_test_hook(task.name), simulate=True, video=False)
    except UnicodeDecodeError as exc:
        return result("bad_input", f"{task.label}: cannot read ({exc})")
    except ValueError as exc:
        return result("bad_input", unmirror(str(exc)))
    files, info = _folder_files(out)
    failed = tuple(c.name for c in res.verdict.failed) if res.verdict is not None else ()
    status = "feasible" if res.feasible else "infeasible"
    return result(status, res.verdict.summary() if res.verdict else "", failed_checks=failed,
                  files=files, info=info)  # fmt: skip


def run_task(task: JobTask) -> TaskResult:
    """Plan ``task`` on this worker (see the module doc); never raises for the job's sake."""
    t0 = time.perf_counter()
    try:
        mine = code_identity().id
        if task.code and task.code != mine:
            return TaskResult(task.name, "crashed", f"worker {_where()} runs ruledrobot {mine}, "
                              f"the batch was started with {task.code}: install the same "
                              "version on every worker", plan_s=time.perf_counter() - t0,
                              worker=_where())  # fmt: skip
        with tempfile.TemporaryDirectory(prefix="ruledrobot-batch-") as tmp:
            return _plan(task, Path(tmp), t0)
    except Exception:
        return TaskResult(task.name, "crashed", traceback.format_exc(),
                          plan_s=time.perf_counter() - t0, worker=_where())  # fmt: skip
