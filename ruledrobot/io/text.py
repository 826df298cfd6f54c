"""Reading a user's text file with the project's error contract."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["read_user_text"]


def read_user_text(path: str | os.PathLike[str], kind: str = "file") -> tuple[Path, str]:
    """``(path, text)`` of a utf-8 file; ValueError naming the file when it is missing
    (``"no such <kind>"``) or unreadable."""
    p = Path(path)
    try:
        return p, p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ValueError(f"{p}: no such {kind}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{p}: cannot read ({exc})") from None
