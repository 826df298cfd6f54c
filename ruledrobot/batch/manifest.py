"""The batch's result manifest: ``batch.json`` (the authority) and ``batch.csv`` (the same
table for a spreadsheet), in the batch's output folder.

One record per job: its status — ``feasible``, ``infeasible`` (the failing checks),
``bad_input`` (the message), ``crashed`` (the traceback, or the worker that died),
or ``pending`` (not planned: the run was stopped before, or is still going) — its
content hash, when and where it was planned and how long it took, the cut's
duration, the worst margins of its checks, and its output files.  Both files are
rewritten atomically (:mod:`ruledrobot.io.atomic`) after every job, so they are
true at every moment: a record is written only after its folder is in place.

A rerun skips a job whose record has the same hash and a final status
(``feasible``, ``infeasible``, ``bad_input``) and whose folder still holds the
files the record lists (:func:`resumable`); ``crashed`` and ``pending`` jobs are
planned again.
"""

from __future__ import annotations

import csv
import io
import json
import math
import time
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

from ..io.atomic import atomic_write_json, atomic_write_text
from ..io.outdir import read_manifest
from .jobs import BatchInputError

__all__ = ["BATCH_CSV", "BATCH_FORMAT", "BATCH_JSON", "FIGURES", "FINAL", "STATUSES",
           "JobRecord", "figures_of", "load_records", "now", "pending", "resumable",
           "write_manifest"]  # fmt: skip

BATCH_FORMAT = "ruledrobot.batch/1"
BATCH_JSON = "batch.json"
BATCH_CSV = "batch.csv"
STATUSES = ("feasible", "infeasible", "bad_input", "crashed", "pending")
#: statuses a rerun keeps (when the hash is unchanged)
FINAL = ("feasible", "infeasible", "bad_input")
#: figures of a plan's report.json copied into the record (units in the names)
FIGURES = (
    "duration_s", "cut_duration_s", "max_wire_deviation_mm", "max_planned_wire_deviation_mm",
    "feed_speed_mm_s", "max_feed_speed_mm_s", "min_feed_speed_mm_s", "max_joint_position_ratio",
    "max_joint_speed_ratio", "max_joint_accel_ratio", "max_joint_torque_ratio",
    "min_singularity_measure",
)  # fmt: skip


def now() -> str:
    """Local time, ISO 8601 with the UTC offset."""
    return time.strftime("%Y-%m-%dT%H:%M:%S%z")


@dataclass(frozen=True)
class JobRecord:
    """One job's line of the manifest.

    ``job``: the path its reports name; ``hash``: its content hash
    (:mod:`.content`); ``message``: the verdict's summary, the bad input's message or
    the crash's traceback; ``failed_checks``: the failing checks of an infeasible plan;
    ``planned_at``: when the result came back; ``plan_s``: seconds the worker spent on
    it; ``wait_s``: seconds from dispatch to result beyond that (queue, transfer,
    retries); ``worker``: ``host:pid`` of the worker; ``figures``: from the report
    (:data:`FIGURES`, and ``collisions``: their count); ``margins``: per gating check
    with a numeric, non-zero limit, the relative margin (limit - value) / |limit|
    (``<=`` checks; value - limit for ``>=``): negative fails (:attr:`worst_check`
    names the first failing check, else the smallest margin); ``files``: the output files,
    relative to the batch's folder; ``code``: the code identity it was planned with;
    ``attempts``: how often the batch dispatched it (2: its first worker died).
    """

    name: str
    job: str
    status: str
    hash: str
    message: str = ""
    failed_checks: tuple[str, ...] = ()
    planned_at: str | None = None
    plan_s: float | None = None
    wait_s: float | None = None
    worker: str | None = None
    figures: dict[str, Any] = field(default_factory=dict)
    margins: dict[str, float] = field(default_factory=dict)
    files: tuple[str, ...] = ()
    code: str | None = None
    attempts: int | None = None

    @property
    def worst_check(self) -> str | None:
        """The first failing check, else the check with the smallest margin."""
        if self.failed_checks:
            return self.failed_checks[0]
        return min(self.margins, key=self.margins.__getitem__) if self.margins else None

    @property
    def worst_margin(self) -> float | None:
        """Its margin (None: a check without a relative margin, e.g. collisions <= 0)."""
        return self.margins.get(self.worst_check) if self.worst_check else None

    @property
    def failed(self) -> bool:
        """Neither feasible nor waiting: infeasible, bad input or crashed."""
        return self.status in ("infeasible", "bad_input", "crashed")

    def as_dict(self) -> dict[str, Any]:
        """The record as a JSON-ready dict.

        Its fields (tuples as lists) plus ``worst_check`` and ``worst_margin``."""
        d = asdict(self)
        d["failed_checks"] = list(self.failed_checks)
        d["files"] = list(self.files)
        d["worst_check"], d["worst_margin"] = self.worst_check, self.worst_margin
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> JobRecord:
        """The record of a dict written by :meth:`as_dict`.

        Keys that are not fields (the derived ``worst_check`` / ``worst_margin``, or unknown
        ones) are ignored."""
        known = {f.name for f in fields(cls)}
        kw = {k: v for k, v in d.items() if k in known}
        kw["failed_checks"] = tuple(kw.get("failed_checks") or ())
        kw["files"] = tuple(kw.get("files") or ())
        return cls(**kw)


