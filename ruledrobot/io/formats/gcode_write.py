"""Writing rulings as a 4-axis G-code program for a hot-wire foam cutter.

Each ruling is intersected with the two tower planes (``z = 0`` and
``z = tower_distance`` of the cutter frame, :class:`~.rulings.Planes`); the
points are the towers' coordinates, one ``G1`` move per ruling, absolute, in mm
(``G21``) or inches (``G20``).  The program: a comment block (source, towers,
feed), ``G90 G17 G21``, a rapid to the first ruling, heat on (``M3`` or ``M8``),
an optional dwell ``G4 P<s>`` (seconds, as LinuxCNC and GRBL read P), the cut,
heat off, ``M30``.  No ``G92``: the coordinates are the machine's work
coordinates, whose zero the user sets.

Towers: ``tower_distance`` (m) and the cutter frame ``frame`` (a pose in the
rulings' frame) when given.  A G-code source keeps its towers (and distance).
A source with faces (a wing panel's root and tip) or profile planes (a DXF or
3DM pair) is placed with its first plane ``block_offset`` (m) from tower A,
centred between the towers by default; rulings without planes (a lines file, a
plan's ``refined.json``) get a fitted frame (:func:`~.rulings.fit_planes`).

The feed ``feed`` (m/s) holds where the user says (``feed_at``): at the towers
or at the block faces (``faces``, two z values in the cutter frame; default the
source's faces); on each
move the faster of the two reference points moves at the feed (no point of the
wire there moves faster).  The F word carries it the way the controller reads
F (``feed_mode``): ``inverse_time`` (``G93``, F = 1/minutes of each move; the
same timing on every controller that has it), ``path4d`` (GRBL: F is the speed
along the 4-D path), ``first_tower`` (LinuxCNC's rule: F is the speed of the
first tower when it moves), ``faster_tower``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...geometry import se3
from ...geometry._arrays import FloatArray
from ..atomic import atomic_write_text
from ..units import unit_scale
from .gcode_parse import FEED_MODES, check_axes
from .options import Options
from .rulings import Planes, Rulings, fit_planes, plane_ends

__all__ = ["GcodeWriteOptions", "gcode_text", "resolve_planes", "write_gcode"]


@dataclass(frozen=True)
class GcodeWriteOptions:
    """How to write a foam-cutter program (lengths m, feed m/s, dwell s)."""

    tower_distance: float | None = None  # default: a G-code source's towers
    frame: FloatArray | None = field(default=None, repr=False)  # cutter frame pose (4, 4)
    block_offset: float | None = None  # tower A to the source's first plane (m)
    axes: str = "XYUV"
    units: str = "mm"
    feed: float = 0.005
    feed_at: str = "towers"
    faces: tuple[float, float] | None = None
    feed_mode: str = "inverse_time"
    heat: str = "m3"
    dwell: float = 0.0
    decimals: int = 4

    @classmethod
    def parse(cls, o: Options) -> GcodeWriteOptions:
        """The write options from ``o``; unknown options are refused.

        ``frame`` is a UR pose vector, shape (6,) (position [m], rotation vector [rad]),
        turned into a pose (4, 4); ``feed`` [m/s] is in (0, 1], ``dwell`` [s] >= 0.

        Raises
        ------
        ValueError
            When ``units`` is not ``mm`` or ``in``, the two ``faces`` are equal, both
            ``frame`` and ``block_offset`` are given, or an option is out of range or
            unknown, naming it.
        """
        frame = o.vector("frame", 6)
        axes = o.string("axes", "XYUV")
        axes = check_axes(axes, o.label("axes"))
        units = o.unit("units", "mm")
        if units not in ("mm", "in"):
            raise o.fail("units", f"G-code is in mm (G21) or inches (G20), got {units!r}")
        faces = o.vector("faces", 2)
        feed_at = o.choice("feed_at", ("towers", "faces"), "towers")
        if faces is not None and faces[0] == faces[1]:
            raise o.fail("faces", "expected two different planes")
        if frame is not None and o.has("block_offset"):
            raise o.fail("block_offset", "give frame or block_offset, not both")
        opts = cls(
            tower_distance=o.number("tower_distance", nonzero=True),
            frame=None if frame is None else se3.pose_from_ur_vector(frame),
            block_offset=o.number("block_offset"),
            axes=axes,
            units=units,
            feed=float(o.number("feed", 0.005, positive=True, hi=1.0)),
            feed_at=feed_at,
            faces=None if faces is None else (float(faces[0]), float(faces[1])),
            feed_mode=o.choice("feed_mode", FEED_MODES, "inverse_time"),
            heat=o.choice("heat", ("m3", "m8", "none"), "m3"),
            dwell=float(o.number("dwell", 0.0, lo=0.0)),
            decimals=int(o.integer("decimals", 4, lo=1, hi=9)),
        )
        o.done()
        return opts


def resolve_planes(rulings: Rulings, opts: GcodeWriteOptions, where: str) -> Planes:
    """The tower planes (see the module doc).

    A G-code source keeps its towers; the faces or profiles of a source are placed
    ``block_offset`` from tower A (default: centred between the towers); rulings without planes
    get fitted ones."""
    src = rulings.planes
    distance = opts.tower_distance
    if distance is None:
        if src is None or src.name != "towers":
            what = f"planes that are {src.name}, not towers" if src else "no towers"
            raise ValueError(f"{where}: tower_distance: missing; these rulings come with "
                             f"{what}: give the distance between the towers of the foam "
                             "cutter (m)")  # fmt: skip
        distance = src.distance
    if opts.frame is not None:
        return Planes(opts.frame, distance, "towers")
    if src is None:
        return Planes(fit_planes(rulings.lines, distance).pose, distance, "towers")
    if src.name == "towers" and opts.block_offset is None:
        return Planes(src.pose, distance, "towers")
    offset = opts.block_offset if opts.block_offset is not None else \
        0.5 * (distance - src.distance)  # fmt: skip
    return Planes(src.pose @ _shift(-offset), distance, "towers")


def faces_in_cutter_frame(rulings: Rulings, planes: Planes, opts: GcodeWriteOptions,
                          where: str) -> tuple[float, float]:  # fmt: skip
    """The z of the block faces in the cutter frame.

    The option's, else the source's faces or profiles."""
    if opts.faces is not None:
        return opts.faces
    src = rulings.planes
    if src is None or src.name == "towers":
        raise ValueError(f"{where}: faces (--out-faces): missing; feed_at = faces needs the z "
                         "of the two block faces in the cutter frame (m), e.g. [0.3, 0.5]")
    rel = np.linalg.inv(planes.pose) @ src.pose
    if not np.allclose(rel[:3, 2], [0.0, 0.0, 1.0], atol=1e-9):
        raise ValueError(f"{where}: faces: the source's planes are not parallel to the towers; "
                         "give faces")  # fmt: skip
    z0 = float(rel[2, 3])
    return z0, z0 + src.distance


def _num(v: np.ndarray, decimals: int) -> list[str]:
    out = []
    for x in v.tolist():
        s = f"{x:.{decimals}f}".rstrip("0").rstrip(".")
        out.append("0" if s in ("-0", "") else s)
    return out


def gcode_text(rulings: Rulings, opts: GcodeWriteOptions, where: str = "G-code") -> str:
    """The program (see the module doc) as text."""
    planes = resolve_planes(rulings, opts, where)
    lines = rulings.path_lines()
    ends = plane_ends(lines, planes, where)
    T = planes.pose
    local = (ends - T[:3, 3]) @ T[:3, :3]  # (N, 2, 3) in the cutter frame
    scale = unit_scale(opts.units, where)
    q = np.round(np.concatenate([local[:, 0, :2], local[:, 1, :2]], axis=1) / scale,
                 opts.decimals)  # fmt: skip
    if len(opts.axes) == 2:
        skew = np.abs(q[:, :2] - q[:, 2:]).max()
        if skew > 0:
            raise ValueError(f"{where}: axes = {opts.axes}: a 2-axis machine keeps the wire "
                             f"parallel to its axis, but the towers differ by up to "
                             f"{skew * scale * 1e3:.4g} mm; expected rulings along z")  # fmt: skip
    keep = np.r_[True, np.any(q[1:] != q[:-1], axis=1)]
    q = q[keep]
    if opts.feed_at == "faces":
        f0, f1 = faces_in_cutter_frame(rulings, planes, opts, where)
        ref = plane_ends(lines[np.flatnonzero(keep)], Planes(T @ _shift(f0), f1 - f0), where)
        ref = (ref - T[:3, 3]) @ T[:3, :3]
        dref = np.linalg.norm(np.diff(ref[..., :2], axis=0), axis=2).max(axis=1)
    else:
        dq = np.diff(q, axis=0) * scale
        dref = np.maximum(np.hypot(dq[:, 0], dq[:, 1]), np.hypot(dq[:, 2], dq[:, 3]))
    dq = np.abs(np.diff(q, axis=0))
    da, db = np.hypot(dq[:, 0], dq[:, 1]), np.hypot(dq[:, 2], dq[:, 3])
    t_min = np.maximum(dref, 1e-15) / opts.feed / 60.0  # minutes per move
    if opts.feed_mode == "inverse_time":
        f = 1.0 / t_min
    elif opts.feed_mode == "path4d":
        f = np.sqrt((dq**2).sum(axis=1)) / t_min
    elif opts.feed_mode == "first_tower":
        f = np.where(da > 0, da, db) / t_min
    else:
        f = np.maximum(da, db) / t_min
    axes = opts.axes
    n_ax = len(axes)
    d = opts.decimals
    unit_word, unit_name = ("G21", "mm") if opts.units == "mm" else ("G20", "in")
    source = (rulings.source or "rulings").replace("(", "[").replace(")", "]")
    out = [
        f"(ruledrobot: {len(q)} wire positions from {source})",
        f"(towers: {axes[:2]} at z = 0, {axes[2:] or axes[:2]} at z = "
        f"{planes.distance / scale:.{d}f} {unit_name} of the cutter frame: set the machine's "
        "tower distance to this)",
        f"(feed: {opts.feed * 1e3:.4g} mm/s at the {opts.feed_at}, the faster end; "
        f"F: {opts.feed_mode.replace('_', ' ')})",
        f"G90 G17 {unit_word}",
    ]
    words = [_num(q[:, k], d) for k in range(n_ax)]
    first = " ".join(f"{axes[k]}{words[k][0]}" for k in range(n_ax))
    out.append(f"G0 {first}")
    heat_on, heat_off = {"m3": ("M3", "M5"), "m8": ("M8", "M9"), "none": (None, None)}[opts.heat]
    if heat_on:
        out.append(heat_on)
    if opts.dwell > 0:
        out.append(f"G4 P{_num(np.array([opts.dwell]), 3)[0]}")
    if opts.feed_mode == "inverse_time":
        out.append("G93")
    fw = _num(f, max(d, 4))
    last_f = None
    for i in range(1, len(q)):
        move = " ".join(f"{axes[k]}{words[k][i]}" for k in range(n_ax))
        if opts.feed_mode == "inverse_time" or fw[i - 1] != last_f:
            move += f" F{fw[i - 1]}"
            last_f = fw[i - 1]
        out.append(f"G1 {move}")
    if opts.feed_mode == "inverse_time":
        out.append("G94")
    if heat_off:
        out.append(heat_off)
    out.append("M30")
    return "\n".join(out) + "\n"


def _shift(z: float) -> FloatArray:
    T = np.eye(4)
    T[2, 3] = z
    return T


def write_gcode(path: str | os.PathLike[str], rulings: Rulings,
                opts: GcodeWriteOptions | None = None) -> Path:  # fmt: skip
    """Write the program of ``rulings`` to ``path`` atomically; returns the path."""
    opts = opts or GcodeWriteOptions()
    text = gcode_text(rulings, opts, str(path))
    return atomic_write_text(path, text)
