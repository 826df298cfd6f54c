"""Reading a user's text file with the project's error contract."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

__all__ = ["json_object", "read_user_bytes", "read_user_text", "user_text"]


def read_user_bytes(
    path: str | os.PathLike[str], kind: str = "file", error: type[ValueError] = ValueError
) -> tuple[Path, bytes]:
    """The path and the bytes of a user's file.

    ``error`` (a ValueError) names the file when it is missing (``"no such <kind>"``) or
    unreadable.
    """
    p = Path(path)
    try:
        return p, p.read_bytes()
    except FileNotFoundError:
        raise error(f"{p}: no such {kind}") from None
    except OSError as exc:
        raise error(f"{p}: cannot read ({exc})") from None


def user_text(path: Path, data: bytes, error: type[ValueError] = ValueError) -> str:
    """The utf-8 text of a file's bytes, with universal newlines.

    ``data`` are the bytes of the file ``path``, decoded as ``Path.read_text`` reads it;
    ``error`` names the file when they are not utf-8.
    """
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: cannot read ({exc})") from None
    return text.replace("\r\n", "\n").replace("\r", "\n")


def read_user_text(
    path: str | os.PathLike[str], kind: str = "file", error: type[ValueError] = ValueError
) -> tuple[Path, str]:
    """The path and the text of a user's utf-8 file.

    ``error`` (a ValueError) names the file when it is missing (``"no such <kind>"``) or
    unreadable.
    """
    p, data = read_user_bytes(path, kind, error)
    return p, user_text(p, data, error)


def json_object(
    text: str,
    where: str,
    error: type[ValueError] = ValueError,
    not_json: str = "line {line}: not valid JSON ({msg})",
) -> dict[str, Any]:
    """Return the JSON object the text of the file ``where`` holds.

    ``text`` is the file's text; ``error`` names the file when it is not JSON (``not_json``
    with the line and the parser's message) or not an object.
    """
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise error(f"{where}: " + not_json.format(line=exc.lineno, msg=exc.msg)) from None
    if not isinstance(doc, dict):
        raise error(f"{where}: expected a JSON object, got {type(doc).__name__}")
    return doc
