"""The engine: Dask distributed — a local cluster of worker processes by default, or the
scheduler of a cluster the user runs.

* **Local** (no scheduler address): a ``distributed.LocalCluster`` on loopback with
  one single-threaded worker process per usable core (planning is CPU-bound numpy
  and MuJoCo; processes sidestep the GIL), fewer when memory is short
  (:data:`WORKER_MEMORY` each), no dashboard.  Each worker's nanny starts a new
  worker process in place of a dead one.  Its workers ignore SIGINT: a Ctrl-C in
  the terminal reaches the whole process group, and the client alone stops the
  batch (it cancels the jobs and closes the cluster).
* **Cluster** (``tcp://HOST:8786``): a ``distributed.Client`` of that scheduler.

**A worker that dies** (killed, out of memory) costs only the job it was planning.
The scheduler reports that job at once as ``KilledWorker`` (the local cluster's
scheduler runs with ``allowed_failures=0``) and the batch dispatches it once more,
when a worker is free; a second death is the job's record (``crashed``).  The
retry is the client's rather than the scheduler's (``allowed_failures=1``) because
the scheduler re-queues the job at once on any worker, behind the job that worker
is planning: when the job kills that worker too, the innocent job dies with it
(the tests saw it in 2 runs of 12).  A cluster's scheduler keeps its own setting
(:attr:`Engine.allowed_failures`): with 0 the batch retries once as above, with
more the scheduler retries that often and the batch not again; start it with
``DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES=0`` for the local behaviour.

The batch keeps at most one job per worker thread in flight (:meth:`Engine.slots`)
and fetches each result as soon as it is done: a worker never holds a queued job
or a result a later job could take down with it, and a Ctrl-C has only running
jobs to cancel.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from typing import Any

__all__ = [
    "TIMEOUT_S",
    "WORKER_MALLOC",
    "WORKER_MEMORY",
    "Engine",
    "EngineUnavailable",
    "default_workers",
    "local_cluster",
]

#: memory [bytes] each local worker should have (sizes the cluster; the nanny's limit is
#: the machine's memory shared out): a plan of the demo job peaks near 200 MB
WORKER_MEMORY = 1 << 30

#: seconds to reach a scheduler, or the local cluster's own, by default: an address where
#: nothing listens is retried until then (the tests make it shorter)
TIMEOUT_S = 10.0


class EngineUnavailable(RuntimeError):
    """Dask is not installed, or the scheduler cannot be reached (bad input: exit 2)."""


def _distributed():
    try:
        import distributed
    except ImportError:
        raise EngineUnavailable("batch planning needs Dask: pip install 'ruledrobot[batch]'"
                                ) from None  # fmt: skip
    return distributed


def default_workers() -> int:
    """Worker processes for this machine.

    Its usable cores, fewer when the available memory cannot give each :data:`WORKER_MEMORY`;
    at least one."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        cores = os.cpu_count() or 1
    try:
        import psutil

        by_memory = int(psutil.virtual_memory().available // WORKER_MEMORY)
    except ImportError:  # pragma: no cover - psutil comes with distributed
        by_memory = cores
    return max(1, min(cores, by_memory))


#: glibc malloc settings of the worker processes, set before they start (Dask's own
#: default, ``MALLOC_TRIM_THRESHOLD_=65536``, returns every freed block to the system:
#: numpy's large temporaries then page-fault afresh on every allocation — 1.65 M faults
#: and 40-60 % more time for the same placement scores, measured; docs/batch.md)
WORKER_MALLOC = {"MALLOC_TRIM_THRESHOLD_": 256 << 20, "MALLOC_MMAP_THRESHOLD_": 32 << 20}


def local_cluster(workers: int, quiet: bool = True):
    """A ``LocalCluster`` for planning.

    ``workers`` single-threaded processes on loopback (with :data:`WORKER_MALLOC`), a job whose
    worker died reported at once (the batch retries it), no dashboard."""
    distributed = _distributed()
    import dask

    env = {f"distributed.nanny.pre-spawn-environ.{k}": v for k, v in WORKER_MALLOC.items()}
    with dask.config.set(env):  # read by each nanny as it is made (and kept for restarts)
        return distributed.LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
            dashboard_address=None, scheduler_kwargs={"allowed_failures": 0},
            # quiet: the batch reports its jobs itself; a worker that loses the scheduler
            # while the batch stops (Ctrl-C on a busy machine) would print its traceback
            silence_logs=logging.CRITICAL if quiet else logging.WARNING,
        )  # fmt: skip


