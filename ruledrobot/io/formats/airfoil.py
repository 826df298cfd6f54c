"""Airfoil coordinate files (``.dat``): Selig and Lednicer formats (UIUC database).

* **Selig**: a name line, then ``x y`` pairs from the trailing edge over the upper
  surface to the leading edge and back along the lower surface (either way round;
  the name line may be missing, as XFOIL's plain files have it).
* **Lednicer**: a name line, a line with the two point counts (``17. 17.``), then
  the upper surface from leading to trailing edge, a blank line, the lower surface
  from leading to trailing edge.

Both are returned in one order — Selig's, counter-clockwise: trailing edge, upper
surface, leading edge, lower surface, trailing edge — in chord units (x from 0 at
the leading edge to 1 at the trailing edge).  Lines starting with ``#`` are
comments.  Refused, with the line: anything that is not a pair of numbers, counts
that do not match the points, fewer than 5 points, coordinates that are not in
chord units (x must run over 0..1 within 5 %: a file in mm or in percent is a
unit mismatch), a profile that crosses itself.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ...geometry._arrays import FloatArray
from ..text import read_user_text
from .profiles import check_simple

__all__ = ["Airfoil", "leading_edge_index", "read_airfoil"]


@dataclass(frozen=True)
class Airfoil:
    """A profile: its name, its points in chord units and the format it was read from.

    ``name``, ``points`` (N, 2) in chord units (Selig order, see the module doc), the
    ``format`` it was read from (``"selig"``/``"lednicer"``).
    """

    name: str
    points: FloatArray = field(repr=False)
    format: str = "selig"


def _pair(s: str) -> tuple[float, float] | None:
    parts = s.replace(",", " ").split()
    if len(parts) != 2:
        return None
    try:
        x, y = float(parts[0]), float(parts[1])
    except ValueError:
        return None
    return (x, y) if np.isfinite(x) and np.isfinite(y) else None


def leading_edge_index(points: FloatArray) -> int:
    """Index of the leading edge: the point farthest from the trailing-edge midpoint."""
    te = 0.5 * (points[0] + points[-1])
    return int(np.argmax(np.linalg.norm(points - te, axis=1)))


def read_airfoil(path: str | os.PathLike[str]) -> Airfoil:
    """Read a Selig or Lednicer airfoil file (see the module doc)."""
    p, text = read_user_text(path, "airfoil file")
    where = str(p)
    rows: list[tuple[int, str]] = [
        (k, s.strip()) for k, s in enumerate(text.splitlines(), start=1)
        if not s.strip().startswith("#")
    ]  # fmt: skip
    data = [(k, s) for k, s in rows if s]
    if not data:
        raise ValueError(f"{where}: empty file; expected an airfoil name and x y pairs")
    name = ""
    if _pair(data[0][1]) is None:
        name = data[0][1]
        data = data[1:]
    pts: list[tuple[float, float]] = []
    lines: list[int] = []
    for k, s in data:
        xy = _pair(s)
        if xy is None:
            raise ValueError(f"{where}: line {k}: expected two numbers 'x y', got {s!r}")
        pts.append(xy)
        lines.append(k)
    if not pts:
        raise ValueError(f"{where}: no coordinates after the name line")
    fmt = "selig"
    first = pts[0]
    if first[0] >= 2 and first[1] >= 2 and float(first[0]).is_integer() \
            and float(first[1]).is_integer():  # fmt: skip
        fmt = "lednicer"
        nu, nl = int(first[0]), int(first[1])
        body = np.asarray(pts[1:], dtype=np.float64)
        if len(body) != nu + nl:
            raise ValueError(f"{where}: line {lines[0]}: Lednicer counts say {nu} upper and {nl} "
                             f"lower points, the file has {len(body)}")  # fmt: skip
        upper, lower = body[:nu], body[nu:]
        if np.linalg.norm(upper[0] - lower[0]) <= 1e-12:
            lower = lower[1:]
        xy = np.concatenate([upper[::-1], lower])
        labels = None
    else:
        xy = np.asarray(pts, dtype=np.float64)
        labels = [f"line {k}" for k in lines]
    if len(xy) < 5:
        raise ValueError(f"{where}: {len(xy)} points; expected at least 5")
    lo, hi = float(xy[:, 0].min()), float(xy[:, 0].max())
    if lo < -0.05 or hi > 1.05 or hi - lo < 0.95:
        raise ValueError(f"{where}: x runs from {lo:g} to {hi:g}: not in chord units (unit "
                         "mismatch: expected x from 0 at the leading edge to 1 at the trailing "
                         "edge; divide by the chord)")  # fmt: skip
    check_simple(xy, where, labels=labels)
    area = 0.5 * float(np.sum(xy[:-1, 0] * xy[1:, 1] - xy[1:, 0] * xy[:-1, 1])
                       + xy[-1, 0] * xy[0, 1] - xy[0, 0] * xy[-1, 1])  # fmt: skip
    if area < 0:
        xy = xy[::-1].copy()
    return Airfoil(name, xy, fmt)
