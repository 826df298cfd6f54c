"""Many jobs: batch planning on Dask — a local cluster by default, a cluster's scheduler
when the work outgrows one machine (``docs/batch.md``).

* :mod:`.jobs` — finding the jobs (files, globs, job lists with overrides) and names;
* :mod:`.content` — what a job is made of and its content hash, the code's identity;
* :mod:`.manifest` — ``batch.json`` / ``batch.csv``, the records, the resume rule;
* :mod:`.task` — the worker's task: plan one job from its bytes, return its files;
* :mod:`.engine` — Dask: the local cluster or a scheduler, one job per worker thread;
* :mod:`.run` — :func:`run_batch`, the whole batch.
* :mod:`.place` — the placement search's candidates scored on the same workers.

Planning itself is :func:`ruledrobot.wirecut.planner.plan`; this package only
distributes it.  Dask (the ``batch`` extra) is imported when a batch starts.
"""

from __future__ import annotations

from .engine import Engine, EngineUnavailable, default_workers, local_cluster
from .jobs import BatchInputError, JobEntry, find_jobs
from .manifest import JobRecord
from .run import BatchProgress, BatchResult, run_batch

__all__ = [
    "BatchInputError",
    "BatchProgress",
    "BatchResult",
    "Engine",
    "EngineUnavailable",
    "JobEntry",
    "JobRecord",
    "default_workers",
    "find_jobs",
    "local_cluster",
    "run_batch",
]
