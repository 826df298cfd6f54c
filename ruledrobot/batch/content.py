"""What a job is made of, and its content hash: the job's text, every input file it
names, and the code that plans it.

The hash (SHA-256 of a canonical JSON document) covers

* the job's effective text (the file's bytes, or its document with the job list's
  overrides merged in, written back as TOML);
* every input file the job names (``[surface] file``, a G-code, airfoil, DXF or 3DM
  file, ``[robot] calibration``; :func:`ruledrobot.wirecut.job.load.file_fields`): the
  path as written and the SHA-256 of the bytes (or ``null``: missing);
* the code: ruledrobot's version and the SHA-256 of the sources that make a plan
  (:data:`PLANNING_CODE`: an uncommitted change counts too), and the plan's options.

The job's path is *not* hashed: moving the files, or running from another folder,
does not replan (the reports keep the path they were planned with).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from ..io.paths import input_path
from ..wirecut.job.load import file_fields, job_document
from .jobs import BatchInputError, JobEntry, merge_overrides

__all__ = ["HASH_FORMAT", "CodeIdentity", "InputFile", "JobContent", "code_identity",
           "read_content", "resolve_input"]  # fmt: skip

HASH_FORMAT = "ruledrobot.batch-hash/1"
#: options of the plan every batch job is planned with (part of the hash)
PLAN_OPTIONS = {"simulate": True, "video": False}


@dataclass(frozen=True)
class CodeIdentity:
    """The code that plans.

    ``version`` of ruledrobot, ``sources`` the SHA-256 of the ``.py`` files of
    :data:`PLANNING_CODE` (relative path and bytes, sorted), ``commit`` the git commit of the
    checkout it runs from (None when it is not one). ``id`` is what jobs are hashed with and
    what every worker must match."""

    version: str
    sources: str
    commit: str | None = None

    @property
    def id(self) -> str:
        """``version+sources``: the version and the first 16 hex digits of ``sources``."""
        return f"{self.version}+{self.sources[:16]}"

    def as_dict(self) -> dict[str, str | None]:
        """The identity as a JSON-ready dict.

        ``id``, ``version``, ``sources_sha256``, ``commit``."""
        return {"id": self.id, "version": self.version, "sources_sha256": self.sources,
                "commit": self.commit}  # fmt: skip


def _git_commit(folder: Path) -> str | None:
    try:
        out = subprocess.run(["git", "-C", str(folder), "rev-parse", "HEAD"], capture_output=True,
                             text=True, timeout=5, check=False)  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return None
    commit = out.stdout.strip()
    return commit if out.returncode == 0 and len(commit) == 40 else None


#: the packages a plan is made by (wirecut and the layers below it, docs/architecture.md)
#: and the batch's own task: a change anywhere else (the CLI, the viewer, the batch's
#: bookkeeping) does not replan
PLANNING_CODE = ("algorithms", "geometry", "io", "protocol", "robot", "sim", "subdivision",
                 "wirecut", "batch/task.py")  # fmt: skip


@functools.lru_cache(maxsize=1)
def code_identity() -> CodeIdentity:
    """The identity of the ruledrobot this process runs (computed once, about 10 ms)."""
    from importlib.metadata import PackageNotFoundError, version

    try:  # the installed distribution's version (the package root is above this layer)
        release = version("ruledrobot")
    except PackageNotFoundError:  # run from a source tree that is not installed
        release = "unknown"
    root = Path(__file__).resolve().parents[1]
    files = set(root.glob("*.py"))
    for part in PLANNING_CODE:
        files |= {root / part} if part.endswith(".py") else set((root / part).rglob("*.py"))
    h = hashlib.sha256()
    for p in sorted(files):
        h.update(p.relative_to(root).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(p.read_bytes()).digest())
    return CodeIdentity(release, h.hexdigest(), _git_commit(root))


@dataclass(frozen=True)
class InputFile:
    """An input file a job names.

    ``named`` as written in the job, ``path`` where it is on this machine (absolute,
    normalised), ``sha256`` of its bytes (None: cannot be read), ``data`` the bytes when they
    were kept (:func:`read_content`)."""

    named: str
    path: Path
    sha256: str | None
    data: bytes | None = field(default=None, repr=False)


@dataclass(frozen=True)
class JobContent:
    """A job read for planning.

    ``text`` the effective job's bytes (None when the job file cannot be read or is not valid
    TOML: ``error`` says why, a bad input found without planning), its input files, and
    ``digest``, the content hash."""

    entry: JobEntry
    text: bytes | None
    inputs: tuple[InputFile, ...]
    digest: str
    error: str | None = None

    @property
    def job_path(self) -> Path:
        """The job file, absolute (relative paths in the job are taken from its folder)."""
        return Path(os.path.abspath(self.entry.path))


def resolve_input(named: str, job_path: Path) -> Path:
    """Where an input file named ``named`` by the job file at ``job_path`` (absolute) is.

    Relative paths from the job's folder, normalised (:func:`ruledrobot.io.paths.input_path`,
    the one rule of every format)."""
    return input_path(named, job_path.parent)


def _digest(text: bytes | None, error: str | None, inputs: tuple[InputFile, ...],
            code: str) -> str:  # fmt: skip
    doc = {
        "format": HASH_FORMAT,
        "job": hashlib.sha256(text).hexdigest() if text is not None else None,
        "error": error,
        "inputs": [[f.named, f.sha256] for f in inputs],
        "code": code,
        "options": PLAN_OPTIONS,
    }
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def _read(path: Path) -> bytes | None:
    try:
        return path.read_bytes()
    except OSError:
        return None


def read_content(entry: JobEntry, code: str | None = None, keep: bool = False) -> JobContent:
    """Read ``entry``'s job file and every input file it names, apply its overrides, hash them.

    Hashed with ``code`` (default: this process's :func:`code_identity`).  ``keep``: keep
    the input files' bytes (to send them; a batch reads them again at dispatch rather than
    holding every job's inputs from the start).
    """
    code = code_identity().id if code is None else code
    path = entry.path
    job_path = Path(os.path.abspath(path))
    try:
        raw = path.read_bytes()
        doc = job_document(raw.decode("utf-8"), entry.label)
    except FileNotFoundError:
        return _bad(entry, f"{path}: no such job file", code)
    except (OSError, UnicodeDecodeError) as exc:
        return _bad(entry, f"{path}: cannot read ({exc})", code)
    except ValueError as exc:
        return _bad(entry, str(exc), code)
    if entry.overrides:
        try:
            import tomli_w
        except ImportError:
            raise BatchInputError(f"{entry.origin}: overrides need tomli-w (pip install "
                                  "'ruledrobot[batch]')") from None  # fmt: skip
        doc = merge_overrides(doc, entry.overrides)
        try:
            raw = tomli_w.dumps(doc).encode("utf-8")
        except (TypeError, ValueError) as exc:
            return _bad(entry, f"{entry.origin}: overrides: cannot be written as TOML ({exc})",
                        code)  # fmt: skip
    seen: dict[str, InputFile] = {}
    for _, named in file_fields(doc):
        where = resolve_input(named, job_path)
        if named not in seen:
            data = _read(where) if where.is_file() else None
            sha = None if data is None else hashlib.sha256(data).hexdigest()
            seen[named] = InputFile(named, where, sha, data if keep else None)
    inputs = tuple(seen[k] for k in sorted(seen))
    return JobContent(entry, raw, inputs, _digest(raw, None, inputs, code))


def _bad(entry: JobEntry, message: str, code: str) -> JobContent:
    return JobContent(entry, None, (), _digest(None, message, (), code), error=message)
