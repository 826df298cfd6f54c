"""Which files a piece of code opens: every ``open`` audit event (``open``, ``io.open``,
``Path.read_*``, ``os.open``, numpy's loaders) under a folder, recorded while a block runs.

Python's audit hooks cannot be removed, so one hook is installed once per process and
records only while a :func:`opened_under` block is active.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["opened_under"]

_WATCHES: list[tuple[str, list[str]]] = []  # (folder, paths opened under it), while active
_installed = False


def _hook(event: str, args: tuple) -> None:
    if event != "open" or not _WATCHES or not isinstance(args[0], (str, bytes, os.PathLike)):
        return
    path = os.path.realpath(os.fsdecode(args[0]))
    for folder, seen in _WATCHES:
        if path == folder or path.startswith(folder + os.sep):
            seen.append(path)


@contextmanager
def opened_under(folder: str | os.PathLike[str]) -> Iterator[list[str]]:
    """The list (filled while the block runs) of the absolute paths under ``folder`` that
    the process tried to open, found or not."""
    global _installed
    if not _installed:
        sys.addaudithook(_hook)
        _installed = True
    seen: list[str] = []
    watch = (os.path.realpath(Path(folder)), seen)
    _WATCHES.append(watch)
    try:
        yield seen
    finally:
        _WATCHES.remove(watch)
