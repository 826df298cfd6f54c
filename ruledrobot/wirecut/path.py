"""From a cut to its geometric path: refined rulings, kerf offset, lead-in/out, wire motion.

1. The input rulings are refined (the cut's surface: algorithm, scheme, and either
   a number of steps or a target ``spacing`` — the largest gap between
   consecutive rulings inside the stock, the distance from the chord ends of one
   to the next — for which the fewest steps that meet it are taken).
2. The frame motion (the refined DH frames of ``dh``; sign-continuous DH frames
   of the refined rulings otherwise) is moved ``kerf / 2`` into the waste when the
   cut names the part's side (:mod:`.kerf`).
3. Open surfaces: the frames are kept between the first and the last ruling that
   meets the stock grown by the lead distance on every side, and extended at
   either end by screw-geodesic extrapolation of the frame motion when the
   surface stops before the wire is clear of the stock by the lead distance.
   Closed surfaces are cut as loops entered through a slit (:mod:`.closed`).
4. The redundancy search (:mod:`.redundancy`) chooses roll, slide, wire
   direction and IK branch.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np

from ..algorithms import check_distinct_neighbours, refine
from ..geometry import se3
from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..geometry.ruled import RuledSurface
from ..subdivision import check_size, get_scheme, refined_count
from .closed import loop_paths
from .corners import CORNER_ANGLE, polygon_corners
from .cutpath import CutPath, RefinedCut
from .kerf import kerf_offsets
from .redundancy import solve_redundancy
from .spec import CutSpec, Job
from .toolpath import anchored_frames, chords, world_referenced

__all__ = [
    "CutPath",
    "RefinedCut",
    "chord_ends_in_flange",
    "cut_path",
    "cut_paths",
    "refine_cut",
    "refine_for_job",
]

MAX_STEPS = 10
#: Most refined rulings a cut may have (the redundancy search, the time law and the
#: simulation scale with them: ~2 min of planning and ~2 GB at this size).
MAX_PATH_RULINGS = 250_000


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
    lines, closed: bool, cut: CutSpec, steps: int, stock: Box, half: float
) -> tuple[FloatArray, bool]:
    """Refined frames (anchored at the rulings' points nearest the stock centre where
    their origins stray).  A foam cutter's open polygon of moves is refined piece by
    piece between its corners (:func:`.corners.polygon_corners`), which stay corners;
    ``half`` [m]: half the wire."""
    s = cut.surface
    pieces = [lines]
    if s.kind == "gcode" and not closed:
        cuts = [0, *polygon_corners(lines.plucker, stock.centre, half).tolist(), len(lines) - 1]
        pieces = [lines[a : b + 1] for a, b in pairwise(cuts)]
    frames, flip = [], False
    for k, piece in enumerate(pieces):
        scheme = s.scheme if len(piece) >= get_scheme(s.scheme).min_points else "linear"
        res = refine(RuledSurface(piece, closed=closed), s.algorithm, scheme, steps)
        F = res.frames
        if F is None:
            F = RuledSurface(res.lines, closed=closed).dh_frames("continuous")
        frames.append(F if k == 0 else F[1:])  # a piece starts where the last one ends
        flip = bool(res.flip)
    F = np.concatenate(frames)
    # the striction points of nearly parallel rulings run off to metres away: then every
    # frame is anchored nearest the stock centre (a slide means the same on each)
    reach = float(np.linalg.norm(stock.size)) + 2.0 * half
    if (np.linalg.norm(F[:, :3, 3] - stock.centre, axis=1) > reach).any():
        F = anchored_frames(F, stock.centre)
    return F, flip


def refine_cut(
    cut: CutSpec, stock: Box, where: str = "job", wire_length: float = 0.4
) -> RefinedCut:
    """Refined frames of ``cut`` (see the module doc): ``spacing`` takes the fewest
    steps whose largest gap inside the stock meets it.  ``wire_length`` [m] (the
    tool's) places the wire points whose turns are a polygon's corners."""
    s = cut.surface
    label = f"{where}: [surface]" if cut.name == "cut" else f"{where}: [cut '{cut.name}'.surface]"
    doc = s.document()
    lines, closed = doc.lines, bool(doc.closed)
    check_distinct_neighbours(lines.plucker, closed, f"{label} {s.label}")
    n = len(lines)
    sch = get_scheme(s.scheme)
    half = 0.5 * wire_length
    if s.steps is not None:
        check_size(sch, n, s.steps, closed, f"{label} steps", MAX_PATH_RULINGS, None)
        F, flip = _frames(lines, closed, cut, s.steps, stock, half)
        return RefinedCut(F, s.steps, closed, flip, n)
    gap = np.inf
    for steps in range(MAX_STEPS + 1):
        if refined_count(sch, n, steps, closed) > MAX_PATH_RULINGS:
            raise ValueError(
                f"{label} spacing: {s.spacing} m needs more than "
                f"{MAX_PATH_RULINGS:,} rulings (the limit of a cut); {steps - 1} steps give a "
                f"largest gap of {gap:.3g} m: ask for a larger spacing"
            )
        F, flip = _frames(lines, closed, cut, steps, stock, half)
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
    (:func:`.toolpath.world_referenced`)."""
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


def _extend(F: FloatArray, grown: Box, limit: int = 400) -> tuple[FloatArray, int, int]:
    """Extrapolate the frame motion at each end until the end frames clear ``grown``."""
    added = [0, 0]
    parts = [F]
    for side in (0, 1):
        a, b = (F[1], F[0]) if side == 0 else (F[-2], F[-1])
        a = _untwisted(a, b)
        new = []
        k = 1
        last = b
        while grown.clip_lines(last[None, :3, 3], last[None, :3, 2])[2][0]:
            if k > limit:
                raise ValueError(
                    "lead-in/out: the frame motion does not leave the stock within "
                    f"{limit} extrapolated rulings; extend the surface past the stock, or "
                    "mark it closed (closed = true) if it goes all the way round"
                )
            last = se3.geodesic(a, b, 1.0 + k)
            new.append(last)
            k += 1
        added[side] = len(new)
        if new:
            ext = np.array(new)
            parts.insert(0, ext[::-1]) if side == 0 else parts.append(ext)
    return np.concatenate(parts), added[0], added[1]


def _translated(F: FloatArray, offset: FloatArray) -> FloatArray:
    out = F.copy()
    out[:, :3, 3] += offset
    return out


def cut_paths(
    job: Job, cut: CutSpec | None = None, model=None, **search
) -> list[CutPath]:
    """The passes of ``cut`` (default: the job's first): one for an open surface or a
    closed one cut in one pass, two when a loop must be split (:mod:`.closed`)."""
    cut = job.cut if cut is None else cut
    if model is None:
        model = job.robot_model()
    rc = refine_cut(cut, job.stock, str(job.source or "job"), job.tool.wire_length)
    try:
        kerf = kerf_offsets(rc.frames, job.stock, cut.kerf, cut.keep, rc.closed)
    except ValueError as exc:  # name the job file and the cut's section
        where = "[cut]" if cut.name == "cut" else f"[cut '{cut.name}']"
        raise ValueError(f"{job.source or 'job'}: {where} {exc}") from None
    wire = _translated(rc.frames, kerf.offset)
    if job.robot.home is not None:
        search.setdefault("q_start", job.robot.home)
    if rc.closed:
        return loop_paths(job, cut, model, rc, wire, kerf, **search)
    lead = max(cut.lead_in, cut.lead_out)
    grown = Box(job.stock.centre, job.stock.size + 2.0 * lead, job.stock.rotation)
    _, _, near = chords(wire, grown)
    if not near.any():
        raise ValueError(f"cut '{cut.name}': no refined ruling comes near the stock; check the "
                         "surface's pose")  # fmt: skip
    first, last = np.flatnonzero(near)[[0, -1]]
    keep = slice(max(first - 1, 0), last + 2)
    F, before, after = _extend(wire[keep], grown)
    if _x_jumps(F):  # a corner turned the frames about the rulings: roll = bow attitude
        F = world_referenced(F)
    off = kerf.offset[keep]
    off = np.concatenate([np.repeat(off[:1], before, 0), off, np.repeat(off[-1:], after, 0)])
    S = _translated(F, -off)  # the target rulings (the lead-in/out ones lie outside the stock)
    err = np.r_[np.zeros(before), kerf.error[keep], np.zeros(after)]
    motion = solve_redundancy(F, job.stock, job.tool, model, **search)
    return [CutPath(F, motion, rc.steps, (before, after), rc.input_rulings, cut.name,
                    S, err, kerf.compensated)]  # fmt: skip


def cut_path(job: Job, model=None, **search: float) -> CutPath:
    """The geometric cut of the job's first cut (see the module doc); ``search`` goes
    to the redundancy search.  ``model`` defaults to the job's robot (flange, no tool)."""
    return cut_paths(job, None, model, **search)[0]


def chord_ends_in_flange(path: CutPath) -> FloatArray:
    """Chord end points (M, 2, 3) as points of the wire in the flange frame (NaN: no chord)."""
    F, m = path.frames, path.motion
    ends_world = F[:, None, :3, 3] + m.chord[:, :, None] * F[:, None, :3, 2]
    P_inv = se3.inverse(m.flange)
    return np.einsum("mij,mkj->mki", P_inv[:, :3, :3], ends_world) + P_inv[:, None, :3, 3]
