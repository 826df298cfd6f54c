"""From a cut to its geometric path: refined rulings, kerf offset, lead-in/out, wire motion.

1. The input rulings are refined (the cut's surface: algorithm, scheme, and either
   a number of steps or a target ``spacing`` — the largest gap between
   consecutive rulings inside the stock, the distance from the chord ends of one
   to the next — for which the fewest steps that meet it are taken).  There must
   be as many as the scheme needs, checked as ``ruledrobot refine`` checks them
   (the open rulings of any file are refined between the corners of their
   polyline, a piece too short for the scheme linearly: :func:`_polyline_pieces`).
2. The frame motion (the refined DH frames of ``dh``; sign-continuous DH frames
   of the refined rulings otherwise) is moved ``kerf / 2`` into the waste when the
   cut names the part's side (:mod:`.kerf`).
3. Open surfaces: the frames are kept between the first and the last ruling that
   meets the stock grown by the lead distance on every side, and extended at
   either end by screw-geodesic extrapolation of the frame motion when the
   surface stops before the wire is clear of the stock by the lead distance.
   The extrapolation is a lead-in/out: it may not cut the block.  A surface that
   stops short of the block -- an extrapolated target ruling (tested at each
   extrapolated ruling and every :data:`SPAN_STEP` within the first gap) with a
   chord in the block longer than :data:`SPAN_TOLERANCE` reaching farther than the
   cut's ``wire_tolerance`` from the end ruling -- is refused, naming where it ends
   and where the block does, unless the cut says ``extend = true``: then it is cut
   on along the extrapolation and the pass notes how far and on how many rulings.
   Closed surfaces are cut as loops entered through a slit (:mod:`.closed`).
4. The redundancy search (:mod:`.wire_pose`) chooses roll, slide, wire
   direction and IK branch.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from ...algorithms import check_distinct_neighbours, refine
from ...geometry import se3
from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...geometry.lines import coincident_neighbours
from ...geometry.ruled import RuledSurface
from ...io.lines import LinesDocument
from ...io.words import counted
from ...robot.arm.model import RobotModel
from ...subdivision import check_length, check_size, get_scheme, refined_count
from ..job.spec import CutSpec, Job
from ..motion.corners import CORNER_ANGLE, polygon_corners
from .clearance import Cell
from .closed import loop_paths
from .cutpath import CutPath, RefinedCut
from .entry import PROFILE_KINDS, profile_entry
from .heat_power import clipping_note
from .kerf import cut_offsets
from .wire_geometry import anchored_frames, chords, world_referenced
from .wire_pose import SearchOptions, search_wire_pose

__all__ = [
    "SPAN_TOLERANCE",
    "CutPath",
    "RefinedCut",
    "chord_ends_in_flange",
    "cut_path",
    "cut_paths",
    "job_search",
    "refine_cut",
    "refine_for_job",
]

MAX_STEPS = 10
#: files whose rulings are a foam cutter's profile pair (world-referenced roll)
FIELD_PROFILE_KINDS = (*PROFILE_KINDS, "gcode")
#: Most refined rulings a cut may have (the redundancy search, the time law and the
#: simulation scale with them: ~2 min of planning and ~2 GB at this size).
MAX_PATH_RULINGS = 250_000
#: An extrapolated target ruling cuts the block when its chord in it is longer than
#: this [m]; one through an edge or along a face (a surface that ends on the block's
#: face) does not.
SPAN_TOLERANCE = 1e-6
#: Spacing [m] at which the extrapolation is checked within its first gap past an end
SPAN_STEP = 1e-4


def _gaps(frames: FloatArray, stock: Box) -> float:
    """Largest gap (m) between consecutive rulings inside the stock: the distance from
    the chord ends of ruling i to ruling i+1, and back, where both cross the stock."""
    c0, c1, hit = chords(frames, stock)
    o, z = frames[:, :3, 3], frames[:, :3, 2]
    both = hit[:-1] & hit[1:]
    if not both.any():
        return np.inf

    def to_line(p: FloatArray, k: slice) -> FloatArray:
        d = p - o[k]
        return np.linalg.norm(d - (d * z[k]).sum(axis=1, keepdims=True) * z[k], axis=1)

    gaps = [to_line(o[a] + c[a, None] * z[a], b)
            for a, b in ((slice(0, -1), slice(1, None)), (slice(1, None), slice(0, -1)))
            for c in (c0, c1)]  # fmt: skip
    return float(np.max(gaps, axis=0)[both].max())


def _frames(
    lines, closed: bool, cut: CutSpec, steps: int, stock: Box, half: float,
    straight: tuple[int, int] = (0, 0),
) -> tuple[FloatArray, bool]:
    """Refined frames (anchored at the rulings' points nearest the stock centre where
    their origins stray).  An open polyline of a file (:func:`_polyline_pieces`) is
    refined piece by piece between its corners, which stay corners; ``half`` [m]: half
    the wire.  ``straight``: rulings of a profile's entry and exit moves
    (:mod:`.entry`) ahead of and past the profile, each move refined as a piece
    of its own by ``projection`` and ``linear`` (the wire's ends stay on their straight
    lines, as a foam cutter's towers move).  The profile's end pieces are refined
    with the moves as context (an interpolatory scheme, then cut where the moves begin),
    so that the spacing runs on smoothly into them: refined alone, a four-point piece's
    end steps shrank to a sixteenth of the move's first step, and the time law slowed
    the wire to 5.9 mm/s of 8 there."""
    s = cut.surface
    before, after = straight
    n = len(lines)
    inner = lines[before : n - after]
    cuts = _polyline_pieces(inner, closed, s.kind, stock, half, bounds=True)
    # (start, stop, context before, context after, algorithm, scheme) per piece
    pieces = [(a + before, b + before, 0, 0, s.algorithm, s.scheme) for a, b in cuts]
    sch = get_scheme(s.scheme)
    if (before or after) and sch.interpolatory:
        a, b, _, _, alg, name = pieces[0]
        pieces[0] = (a, b, before, 0, alg, name)
        a, b, c0, _, alg, name = pieces[-1]
        pieces[-1] = (a, b, c0, after, alg, name)
    if before:
        pieces.insert(0, (0, before, 0, 0, "projection", "linear"))
    if after:
        pieces.append((n - after - 1, n - 1, 0, 0, "projection", "linear"))
    frames, flip = [], False
    for k, (a, b, c0, c1, algorithm, scheme) in enumerate(pieces):
        piece = lines[a - c0 : b + c1 + 1]
        if len(piece) < get_scheme(scheme).min_points:
            scheme, c0, c1 = "linear", 0, 0
            piece = lines[a : b + 1]
        res = refine(RuledSurface(piece, closed=closed), algorithm, scheme, steps)
        F = res.frames
        if F is None:
            F = RuledSurface(res.lines, closed=closed).dh_frames("continuous")
        per = get_scheme(scheme).arity ** steps  # refined intervals per input interval
        F = F[c0 * per : len(F) - c1 * per]
        frames.append(F if k == 0 else F[1:])  # a piece starts where the last one ends
        flip = bool(res.flip)
    F = np.concatenate(frames)
    # the striction points of nearly parallel rulings run off to metres away: then every
    # frame is anchored nearest the stock centre (a slide means the same on each)
    reach = float(np.linalg.norm(stock.size)) + 2.0 * half
    if (np.linalg.norm(F[:, :3, 3] - stock.centre, axis=1) > reach).any():
        F = anchored_frames(F, stock.centre)
    return F, flip


def _polyline_pieces(lines, closed: bool, kind: str | None, stock: Box, half: float,
                     bounds: bool = False) -> list:
    """The rulings split at their corners (:func:`..motion.corners.polygon_corners`: the wire's
    travel turns by more than ``CORNER_ANGLE``), each piece refined on its own: the one
    rule for the open rulings of every file — G-code, DXF, 3DM, airfoil, lines — whose
    rulings form a polyline with corners (a foam cutter's entry and exit moves, a
    trailing edge).  Refined over a corner, a scheme swings the wire centimetres off the
    file's straight moves and the wire cannot stop there.  A built-in surface is smooth
    (its samples are not a polygon): one piece, as is a closed surface.  ``bounds``:
    each piece as its first and last index instead."""
    if closed or kind is None:
        return [(0, len(lines) - 1)] if bounds else [lines]
    cuts = [0, *polygon_corners(lines.plucker, stock.centre, half).tolist(), len(lines) - 1]
    if bounds:  # the first and last index of each piece
        return list(pairwise(cuts))
    return [lines[a : b + 1] for a, b in pairwise(cuts)]


def refine_cut(
    cut: CutSpec, stock: Box, where: str = "job", wire_length: float = 0.4,
    document: LinesDocument | None = None,
) -> RefinedCut:
    """Return the refined frames of ``cut`` (see the module doc).

    ``spacing`` takes the fewest steps whose largest gap inside the stock meets it.
    ``wire_length`` [m] (the tool's) places the wire points whose turns are a polygon's
    corners.  ``document``: the cut's input rulings (``cut.surface.document()``) when the
    caller has them.
    """
    s = cut.surface
    label = f"{where}: [surface]" if cut.name == "cut" else f"{where}: [cut '{cut.name}'.surface]"
    doc = s.document() if document is None else document
    lines, closed = doc.lines, bool(doc.closed)
    if closed and len(lines) > 3 and (len(lines) - 1) in coincident_neighbours(
            lines.plucker, closed=True):  # fmt: skip
        lines = lines[:-1]  # a closed profile drawn back to its start: the end is the start
    check_distinct_neighbours(lines.plucker, closed, f"{label} {s.label}")
    sch = get_scheme(s.scheme)
    half = 0.5 * wire_length
    try:
        entry = profile_entry(lines, s.kind, closed, stock, half, s.planes())
    except ValueError as exc:
        raise ValueError(f"{label} {s.label}: {exc}") from None
    straight = (0, 0)
    if entry is not None:  # a profile's straight entry and exit moves (:mod:`.entry`)
        lines, straight = entry.lines, (entry.before, entry.after)
    n = len(lines)
    if len(_polyline_pieces(lines, closed, s.kind, stock, half)) == 1 and s.kind != "gcode":
        check_length(sch, n, f"{label} {s.label}")  # (a polyline's short pieces: linearly)
    if s.steps is not None:
        check_size(sch, n, s.steps, closed, f"{label} steps", MAX_PATH_RULINGS, None)
        F, flip = _frames(lines, closed, cut, s.steps, stock, half, straight)
        return RefinedCut(F, s.steps, closed, flip, n)
    gap = np.inf
    for steps in range(MAX_STEPS + 1):
        if refined_count(sch, n, steps, closed) > MAX_PATH_RULINGS:
            raise ValueError(
                f"{label} spacing: {s.spacing} m needs more than "
                f"{MAX_PATH_RULINGS:,} rulings (the limit of a cut); {steps - 1} steps give a "
                f"largest gap of {gap:.3g} m: ask for a larger spacing"
            )
        F, flip = _frames(lines, closed, cut, steps, stock, half, straight)
        gap = _gaps(F, stock)
        if gap <= s.spacing:
            return RefinedCut(F, steps, closed, flip, n)
    if not np.isfinite(gap):
        raise ValueError(f"{label} spacing: no two consecutive rulings cross the stock: the "
                         "surface misses the block (check [surface] pose, [stock] centre)")
    raise ValueError(
        f"{label} spacing: {s.spacing} m not reached after {MAX_STEPS} steps "
        f"({len(F)} rulings, largest gap {gap:.3g} m)"
    )


def refine_for_job(job: Job) -> tuple[FloatArray, int]:
    """Refined frames (M, 4, 4) of the job's first cut and the number of steps used."""
    rc = refine_cut(job.cut, job.stock, str(job.source or "job"), job.tool.wire_length)
    return rc.frames, rc.steps


def _x_jumps(F: FloatArray, angle: float = CORNER_ANGLE) -> bool:
    """Whether the frames' x axes turn by more than ``angle`` [rad] between neighbours
    (the common normals of a polygon reverse at its corners); smooth DH frames are kept
    as the roll's reference, the others are world referenced
    (:func:`.wire_geometry.world_referenced`)."""
    x = F[:, :3, 0]
    return bool(((x[1:] * x[:-1]).sum(axis=1) < np.cos(angle)).any())


def _untwisted(a: FloatArray, b: FloatArray) -> FloatArray:
    """Frame ``a`` (4, 4) turned about its z axis so that its x axis is ``b``'s projected
    (the least rotation from ``a`` to ``b``): the rulings' motion without the turn of
    the frames about them, which a screw extrapolation would swing out to metres where
    the frames' x axes jump (the corner of a polygon, the end of a foam cutter's file)."""
    x = b[:3, 0] - (b[:3, 0] @ a[:3, 2]) * a[:3, 2]
    size = np.linalg.norm(x)
    if size < 1e-6:  # b's x along a's z: leave a as it is
        return a
    out = a.copy()
    out[:3, 0] = x / size
    out[:3, 1] = np.cross(a[:3, 2], out[:3, 0])
    return out


class _Endless(ValueError):
    """The extrapolation does not clear the grown stock within its limit; ``frames`` the
    extrapolated frames made so far."""

    def __init__(self, message: str, frames: FloatArray) -> None:
        super().__init__(message)
        self.frames = frames


def _extrapolated(F: FloatArray, side: int, t: FloatArray | float) -> FloatArray:
    """The frame motion ``F`` (M, 4, 4) extrapolated ``t`` gaps past its first (``side``
    0) or last (1) frame: the screw motion of the least rotation between the end frame
    and its neighbour (:func:`_untwisted`), at ``1 + t``."""
    a, b = (F[1], F[0]) if side == 0 else (F[-2], F[-1])
    return se3.geodesic(_untwisted(a, b), b, 1.0 + np.asarray(t, dtype=np.float64))


def _extension(F: FloatArray, side: int, grown: Box, limit: int = 400) -> FloatArray:
    """The extrapolated frames (K, 4, 4) past one end of ``F``, outwards, up to the first
    that clears ``grown``; :class:`_Endless` after ``limit`` of them."""
    new: list[FloatArray] = []
    last = F[0] if side == 0 else F[-1]
    while grown.clip_lines(last[None, :3, 3], last[None, :3, 2])[2][0]:
        if len(new) >= limit:
            raise _Endless(
                "lead-in/out: the frame motion does not leave the stock within "
                f"{limit} extrapolated rulings; extend the surface past the stock, or "
                "mark it closed (closed = true) if it goes all the way round",
                np.array(new),
            )
        last = _extrapolated(F, side, float(len(new) + 1))
        new.append(last)
    return np.array(new).reshape(-1, 4, 4)


@dataclass(frozen=True)
class _Overrun:
    """Where the extrapolation past one end of an open surface cuts the block."""

    end: str  #: "first" or "last"
    index: int  #: the surface's end ruling, an index of the input rulings (from 0)
    rulings: int  #: extrapolated rulings that cut the block (:func:`_in_block`)
    reach: float  #: [m] farthest chord end in the block of the extrapolation from the end ruling
    point: FloatArray  #: the end ruling's point nearest the block centre (3,)
    inside: float  #: [m] from ``point`` to where the block ends, the way the surface runs
    block_end: FloatArray  #: that end of the block (3,); NaN when ``point`` is outside it
    more: bool = False  #: the extrapolation went on past its limit (more rulings than counted)


def _off_line(p: FloatArray, F: FloatArray) -> FloatArray:
    """Distances [m] of points (..., 3) from the line of frame ``F`` (4, 4)."""
    d = p - F[:3, 3]
    z = F[:3, 2]
    return np.linalg.norm(d - (d @ z)[..., None] * z, axis=-1)


def _in_block(S: FloatArray, stock: Box, end: FloatArray, reach: float
              ) -> tuple[np.ndarray, FloatArray]:  # fmt: skip
    """Which extrapolated target rulings (K, 4, 4) cut ``stock`` beyond the surface's end
    ruling ``end`` (4, 4) -- a chord longer than :data:`SPAN_TOLERANCE` with an end
    farther than ``reach`` [m] from it -- and the distances (K,) of their chord ends
    from it (NaN where they miss the block)."""
    c0, c1, hit = chords(S, stock)
    ends = S[:, None, :3, 3] + np.stack([c0, c1], 1)[:, :, None] * S[:, None, :3, 2]
    far = _off_line(ends, end).max(axis=1)
    return hit & (np.nan_to_num(c1 - c0) > SPAN_TOLERANCE) & (np.nan_to_num(far) > reach), far


def _first_gap(F: FloatArray, side: int, centre: FloatArray) -> FloatArray:
    """The extrapolated frames within the first gap past an end of ``F`` (M, 4, 4), at
    most :data:`SPAN_STEP` apart where the rulings pass nearest ``centre`` (at most 999)."""
    pair = anchored_frames(F[[0, 1]] if side == 0 else F[[-1, -2]], centre)[:, :3, 3]
    m = int(np.clip(np.ceil(np.linalg.norm(pair[0] - pair[1]) / SPAN_STEP), 2, 1000))
    return _extrapolated(F, side, np.arange(1, m) / m)


def _overrun(
    side: int, pair: FloatArray, ext: FloatArray, gap: FloatArray, stock: Box,
    allowed: float, index: int, more: bool,
) -> _Overrun | None:
    """Whether the extrapolation past an end of the target rulings cuts ``stock`` farther
    than ``allowed`` [m] (the cut's wire tolerance) from the end ruling: ``pair`` (2, 4, 4)
    the end ruling and its neighbour, ``ext`` (K, 4, 4) the extrapolated rulings at whole
    gaps past it (``more``: the extrapolation went on), ``gap`` (G, 4, 4) more within its
    first gap (a surface stopping less than a gap short); None when it does not."""
    e = pair[0]
    cuts, far = _in_block(ext, stock, e, allowed)
    g_cuts, g_far = _in_block(gap, stock, e, allowed)
    if not (cuts.any() or g_cuts.any()):
        return None
    reach = float(np.concatenate([far[cuts], g_far[g_cuts]]).max())
    near = anchored_frames(pair, stock.centre)[:, :3, 3]
    point, run = near[0], near[0] - near[1]  # the way the surface runs past its end
    run = run - (run @ e[:3, 2]) * e[:3, 2]
    inside, block_end = np.nan, np.full(3, np.nan)
    size = float(np.linalg.norm(run))
    if stock.contains(point) and size > 0.0:
        _, t_out, through = stock.clip_lines(point, run / size)
        if through:
            inside = float(t_out)
            block_end = point + inside * run / size
    name = "first" if side == 0 else "last"
    return _Overrun(name, index, int(cuts.sum()), reach, point, inside, block_end, more)


def _mm(x: float) -> str:
    return f"{x * 1e3:.1f} mm"


def _xyz(p: FloatArray) -> str:
    return "[" + ", ".join(f"{round(float(v), 3) + 0.0:.3f}" for v in p) + "]"


def _rulings(r: _Overrun) -> str:
    """How the extrapolation cuts the block, for messages."""
    if r.rulings == 0:
        return ("along the surface's extrapolation (screw motion), between that ruling and "
                "the first extrapolated one")
    n = f"{'more than ' if r.more else ''}{counted(r.rulings, 'ruling')}"
    return f"on {n} extrapolated from the surface (screw motion)"


def _short_of_block(where: str, label: str, n: int, runs: list[_Overrun]) -> str:
    """The refusal of a surface that stops short of the block (see :func:`cut_paths`)."""
    parts = []
    for r in runs:
        at = (f"inside the block, {_mm(r.inside)} short of the block's end at "
              f"{_xyz(r.block_end)} the way the surface runs" if np.isfinite(r.inside)
              else "outside the block")  # fmt: skip
        parts.append(
            f"its {r.end} input ruling (index {r.index} of {n}, from 0) passes {_xyz(r.point)} "
            f"(its point nearest the block centre), {at}; going on would cut the block "
            f"{_rulings(r)}, up to {_mm(r.reach)} past that ruling"
        )
    return (
        f"{where} the surface ({label}) stops short of the block: "
        + "; ".join(parts)
        + ". Extend the surface past the block (a built-in surface's u range, a file's "
        f"rulings) or move the block; or add extend = true to {where} to cut the block "
        "along the extrapolation"
    )


def _extended_note(where: str, runs: list[_Overrun]) -> str:
    """The plan's note on a cut extended through the block (``extend = true``)."""
    parts = [f"up to {_mm(r.reach)} past its {r.end} input ruling {_rulings(r)}"
             for r in runs]  # fmt: skip
    return (
        f"{where} extend = true: the surface stops short of the block and the wire cuts on "
        f"{' and '.join(parts)}; the wire deviation there is measured against those "
        "extrapolated rulings"
    )


def job_search(job: Job, search: SearchOptions | None = None) -> SearchOptions:
    """Return the search options of ``job``'s passes.

    ``search`` (default: the planner's), whose motion starts near the job's ``[robot] home``
    when it names one and the options no ``q_start``.
    """
    options = SearchOptions() if search is None else search
    if job.robot.home is not None and options.q_start is None:
        options = dataclasses.replace(options, q_start=job.robot.home)
    return options


def cut_paths(
    job: Job, cut: CutSpec | None = None, model: RobotModel | None = None,
    search: SearchOptions | None = None, *, cell: Cell | None = None,
    document: LinesDocument | None = None,
) -> list[CutPath]:
    """Return the passes of ``cut`` (default: the job's first).

    One for an open surface or a closed one cut in one pass, two when a loop must be split
    (:mod:`.closed`).

    ``search``: the wire-pose search's options (:func:`job_search` of them is used);
    ``cell``: their clearance cell when the caller built it once for every cut
    (:meth:`~.wire_pose.SearchOptions.cell`); ``document``: the cut's input rulings
    when the caller read them (:meth:`~ruledrobot.wirecut.job.spec.SurfaceSpec.document`).
    """
    cut = job.cut if cut is None else cut
    if model is None:
        model = job.robot_model() if cell is None else cell.model
    options = job_search(job, search)
    if cell is None:
        cell = options.cell(model, job.tool, job.stock)
    rc = refine_cut(cut, job.stock, str(job.source or "job"), job.tool.wire_length, document)
    where = "[cut]" if cut.name == "cut" else f"[cut '{cut.name}']"
    try:
        kerf = cut_offsets(rc.frames, job.stock, cut, job.tool.heat, job.material, rc.closed)
    except ValueError as exc:  # name the job file and the cut's section
        raise ValueError(f"{job.source or 'job'}: {where} {exc}") from None
    wire = kerf.moved(rc.frames)
    clipped = clipping_note(cut, job.tool.heat, job.material)  # a warning: face_error judges
    if rc.closed:
        paths = loop_paths(job, cut, rc, wire, kerf, cell, options)
        if clipped:
            paths[0] = dataclasses.replace(paths[0], notes=(clipped, *paths[0].notes))
        return paths
    lead = max(cut.lead_in, cut.lead_out)
    grown = job.stock.grown(lead)
    _, _, near = chords(wire, grown)
    if not near.any():
        raise ValueError(f"cut '{cut.name}': no refined ruling comes near the stock; check the "
                         "surface's pose")  # fmt: skip
    first, last = np.flatnonzero(near)[[0, -1]]
    keep = slice(max(first - 1, 0), last + 2)
    W, rows = wire[keep], np.arange(len(wire))[keep]
    ext, runs = [], []
    for side in (0, 1):
        end = 0 if side == 0 else len(W) - 1
        endless = None
        try:
            frames = _extension(W, side, grown)
        except _Endless as exc:
            frames, endless = exc.frames, exc
        run = None
        if len(frames):  # the surface ends within the lead of the stock, or in it
            # the target rulings past this end (the wire's, moved back by its kerf offset)
            back = rows[end]
            run = _overrun(side, kerf.moved(W[[end, end + 1 - 2 * side]], back, back=True),
                           kerf.moved(frames, back, back=True),
                           kerf.moved(_first_gap(W, side, job.stock.centre), back, back=True),
                           job.stock, cut.wire_tolerance,
                           0 if side == 0 else rc.input_rulings - 1,
                           endless is not None)  # fmt: skip
        if endless is not None and (run is None or cut.extend):
            raise ValueError(f"{job.source or 'job'}: {where} {endless}") from None
        if run is not None:
            runs.append(run)
        ext.append(frames)
    if runs and not cut.extend:  # the extrapolation is a lead-in/out, never the surface
        raise ValueError(f"{job.source or 'job'}: " + _short_of_block(
            where, cut.surface.label, rc.input_rulings, runs))  # fmt: skip
    before, after = len(ext[0]), len(ext[1])
    F = np.concatenate([ext[0][::-1], W, ext[1]])
    if _x_jumps(F) or cut.surface.kind in FIELD_PROFILE_KINDS:
        # a corner turned the frames about the rulings, or a profile of the field (whose
        # common normals turn with its travel, half a turn round a leading edge): the
        # roll is the bow's attitude in the world, as a foam cutter's frame keeps it
        F = world_referenced(F)
    rows = np.r_[np.repeat(rows[:1], before), rows, np.repeat(rows[-1:], after)]
    S = kerf.moved(F, rows, back=True)  # the target rulings (lead-in/out ones: outside the stock)
    notes = ((_extended_note(where, runs),) if runs else ()) + ((clipped,) if clipped else ())
    err = np.r_[np.zeros(before), kerf.error[keep], np.zeros(after)]
    motion = search_wire_pose(F, job.tool, cell, options)
    return [CutPath(F, motion, rc.steps, (before, after), rc.input_rulings, cut.name,
                    S, err, kerf.compensated, notes=notes, cut=cut)]  # fmt: skip


def cut_path(
    job: Job, model: RobotModel | None = None, search: SearchOptions | None = None
) -> CutPath:
    """Return the geometric cut of the job's first cut (see the module doc).

    ``search``: the wire-pose search's options.  ``model`` defaults to the job's robot
    (flange, no tool).
    """
    return cut_paths(job, None, model, search)[0]


def chord_ends_in_flange(path: CutPath) -> FloatArray:
    """Chord end points (M, 2, 3) as points of the wire in the flange frame (NaN: no chord)."""
    F, m = path.frames, path.motion
    ends_world = F[:, None, :3, 3] + m.chord[:, :, None] * F[:, None, :3, 2]
    P_inv = se3.inverse(m.flange)
    return se3.transform_points(P_inv, ends_world)
