"""Parsing 4-axis hot-wire G-code into tower moves (the interpreter, no geometry).

A foam cutter has two towers; the wire runs between them.  The *axis mapping*
names the four axis letters in the order (tower A horizontal, tower A vertical,
tower B horizontal, tower B vertical): ``"XYUV"`` (LinuxCNC, Mach3, most foam
software), ``"XYZA"`` or ``"XYZB"`` (GRBL-family firmware, which has no U/V
words).  ``"XY"`` is a 2-axis file: the controller copies X/Y to the second tower.

What is read (RS274/NGC semantics, the subset foam software writes): ``G0`` ``G1``
(modal), ``G4 P`` (dwell, value ignored), ``G17`` ``G40`` ``G49`` ``G54`` ``G61``
``G64`` ``G80`` ``G90.1`` ``G91.1`` (accepted, no effect here), ``G20``/``G21``
(inches/mm), ``G90``/``G91`` (absolute/relative), ``G92`` (declare the current
position; ``G92.1`` clears it), ``G28`` (home: position unknown afterwards),
``G93``/``G94`` (inverse time / units per minute); ``F``; ``M3`` ``M4`` ``M8``
(heat on), ``M5`` ``M9`` (heat off), ``M0`` ``M1`` ``M17`` ``M18`` ``M84``
(no effect), ``M2``/``M30`` (end: the rest of the file is not read); ``S``
(heat power, ignored); ``N`` line numbers; comments ``( )`` and ``;``.
Everything else is refused with the line: unknown words, axis letters outside
the mapping, arcs (``G2``/``G3``: a 4-axis arc is not defined), a cutting move
whose start is not known (relative moves without a start, an axis never set).

Positions are kept in the coordinates of the first coordinate system the file
sets (a later ``G92`` shifts the program's numbers, not the geometry) and are
converted to metres as they are read.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ...geometry._arrays import FloatArray
from ..units import unit_scale

__all__ = ["AXIS_LETTERS", "FEED_MODES", "TowerMoves", "check_axes", "parse_gcode"]

AXIS_LETTERS = "XYZABCUVW"
#: how a file's F is read (G93 in a file switches to inverse time by itself)
FEED_MODES = ("path4d", "first_tower", "faster_tower", "inverse_time")
_IGNORED_G = {17.0, 40.0, 49.0, 54.0, 61.0, 64.0, 80.0, 90.1, 91.1}
_KNOWN_G = "G0 G1 G4 G17 G20 G21 G28 G40 G49 G54 G61 G64 G80 G90 G91 G92 G92.1 G93 G94"
_HEAT_ON, _HEAT_OFF, _NO_EFFECT, _END = {3, 4, 8}, {5, 9}, {0, 1, 17, 18, 84}, {2, 30}
_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")


def _strip_comments(raw: str, where: str) -> str:
    """The line without ``( )`` comments and without a ``;`` comment (outside parentheses)."""
    out = []
    k = 0
    while k < len(raw):
        c = raw[k]
        if c == ";":
            break
        if c == "(":
            end = raw.find(")", k + 1)
            if end < 0 or "(" in raw[k + 1 : end]:
                raise ValueError(f"{where}: unbalanced or nested '(' ')' comment")
            out.append(" ")
            k = end + 1
            continue
        if c == ")":
            raise ValueError(f"{where}: ')' without '('")
        out.append(c)
        k += 1
    return "".join(out).strip()


@dataclass(frozen=True)
class TowerMoves:
    """The moves of a G-code file, in file order; tower coordinates in metres.

    ``start``, ``end`` (K, 4): ``[a_h, a_v, b_h, b_v]`` (tower A horizontal and
    vertical, tower B horizontal and vertical) before and after each move (NaN:
    not known, only possible for rapids); ``line`` (K,) 1-based line numbers;
    ``rapid`` (K,) G0; ``heat`` (K,) wire on during the move; ``duration`` (K,) s
    from F and the feed mode (NaN: rapid, or F not given); ``heat_codes``: the
    file switches the heat at all; ``units``: ``"mm"``/``"in"``, and whether the
    file said so (``units_given``).
    """

    start: FloatArray = field(repr=False)
    end: FloatArray = field(repr=False)
    line: np.ndarray = field(repr=False)
    rapid: np.ndarray = field(repr=False)
    heat: np.ndarray = field(repr=False)
    duration: FloatArray = field(repr=False)
    heat_codes: bool = False
    units: str = "mm"
    units_given: bool = False

    def __len__(self) -> int:
        return self.line.shape[0]


def check_axes(axes: str, where: str) -> str:
    """The axis mapping in upper case; ValueError unless 4 (or 2) distinct axis letters."""
    a = axes.upper() if isinstance(axes, str) else ""
    if len(a) not in (2, 4) or len(set(a)) != len(a) or any(c not in AXIS_LETTERS for c in a):
        raise ValueError(
            f"{where}: axis mapping {axes!r}: expected four distinct axis letters in the order "
            "tower A horizontal, A vertical, B horizontal, B vertical (e.g. XYUV, XYZA), "
            "or two (XY) for a 2-axis file"
        )
    return a


def _durations(start: FloatArray, end: FloatArray, f: FloatArray, mode: FloatArray,
               feed_mode: str) -> FloatArray:  # fmt: skip
    """Seconds per move from F (m/s, or 1/s in inverse time) and the feed mode."""
    d = np.abs(end - start)
    da, db = np.hypot(d[:, 0], d[:, 1]), np.hypot(d[:, 2], d[:, 3])
    if feed_mode == "path4d":
        length = np.sqrt((d**2).sum(axis=1))
    elif feed_mode == "first_tower":
        length = np.where(da > 0, da, db)
    else:  # faster_tower (inverse_time files say G93 themselves)
        length = np.maximum(da, db)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mode == 93, 1.0 / f, length / f)


def parse_gcode(text: str, where: str, axes: str = "XYUV", units: str | None = None,
                distance_mode: str = "absolute", feed_mode: str = "path4d",
                ) -> TowerMoves:  # fmt: skip
    """Interpret a 4-axis (or 2-axis) hot-wire G-code program (see the module doc).

    ``units`` (``"mm"``/``"in"``) is what the file is in when it does not say
    (default mm); given and contradicted by a ``G20``/``G21`` it is an error.
    ``distance_mode`` is the mode before any ``G90``/``G91``; ``feed_mode``
    ``"inverse_time"`` reads every F as 1/minutes (a controller in G93 by default),
    the others read F as a speed unless the file says ``G93``.
    """
    axes = check_axes(axes, where)
    two_axis = len(axes) == 2
    letters = {c: i for i, c in enumerate(axes)}
    scale = unit_scale(units or "mm", f"{where}: units")
    file_units: str | None = None
    relative = distance_mode == "relative"
    pos = np.full(4, np.nan)
    off = np.zeros(4)
    motion: int | None = None
    fmode, feed = 94, np.nan
    heat, heat_codes = False, False
    rows: list[tuple] = []  # (start, end, line, rapid, heat, F, feed mode)

    for lineno, raw in enumerate(text.splitlines(), start=1):
        s = _strip_comments(raw, f"{where}: line {lineno}")
        if not s or s == "%":
            continue
        pos_end = 0
        words: list[tuple[str, float, str]] = []
        for m in _WORD.finditer(s):
            if s[pos_end : m.start()].strip():
                break
            words.append((m.group(1).upper(), float(m.group(2)), m.group(0)))
            pos_end = m.end()
        rest = s[pos_end:].strip()
        if rest:
            raise ValueError(f"{where}: line {lineno}: cannot read {rest!r}; expected words "
                             "such as G1 X10.5 Y20 (a letter and a number)")  # fmt: skip
        gs = [v for c, v, _ in words if c == "G"]
        ms = [v for c, v, _ in words if c == "M"]
        for g in gs:
            if g in (2.0, 3.0):
                raise ValueError(f"{where}: line {lineno}: G{g:g} is an arc; arcs are not "
                                 "defined for moves of two towers (export straight G1 "
                                 "segments)")  # fmt: skip
            if g not in _IGNORED_G and g not in (0, 1, 4, 20, 21, 28, 90, 91, 92, 92.1, 93, 94):
                raise ValueError(f"{where}: line {lineno}: G{g:g} is not supported; expected "
                                 f"one of {_KNOWN_G}")  # fmt: skip
        vals: dict[str, float] = {}
        for c, v, text_word in words:
            if c in "GM":
                continue
            if c in vals:
                raise ValueError(f"{where}: line {lineno}: {c} given twice")
            if c in letters or c in "FNPS":
                vals[c] = v
            elif c in AXIS_LETTERS:
                hint = (" (a 2-axis file: the second tower copies X/Y; give axes = \"XYUV\" "
                        "or the mapping of your machine)") if two_axis else \
                       " (the file's machine may map its axes otherwise: give its axes, " \
                       "e.g. axes = \"XYZA\")"  # fmt: skip
                raise ValueError(f"{where}: line {lineno}: axis word {text_word!r} is not an "
                                 f"axis of the mapping {axes}{hint}")  # fmt: skip
            else:
                raise ValueError(f"{where}: line {lineno}: unknown word {text_word!r}; expected "
                                 f"G, M, F, P, S, N or the axes {axes}")  # fmt: skip
        for mc in ms:
            if mc not in _HEAT_ON | _HEAT_OFF | _NO_EFFECT | _END:
                raise ValueError(f"{where}: line {lineno}: M{mc:g} is not supported; expected "
                                 "M3/M4/M8 (heat on), M5/M9 (heat off), M0 M1 M2 M17 M18 M30 "
                                 "M84")  # fmt: skip
        for g in gs:
            if g in (20.0, 21.0):
                said = "in" if g == 20 else "mm"
                if units is not None and said != units:
                    raise ValueError(f"{where}: line {lineno}: G{g:g} says the file is in {said}, "
                                     f"but units = {units!r} was given (unit mismatch): remove "
                                     "the option or correct the file")  # fmt: skip
                file_units, scale = said, unit_scale(said, where)
            elif g in (90.0, 91.0):
                relative = g == 91
            elif g in (93.0, 94.0):
                fmode = int(g)
            elif g in (0.0, 1.0):
                motion = int(g)
        if "F" in vals:
            if vals["F"] <= 0:
                raise ValueError(f"{where}: line {lineno}: F{vals['F']:g}: expected F > 0")
            inverse = fmode == 93 or feed_mode == "inverse_time"
            feed = vals["F"] / 60.0 * (1.0 if inverse else scale)
        if any(mc in _HEAT_ON for mc in ms):
            heat, heat_codes = True, True
        if any(mc in _HEAT_OFF for mc in ms):
            heat, heat_codes = False, True
        axis_vals = np.full(4, np.nan)
        for c, i in letters.items():
            if c in vals:
                axis_vals[i] = vals[c] * scale
        if two_axis:
            axis_vals[2:] = axis_vals[:2]
        given = ~np.isnan(axis_vals)
        if 4.0 in gs:
            if "P" not in vals:
                raise ValueError(f"{where}: line {lineno}: G4 (dwell) without P")
            if given.any():
                raise ValueError(f"{where}: line {lineno}: G4 (dwell) with axis words")
        elif "P" in vals:
            raise ValueError(f"{where}: line {lineno}: P without G4; expected G4 P<seconds>")
        if 92.1 in gs:
            off[:] = 0.0
        if 92.0 in gs:
            if not given.any():
                raise ValueError(f"{where}: line {lineno}: G92 without axis words; expected e.g. "
                                 f"G92 {' '.join(c + '0' for c in axes)}")  # fmt: skip
            known = given & ~np.isnan(pos)
            off[known] = pos[known] - axis_vals[known]
            fresh = given & np.isnan(pos)
            pos[fresh], off[fresh] = axis_vals[fresh], 0.0
            continue
        if 28.0 in gs:
            pos[:] = np.nan  # the machine goes home: where that is, the file does not say
            continue
        if not given.any() or 4.0 in gs:
            if any(mc in _END for mc in ms):
                break
            continue
        if motion is None:
            raise ValueError(f"{where}: line {lineno}: axis words without G0 or G1 before them")
        if relative:
            missing = given & np.isnan(pos)
            if missing.any():
                names = " ".join(axes[i] for i in np.flatnonzero(missing) if i < len(axes))
                raise ValueError(f"{where}: line {lineno}: relative move (G91) of {names} without "
                                 "a start: no earlier position; expected G92 or an absolute "
                                 "move first")  # fmt: skip
            target = np.where(given, pos + np.nan_to_num(axis_vals), pos)
        else:
            target = np.where(given, axis_vals + off, pos)
        positioning = motion == 0
        if motion == 1 and np.isnan(pos).any() and not np.isnan(target).any():
            # a first G1 naming every axis (from wherever the wire is, e.g. after G28):
            # it brings the wire to a known place; it is no ruling of the cut (as a G0)
            positioning = True
        elif motion == 1:
            unknown = np.isnan(pos) | np.isnan(target)
            if unknown.any():
                idx = sorted({i % len(axes) for i in np.flatnonzero(unknown)})
                names = " ".join(axes[i] for i in idx)
                raise ValueError(f"{where}: line {lineno}: cutting move (G1) from an unknown "
                                 f"position of {names}: no G92 or move has set it; expected a "
                                 f"first move naming every axis, or G92 "
                                 f"{' '.join(c + '0' for c in axes)}")  # fmt: skip
            if fmode == 93 and "F" not in vals:
                raise ValueError(f"{where}: line {lineno}: G1 in inverse time mode (G93) without "
                                 "F; expected F on every move")  # fmt: skip
        rows.append((pos.copy(), target.copy(), lineno, positioning, heat, feed,
                     93 if feed_mode == "inverse_time" else fmode))  # fmt: skip
        pos = target
        if any(mc in _END for mc in ms):
            break

    k = len(rows)
    start = np.array([r[0] for r in rows]).reshape(k, 4)
    end = np.array([r[1] for r in rows]).reshape(k, 4)
    f = np.array([r[5] for r in rows], dtype=np.float64)
    mode = np.array([r[6] for r in rows], dtype=np.int64)
    rapid = np.array([r[3] for r in rows], dtype=bool)
    dur = _durations(start, end, f, mode, feed_mode)
    dur[rapid] = np.nan
    return TowerMoves(
        start, end, np.array([r[2] for r in rows], dtype=np.int64), rapid,
        np.array([r[4] for r in rows], dtype=bool), dur, heat_codes,
        file_units or units or "mm", file_units is not None,
    )  # fmt: skip
