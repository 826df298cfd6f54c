"""Reading and writing line sequences: JSON (``ruledrobot.lines/1``) and CSV.

JSON::

    {"format": "ruledrobot.lines/1", "units": "m", "closed": false,
     "lines": [{"point": [0, 0, 0], "direction": [1, 0, 0]}, ...]}

``"lines"`` may instead hold Plücker rows ``[l1, l2, l3, m1, m2, m3]``.  A refined
file may add ``"frames"`` (row-major 4x4 each) and ``"striction"`` (points).
CSV: header ``px,py,pz,dx,dy,dz``, one line per row (``#`` comments allowed;
a comment ``# closed: true`` marks a closed sequence).

Units: ``"units"`` (JSON) or a comment ``# units: mm`` (CSV, before the header)
may be ``"m"`` (the default), ``"cm"``, ``"mm"`` or ``"in"``; lengths (points,
moments, frame translations, striction points) are converted to metres on
reading.  Files are always written in metres.

Every error names the file and the item (JSON index, CSV line number).
"""

from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.checks import FloatArray
from ..geometry.lines import Lines, plucker_from_point_direction, validate_plucker
from .atomic import atomic_write_json, atomic_write_text
from .text import json_object, read_user_text
from .units import unit_scale

__all__ = ["FORMAT", "LinesDocument", "load_lines", "read_lines_document", "save_lines"]

FORMAT = "ruledrobot.lines/1"
CSV_HEADER = ["px", "py", "pz", "dx", "dy", "dz"]


@dataclass(frozen=True)
class LinesDocument:
    """Contents of a lines file: the lines, whether closed, optional frames/striction."""

    lines: Lines
    closed: bool = False
    frames: FloatArray | None = field(default=None, repr=False)
    striction: FloatArray | None = field(default=None, repr=False)


def _vector(value: object, n: int, where: str) -> list[float]:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise ValueError(f"{where}: expected a list of {n} numbers, got {value!r}")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ValueError(f"{where}: expected numbers, got {v!r}")
        out.append(float(v))
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{where}: contains NaN or infinity")
    return out


def _lines_from_entries(entries: list, where: str) -> Lines:
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{where}: 'lines' must be a non-empty list")
    if all(isinstance(e, dict) for e in entries):
        pts, dirs = [], []
        for i, e in enumerate(entries):
            missing = {"point", "direction"} - set(e)
            if missing:
                raise ValueError(f"{where}: lines[{i}] lacks {sorted(missing)}")
            pts.append(_vector(e["point"], 3, f"{where}: lines[{i}].point"))
            dirs.append(_vector(e["direction"], 3, f"{where}: lines[{i}].direction"))
        d = np.asarray(dirs)
        zero = np.linalg.norm(d, axis=1) <= 1e-12
        if zero.any():
            raise ValueError(f"{where}: lines[{int(np.argmax(zero))}].direction is the zero vector")
        return Lines(plucker_from_point_direction(np.asarray(pts), d))
    if all(isinstance(e, (list, tuple)) for e in entries):
        rows = [_vector(e, 6, f"{where}: lines[{i}]") for i, e in enumerate(entries)]
        try:
            return Lines(validate_plucker(np.asarray(rows), "lines", tol=1e-9))
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
    raise ValueError(
        f"{where}: 'lines' entries must all be objects {{point, direction}} or all Plücker rows"
    )


def _read_json(path: Path, text: str) -> LinesDocument:
    where = str(path)
    doc = json_object(text, where)
    fmt = doc.get("format", FORMAT)
    if fmt != FORMAT:
        raise ValueError(f"{where}: format {fmt!r} is not supported; expected {FORMAT!r}")
    scale = unit_scale(doc.get("units", "m"), f"{where}: 'units'")
    closed = doc.get("closed", False)
    if not isinstance(closed, bool):
        raise ValueError(f"{where}: 'closed' must be true or false, got {closed!r}")
    if "lines" not in doc:
        raise ValueError(f"{where}: missing 'lines'")
    lines = _lines_from_entries(doc["lines"], where)
    if scale != 1.0:
        lines = Lines(lines.plucker * np.r_[1.0, 1.0, 1.0, scale, scale, scale])
    frames = striction = None
    if "frames" in doc:
        fr = doc["frames"]
        if not isinstance(fr, list) or len(fr) != len(lines):
            raise ValueError(f"{where}: 'frames' must hold one 4x4 matrix per line")
        rows = []
        for i, f in enumerate(fr):
            # a frame is 16 numbers (row-major) or a nested 4x4 list
            if isinstance(f, list) and f and all(isinstance(r, list) for r in f):
                f = [v for r in f for v in r]
            rows.append(_vector(f, 16, f"{where}: frames[{i}]"))
        frames = np.asarray(rows).reshape(-1, 4, 4)
        frames[:, :3, 3] *= scale
    if "striction" in doc:
        st = doc["striction"]
        if not isinstance(st, list) or len(st) != len(lines):
            raise ValueError(f"{where}: 'striction' must hold one point per line")
        striction = np.asarray(
            [_vector(p, 3, f"{where}: striction[{i}]") for i, p in enumerate(st)]
        ) * scale
    return LinesDocument(lines, closed, frames, striction)


