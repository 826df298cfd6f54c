"""Closed surfaces: the wire goes all the way round, entered and left through a slit.

A closed sequence of rulings (a column, a band, a Möbius strip) has no ends to
lead in from.  The wire enters at one ruling through a **slit**: a straight move
along the loop's tangent there (the direction the wire is about to move in), from
``lead_in`` beyond the stock — a tangent of a convex loop runs outside it, in the
waste of a kept inside.  It then follows the loop back to that ruling — the cut
closes on its start (after a loop with a flip, the wire is reversed end for end) —
and leaves straight on along the tangent.  Entering and leaving along the tangent
keeps the wire moving at the feed through the corner a slit normal to the surface
would make (a wire that stops in the foam melts a wider kerf there).

**One pass** is tried first, from the slit positions in order of their length
(a short slit removes the least material): the redundancy search (roll, slide,
IK branch, wrist turns within the joint limits) over the whole sequence slit in,
loop, slit out.  When no slit position gives one pass, the loop is **split in
two passes** that meet opposite the slit: each goes out one way from the slit,
comes back along the kerf it made and leaves through the slit; the second enters
through the first's slit.  Each pass turns the wrist through half the loop.  The
notes say why.  When that fails too, the result is infeasible with the reasons of
the best attempt.
"""

from __future__ import annotations

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ..job.spec import CutSpec, Job
from .clearance import Cell
from .cutpath import CutPath, RefinedCut
from .kerf import KerfOffsets
from .wire_geometry import chords, world_referenced
from .wire_pose import SearchOptions, search_wire_pose

__all__ = ["loop_paths", "slit_direction"]

#: slit positions tried for one pass
CANDIDATES = 6
#: spacing of the slit's frames [m]
SLIT_STEP = 0.002


def _flipped(F: FloatArray) -> FloatArray:
    """Frames turned half a turn about their x axis (z reversed: the same ruling,
    the other way round)."""
    out = F.copy()
    out[..., :3, 1] *= -1.0
    out[..., :3, 2] *= -1.0
    return out


def _loop(F: FloatArray, flip: bool, start: int, direction: int, length: int) -> FloatArray:
    """``length + 1`` frames going round the loop from ``start`` (+1 forward, -1
    backward), continuing past the seam (turned when the loop closes with a flip)."""
    M = F.shape[0]
    k = start + direction * np.arange(length + 1)
    laps = np.floor_divide(k, M)
    out = F[np.mod(k, M)].copy()
    if flip:
        odd = np.mod(laps, 2) == 1
        out[odd] = _flipped(out[odd])
    return out


def slit_direction(frames: FloatArray, i: int, stock: Box) -> FloatArray:
    """Unit direction (3,) the wire moves in at ruling ``i`` of a closed sequence.

    The tangent of the chord midpoints' loop there, normal to the ruling (central differences,
    periodic)."""
    c0, c1, hit = chords(frames, stock)
    t = np.where(hit, 0.5 * (c0 + c1), 0.0)[:, None]
    mid = frames[:, :3, 3] + t * frames[:, :3, 2]
    M = len(frames)
    d = mid[(i + 1) % M] - mid[(i - 1) % M]
    z = frames[i, :3, 2]
    d = d - (d @ z) * z
    return d / np.linalg.norm(d)


def _clear_distance(grown: Box, o: FloatArray, z: FloatArray, direction: FloatArray,
                    batch: int = 64) -> float:  # fmt: skip
    """The first of 0, ``SLIT_STEP``, 2 ``SLIT_STEP``, ... (summed step by step) [m] at
    which the line through ``o - dist * direction`` along ``z`` misses ``grown``; the
    distances are tried ``batch`` at a time (one box test each batch).  Raises past
    10 m."""
    start = 0.0
    while True:
        steps = np.full(batch, SLIT_STEP)
        steps[0] = start
        dist = np.cumsum(steps)  # start, start + step, ...: the sums one at a time gives
        dist = dist[dist <= 10.0]
        if len(dist) == 0:
            raise ValueError("slit: the ruling does not leave the stock along the normal")
        hit = grown.clip_lines(o - dist[:, None] * direction, np.broadcast_to(z, (len(dist), 3)))[2]
        if not hit.all():
            return float(dist[int(np.argmin(hit))])
        start = float(dist[-1]) + SLIT_STEP


def _slit(frame: FloatArray, direction: FloatArray, stock: Box, lead: float,
          turn: FloatArray | None = None) -> FloatArray:  # fmt: skip
    """Frames (K, 4, 4) from outside the stock (clear by ``lead``) to ``frame``, the
    wire moving along ``direction`` (from ``frame - dist * direction``).

    ``turn`` (3,): the rotation vector per metre the wire turns at where the slit meets
    the loop.  The slit's frames then turn too, at a rate falling linearly to 0 at the
    slit's outer end, so that the wire's angular velocity, like its velocity, is
    continuous where the slit meets the loop (a jump there jumps the joint rates and the
    feed with them)."""
    grown = stock.grown(lead)
    o, z = frame[:3, 3], frame[:3, 2]
    dist = _clear_distance(grown, o, z, direction)
    n = max(2, int(np.ceil(dist / SLIT_STEP)) + 1)
    out = np.repeat(frame[None], n, axis=0)
    back = np.linspace(dist, 0.0, n)  # metres before the loop
    out[:, :3, 3] = o - back[:, None] * direction
    if turn is not None and dist > 0.0:
        from scipy.spatial.transform import Rotation

        angle = back - back**2 / (2.0 * dist)  # rate falls linearly to 0 at the outer end
        R = Rotation.from_rotvec(-angle[:, None] * turn).as_matrix()
        out[:, :3, :3] = R @ frame[:3, :3]
    return out


