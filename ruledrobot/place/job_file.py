"""Writing a job file with the block moved (and, for setups, some of its cuts only).

The user's file is edited in place, line by line, so its comments and layout stay:
``[stock] centre`` and ``rotvec``, each cut's surface ``pose`` and ``keep`` point and
``[robot] base`` get the values of the placed job (:meth:`~.regions.Placement.job`);
cuts not kept are removed with their tables; paths to other files (``file``, ``calibration``,
``root``, ``tip``, ``gcode`` ...) are rewritten relative to the new file's folder.
The text written is read back with the job parser and compared with the moved job;
when the edit cannot be made (a table written inline, say) or does not read back
the same, the file is written whole from the parsed document instead (comments
lost, said in its first line).  Units: metres, radians (as in every job file).
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

import numpy as np

from ..geometry import se3
from ..io.atomic import atomic_write_text
from ..io.text import user_text
from ..io.toml_text import toml_document, toml_value
from ..wirecut.job.spec import Job

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["write_job_file"]

_HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\"' -]+?)\s*(\]\]?)\s*(#.*)?$")
_PATH_KEYS = ("file", "calibration", "root", "tip", "gcode", "airfoil", "dxf", "rhino")
_PATH = re.compile(r'(\b(?:' + "|".join(_PATH_KEYS) + r')\s*=\s*)"([^"]*)"')


def _vec(v) -> str:
    """A vector as a TOML list of floats."""
    return toml_value(np.asarray(v, dtype=float).ravel())


def _table_spans(lines: list[str]) -> list[tuple[str, int, int, int]]:
    """``(name, cut, first, end)`` of every table: its dotted name, the index of the
    ``[[cut]]`` entry it belongs to (-1: none), its header line and the line after it."""
    spans: list[tuple[str, int, int, int]] = []
    cut = -1
    for n, line in enumerate(lines):
        m = _HEADER.match(line)
        if not m or "=" in line.split("#")[0]:
            continue
        name = m.group(2).replace('"', "").replace("'", "").replace(" ", "")
        if m.group(1) == "[[" and name == "cut":
            cut += 1
        idx = cut if m.group(1) == "[[" or name.startswith("cut.") else -1
        if name != "cut" and not name.startswith("cut."):
            idx = -1
        if spans:
            spans[-1] = (*spans[-1][:3], n)
        spans.append((name, idx, n, len(lines)))
    return spans


def _set_key(lines: list[str], start: int, end: int, key: str, value: str) -> None:
    """Set ``key = value`` in the table whose header is line ``start`` (body up to ``end``):
    the old value (one line, or an array over several) is replaced, a comment after a
    one-line value kept; a missing key is added under the header."""
    pat = re.compile(rf"^(\s*{re.escape(key)}\s*=\s*)(.*)$")
    for n in range(start + 1, end):
        m = pat.match(lines[n])
        if not m:
            continue
        depth, last, text = 0, n, m.group(2)
        while True:
            code = text.split("#")[0]
            depth += code.count("[") - code.count("]")
            if depth <= 0 or last + 1 >= end:
                break
            last += 1
            text = lines[last]
        comment = ""
        if last == n and "#" in m.group(2):
            comment = "  #" + m.group(2).split("#", 1)[1]
        lines[n] = f"{m.group(1)}{value}{comment}"
        del lines[n + 1:last + 1]
        return
    lines.insert(start + 1, f"{key} = {value}")


def _rebase_paths(text: str, src: Path, dst: Path) -> str:
    """Relative paths that exist next to ``src`` rewritten relative to ``dst``'s folder."""

    def fix(m: re.Match) -> str:
        p = Path(m.group(2))
        if p.is_absolute() or not (src.parent / p).exists():
            return m.group(0)
        new = os.path.relpath((src.parent / p).resolve(), dst.parent.resolve())
        return f'{m.group(1)}"{Path(new).as_posix()}"'

    return _PATH.sub(fix, text)


def _edit(text: str, job: Job, keep_cuts: list[int] | None) -> str:
    """The file's text with the moved job's values (module doc); ValueError when a table
    to edit is not found (written inline, say)."""
    lines = text.splitlines()
    if keep_cuts is not None:
        drop = [(a, b) for _, i, a, b in _table_spans(lines) if i >= 0 and i not in keep_cuts]
        for a, b in sorted(drop, reverse=True):
            del lines[a:b]
    multi = any(i >= 0 for _, i, _, _ in _table_spans(lines))
    st = job.stock
    edits = [("stock", -1, "centre", _vec(st.centre)),
             ("stock", -1, "rotvec", _vec(se3.rotvec_from_matrix(st.rotation)))]  # fmt: skip
    for i, cut in enumerate(job.cuts):
        k = i if multi else -1
        pose = _vec(se3.ur_vector_from_pose(cut.surface.pose))
        edits.append(("cut.surface" if multi else "surface", k, "pose", pose))
        if cut.keep is not None and not isinstance(cut.keep, str):
            edits.append(("cut", k, "keep", _vec(cut.keep)))
    base = _vec(se3.ur_vector_from_pose(job.robot.base))
    has_robot = any(name == "robot" for name, _, _, _ in _table_spans(lines))
    if has_robot or not np.allclose(job.robot.base, np.eye(4)):
        edits.append(("robot", -1, "base", base))
    for table, k, key, value in edits:
        span = next(((a, b) for name, i, a, b in _table_spans(lines)
                     if name == table and i == k), None)  # fmt: skip
        if span is None:
            raise ValueError(f"table [{table}] not found")
        _set_key(lines, *span, key, value)
    return "\n".join(lines) + "\n"