class Engine:
    """A Dask client for the batch.

    Use as a context manager (closes the client, and the local cluster it started).
    ``workers``: processes of the local cluster (default :func:`default_workers`);
    ``scheduler``: address of a running scheduler instead; ``timeout``: seconds to reach it
    (default :data:`TIMEOUT_S`)."""

    def __init__(self, workers: int | None = None, scheduler: str | None = None,
                 timeout: float | None = None, quiet: bool = True) -> None:  # fmt: skip
        if workers is not None and scheduler is not None:
            raise ValueError("--workers sizes the local cluster; with --scheduler the "
                             "cluster's own workers plan (start more of them there)")  # fmt: skip
        if workers is not None and workers < 1:
            raise ValueError(f"--workers: expected at least 1, got {workers}")
        self.scheduler = scheduler
        self.workers = workers if workers is not None or scheduler else default_workers()
        self.timeout = TIMEOUT_S if timeout is None else timeout
        self.quiet = quiet
        self.cluster: Any = None
        self.client: Any = None
        #: the scheduler's own retries of a job whose worker died (None: cannot ask)
        self.allowed_failures: int | None = None

    def __enter__(self) -> Engine:
        distributed = _distributed()
        if self.quiet:
            for name in ("distributed", "tornado"):
                logging.getLogger(name).setLevel(logging.CRITICAL)
        try:
            if self.scheduler is None:
                from ._plugin import IgnoreSigint

                self.cluster = local_cluster(self.workers, quiet=self.quiet)
                self.client = distributed.Client(self.cluster, timeout=self.timeout)
                self.client.register_plugin(IgnoreSigint())
            else:
                self.client = distributed.Client(self.scheduler, timeout=self.timeout)
        except (OSError, TimeoutError) as exc:
            self.close()
            where = self.scheduler or "a local cluster"
            raise EngineUnavailable(f"cannot reach the Dask scheduler at {where} within "
                                    f"{self.timeout:g} s ({exc}); is `dask scheduler` running "
                                    "there? (docs/batch.md)") from None  # fmt: skip
        except BaseException:
            self.close()
            raise
        self.allowed_failures = self._ask_allowed_failures()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the client and the local cluster (idempotent)."""
        client, cluster = self.client, self.cluster
        self.client = self.cluster = None
        if client is not None:
            try:
                client.close(timeout=10)
            except Exception:  # closing is best effort
                pass
        if cluster is not None:
            try:
                cluster.close(timeout=20)
            except Exception:
                pass

    def threads(self) -> int:
        """Worker threads the scheduler has now (0: no worker)."""
        return sum(self.client.nthreads().values())

    def slots(self, threads: int | None = None) -> int:
        """Jobs to keep in flight.

        One per worker thread, at least 1 (a job then waits for the first worker of a cluster
        that has none yet)."""
        return max(1, self.threads() if threads is None else threads)

    def heal(self, threads: int) -> None:
        """Local cluster: start workers in place of lost ones.

        A nanny restarts a dead worker; one that stayed away longer than
        ``distributed.deploy.lost-worker-timeout`` (15 s: a slow start on a loaded machine) is
        dropped by the cluster for good, and ``scale`` starts it again."""
        if self.cluster is not None and threads < self.workers:
            try:
                self.cluster.scale(self.workers)
            except Exception:  # healing is best effort; the batch's watchdog decides
                pass

    def _ask_allowed_failures(self) -> int | None:
        try:
            return int(self.client.run_on_scheduler(
                lambda dask_scheduler: dask_scheduler.allowed_failures))  # fmt: skip
        except Exception:  # an old or locked-down scheduler
            return None

    def describe(self) -> dict[str, Any]:
        """How the batch runs.

        ``kind`` local or cluster, scheduler address, workers, threads, the scheduler's allowed
        failures."""
        info = self.client.scheduler_info()
        workers = info.get("workers", {})
        return {
            "kind": "local" if self.scheduler is None else "cluster",
            "scheduler": self.client.scheduler.address,
            "workers": len(workers),
            "threads": sum(w.get("nthreads", 0) for w in workers.values()),
            "allowed_failures": self.allowed_failures,
            "client_retries": self.client_retries,
        }

    @property
    def client_retries(self) -> int:
        """How often the batch dispatches a job again after its worker died.

        Once when the scheduler does not retry (``allowed_failures=0``), else never."""
        return 1 if self.allowed_failures == 0 else 0

    def submit(self, fn: Callable[..., Any], arg: Any, key: str):
        """Run ``fn(arg)`` on a worker as task ``key``; the future."""
        return self.client.submit(fn, arg, key=key, pure=False, retries=0)

    def as_completed(self):
        """An empty ``distributed.as_completed`` to add futures to."""
        return _distributed().as_completed()

    def cancel(self, futures: list) -> None:
        """Cancel ``futures`` (best effort: the client may be closing)."""
        if futures and self.client is not None:
            try:
                self.client.cancel(futures, force=True)
            except Exception:
                pass
