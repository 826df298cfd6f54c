"""Finding the jobs of a batch: job files, globs and job lists, each job with its name.

An argument of ``ruledrobot batch`` is

* a job file (``.toml``, the format of ``ruledrobot plan``);
* a glob (``"pieces/*.toml"``, ``"**"`` recursive), for shells that leave it quoted;
* a **job list** (``.toml`` with ``[[jobs]]`` tables, or ``.json``), which names job
  files (or globs) relative to itself, each with an optional folder name and
  overrides of the job's fields (``docs/batch.md``)::

      [defaults]                 # optional: overrides for every job of the list
      robot = { speed_scale = 0.8 }

      [[jobs]]
      job = "pieces/p001.toml"   # a job file or a glob, relative to this file
      name = "p001"              # its output folder (default: the file's stem)
      overrides = { cut = { feed_speed = 0.012 }, stock = { centre = [0.5, 0.1, 0.3] } }

  JSON: ``{"defaults": {...}, "jobs": [{"job": ..., "name": ..., "overrides": {...}}]}``.

Overrides merge into the job's TOML document: a table merges into a table, any
other value (a number, a list, ``[[cut]]`` lists too) replaces the job's.  Paths
in overrides are taken from the job file's folder, as in the job itself.

Errors in the batch's own input — no such file, a pattern matching nothing, a job
list that cannot be read, two jobs with one name — raise :class:`BatchInputError`
naming the file, entry and field.  A broken *job* file is not an error of the
batch: it is planned as usual and reported as bad input.
"""

from __future__ import annotations

import copy
import glob
import json
import re
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["RESERVED_NAMES", "BatchInputError", "JobEntry", "find_jobs", "merge_overrides"]

#: names in the output folder that are not jobs' folders
RESERVED_NAMES = frozenset({"batch.json", "batch.csv"})
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}")
_LIST_KEYS = {"format", "defaults", "jobs"}
_ENTRY_KEYS = {"job", "name", "overrides"}
_MAGIC = set("*?[")


class BatchInputError(ValueError):
    """Bad input to the batch itself (exit 2): the message names the file, entry, field."""


@dataclass(frozen=True)
class JobEntry:
    """One job of a batch.

    ``name``: its output folder under the batch's folder; ``path``: the job file as
    named (relative paths from the current folder); ``overrides``: merged into the
    job's document (empty: the file is planned as it is); ``origin``: where the job
    was listed, for messages; ``job_list``: the job list that named it, if one did.
    ``label`` is the path its reports name.
    """

    name: str
    path: Path
    overrides: Mapping[str, Any] = field(default_factory=dict)
    origin: str = "command line"
    job_list: Path | None = None

    @property
    def label(self) -> str:
        """The job file's path.

        ``<job list>#<name>`` for a job changed by overrides (no file holds its text: the
        output folder's ``job.toml`` does)."""
        if not self.overrides:
            return str(self.path)
        return f"{self.job_list}#{self.name}"


