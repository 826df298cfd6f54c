"""Reading a 4-axis hot-wire G-code file as rulings.

Each position of the wire during the cut is a ruling: the line from tower A's
point ``(a_h, a_v, 0)`` to tower B's point ``(b_h, b_v, D)`` in the *cutter frame*
(x along the horizontal carriages, y along the vertical ones, z from tower A to
tower B; ``D = tower_distance``, a machine setting the file does not hold;
a negative ``D`` puts tower B on the other side, which mirrors the part).

The cut is a run of consecutive ``G1`` moves (while the wire is hot, when the
file switches heat at all); ``G0`` moves and cold moves are not cut.  Its
rulings are the start of its first move and the end of every move; moves of
length zero are skipped (a note says so).  A move of one tower alone is a
ruling like any other: foam software writes them (one carriage stands while the
other moves), and the wire lies on a line all the same; only a 2-axis file
(``axes = "XY"``) refuses U/V words, because there the second tower copies the
first.  A file with several cuts needs ``cut = k`` (1-based).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...geometry.ranges import runs_of
from ..text import read_user_text
from .gcode_parse import FEED_MODES, TowerMoves, check_axes, parse_gcode
from .options import Options
from .rulings import Planes, Rulings, rulings_from_ends

__all__ = ["GCODE_SUFFIXES", "GcodeReadOptions", "read_gcode", "read_gcode_moves"]

GCODE_SUFFIXES = (".ngc", ".gcode", ".nc", ".tap", ".cnc", ".gc")


@dataclass(frozen=True)
class GcodeReadOptions:
    """How to read a foam-cutter G-code file (lengths in metres)."""

    tower_distance: float
    axes: str = "XYUV"
    units: str | None = None  # "mm" or "in" when the file has no G20/G21 (default mm)
    distance_mode: str = "absolute"  # before any G90/G91
    feed_mode: str = "path4d"  # how F is meant (for the feed the reader reports)
    cut: int | None = None  # which cut, 1-based, when the file holds several

    @classmethod
    def parse(cls, o: Options) -> GcodeReadOptions:
        """The read options from ``o``; unknown options are refused.

        ``tower_distance`` [m] is required (non-zero); ``units`` must be ``mm`` or ``in``.

        Raises
        ------
        ValueError
            When an option is missing, out of range or unknown, naming it.
        """
        d = o.number("tower_distance", nonzero=True, required="the distance between the "
                     "towers (m) is a machine setting, not in the file; e.g. 0.8")  # fmt: skip
        axes = o.string("axes", "XYUV")
        axes = check_axes(axes, o.label("axes"))
        units = o.unit("units")
        if units not in (None, "mm", "in"):
            raise o.fail("units", f"G-code is in mm (G21) or inches (G20), got {units!r}")
        opts = cls(
            tower_distance=float(d),
            axes=axes,
            units=units,
            distance_mode=o.choice("distance_mode", ("absolute", "relative"), "absolute"),
            feed_mode=o.choice("feed_mode", FEED_MODES, "path4d"),
            cut=o.integer("cut", lo=1),
        )
        o.done()
        return opts


def read_gcode_moves(path: str | os.PathLike[str], options: GcodeReadOptions) -> TowerMoves:
    """The moves of a G-code file (see :mod:`.gcode_parse`)."""
    p, text = read_user_text(path, "G-code file")
    return parse_gcode(text, str(p), options.axes, options.units, options.distance_mode,
                       options.feed_mode)  # fmt: skip


def read_gcode(path: str | os.PathLike[str], options: GcodeReadOptions) -> Rulings:
    """The rulings of the cut in a G-code file, in the cutter frame (see the module doc)."""
    where = str(Path(path))
    mv = read_gcode_moves(path, options)
    cutting = ~mv.rapid & (mv.heat if mv.heat_codes else True)
    runs = list(runs_of(cutting))
    if not runs:
        hint = " while the wire is hot (M3/M4/M8)" if mv.heat_codes else ""
        raise ValueError(f"{where}: no cutting move (G1{hint}) in the file; expected the "
                         "moves of a cut")  # fmt: skip
    listing = ", ".join(f"{k + 1}: lines {mv.line[a]}-{mv.line[b - 1]}"
                        for k, (a, b) in enumerate(runs))  # fmt: skip
    notes = []
    if options.cut is None:
        if len(runs) > 1:
            raise ValueError(f"{where}: the file holds {len(runs)} cuts ({listing}); choose "
                             "one with cut = k")  # fmt: skip
        a, b = runs[0]
    else:
        if options.cut > len(runs):
            raise ValueError(f"{where}: cut = {options.cut}, but the file holds {len(runs)} "
                             f"cut(s) ({listing})")  # fmt: skip
        a, b = runs[options.cut - 1]
        notes.append(f"cut {options.cut} of {len(runs)}: lines {mv.line[a]}-{mv.line[b - 1]}")
    start, end = mv.start[a:b], mv.end[a:b]
    moved = np.any(end != start, axis=1)
    if not moved.all():
        lines = ", ".join(map(str, mv.line[a:b][~moved][:5].tolist()))
        notes.append(f"skipped {int((~moved).sum())} move(s) of length zero (line {lines}"
                     f"{', ...' if (~moved).sum() > 5 else ''})")  # fmt: skip
    if not moved.any():
        raise ValueError(f"{where}: the cut at lines {mv.line[a]}-{mv.line[b - 1]} does not move")
    pts = np.concatenate([start[:1], end[moved]])
    if not mv.units_given and options.units is None:
        notes.append("the file does not say its units (no G20/G21): read as mm")
    D = options.tower_distance
    n = len(pts)
    ends = np.zeros((n, 2, 3))
    ends[:, 0, :2], ends[:, 1, :2], ends[:, 1, 2] = pts[:, :2], pts[:, 2:], D
    lines = rulings_from_ends(ends[:, 0], ends[:, 1], where)
    d = np.abs(np.diff(pts, axis=0))
    faster = np.maximum(np.hypot(d[:, 0], d[:, 1]), np.hypot(d[:, 2], d[:, 3]))
    with np.errstate(divide="ignore", invalid="ignore"):
        feed = faster / mv.duration[a:b][moved]
    return Rulings(lines, False, ends, Planes(np.eye(4), D, "towers"), feed, where, tuple(notes))
