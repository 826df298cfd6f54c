"""From a job to the geometric cut path: refined rulings, lead-in/out, wire motion.

1. The input rulings are refined (``job.surface``: algorithm, scheme, and either
   a number of steps or a target ``spacing`` — the largest gap between
   consecutive rulings inside the stock, the distance from the chord ends of one
   to the next — for which the fewest steps that meet it are taken).
2. The frame motion (the refined DH frames of ``dh``; sign-continuous DH frames
   of the refined rulings otherwise) is kept between the first and the last
   ruling that meets the stock grown by the lead distance on every side, and
   extended at either end by screw-geodesic extrapolation of the frame motion
   when the surface stops before the wire is clear of the stock by the lead
   distance.
3. The redundancy search (:mod:`.redundancy`) chooses roll, slide, wire
   direction and IK branch.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..algorithms import check_distinct_neighbours, refine
from ..geometry import se3
from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..geometry.ruled import RuledSurface
from ..subdivision import check_size, get_scheme, refined_count
from .job import Job
from .redundancy import RedundancyResult, solve_redundancy
from .toolpath import chords

__all__ = ["CutPath", "chord_ends_in_flange", "cut_path", "refine_for_job"]

MAX_STEPS = 10
#: Most refined rulings a cut may have (the redundancy search, the time law and the
#: simulation scale with them: ~2 min of planning and ~2 GB at this size).
MAX_PATH_RULINGS = 250_000


@dataclass(frozen=True)
class CutPath:
    """The geometric cut: frames (M, 4, 4) on the rulings and the chosen robot motion."""

    frames: FloatArray = field(repr=False)
    motion: RedundancyResult
    steps: int
    extended: tuple[int, int]  # frames added before / after by extrapolation
    input_rulings: int

    @property
    def feasible(self) -> bool:
        return self.motion.feasible


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


def _frames(job: Job, steps: int) -> FloatArray:
    s = job.surface
    lines = job.input_lines()
    res = refine(lines, s.algorithm, s.scheme, steps)
    if res.frames is not None:
        return res.frames
    return RuledSurface(res.lines).dh_frames("continuous")


def refine_for_job(job: Job) -> tuple[FloatArray, int]:
    """Refined frames (M, 4, 4) and the number of steps used (see the module doc):
    ``spacing`` takes the fewest steps whose largest gap inside the stock meets it."""
    where = f"{job.source or 'job'}: [surface]"
    check_distinct_neighbours(job.input_lines().plucker, False,
                              f"{where} {job.surface.file or job.surface.builtin}")  # fmt: skip
    n = len(job.input_lines())
    sch = get_scheme(job.surface.scheme)
    if job.surface.steps is not None:
        check_size(sch, n, job.surface.steps, False, f"{where} steps", MAX_PATH_RULINGS, None)
        return _frames(job, job.surface.steps), job.surface.steps
    gap = np.inf
    for steps in range(MAX_STEPS + 1):
        if refined_count(sch, n, steps, False) > MAX_PATH_RULINGS:
            raise ValueError(
                f"{where} spacing: {job.surface.spacing} m needs more than "
                f"{MAX_PATH_RULINGS:,} rulings (the limit of a cut); {steps - 1} steps give a "
                f"largest gap of {gap:.3g} m: ask for a larger spacing"
            )
        F = _frames(job, steps)
        gap = _gaps(F, job.stock)
        if gap <= job.surface.spacing:
            return F, steps
    if not np.isfinite(gap):
        raise ValueError(f"{where} spacing: no two consecutive rulings cross the stock: the "
                         "surface misses the block (check [surface] pose, [stock] centre)")
    raise ValueError(
        f"{where} spacing: {job.surface.spacing} m not reached after {MAX_STEPS} steps "
        f"({len(F)} rulings, largest gap {gap:.3g} m)"
    )


def _extend(F: FloatArray, grown: Box, limit: int = 400) -> tuple[FloatArray, int, int]:
    """Extrapolate the frame motion at each end until the end frames clear ``grown``."""
    added = [0, 0]
    parts = [F]
    for side in (0, 1):
        a, b = (F[1], F[0]) if side == 0 else (F[-2], F[-1])
        new = []
        k = 1
        last = b
        while grown.clip_lines(last[None, :3, 3], last[None, :3, 2])[2][0]:
            if k > limit:
                raise ValueError(
                    "lead-in/out: the frame motion does not leave the stock within "
                    f"{limit} extrapolated rulings; extend the surface past the stock"
                )
            last = se3.geodesic(a, b, 1.0 + k)
            new.append(last)
            k += 1
        added[side] = len(new)
        if new:
            ext = np.array(new)
            parts.insert(0, ext[::-1]) if side == 0 else parts.append(ext)
    return np.concatenate(parts), added[0], added[1]


def cut_path(job: Job, model=None, **search: float) -> CutPath:
    """The geometric cut of ``job`` (see the module doc); ``search`` goes to the
    redundancy search.  ``model`` defaults to the job's robot (flange, no tool)."""

    if model is None:
        model = job.robot_model()
    F, steps = refine_for_job(job)
    lead = max(job.cut.lead_in, job.cut.lead_out)
    grown = Box(job.stock.centre, job.stock.size + 2.0 * lead, job.stock.rotation)
    _, _, near = chords(F, grown)
    if not near.any():
        raise ValueError("surface: no refined ruling comes near the stock; check [surface] pose")
    first, last = np.flatnonzero(near)[[0, -1]]
    F = F[max(first - 1, 0) : last + 2]
    F, before, after = _extend(F, grown)
    if job.robot.home is not None:
        search.setdefault("q_start", job.robot.home)
    motion = solve_redundancy(F, job.stock, job.tool, model, **search)
    return CutPath(F, motion, steps, (before, after), len(job.input_lines()))


def chord_ends_in_flange(path: CutPath) -> FloatArray:
    """Chord end points (M, 2, 3) as points of the wire in the flange frame (NaN: no chord)."""
    F, m = path.frames, path.motion
    ends_world = F[:, None, :3, 3] + m.chord[:, :, None] * F[:, None, :3, 2]
    P_inv = se3.inverse(m.flange)
    return np.einsum("mij,mkj->mki", P_inv[:, :3, :3], ends_world) + P_inv[:, None, :3, 3]
