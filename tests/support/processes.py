"""Child processes a test stops with Ctrl-C (SIGINT), started as a terminal would start them."""

from __future__ import annotations

import signal
import subprocess
import threading
from typing import Any

__all__ = ["popen_as_from_a_terminal"]


def popen_as_from_a_terminal(cmd: list[str], **kwargs: Any) -> subprocess.Popen:
    """Start ``cmd`` (``subprocess.Popen`` keywords) with Ctrl-C at its default.

    A test run started in the background (``nohup``, ``&`` in a script) ignores SIGINT
    and its children inherit that: a child then never sees the test's Ctrl-C (a batch
    planned to the end and exited 0; ``ursim`` ran on until the test killed it, exit -9,
    in a fresh-clone run started with ``&``).  Here SIGINT has a handler while the child
    starts, which ``exec`` resets to the default, as a terminal's foreground job has it
    (signal handlers are set from the main thread only; elsewhere the child inherits)."""
    main = threading.current_thread() is threading.main_thread()
    old = signal.signal(signal.SIGINT, signal.default_int_handler) if main else None
    try:
        return subprocess.Popen(cmd, **kwargs)
    finally:
        if main:
            signal.signal(signal.SIGINT, old)