def _pass(job: Job, cut: CutSpec, rc: RefinedCut, loop_frames: FloatArray,
          loop_surface: FloatArray, loop_err: FloatArray, slit: FloatArray, exit_: FloatArray,
          notes: tuple[str, ...], compensated: bool, cell: Cell,
          options: SearchOptions) -> CutPath:  # fmt: skip
    """Slit in, the loop's frames, slit out, as one pass through the redundancy search;
    the target of the slits' frames is the wire's own line (they cut waste)."""
    F = np.concatenate([slit[:-1], loop_frames, exit_[1:]])
    S = np.concatenate([slit[:-1], loop_surface, exit_[1:]])
    err = np.r_[np.zeros(len(slit) - 1), loop_err, np.zeros(len(exit_) - 1)]
    motion = search_wire_pose(F, job.tool, cell, options)
    return CutPath(F, motion, rc.steps, (len(slit) - 1, len(exit_) - 1), rc.input_rulings,
                   cut.name, S, err, compensated, True, notes, cut=cut)  # fmt: skip


def _exit(frame: FloatArray, direction: FloatArray, stock: Box, lead: float,
          turn: FloatArray | None = None) -> FloatArray:  # fmt: skip
    """Frames (K, 4, 4) from ``frame`` straight on along ``direction`` until the wire is
    clear of the stock by ``lead`` (``turn``: as :func:`_slit`, the rate the wire turns at
    per metre as it leaves the loop)."""
    return _slit(frame, -direction, stock, lead, None if turn is None else -turn)[::-1]


def _turn_rate(a: FloatArray, b: FloatArray) -> FloatArray:
    """The rotation vector (3,) per metre of wire travel, world frame, taking frame ``a``
    to frame ``b`` (neighbouring frames of the loop) — the rate the wire turns at."""
    from scipy.spatial.transform import Rotation

    R = b[:3, :3] @ a[:3, :3].T
    dist = float(np.linalg.norm(b[:3, 3] - a[:3, 3]))
    return Rotation.from_matrix(R).as_rotvec() / max(dist, 1e-12)


def loop_paths(
    job: Job,
    cut: CutSpec,
    rc: RefinedCut,
    wire: FloatArray,
    kerf: KerfOffsets,
    cell: Cell,
    options: SearchOptions,
) -> list[CutPath]:
    """The passes of a closed cut (module doc).

    One, or two that meet opposite the slit; each pass's wire pose searched in ``cell`` with
    ``options``."""
    M = wire.shape[0]
    wire = world_referenced(wire)
    S = world_referenced(rc.frames)
    _, _, hit = chords(wire, job.stock)
    if not hit.any():
        raise ValueError(f"cut '{cut.name}': no ruling of the closed surface crosses the stock")
    cand = np.flatnonzero(hit)
    slits = {}
    for i in cand[:: max(1, cand.size // (4 * CANDIDATES))]:
        d = slit_direction(wire, int(i), job.stock)
        loop = _loop(wire, rc.flip, int(i), 1, M)
        w_in, w_out = _turn_rate(loop[0], loop[1]), _turn_rate(loop[-2], loop[-1])
        slits[int(i)] = (_slit(loop[0], d, job.stock, cut.lead_in, w_in),
                         _exit(loop[-1], d, job.stock, cut.lead_out, w_out), d)  # fmt: skip
    order = sorted(slits, key=lambda i: len(slits[i][0]) + len(slits[i][1]))
    tried = order[:CANDIDATES]
    best = None
    for i in tried:
        entry, exit_, _ = slits[i]
        lf = _loop(wire, rc.flip, i, 1, M)
        ls = _loop(S, rc.flip, i, 1, M)
        le = kerf.error[np.mod(i + np.arange(M + 1), M)]
        cp = _pass(job, cut, rc, lf, ls, le, entry, exit_,
                   (f"closed: one pass round the loop, entered and left along the tangent at "
                    f"ruling {i}",), kerf.compensated, cell, options)  # fmt: skip
        if cp.feasible:
            return [cp]
        best = best or cp
    i = tried[0]
    entry, exit_, d = slits[i]
    half = M // 2
    why = "; ".join(best.motion.reasons) if best is not None else ""
    note = (f"closed: no single pass round the loop works from {len(tried)} entry rulings "
            f"({why}); cut in two passes from ruling {i}, meeting opposite it: each goes out "
            "and back along its own kerf (the wire turns round in the foam at the meeting "
            "ruling)")
    passes = []
    # forward: in along the tangent, round to the meeting ruling, back, out the way it came;
    # backward: in from the other side (the forward pass's way out), round the other way
    for n_pass, (direction, length, way) in enumerate(((1, half, entry),
                                                       (-1, M - half, exit_[::-1]))):  # fmt: skip
        out = _loop(wire, rc.flip, i, direction, length)
        out_s = _loop(S, rc.flip, i, direction, length)
        idx = np.mod(i + direction * np.arange(length + 1), M)
        lf = np.concatenate([out, out[-2::-1]])  # there and back along its own kerf
        ls = np.concatenate([out_s, out_s[-2::-1]])
        le = np.r_[kerf.error[idx], kerf.error[idx][-2::-1]]
        passes.append(_pass(job, cut, rc, lf, ls, le, way, way[::-1],
                            (note,) if n_pass == 0 else (), kerf.compensated, cell,
                            options))  # fmt: skip
    return passes