def figures_of(report: dict[str, Any]) -> tuple[dict[str, Any], dict[str, float]]:
    """The figures (:data:`FIGURES`, ``collisions``) and check margins of a plan's report."""
    figures = {k: report.get(k) for k in FIGURES if k in report}
    if "collisions" in report:
        figures["collisions"] = len(report["collisions"] or ())
    margins: dict[str, float] = {}
    for c in report.get("verdict", {}).get("checks", ()):
        value, limit, rel = c.get("value"), c.get("limit"), c.get("relation")
        numeric = all(isinstance(x, (int, float)) and not isinstance(x, bool)
                      for x in (value, limit))  # fmt: skip
        if not c.get("gating", True) or rel not in ("<=", ">=") or not numeric or limit == 0:
            continue
        m = (limit - value) / abs(limit) if rel == "<=" else (value - limit) / abs(limit)
        if math.isfinite(m):
            margins[c["name"]] = float(m)
    return figures, margins


def resumable(record: JobRecord | None, digest: str, out: Path) -> bool:
    """Whether a rerun may keep ``record`` for a job whose content hash is ``digest``.

    Same hash, a final status, and (planned jobs) the folder's completion marker and every file
    the record lists still there (sizes and checksums are not re-read)."""
    if record is None or record.hash != digest or record.status not in FINAL:
        return False
    if record.status == "bad_input":
        return True
    if read_manifest(out / record.name) is None:
        return False
    return all((out / f).is_file() for f in record.files)


def load_records(out: Path) -> dict[str, JobRecord]:
    """The records of an earlier run in ``out`` by job name (none: no ``batch.json``).

    BatchInputError when ``batch.json`` is there but is not a batch manifest."""
    path = out / BATCH_JSON
    if not path.exists():
        return {}
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(doc, dict) or doc.get("format") != BATCH_FORMAT:
            raise ValueError(f"format is not {BATCH_FORMAT!r}")
        rows = list(doc.get("jobs", [])) + list(doc.get("earlier", []))
        records = [JobRecord.from_dict(r) for r in rows]
    except (OSError, ValueError, TypeError, KeyError) as exc:
        raise BatchInputError(f"{path}: not a batch manifest of ruledrobot ({exc}); choose "
                              "another output folder or remove it") from None  # fmt: skip
    return {r.name: r for r in records}


_CSV_COLUMNS = (
    "name", "status", "job", "failed_checks", "message", "planned_at", "plan_s", "wait_s",
    "attempts",
    *FIGURES, "collisions", "worst_check", "worst_margin", "files", "worker", "hash",
)  # fmt: skip


def _csv_text(records: list[JobRecord]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(_CSV_COLUMNS)
    for r in records:
        row = r.as_dict()
        row.update(r.figures)
        row["failed_checks"] = ";".join(r.failed_checks)
        lines = r.message.strip().splitlines()
        row["message"] = (lines[-1] if r.status == "crashed" else lines[0]) if lines else ""
        row["files"] = len(r.files)
        w.writerow(["" if row.get(k) is None else row.get(k) for k in _CSV_COLUMNS])
    return buf.getvalue()


def write_manifest(out: Path, records: list[JobRecord], earlier: list[JobRecord],
                   run: dict[str, Any]) -> Path:  # fmt: skip
    """Write ``batch.json`` and ``batch.csv`` into ``out`` (each atomically).

    ``records`` the jobs of this run in order, ``earlier`` records of jobs of earlier runs that
    this one does not name (their folders are still there), ``run`` how and when."""
    counts = {s: sum(r.status == s for r in records) for s in STATUSES}
    doc = {
        "format": BATCH_FORMAT,
        "updated": now(),
        "complete": counts["pending"] == 0,
        "counts": counts,
        "run": run,
        "jobs": [r.as_dict() for r in records],
        "earlier": [r.as_dict() for r in earlier],
    }
    path = atomic_write_json(out / BATCH_JSON, doc)
    atomic_write_text(out / BATCH_CSV, _csv_text(records + earlier))
    return path


def pending(name: str, job: str, digest: str, code: str) -> JobRecord:
    """The record of a job not (yet) planned."""
    return JobRecord(name, job, "pending", digest, code=code)
