"""The guard of trajectory exports: an export replaces only an earlier export of its own
kind, never a run's recording, a folder or a file of the user's (``docs/trajectory.md``).

:func:`file_kind` tells what an existing file is from its first bytes (the trajectory
CSV's header, the sidecar's and the JSON export's ``format``, the NPZ's arrays, the
URScript program's second line) or its name (a recording); :func:`check_export_targets`
refuses an export whose targets hold anything else.
"""

from __future__ import annotations

import json
import os
import re
import zipfile
from pathlib import Path

import numpy as np

from .trajectory import HEADER, HEAT_POWER, META_FORMAT, TRAJECTORY_FORMAT, sidecar_path

__all__ = ["WouldReplace", "check_export_targets", "export_targets", "file_kind"]


class WouldReplace(ValueError):
    """An export would replace a file it did not write (the message names it)."""


#: what each export format writes, as :func:`file_kind` names files
_EXPORT_KINDS = {"csv": ("csv", "sidecar"), "json": ("json",), "npz": ("npz",),
                 "urscript": ("urscript",)}  # fmt: skip
_KIND_WORDS = {
    "csv": "a trajectory CSV", "sidecar": "a trajectory sidecar",
    "json": "a JSON trajectory export", "npz": "an NPZ trajectory export",
    "urscript": "a URScript program of ruledrobot", "recording": "the recording of a run",
    None: "a file ruledrobot did not write",
}  # fmt: skip
_RECORDING_NAME = re.compile(r".+(\.run-\d{3,}|\.actual)\.(csv|json)$")


def export_targets(path: str | os.PathLike[str], fmt: str) -> list[Path]:
    """The files an export of format ``fmt`` writes at ``path`` (a CSV: it and its sidecar)."""
    p = Path(path)
    return [p, sidecar_path(p)] if fmt == "csv" else [p]


def file_kind(path: Path) -> str | None:
    """Return what an existing file is, as far as exports go, or None.

    ``"csv"`` (first line the trajectory header), ``"sidecar"`` (a JSON object of format
    ``ruledrobot.trajectory-meta/1``), ``"json"`` (``ruledrobot.trajectory/1``), ``"npz"``
    (arrays ``t``, ``q``, ``tcp``, ``meta``), ``"urscript"`` (a program ruledrobot wrote: its
    second line), or ``"recording"`` (a run's recording: ``<stem>.run-NNN.csv/json`` or a
    sidecar with ``"run"``); None: anything else -- a file ruledrobot did not write."""
    if _RECORDING_NAME.fullmatch(path.name):
        return "recording"
    try:
        with path.open("rb") as f:
            head = f.read(4096)
    except OSError:
        return None
    suffix = path.suffix.lower()
    if suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as z:
                if {"t", "q", "tcp", "meta"} <= set(z.files):
                    doc = json.loads(str(z["meta"]))
                    return "npz" if doc.get("format") == META_FORMAT else None
        except (OSError, ValueError, zipfile.BadZipFile, AttributeError):
            return None
        return None
    text = head.decode("utf-8", errors="replace")
    first = text.splitlines()[:2]
    if first and first[0].strip() in (",".join(HEADER), ",".join([*HEADER, HEAT_POWER])):
        return "csv"
    if len(first) == 2 and first[0].startswith("def ") and \
            first[1].strip().startswith("# ruledrobot trajectory program"):  # fmt: skip
        return "urscript"
    if text.lstrip().startswith("{"):
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        if isinstance(doc, dict) and doc.get("format") == TRAJECTORY_FORMAT:
            return "json"
        if isinstance(doc, dict) and doc.get("format") == META_FORMAT:
            return "recording" if "run" in doc else "sidecar"
    return None


def _size(n: int) -> str:
    return f"{n / 1e6:.2f} MB" if n >= 1e5 else f"{n:,} bytes"


def check_export_targets(path: str | os.PathLike[str], fmt: str) -> None:
    """Refuse an export that would replace a file it did not write (:class:`WouldReplace`).

    An export of ``fmt`` at ``path``: each existing target must be of the kind the export
    writes there (:func:`file_kind`: a CSV over a trajectory CSV, a sidecar over a sidecar, a
    JSON export over a JSON export, ...).  Never over a recording of a run, a folder, a JSON
    export in the place of a sidecar, or a file of the user's."""
    wanted = _EXPORT_KINDS.get(fmt)
    if wanted is None:
        return
    for target, kind in zip(export_targets(path, fmt), wanted, strict=True):
        if not target.exists() and not target.is_symlink():
            continue
        if target.is_dir():
            raise WouldReplace(f"{target}: is a folder; the export would write a file there")
        found = file_kind(target)
        if found == kind:
            continue
        role = "" if target == Path(path) else f" (the sidecar of {Path(path).name})"
        raise WouldReplace(
            f"{target}: exists and is {_KIND_WORDS[found]} ({_size(target.stat().st_size)}); "
            f"the export would replace it with {_KIND_WORDS[kind]}{role}. An export replaces "
            "only an earlier export of its own kind: choose another name, or force it "
            "(--force)")
