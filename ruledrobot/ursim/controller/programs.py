"""The controller's program folder: which files the dashboard may load."""

from __future__ import annotations

from pathlib import Path

__all__ = ["program_in"]


def program_in(root: Path | None, path: str) -> Path | None:
    """Return the file ``path`` names inside the folder ``root``, or None.

    ``path`` relative to ``root``, or absolute within it, symbolic links resolved; None:
    no folder, outside it, missing, not a file (the dashboard's ``load``).
    """
    if root is None or not path or "\x00" in path:
        return None
    p = Path(path)
    try:
        real = (p if p.is_absolute() else root / p).resolve(strict=True)
    except (OSError, RuntimeError, ValueError):
        return None
    return real if real.is_relative_to(root) and real.is_file() else None