def _close(a, b, tol: float = 1e-6) -> bool:
    return np.allclose(np.asarray(a, float), np.asarray(b, float), atol=tol)


def _same(job: Job, back: Job) -> bool:
    if len(job.cuts) != len(back.cuts) or [c.name for c in job.cuts] != [c.name for c in back.cuts]:
        return False
    if not (_close(job.stock.centre, back.stock.centre) and
            _close(job.stock.rotation, back.stock.rotation) and
            _close(job.robot.base, back.robot.base)):  # fmt: skip
        return False
    for a, b in zip(job.cuts, back.cuts, strict=True):
        if not _close(a.surface.pose, b.surface.pose):
            return False
        if (a.keep is None) != (b.keep is None):
            return False
        if a.keep is not None and not isinstance(a.keep, str) and not _close(a.keep, b.keep):
            return False
    return True


def write_job_file(
    job: Job,
    path: str | os.PathLike[str],
    *,
    keep_cuts: list[int] | None = None,
    note: str = "",
    check_as: str | os.PathLike[str] | None = None,
) -> Path:
    """Write ``job``, the moved job of ``job.source``'s file, to ``path`` (see the module doc).

    With the cuts ``keep_cuts`` (indices into the file's cuts; None: all).

    ``job`` has only the kept cuts, in order.  ``note`` is put first as a comment.
    ``check_as``: where the file will finally live (relative paths are written for
    that folder; default ``path``).  Returns ``path``.
    """
    from ..wirecut.job.load import load_job, parse_job

    if job.source is None:
        raise ValueError("write_job_file: the job has no source file to edit")
    src = Path(job.source)
    path = Path(path)
    final = Path(check_as) if check_as is not None else path
    # the bytes the job was loaded from (the job file is not read again), else the file
    text = (user_text(src, job.source_bytes) if job.source_bytes is not None
            else src.read_text(encoding="utf-8"))  # fmt: skip
    head = "".join(f"# {line}\n" for line in note.splitlines()) if note else ""
    try:
        out = head + _rebase_paths(_edit(text, job, keep_cuts), src, final)
        atomic_write_text(path, out)
        if _same(job, load_job(path)):
            return path
    except (ValueError, KeyError, StopIteration):
        pass
    doc = tomllib.loads(text)
    out = head + "# (written whole from the parsed job: the original's comments are not kept)\n"
    out += toml_document(_moved_doc(doc, job, keep_cuts))
    out = _rebase_paths(out, src, final)
    atomic_write_text(path, out)
    back = parse_job(tomllib.loads(out), str(path), base_dir=path.parent)
    if not _same(job, back):
        raise ValueError(f"{path}: the job written does not read back as the moved job")
    return path


def _moved_doc(doc: dict, job: Job, keep_cuts: list[int] | None) -> dict:
    doc = dict(doc)
    st = job.stock
    doc["stock"] = {**doc.get("stock", {}), "centre": list(map(float, st.centre)),
                    "rotvec": list(map(float, se3.rotvec_from_matrix(st.rotation)))}  # fmt: skip
    doc["robot"] = {**doc.get("robot", {}),
                    "base": list(map(float, se3.ur_vector_from_pose(job.robot.base)))}
    if isinstance(doc.get("cut"), list):
        entries = doc["cut"] if keep_cuts is None else [doc["cut"][i] for i in keep_cuts]
        new = []
        for entry, cut in zip(entries, job.cuts, strict=True):
            entry = dict(entry)
            entry["surface"] = {**entry.get("surface", {}),
                                "pose": list(map(float, se3.ur_vector_from_pose(cut.surface.pose)))}
            if cut.keep is not None and not isinstance(cut.keep, str):
                entry["keep"] = list(map(float, cut.keep))
            new.append(entry)
        doc["cut"] = new
    else:
        cut = job.cuts[0]
        doc["surface"] = {**doc.get("surface", {}),
                          "pose": list(map(float, se3.ur_vector_from_pose(cut.surface.pose)))}
        if cut.keep is not None and not isinstance(cut.keep, str):
            doc["cut"] = {**doc.get("cut", {}), "keep": list(map(float, cut.keep))}
    return doc
