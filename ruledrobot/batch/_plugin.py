"""A Dask worker plugin of the local cluster (imported only when a local cluster starts).

Ctrl-C in a terminal sends SIGINT to the whole process group — the client and the
local cluster's worker processes.  The client alone handles it (it cancels the jobs
and closes the cluster); the workers ignore it, so they print no tracebacks and end
when the cluster closes them.  Registered with the scheduler, the plugin also
reaches the workers a nanny starts in place of dead ones.
"""

from __future__ import annotations

import signal
import threading

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["IgnoreSigint"]


class IgnoreSigint(WorkerPlugin):
    """Make a worker process ignore SIGINT (set from its main thread, where it runs)."""

    idempotent = True
    name = "ruledrobot-ignore-sigint"

    def setup(self, worker) -> None:
        """Ignore SIGINT in ``worker``'s process (only when called from its main thread)."""
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