def _read_csv(path: Path, text: str) -> LinesDocument:
    where = str(path)
    closed = False
    scale = 1.0
    rows: list[tuple[int, list[str]]] = []
    header_seen = False
    for lineno, raw in enumerate(io.StringIO(text), start=1):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#"):
            key, _, val = s[1:].partition(":")
            if key.strip().lower() == "closed":
                closed = val.strip().lower() in ("true", "1", "yes")
            elif key.strip().lower() == "units":
                if header_seen:
                    raise ValueError(f"{where}: line {lineno}: '# units:' must come before the "
                                     "header (it applies to every row)")  # fmt: skip
                scale = unit_scale(val.strip(), f"{where}: line {lineno}: units")
            continue
        cells = next(csv.reader([s]))
        if not header_seen:
            if [c.strip().lower() for c in cells] != CSV_HEADER:
                raise ValueError(
                    f"{where}: line {lineno}: expected the header {','.join(CSV_HEADER)}, got {s!r}"
                )
            header_seen = True
            continue
        rows.append((lineno, cells))
    if not header_seen:
        raise ValueError(f"{where}: empty file; expected the header {','.join(CSV_HEADER)}")
    if not rows:
        raise ValueError(f"{where}: no lines after the header")
    values = np.empty((len(rows), 6))
    for k, (lineno, cells) in enumerate(rows):
        if len(cells) != 6:
            raise ValueError(f"{where}: line {lineno}: expected 6 values, got {len(cells)}")
        try:
            values[k] = [float(c) for c in cells]
        except ValueError:
            raise ValueError(f"{where}: line {lineno}: not a number in {cells!r}") from None
        if not np.all(np.isfinite(values[k])):
            raise ValueError(f"{where}: line {lineno}: contains NaN or infinity")
        if np.linalg.norm(values[k, 3:]) <= 1e-12:
            raise ValueError(f"{where}: line {lineno}: direction is the zero vector")
    points = values[:, :3] * scale
    return LinesDocument(Lines(plucker_from_point_direction(points, values[:, 3:])), closed)


def read_lines_document(path: str | os.PathLike[str]) -> LinesDocument:
    """Read a ``.json`` or ``.csv`` lines file (see module doc); ValueError on bad content."""
    p, text = read_user_text(path, "file")
    suffix = p.suffix.lower()
    if suffix == ".json":
        return _read_json(p, text)
    if suffix == ".csv":
        return _read_csv(p, text)
    raise ValueError(f"{p}: unknown file type {suffix!r}; expected .json or .csv")


def load_lines(path: str | os.PathLike[str]) -> Lines:
    """The lines of a ``.json`` or ``.csv`` lines file."""
    return read_lines_document(path).lines


def save_lines(
    path: str | os.PathLike[str],
    lines: Lines,
    closed: bool = False,
    frames: ArrayLike | None = None,
    striction: ArrayLike | None = None,
    plucker: bool = False,
) -> Path:
    """Write lines to ``.json`` or ``.csv`` atomically; return the path.

    ``.json``: point/direction objects, or Plücker rows with ``plucker=True``; optional
    ``frames`` (N,4,4) and ``striction`` (N,3).  ``.csv``: point nearest the origin +
    direction.
    """
    p = Path(path)
    if not isinstance(lines, Lines):
        raise ValueError(f"{p}: expected ruledrobot.Lines, got {type(lines).__name__}")
    n = len(lines)
    suffix = p.suffix.lower()
    if suffix == ".csv":
        if frames is not None or striction is not None:
            raise ValueError(f"{p}: CSV holds lines only; save frames/striction as .json")
        buf = io.StringIO()
        if closed:
            buf.write("# closed: true\n")
        buf.write(",".join(CSV_HEADER) + "\n")
        data = np.concatenate([lines.point, lines.direction], axis=1)
        for row in data:
            buf.write(",".join(repr(float(v)) for v in row) + "\n")
        return atomic_write_text(p, buf.getvalue())
    if suffix != ".json":
        raise ValueError(f"{p}: unknown file type {suffix!r}; expected .json or .csv")
    if plucker:
        entries: list = lines.plucker.tolist()
    else:
        entries = [
            {"point": pt.tolist(), "direction": d.tolist()}
            for pt, d in zip(lines.point, lines.direction, strict=True)
        ]
    doc: dict = {"format": FORMAT, "units": "m", "closed": bool(closed), "lines": entries}
    if frames is not None:
        fr = np.asarray(frames, dtype=np.float64)
        if fr.shape != (n, 4, 4):
            raise ValueError(f"{p}: frames must have shape ({n}, 4, 4), got {fr.shape}")
        doc["frames"] = fr.reshape(n, 16).tolist()
    if striction is not None:
        st = np.asarray(striction, dtype=np.float64)
        if st.shape != (n, 3):
            raise ValueError(f"{p}: striction must have shape ({n}, 3), got {st.shape}")
        doc["striction"] = st.tolist()
    return atomic_write_json(p, doc)
