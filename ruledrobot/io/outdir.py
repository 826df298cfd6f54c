"""Output folders that cannot mislead: written whole in a staging folder, swapped in at once.

:class:`StagedFolder` gives a fresh temporary folder beside the target (same file
system).  Results are written there; :meth:`StagedFolder.commit` writes the
completion marker ``manifest.json`` (every file with its size and SHA-256) and
puts the folder in place of the target in one step — ``renameat2`` with
``RENAME_EXCHANGE`` on Linux, which swaps the two folders atomically; elsewhere
two renames, the old folder moved aside first.  A run that fails or is killed
before the commit leaves the target as it was (the staging folder, named
``.<target>.staging-*``, is removed on failure, or by the next run).

The target must be new, empty, or an earlier output folder of ruledrobot (it
holds a ``manifest.json`` of ours, or only names this project writes): a folder
of the user's own files is never replaced, and neither is one where a user's file
was put beside the results (a name neither the manifest lists nor this project
writes): the error names it.

**Recordings survive.** The recordings of runs (``<stem>.run-NNN.csv`` and its
sidecar ``.json``, as the runner names them; the older ``<stem>.actual.csv/json``)
are the only evidence of what a robot did: :meth:`StagedFolder.commit` carries them
over into the new folder (hard links, else copies, before the swap), lists them in
the manifest's ``"kept"`` (not ``"files"``: they are not the plan's) and says so in
:attr:`StagedFolder.kept`.
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import os
import re
import shutil
import tempfile
import time
from fnmatch import fnmatch
from pathlib import Path
from typing import Any

from .atomic import atomic_write_json

__all__ = ["MANIFEST", "MANIFEST_FORMAT", "StagedFolder", "check_replaceable", "is_recording",
           "read_manifest"]

MANIFEST = "manifest.json"
MANIFEST_FORMAT = "ruledrobot.output/1"
#: Names an output folder of ruledrobot may hold (earlier versions wrote no manifest).
_OURS = {
    MANIFEST, "trajectory.csv", "trajectory.json", "refined.json", "surface.stl", "report.json",
    "plots.png", "simulation", "video.mp4", "strip.png", "job.toml", "cut.script", "reach.png",
    "reach.json", "part.stl",
}  # fmt: skip
_OUR_PATTERNS = ("*.run-*.csv", "*.run-*.json", "*.actual.csv", "*.actual.json", "cut.*")
#: recordings of runs (``export/run_plan.recording_path_for``): carried over, never replaced
_RECORDING = re.compile(r".+(\.run-\d{3,}|\.actual)\.(csv|json)$")


def is_recording(name: str) -> bool:
    """Whether a file name is a run's recording (or its sidecar)."""
    return _RECORDING.fullmatch(name) is not None


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths atomically (Linux ``renameat2(RENAME_EXCHANGE)``); False if unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    rc = fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), ctypes.c_uint(rename_exchange))
    return rc == 0


def read_manifest(folder: str | os.PathLike[str]) -> dict[str, Any] | None:
    """The completion marker of an output folder, or None when it has none."""
    p = Path(folder) / MANIFEST
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) and doc.get("format") == MANIFEST_FORMAT else None


def _replaceable(target: Path) -> str | None:
    """None if ``target`` may be replaced, else why not."""
    if not target.exists():
        return None
    if not target.is_dir():
        return f"{target} exists and is not a folder"
    man = read_manifest(target) or {}
    listed = {k.split("/")[0] for k in man.get("files", {})} | set(man.get("kept", {}))
    foreign = sorted(p.name for p in target.iterdir()
                     if p.name not in _OURS and p.name not in listed
                     and not p.name.startswith(".")
                     and not any(fnmatch(p.name, pat) for pat in _OUR_PATTERNS))  # fmt: skip
    if foreign:
        shown = ", ".join(foreign[:5]) + (" ..." if len(foreign) > 5 else "")
        return (f"{target} holds files that ruledrobot did not write ({shown}); move them, or "
                "choose a new or empty output folder")  # fmt: skip
    return None


def check_replaceable(target: str | os.PathLike[str]) -> None:
    """ValueError (saying why) when a plan may not replace the folder ``target``."""
    why = _replaceable(Path(target).absolute())
    if why is not None:
        raise ValueError(why)


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


class StagedFolder:
    """A staging folder for the results that will replace ``target`` as a whole.

    Use as a context manager: leaving it by an exception removes the staging
    folder and leaves ``target`` untouched.  Raises ValueError at once when
    ``target`` may not be replaced (see the module doc).
    """

    def __init__(self, target: str | os.PathLike[str]) -> None:
        self.target = Path(target).absolute()
        why = _replaceable(self.target)
        if why is not None:
            raise ValueError(why)
        self.target.parent.mkdir(parents=True, exist_ok=True)
        self._sweep()
        self.path = Path(tempfile.mkdtemp(prefix=f".{self.target.name}.staging-",
                                          dir=self.target.parent))  # fmt: skip
        self.committed = False
        #: recordings carried over from the folder replaced (names), set by :meth:`commit`
        self.kept: list[str] = []

    def _sweep(self) -> None:
        """Remove staging folders of runs that were killed (older than an hour)."""
        now = time.time()
        for p in self.target.parent.glob(f".{self.target.name}.staging-*"):
            try:
                if now - p.stat().st_mtime > 3600:
                    shutil.rmtree(p, ignore_errors=True)
            except OSError:
                pass

    def __enter__(self) -> StagedFolder:
        return self

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        if not self.committed:
            self.abort()

    def abort(self) -> None:
        """Remove the staging folder and what it holds; ``target`` is left untouched."""
        shutil.rmtree(self.path, ignore_errors=True)

    def commit(self, info: dict[str, Any] | None = None) -> Path:
        """Write ``manifest.json`` and put the staged folder in place of the target; return it.

        The manifest holds ``info`` plus every file's size and SHA-256; the target is
        returned.
        """
        files = {}
        for p in sorted(self.path.rglob("*")):
            if p.is_file():
                rel = p.relative_to(self.path).as_posix()
                files[rel] = {"bytes": p.stat().st_size, "sha256": _sha256(p)}
        kept = self._carry_recordings()
        doc = {"format": MANIFEST_FORMAT, "complete": True,
               "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"), **(info or {}),
               "files": files}  # fmt: skip
        if kept:
            doc["kept"] = kept
        atomic_write_json(self.path / MANIFEST, doc)
        os.chmod(self.path, 0o755)
        if not self.target.exists():
            os.rename(self.path, self.target)
        elif _exchange(self.path, self.target):
            shutil.rmtree(self.path, ignore_errors=True)  # now holds the old results
        else:
            old = self.target.with_name(f".{self.target.name}.old-{os.getpid()}")
            os.rename(self.target, old)
            os.rename(self.path, self.target)
            shutil.rmtree(old, ignore_errors=True)
        self.committed = True
        return self.target

    def _carry_recordings(self) -> dict[str, dict[str, Any]]:
        """Hard-link (else copy) the target's recordings into the staging folder; their
        sizes and SHA-256 by name."""
        kept: dict[str, dict[str, Any]] = {}
        if not self.target.is_dir():
            return kept
        for src in sorted(self.target.iterdir()):
            if not (src.is_file() and is_recording(src.name)):
                continue
            dst = self.path / src.name
            if dst.exists():  # never over a file of the new results
                continue
            try:
                os.link(src, dst)
            except OSError:
                shutil.copy2(src, dst)
            kept[src.name] = {"bytes": dst.stat().st_size, "sha256": _sha256(dst)}
        self.kept = sorted(kept)
        return kept
