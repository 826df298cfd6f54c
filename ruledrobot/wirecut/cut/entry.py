"""Entry and exit moves of a profile cut: straight, from outside the block.

A profile read from a file of the field — an airfoil panel (trailing edge, upper
surface, leading edge, lower surface, trailing edge), a DXF or 3DM profile pair
drawn as one open curve that comes back to where it started — begins and ends at a
point of the part, usually inside the block.  A foam cutter's program reaches that
point from outside the block and leaves it the same way; the file does not say how.
Extrapolating the frame motion past the end does not do it: the cosine spacing of
an airfoil makes the end steps hundredths of a millimetre.

So, before refinement, such a profile gets **straight entry and exit moves** (input
rulings of their own): each end of the rulings — where they cross the file's two
planes (a panel's root and tip faces, the planes of a CAD profile pair: the towers
of the foam cutter that would cut it), else the wire points ``o ± (L/2) z`` (``o``
the ruling's point nearest the block centre, ``L`` the wire) — moves in a straight
line along the profile's own first (last) move, continued backwards (forwards) out
of the block, each end in proportion to its own step (as a foam cutter's towers in
one G1 move; the same wing as XYUV G-code with such a move plans to the same rulings,
``tests/formats/test_formats_matrix.py``) —
the wire enters along the tangent of the upper surface at the trailing edge and
leaves along the tangent of the lower one: two straight slits in the waste behind
the trailing edge meeting at its angle.  Entering along the tangent keeps the wire
moving at its feed at the trailing edge (a move along the chord would turn it by
half the trailing-edge angle there, in the foam, where a wire that slows melts a
wider kerf at the part's thinnest edge) — the rule of :mod:`.closed`'s slits.  The
steps grow from the profile's end step by :data:`GROWTH` each up to the first
ruling clear of the block grown by :data:`CLEAR` (the refinement sees a smooth
spacing); the lead-in and lead-out then go on from there as for any cut.

Which profiles: the kinds in :data:`PROFILE_KINDS`, open, whose two end rulings lie
within :data:`RETURN` of the profile's size of each other (a closed trailing edge, or
an open one a fraction of the chord thick), at an end that cuts the block.  Other
open surfaces keep their own ends (a surface that stops short of its block is
refused: :mod:`.passes`); G-code files carry their own entry and exit moves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...geometry.lines import Lines, point_nearest_origin

__all__ = ["CLEAR", "GROWTH", "PROFILE_KINDS", "RETURN", "ProfileEntry", "profile_entry"]

#: kinds of file whose open rulings are a profile (``gcode`` carries its own moves)
PROFILE_KINDS = ("airfoil", "dxf", "rhino")
#: ends nearer each other than this fraction of the profile's size: a profile that returns
RETURN = 0.1
#: growth of the step of the entry (exit) move from the profile's end step
GROWTH = 1.5
#: [m] the entry (exit) move ends on the first ruling clear of the block grown by this
CLEAR = 0.001
#: most rulings of one entry (exit) move
MAX_RULINGS = 60


@dataclass(frozen=True)
class ProfileEntry:
    """The profile's rulings with their moves.

    ``lines`` (N + before + after), ``before`` rulings of the entry move ahead of the profile's
    first and ``after`` of the exit move past its last."""

    lines: Lines
    before: int
    after: int


def _end_points(lines: Lines, centre: FloatArray, half: float,
                planes: tuple[FloatArray, float] | None) -> tuple[FloatArray, FloatArray]:
    """The two end points (N, 2, 3) of each ruling and the unit directions (N, 3): on
    the ``planes`` (their frame (4, 4) in the rulings' frame, the distance [m] of the
    second from the first along its z) where every ruling crosses both, else ``half``
    [m] either side of the ruling's point nearest ``centre``."""
    L = lines.plucker / np.linalg.norm(lines.plucker[:, :3], axis=1, keepdims=True)
    z, p0 = L[:, :3], point_nearest_origin(L)
    if planes is not None:
        T, distance = planes
        n, c = T[:3, 2], T[:3, 3]
        across = z @ n
        if (np.abs(across) > 1e-6).all():
            ends = [p0 + (((c + h * n - p0) @ n) / across)[:, None] * z for h in (0.0, distance)]
            return np.stack(ends, axis=1), z
    o = p0 + ((centre - p0) * z).sum(axis=1)[:, None] * z
    return np.stack([o - half * z, o + half * z], axis=1), z


def _move(ends: FloatArray, step: FloatArray, stock: Box) -> FloatArray:
    """Wire end points (K, 2, 3) of a straight move from ``ends`` (2, 3) along the unit
    steps ``step`` (2, 3) of each end, the steps growing by GROWTH from the end step,
    up to the first ruling clear of ``stock`` grown by CLEAR (that one included).  Each
    end keeps its own step (their ratio, the turn of the ruling per step, runs on from
    the profile's: a jump in it would kink the arm's path where the move meets the
    profile)."""
    h = np.linalg.norm(step, axis=1)
    if not (h > 0.0).any():
        raise ValueError("the profile's end rulings coincide: no direction to enter along")
    u = step / np.where(h > 0.0, h, 1.0)[:, None]  # an end that does not move stays
    grown = stock.grown(CLEAR)
    k = np.arange(1, MAX_RULINGS + 1)
    s = np.cumsum(GROWTH ** (k - 1))  # in units of the end step
    pts = ends[None] + s[:, None, None] * h[None, :, None] * u[None]
    d = pts[:, 1] - pts[:, 0]
    _, _, hit = grown.clip_lines(pts[:, 0], d / np.linalg.norm(d, axis=1, keepdims=True))
    clear = np.flatnonzero(~hit)
    if not len(clear):
        raise ValueError(f"the profile's straight entry/exit move does not leave the block "
                         f"within {MAX_RULINGS} rulings")  # fmt: skip
    return pts[: clear[0] + 1]


def profile_entry(lines: Lines, kind: str | None, closed: bool, stock: Box, half: float,
                  planes: tuple[FloatArray, float] | None = None) -> ProfileEntry | None:
    """Return the entry and exit moves of a profile (see the module doc), or None.

    None when ``lines`` (N) of a file of ``kind`` are not a profile that returns to its
    start, or neither end cuts the block.  ``half`` [m]: half the wire; ``planes``: the
    file's (:meth:`~..job.spec.SurfaceSpec.planes`), in the frame of ``lines`` and
    ``stock``.
    """
    n = len(lines)
    if closed or kind not in PROFILE_KINDS or n < 3:
        return None
    w, z = _end_points(lines, np.asarray(stock.centre, dtype=np.float64), half, planes)
    o = w.mean(axis=1)
    size = float(np.linalg.norm(o.max(axis=0) - o.min(axis=0)))
    if size == 0.0 or np.linalg.norm(o[0] - o[-1]) > RETURN * size:
        return None
    _, _, cuts = stock.clip_lines(o[[0, -1]], z[[0, -1]])
    if not cuts.any():
        return None
    entry = _move(w[0], w[0] - w[1], stock)[::-1] if cuts[0] else np.zeros((0, 2, 3))
    exit_ = _move(w[-1], w[-1] - w[-2], stock) if cuts[1] else np.zeros((0, 2, 3))
    pts = np.concatenate([entry, w, exit_])
    out = Lines.from_two_points(pts[:, 0], pts[:, 1])
    return ProfileEntry(out, len(entry), len(exit_))