def merge_overrides(doc: Mapping[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """``doc`` with ``overrides`` merged in (a copy): tables merge, other values replace."""
    out = copy.deepcopy(dict(doc))
    for key, value in overrides.items():
        if isinstance(value, Mapping) and isinstance(out.get(key), Mapping):
            out[key] = merge_overrides(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _check_name(name: object, where: str) -> str:
    if not isinstance(name, str) or not _NAME.fullmatch(name) or name in RESERVED_NAMES:
        raise BatchInputError(
            f"{where}: name: expected a folder name of letters, digits, '.', '_' and '-' "
            f"(at most 100, not starting with '.' or '-', not batch.json or batch.csv), "
            f"got {name!r}"
        )
    return name


def _expand(pattern: str, where: str, exclude: Path | None = None) -> list[Path]:
    """The files a glob matches (sorted), but none under ``exclude`` (the batch's output
    folder: its ``job.toml`` copies); BatchInputError when it matches none."""
    found = sorted(Path(p) for p in glob.glob(pattern, recursive=True) if Path(p).is_file())
    if exclude is not None:
        root = exclude.resolve()
        found = [p for p in found if not p.resolve().is_relative_to(root)]
    if not found:
        raise BatchInputError(f"{where}: pattern {pattern!r} matches no file"
                              + (f" outside {exclude}" if exclude is not None else ""))  # fmt: skip
    return found


def _is_job_list(path: Path) -> bool:
    """A ``.json`` file, or a ``.toml`` file with ``[[jobs]]`` tables (a job file has none)."""
    if path.suffix.lower() == ".json":
        return True
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return False  # a job file that cannot be read: reported as that job's bad input
    try:
        return "jobs" in tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return bool(re.search(r"^\s*(\[\[\s*jobs\s*\]\]|jobs\s*=)", text, re.MULTILINE))


def _read_list(path: Path) -> dict[str, Any]:
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise BatchInputError(f"{path}: cannot read the job list ({exc})") from None
    try:
        doc = json.loads(text) if path.suffix.lower() == ".json" else tomllib.loads(text)
    except (ValueError, tomllib.TOMLDecodeError) as exc:
        kind = "JSON" if path.suffix.lower() == ".json" else "TOML"
        raise BatchInputError(f"{path}: not valid {kind} ({exc})") from None
    if not isinstance(doc, dict):
        raise BatchInputError(f"{path}: expected a table with a list 'jobs', got "
                              f"{type(doc).__name__}")  # fmt: skip
    extra = sorted(set(doc) - _LIST_KEYS)
    if extra:
        raise BatchInputError(f"{path}: unknown field(s) {', '.join(extra)}; expected some of "
                              f"{', '.join(sorted(_LIST_KEYS))}")  # fmt: skip
    jobs = doc.get("jobs")
    if not isinstance(jobs, list) or not jobs:
        raise BatchInputError(f"{path}: jobs: expected a non-empty list of job entries "
                              "([[jobs]] tables)")  # fmt: skip
    defaults = doc.get("defaults", {})
    if not isinstance(defaults, dict):
        raise BatchInputError(f"{path}: defaults: expected a table of overrides, got "
                              f"{defaults!r}")  # fmt: skip
    return doc


def _from_list(path: Path) -> list[JobEntry]:
    doc = _read_list(path)
    defaults = doc.get("defaults", {})
    entries: list[JobEntry] = []
    for i, raw in enumerate(doc["jobs"], start=1):
        where = f"{path}, [[jobs]] entry {i}"
        if not isinstance(raw, dict):
            raise BatchInputError(f"{where}: expected a table with job, name, overrides")
        extra = sorted(set(raw) - _ENTRY_KEYS)
        if extra:
            raise BatchInputError(f"{where}: unknown field(s) {', '.join(extra)}; expected "
                                  "some of job, name, overrides")  # fmt: skip
        job = raw.get("job")
        if not isinstance(job, str) or not job:
            raise BatchInputError(f"{where}: job: expected the path of a job file (or a "
                                  f"glob), got {job!r}")  # fmt: skip
        over = raw.get("overrides", {})
        if not isinstance(over, dict):
            raise BatchInputError(f"{where}: overrides: expected a table, got {over!r}")
        overrides = merge_overrides(defaults, over)
        target = job if Path(job).is_absolute() else str(path.parent / job)
        if _MAGIC & set(job):
            if "name" in raw:
                raise BatchInputError(f"{where}: name: not with a glob ({job!r} may match "
                                      "several files; each is named by its stem)")  # fmt: skip
            files = _expand(target, where)
        else:
            files = [Path(target)]
            if not files[0].is_file():
                raise BatchInputError(f"{where}: job: no such job file: {files[0]}")
        for f in files:
            if f.suffix.lower() == ".json" or _is_job_list(f):
                raise BatchInputError(f"{where}: job: {f} is a job list; lists do not nest")
            name = _check_name(raw.get("name", f.stem), where)
            entries.append(JobEntry(name, f, overrides, where, path))
    return entries


def _from_path(path: Path, where: str) -> list[JobEntry]:
    if path.is_dir():
        raise BatchInputError(f"{where}: {path} is a folder; give its job files "
                              f"({path}/*.toml) or a job list")  # fmt: skip
    if not path.exists():
        raise BatchInputError(f"{where}: no such job file or job list: {path}")
    if _is_job_list(path):
        return _from_list(path)
    return [JobEntry(_check_name(path.stem, f"{where}: {path}"), path, {}, where)]


def find_jobs(args: Sequence[str | Path], exclude: Path | None = None) -> tuple[JobEntry, ...]:
    """The jobs named by ``args`` (job files, globs, job lists), in order; see the module doc.

    Globs on the command line match nothing under ``exclude`` (the batch's output folder).
    BatchInputError when an argument names nothing, a list is unreadable, no job is found, or
    two jobs would share an output folder."""
    entries: list[JobEntry] = []
    for arg in args:
        text = str(arg)
        where = "command line"
        if _MAGIC & set(text) and not Path(text).exists():
            for p in _expand(text, where, exclude):
                entries += _from_path(p, where)
        else:
            entries += _from_path(Path(text), where)
    if not entries:
        raise BatchInputError("no jobs: give job files (.toml), globs or job lists")
    seen: dict[str, JobEntry] = {}
    for e in entries:
        if e.name in seen:
            first = seen[e.name]
            raise BatchInputError(
                f"two jobs named {e.name!r} would share the output folder {e.name}/: "
                f"{first.path} ({first.origin}) and {e.path} ({e.origin}); name them in a "
                "job list (name = ...)"
            )
        seen[e.name] = e
    return tuple(entries)
