"""Atomic file output: write to a temporary name in the target folder, then rename.

A reader never sees a half-written file and a failed write leaves nothing
behind (DESIGN: "Nothing is written half").
"""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

__all__ = ["JSON_INDENT", "atomic_open", "atomic_write_bytes", "atomic_write_json",
           "atomic_write_text"]

#: how ruledrobot's JSON files are laid out: one space per level (short lines, small
#: files), a newline at the end (the formatting rule of every JSON file the product writes)
JSON_INDENT = 1


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w", **kwargs) -> Iterator[IO]:
    """Open a temporary file beside ``path``; on success rename it onto ``path``.

    ``mode`` is "w" (text, utf-8 unless ``encoding`` is given, ``newline``
    passed through) or "wb".  On an exception the temporary file is removed and
    ``path`` is left as it was.  Missing parent folders are created.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open: mode must be 'w' or 'wb', got {mode!r}")
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        # mkstemp creates 0600; give the file the mode a plain open() would
        os.chmod(tmp, _mode_for(target))
        if mode == "w":
            kwargs.setdefault("encoding", "utf-8")
        with os.fdopen(fd, mode, **kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def _mode_for(target: Path) -> int:
    """The existing file's permission bits, else 0o666 less the process umask."""
    try:
        return target.stat().st_mode & 0o7777
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (utf-8) to ``path`` atomically; returns the path."""
    with atomic_open(path, "w") as fh:
        fh.write(text)
    return Path(path)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    with atomic_open(path, "wb") as fh:
        fh.write(data)
    return Path(path)


def _nonfinite(doc: object, where: str = "") -> str | None:
    """Return the path (``cuts[2].depth_mm``) of the first NaN or infinity in ``doc``."""
    if isinstance(doc, float):
        return None if math.isfinite(doc) else (where or "the document")
    items = (doc.items() if isinstance(doc, dict)
             else enumerate(doc) if isinstance(doc, list | tuple) else ())  # fmt: skip
    for k, v in items:
        found = _nonfinite(v, f"{where}[{k}]" if isinstance(k, int) else
                           (f"{where}.{k}" if where else str(k)))  # fmt: skip
        if found:
            return found
    return None


def atomic_write_json(path: str | os.PathLike[str], doc: object, *, compact: bool = False) -> Path:
    """Write ``doc`` as JSON to ``path`` atomically; return the path.

    Indented by :data:`JSON_INDENT`, with a final newline; ``compact``: no whitespace at
    all, for large arrays.  The one writer of the product's JSON files
    (``tests/architecture/test_one_home.py``).
    """
    import json

    try:  # strict JSON: NaN and Infinity are not JSON, other readers refuse them
        text = (json.dumps(doc, separators=(",", ":"), allow_nan=False) if compact
                else json.dumps(doc, indent=JSON_INDENT, allow_nan=False))  # fmt: skip
    except ValueError as exc:
        raise ValueError(f"{path}: {exc} at {_nonfinite(doc) or '?'} (write null, or a word, "
                         "for a value that is not a finite number)") from None
    return atomic_write_text(path, text + "\n")
