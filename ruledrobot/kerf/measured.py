"""The measured ladder: a CSV of (speed, power, kerf) rows as a fabricator fills it in.

Columns (a header line names them, in any order; other columns are kept as they are
and ignored)::

    speed_mm_s   the feed the cut was made at [mm/s]              (> 0)
    power_w_m    the heat put into one metre of wire [W/m]        (>= 0)
    kerf_mm      the slot's width measured [mm]        (KERF_MM_RANGE; empty on a failed row)
    failed       optional: yes / no (also true/false, 1/0, empty = no): the wire dragged,
                 bowed or snapped; its kerf is not fitted, its speed bounds max_speed

Blank lines and lines starting with ``#`` are skipped.  Every error names the file, the
line and the column (:func:`read_measured`).  Units in the returned value are SI
(m/s, W/m, m).
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass

import numpy as np

from ..io.text import read_user_text

__all__ = ["COLUMNS", "KERF_MM_RANGE", "Measured", "read_measured"]

#: the columns every measured file has (the fit's inputs), in the template's order
COLUMNS = ("speed_mm_s", "power_w_m", "kerf_mm")
_FAILED = "failed"
#: the widths [mm] a hot wire's slot can have: thinner than the thinnest wire, or wider than
#: a hand, is a reading in another unit (metres, inches) or a slip of the pen
KERF_MM_RANGE = (0.05, 50.0)
_YES = ("yes", "true", "1", "y")
_NO = ("no", "false", "0", "n", "")


@dataclass(frozen=True)
class Measured:
    """The rows of a measured ladder.

    ``speed`` (N,) m/s, ``power`` (N,) W/m, ``kerf`` (N,)
    m (NaN on failed rows), ``failed`` (N,) bool, ``lines`` (N,) the file's line numbers,
    ``source`` the file."""

    speed: np.ndarray
    power: np.ndarray
    kerf: np.ndarray
    failed: np.ndarray
    lines: np.ndarray
    source: str = "measured"


def _number(cell: str, where: str, column: str, lo: float, strict: bool) -> float:
    try:
        x = float(cell)
    except ValueError:
        raise ValueError(f"{where}, column {column}: expected a number, got {cell!r}") from None
    if not math.isfinite(x) or x < lo or (strict and x == lo):
        raise ValueError(f"{where}, column {column}: expected a finite number "
                         f"{'>' if strict else '>='} {lo:g}, got {cell!r}")  # fmt: skip
    return x


def read_measured(path: str | os.PathLike[str]) -> Measured:
    """Read a measured ladder (module doc); ValueError naming the file, line and column."""
    p, text = read_user_text(path, "measured file")
    where = str(p)
    rows: list[tuple[float, float, float, bool, int]] = []
    header: list[str] | None = None
    for lineno, raw in enumerate(io.StringIO(text), start=1):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        cells = [c.strip() for c in next(csv.reader([s]))]
        at = f"{where}: line {lineno}"
        if header is None:
            header = [c.lower() for c in cells]
            missing = [c for c in COLUMNS if c not in header]
            if missing:
                raise ValueError(f"{at}: the header has no column {', '.join(missing)}; "
                                 f"expected at least {','.join(COLUMNS)} (and optionally "
                                 f"{_FAILED}), got {s[:80]!r}")  # fmt: skip
            continue
        if len(cells) != len(header):
            raise ValueError(f"{at}: expected {len(header)} values (the header's columns), "
                             f"got {len(cells)}")  # fmt: skip
        cell = dict(zip(header, cells, strict=True))
        flag = cell.get(_FAILED, "").lower()
        if flag not in _YES + _NO:
            raise ValueError(f"{at}, column {_FAILED}: expected yes or no, got "
                             f"{cell[_FAILED]!r}")  # fmt: skip
        failed = flag in _YES
        v = _number(cell["speed_mm_s"], at, "speed_mm_s", 0.0, strict=True)
        pw = _number(cell["power_w_m"], at, "power_w_m", 0.0, strict=False)
        if failed and not cell["kerf_mm"]:
            w = math.nan
        elif not cell["kerf_mm"]:
            raise ValueError(f"{at}, column kerf_mm: empty; measure the slot, mark the row "
                             f"{_FAILED} = yes, or delete it")  # fmt: skip
        else:
            w = _number(cell["kerf_mm"], at, "kerf_mm", 0.0, strict=True)
            lo, hi = KERF_MM_RANGE
            if not lo <= w <= hi:
                raise ValueError(f"{at}, column kerf_mm: expected the slot's width in "
                                 f"millimetres, {lo:g} to {hi:g}, got {cell['kerf_mm']!r} "
                                 "(a reading in metres or inches?)")  # fmt: skip
        rows.append((v, pw, w, failed, lineno))
    if header is None:
        raise ValueError(f"{where}: empty file; expected the header {','.join(COLUMNS)}")
    if not rows:
        raise ValueError(f"{where}: no rows after the header")
    a = np.array([r[:3] for r in rows], dtype=np.float64)
    return Measured(speed=a[:, 0] * 1e-3, power=a[:, 1], kerf=a[:, 2] * 1e-3,
                    failed=np.array([r[3] for r in rows]),
                    lines=np.array([r[4] for r in rows]), source=where)  # fmt: skip
