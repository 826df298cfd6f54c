"""Closed surfaces: the wire goes all the way round, entered and left through a slit.

A closed sequence of rulings (a column, a band, a Möbius strip) has no ends to
lead in from.  The wire enters at one ruling through a **slit**: a straight move
normal to the ruling, from ``lead_in`` beyond the stock to the surface, on the
waste side (outwards when no side is kept).  It then follows the loop back to
that ruling — the cut closes on its start (after a loop with a flip, the wire is
reversed end for end) — and leaves through the slit.

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

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from .cutpath import CutPath, RefinedCut
from .kerf import KerfOffsets, ruling_normals, waste_sign
from .redundancy import solve_redundancy
from .spec import CutSpec, Job
from .toolpath import chords

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


def slit_direction(
    frames: FloatArray, i: int, stock: Box, keep, closed: bool = True
) -> FloatArray:
    """Unit direction (3,) of the slit at ruling ``i``: the surface normal at the chord's
    middle, normal to the ruling, pointing into the waste (outwards from the loop's
    centre when ``keep`` is None)."""
    c0, c1, hit = chords(frames, stock)
    t = np.where(hit, 0.5 * (c0 + c1), 0.0)[:, None]
    n = ruling_normals(frames, t, closed)[:, 0]
    if keep is None:
        mid = frames[:, :3, 3] + t * frames[:, :3, 2]
        centre = mid[hit].mean(axis=0)
        sign = 1.0 if float((mid[i] - centre) @ n[i]) > 0.0 else -1.0
    else:
        sign = waste_sign(frames, stock, keep, closed)
    d = sign * n[i]
    z = frames[i, :3, 2]
    d = d - (d @ z) * z
    return d / np.linalg.norm(d)


def _slit(frame: FloatArray, direction: FloatArray, stock: Box, lead: float) -> FloatArray:
    """Frames (K, 4, 4) from outside the stock (clear by ``lead``) to ``frame``, moving
    along ``-direction``."""
    grown = Box(stock.centre, stock.size + 2.0 * lead, stock.rotation)
    o, z = frame[:3, 3], frame[:3, 2]
    dist = 0.0
    while grown.clip_lines((o + dist * direction)[None], z[None])[2][0]:
        dist += SLIT_STEP
        if dist > 10.0:
            raise ValueError("slit: the ruling does not leave the stock along the normal")
    n = max(2, int(np.ceil(dist / SLIT_STEP)) + 1)
    out = np.repeat(frame[None], n, axis=0)
    out[:, :3, 3] = o + np.linspace(dist, 0.0, n)[:, None] * direction
    return out


def _pass(job: Job, cut: CutSpec, model, rc: RefinedCut, loop_frames: FloatArray,
          loop_surface: FloatArray, loop_err: FloatArray, slit: FloatArray, name: str,
          notes: tuple[str, ...], compensated: bool, **search) -> CutPath:  # fmt: skip
    back = slit[::-1]
    back_surface = back.copy()
    back_surface[:, :3, 3] += loop_surface[-1, :3, 3] - loop_frames[-1, :3, 3]
    front_surface = slit.copy()
    front_surface[:, :3, 3] += loop_surface[0, :3, 3] - loop_frames[0, :3, 3]
    F = np.concatenate([slit[:-1], loop_frames, back[1:]])
    S = np.concatenate([front_surface[:-1], loop_surface, back_surface[1:]])
    err = np.r_[np.zeros(len(slit) - 1), loop_err, np.zeros(len(back) - 1)]
    motion = solve_redundancy(F, job.stock, job.tool, model, **search)
    return CutPath(F, motion, rc.steps, (len(slit) - 1, len(back) - 1), rc.input_rulings,
                   name, S, err, compensated, True, notes)  # fmt: skip


def loop_paths(
    job: Job,
    cut: CutSpec,
    model,
    rc: RefinedCut,
    wire: FloatArray,
    kerf: KerfOffsets,
    **search,
) -> list[CutPath]:
    """The passes of a closed cut (module doc): one, or two that meet opposite the slit."""
    M = wire.shape[0]
    S = rc.frames
    _, _, hit = chords(wire, job.stock)
    if not hit.any():
        raise ValueError(f"cut '{cut.name}': no ruling of the closed surface crosses the stock")
    cand = np.flatnonzero(hit)
    slits = {}
    for i in cand[:: max(1, cand.size // (4 * CANDIDATES))]:
        d = slit_direction(S, int(i), job.stock, cut.keep)
        slits[int(i)] = (_slit(wire[i], d, job.stock, cut.lead_in), d)
    order = sorted(slits, key=lambda i: len(slits[i][0]))
    tried = order[:CANDIDATES]
    best = None
    for i in tried:
        slit, _ = slits[i]
        lf = _loop(wire, rc.flip, i, 1, M)
        ls = _loop(S, rc.flip, i, 1, M)
        le = kerf.error[np.mod(i + np.arange(M + 1), M)]
        cp = _pass(job, cut, model, rc, lf, ls, le, slit, cut.name,
                   (f"closed: one pass round the loop, slit at ruling {i}",), kerf.compensated,
                   **search)  # fmt: skip
        if cp.feasible:
            return [cp]
        best = best or cp
    i = tried[0]
    slit, _ = slits[i]
    half = M // 2
    why = "; ".join(best.motion.reasons) if best is not None else ""
    note = (f"closed: no single pass round the loop works from {len(tried)} slit positions "
            f"({why}); cut in two passes from the slit at ruling {i}, meeting opposite it")
    passes = []
    for n_pass, (direction, length) in enumerate(((1, half), (-1, M - half))):
        out = _loop(wire, rc.flip, i, direction, length)
        out_s = _loop(S, rc.flip, i, direction, length)
        idx = np.mod(i + direction * np.arange(length + 1), M)
        lf = np.concatenate([out, out[-2::-1]])  # there and back along its own kerf
        ls = np.concatenate([out_s, out_s[-2::-1]])
        le = np.r_[kerf.error[idx], kerf.error[idx][-2::-1]]
        passes.append(_pass(job, cut, model, rc, lf, ls, le, slit,
                            cut.name, (note,) if n_pass == 0 else (), kerf.compensated,
                            **search))  # fmt: skip
    return passes
