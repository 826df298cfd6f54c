"""Kerf compensation: the wire runs half a kerf off the surface, in the waste.

The hot wire melts a slot of width ``kerf`` centred on itself, so a wire on the
CAD surface leaves the part ``kerf / 2`` too small.  The compensated wire path
moves each ruling ``kerf / 2`` towards the waste side of the surface.

The surface is ruled but not in general developable: along one ruling its
normal turns about the ruling (by an angle ``Delta`` over the chord inside the
stock).  Every tangent plane along a ruling contains it, so a line parallel to
the ruling, moved by ``d`` (normal to the ruling), lies ``d . n(t)`` from the
tangent plane at ``t``: the kept surface is then ``d . n(t) - kerf/2`` off the
target.  The offset minimising the largest error over the chord is along the
bisector of the normals' range, of length ``m = kerf / (1 + cos(Delta / 2))``;
its error is at most ``kerf/2 * tan^2(Delta / 4)`` (0.03 mm at ``kerf`` 0.8 mm
and ``Delta`` 60 deg).  :func:`kept_surface_error` measures the error the
offsets give.

Normals: ``n(t) = z x (o' + t z')`` of the discrete frame motion (origins ``o``,
ruling directions ``z``), by central differences along the rulings (one-sided
at the ends of open sequences).

**Per point** (a job with ``[material]``, docs/kerf.md): the kerf follows the speed of
each point of the wire, and on a robot-held wire the two chord ends move at different
speeds.  The time law holds the chord's fastest point at the feed, so on the held
stretches the reference end moves at the feed and the other at ``feed * ratio`` with
``ratio = v_end / v_ref <= 1`` the ratio of their speeds across the wire per unit of
path (:func:`~ruledrobot.robot.wire.in_stock.across_speeds` with the ruling index as
parameter).  Each chord end ``P`` of the target ruling is moved by half the kerf
predicted there along the normal ``n`` into the waste, ``P + w / 2 n``, and the wire is
the line through the two moved ends (still a ruling: the frame turns by the smallest
rotation from the old direction to the new).  The moved wire has other speeds, so the
ratios are taken again on it, :data:`ROUNDS` times (the offsets change by less than a
micrometre after two).  Kerf per end (:func:`.heat_power.held_kerf`):
``w = material.kerf(feed * ratio, p)`` with ``p`` the power the heat schedule sets at the
feed (:func:`.heat_power.set_power`, clipped at the output's ``full_scale``); unclipped
``constant_kerf`` gives ``w = kerf_base + (kerf - kerf_base) / ratio`` (the power that
holds ``kerf`` at the reference point melts that at the end moving ``ratio`` as fast).

**Sharp corners** (:mod:`.kerf_corners`): where the path turns by more than the corner
angle, each end goes to the corner point of the offset profile (the two offset faces'
intersection) instead of along the bisecting normal, with or without a material.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...robot.wire.in_stock import across_speeds
from ...robot.wire.kerf import Material
from ..job.spec import CutSpec, HeatSpec
from .heat_power import held_kerf
from .kerf_corners import (
    MITRE_LIMIT,
    corner_ends,
    corner_error,
    face_rulings_at_corners,
    neighbours,
)
from .wire_geometry import chords

__all__ = ["KerfOffsets", "cut_offsets", "face_rulings", "kept_surface_error", "kerf_offsets",
           "offset_ends", "point_kerf_offsets", "ruling_normals", "waste_sign"]

#: points per chord at which the normals are sampled
SAMPLES = 9
#: a ``keep`` point nearer the surface than this [m] does not say which side is the part
KEEP_CLEARANCE = 1e-4
#: rounds of the per-point compensation (module doc)
ROUNDS = 4
#: m: half the length of the line the across-speeds are taken on (any length past the chord)
_REACH = 10.0
#: m: a chord shorter than this does not set the wire's tilt (the line through two moved
#: ends a hair apart, where the wire enters the block across a corner, points anywhere):
#: it moves as the nearest ruling with a longer chord
SHORT_CHORD = 0.002


@dataclass(frozen=True)
class KerfOffsets:
    """Per ruling, the wire's offset vector and the predicted error of the kept surface.

    Per ruling (M,) the offset vector (M, 3) [m] and the predicted error (M,) [m] (the
    largest over the chord, >= 0); zeros when not compensated.

    ``turn`` (M, 3, 3): the rotation (world frame) of the wire's axes about its moved
    origin, per point compensated (None: parallel offsets, the axes unchanged);
    ``end_kerf`` (M, 2): the kerf [m] predicted at the chord's ends on the held feed
    (NaN outside the stock; None: constant).  The wire frame of target frame ``S``:
    axes ``turn @ S[:3, :3]``, origin ``S[:3, 3] + offset`` (:meth:`moved`)."""

    offset: FloatArray
    error: FloatArray
    compensated: bool
    turn: FloatArray | None = None
    end_kerf: FloatArray | None = None

    def moved(self, frames: FloatArray, index: ArrayLike | None = None,
              back: bool = False) -> FloatArray:  # fmt: skip
        """Return frames moved as the wire of the given rulings is moved from its target.

        Frames (K, 4, 4) moved as the wire of rulings ``index`` (K,) (default all) is moved
        from its target; ``back``: the target of wire frames (the inverse).
        """
        k = slice(None) if index is None else np.asarray(index)
        out = np.array(frames, dtype=np.float64)
        off = np.broadcast_to(self.offset[k], out[:, :3, 3].shape)
        if self.turn is not None:
            R = np.broadcast_to(self.turn[k], out[:, :3, :3].shape)
            R = np.swapaxes(R, -1, -2) if back else R
            out[:, :3, :3] = R @ out[:, :3, :3]
        out[:, :3, 3] += -off if back else off
        return out


def _derivative(x: FloatArray, closed: bool) -> FloatArray:
    """d/di of samples x (M, 3) by central differences: periodic when ``closed``, else
    one-sided at the ends."""
    if closed:
        return 0.5 * (np.roll(x, -1, axis=0) - np.roll(x, 1, axis=0))
    return np.gradient(x, axis=0)


def ruling_normals(frames: FloatArray, t: FloatArray, closed: bool = False) -> FloatArray:
    """Return unit normals of the surface swept by the frames' z axes at wire parameters ``t``.

    Normals (M, K, 3) at ``t`` (M, K) [m along z from the origin]: ``z x (o' + t z')`` by
    central differences along the rulings (their mean direction at a sharp corner of the
    path, where the faces behind and ahead differ: :func:`face_normals`)."""
    o, z = frames[:, :3, 3], frames[:, :3, 2]
    do, dz = _derivative(o, closed), _derivative(z, closed)
    return _unit(np.cross(z[:, None, :], do[:, None, :] + t[..., None] * dz[:, None, :]))


def face_normals(
    frames: FloatArray, t: FloatArray, before: np.ndarray, after: np.ndarray
) -> tuple[FloatArray, FloatArray]:
    """Return unit normals of the faces behind and ahead of each ruling at wire parameters ``t``.

    Normals (M, K, 3), (M, K, 3) at ``t`` (M, K) [m along z], each ``z_i x T`` with ``T``
    the face's direction of travel at ruling ``i``'s point ``P_i(t) = o_i + t z_i``,
    sampled by the rulings ``j1, j2 = before[i]`` (behind) and ``after[i]`` (ahead), (M, 2)
    each: the one-sided difference ``P_j1 - P_i`` when ``j1 == j2`` (the neighbours:
    ``z x (o' + t z')`` of the face), else the derivative at ``P_i`` of the quadratic
    through ``P_i``, ``P_j1``, ``P_j2`` at the distances ``s1``, ``s2`` from it,
    ``(s2^2 (P_j1 - P_i) - s1^2 (P_j2 - P_i)) / (s1 s2 (s2 - s1))`` (the one-sided
    second-order difference: exact on a face curved in a circle to first order).  A
    ruling that is its own neighbour (an open path's end) takes the other side's face."""
    o, z = frames[:, :3, 3], frames[:, :3, 2]
    P = o[:, None, :] + t[..., None] * z[:, None, :]
    idx = np.arange(len(o))

    def travel(j: np.ndarray) -> FloatArray:
        d1 = o[j[:, 0], None, :] + t[..., None] * z[j[:, 0], None, :] - P
        d2 = o[j[:, 1], None, :] + t[..., None] * z[j[:, 1], None, :] - P
        s1 = np.linalg.norm(d1, axis=-1, keepdims=True)
        s2 = np.linalg.norm(d2, axis=-1, keepdims=True)
        two = (j[:, 0] != j[:, 1])[:, None, None] & (s2 > s1) & (s1 > 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            q = (s2 * s2 * d1 - s1 * s1 * d2) / (s1 * s2 * (s2 - s1))
        return np.where(two, q, d1)

    back, ahead = -travel(before), travel(after)
    back = np.where((before[:, 0] == idx)[:, None, None], ahead, back)
    ahead = np.where((after[:, 0] == idx)[:, None, None], back, ahead)
    zz = np.broadcast_to(z[:, None, :], P.shape)
    return _unit(np.cross(zz, back)), _unit(np.cross(zz, ahead))


def _unit(n: FloatArray) -> FloatArray:
    """Vectors (..., 3) scaled to unit length (zeros stay zero)."""
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    return n / np.where(norm > 0.0, norm, 1.0)


def _chord_samples(frames: FloatArray, stock: Box) -> tuple[FloatArray, np.ndarray]:
    c0, c1, hit = chords(frames, stock)
    a = np.where(hit, c0, 0.0)
    b = np.where(hit, c1, 0.0)
    u = np.linspace(0.0, 1.0, SAMPLES)
    return a[:, None] + (b - a)[:, None] * u[None, :], hit


def waste_sign(
    frames: FloatArray, stock: Box, keep: str | FloatArray, closed: bool = False
) -> float:
    """+1 when the normals ``z x (o' + t z')`` point into the waste, -1 when into the part.

    ``keep``: a point of the part (3,) — its side of the surface at the nearest sampled
    surface point — or ``"inside"`` / ``"outside"`` of a closed surface (the side of the
    centroid of the chord midpoints).
    """
    t, hit = _chord_samples(frames, stock)
    if not hit.any():
        raise ValueError("keep: the surface does not cross the stock")
    n = ruling_normals(frames, t, closed)
    pts = frames[:, None, :3, 3] + t[..., None] * frames[:, None, :3, 2]
    if isinstance(keep, str):
        mid = pts[hit, SAMPLES // 2]
        inward = np.einsum("mi,mi->m", mid.mean(axis=0) - mid, n[hit, SAMPLES // 2])
        normals_inside = float(np.mean(inward)) > 0.0
        part_along_normal = normals_inside == (keep == "inside")
    else:
        P = np.asarray(keep, dtype=np.float64)
        flat, nflat = pts[hit].reshape(-1, 3), n[hit].reshape(-1, 3)
        k = int(np.argmin(np.linalg.norm(flat - P, axis=1)))
        side = float((P - flat[k]) @ nflat[k]) / max(float(np.linalg.norm(nflat[k])), 1e-300)
        if abs(side) < KEEP_CLEARANCE:
            raise ValueError(
                f"keep: the point lies on the surface ({abs(side) * 1e3:.3g} mm from it, "
                f"less than {KEEP_CLEARANCE * 1e3:g} mm): which side is the part is "
                "ambiguous; give a point well inside the part")
        part_along_normal = side > 0.0
    return -1.0 if part_along_normal else 1.0


def kerf_offsets(
    frames: FloatArray, stock: Box, kerf: float, keep: str | FloatArray | None, closed: bool
) -> KerfOffsets:
    """Return the minimax offsets of every ruling towards the waste by ``kerf / 2``.

    The offsets are the module doc's; zero offsets when ``keep`` is None or ``kerf`` is 0.
    At a sharp corner of the path the wire's ends go to the corner points of the offset
    profile (:mod:`.kerf_corners`; the wire then turns: ``turn``).  Rulings that miss the
    stock get the offset of the nearest ruling that crosses it (the lead-in/out keeps its
    side)."""
    M = frames.shape[0]
    if keep is None or kerf <= 0.0:
        return KerfOffsets(np.zeros((M, 3)), np.zeros(M), False)
    sign = waste_sign(frames, stock, keep, closed)
    t, hit = _chord_samples(frames, stock)
    n = sign * ruling_normals(frames, t, closed)  # (M, K, 3) into the waste
    # angles of the normals in the plane normal to the ruling, about the first sample
    ref = n[:, SAMPLES // 2]
    side = np.cross(frames[:, :3, 2], ref)
    ang = np.arctan2(np.einsum("mki,mi->mk", n, side), np.einsum("mki,mi->mk", n, ref))
    lo, hi = ang.min(axis=1), ang.max(axis=1)
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    bis = np.cos(mid)[:, None] * ref + np.sin(mid)[:, None] * side
    r = 0.5 * kerf
    # the bisector's length, held to the corners' mitre cap (MITRE_LIMIT half kerfs): where
    # the normals along a ruling turn by nearly 180 degrees (rulings pivoting about a point
    # in the block) no offset holds the face, and ``err`` names the shortfall
    length = 2.0 * r / np.maximum(1.0 + np.cos(half), 2.0 / MITRE_LIMIT)
    offset = length[:, None] * bis
    err = np.abs(np.einsum("mi,mki->mk", offset, n) - r).max(axis=1)
    P = frames[:, None, :3, 3] + t[..., None] * frames[:, None, :3, 2]  # (M, K, 3)
    ends, turn = _corners(frames, t, P[:, [0, -1]] + offset[:, None, :], np.full((M, 2), r),
                          sign, closed, hit)  # fmt: skip
    if turn is not None:  # the rulings at the corners: the line through their moved ends
        at = ~np.isnan(ends[:, 0, 0])
        o, z = frames[at, :3, 3], frames[at, :3, 2]
        wo, _ = _line_through(ends[at], t[at, 0], z)
        offset[at] = wo - o
        W = ends[at, :1] + np.linspace(0.0, 1.0, SAMPLES)[None, :, None] * (
            ends[at, 1:] - ends[at, :1])  # fmt: skip
        err[at] = _corner_error(frames, t, W, P, np.full(t.shape, r), sign, closed, at, hit)
    nearest = _nearest_hit(hit)
    offset = np.where(hit[:, None], offset, offset[nearest])
    turn = None if turn is None else turn[nearest]
    return KerfOffsets(offset, np.where(hit, err, 0.0), True, turn)


def offset_ends(
    frames: FloatArray, chord: FloatArray, half: FloatArray, sign: float, closed: bool = False,
    hit: np.ndarray | None = None,
) -> tuple[FloatArray, np.ndarray]:
    """The chord ends moved by their half kerfs into the waste, corners to corner points.

    The chord ends (M, 2, 3) [m] of rulings ``frames`` (M, 4, 4) at ``chord`` (M, 2) [m
    along z] each moved by its half kerf ``half`` (M, 2) [m] into the waste (``sign`` times
    the normal ``z x (o' + t z')``): along the normal, or at a sharp corner of the path to
    the offset profile's corner point (:func:`.kerf_corners.corner_ends`); and the rulings
    (M,) whose ends the corners moved.  ``hit`` (M,): the rulings in the stock (default
    all)."""
    hit = np.ones(len(frames), dtype=bool) if hit is None else hit
    n = sign * ruling_normals(frames, chord, closed)
    ends = frames[:, None, :3, 3] + chord[..., None] * frames[:, None, :3, 2]
    ends = ends + half[..., None] * n
    at_corner, _ = _corners(frames, chord, ends, half, sign, closed, hit)
    return np.where(np.isnan(at_corner), ends, at_corner), ~np.isnan(at_corner[:, 0, 0])


def _line_through(ends: FloatArray, c0: FloatArray, z: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The wire's origin and direction (K, 3) through moved chord ends ``ends`` (K, 2, 3),
    its first end at parameter ``c0`` (K,) like the target's (``z`` (K, 3) where the ends
    coincide)."""
    d = ends[:, 1] - ends[:, 0]
    length = np.linalg.norm(d, axis=1, keepdims=True)
    wz = np.where(length > 0.0, d / np.where(length > 0, length, 1.0), z)
    return ends[:, 0] - c0[:, None] * wz, wz


def _corners(
    frames: FloatArray, t: FloatArray, moved: FloatArray, half: FloatArray, sign: float,
    closed: bool, hit: np.ndarray,
) -> tuple[FloatArray, FloatArray | None]:
    """The chord ends (M, 2, 3) moved at the path's sharp corners (:func:`.kerf_corners.
    corner_ends`; NaN at the rulings that did not change) and the wire's turn (M, 3, 3)
    (identity elsewhere; None: no corner)."""
    te = t[:, [0, -1]]
    back, ahead = _faces(frames, te, te, half, sign, closed, hit)
    target = frames[:, None, :3, 3] + te[..., None] * frames[:, None, :3, 2]
    z = frames[:, :3, 2]
    ends, changed, _ = corner_ends(target, moved, z, back, ahead, half, sign, closed, hit)
    if not changed.any():
        return np.full(moved.shape, np.nan), None
    turn = np.broadcast_to(np.eye(3), (len(z), 3, 3)).copy()
    _, wz = _line_through(ends[changed], te[changed, 0], z[changed])
    turn[changed] = _rotation_between(z[changed], wz)
    return np.where(changed[:, None, None], ends, np.nan), turn


def _faces(
    frames: FloatArray, te: FloatArray, t: FloatArray, half: FloatArray, sign: float,
    closed: bool, hit: np.ndarray,
) -> tuple[FloatArray, FloatArray]:
    """The unit normals (M, K, 3) into the waste of the faces behind and ahead of each
    ruling at ``t`` (M, K), sampled by :func:`.kerf_corners.face_rulings_at_corners` from the chord
    ends ``te`` (M, 2) [m along z] with half kerfs ``half`` (M, 2) [m] (:func:`face_normals`:
    the neighbours' faces; at a sharp corner the rulings beside it up to the distance
    of its offset corner point's foot)."""
    o, z = frames[:, :3, 3], frames[:, :3, 2]
    before, after = (np.repeat(j[:, None], 2, axis=1) for j in neighbours(len(frames), closed))
    back, ahead = face_normals(frames, te, before, after)
    before, after = face_rulings_at_corners(o, z, te, sign * back, sign * ahead, half, closed, hit)
    back, ahead = face_normals(frames, t, before, after)
    return sign * back, sign * ahead


def _corner_error(
    frames: FloatArray, t: FloatArray, W: FloatArray, P: FloatArray, half: FloatArray,
    sign: float, closed: bool, at: np.ndarray, hit: np.ndarray,
) -> FloatArray:
    """:func:`.kerf_corners.corner_error` of rulings ``at`` (M,) whose moved wire has the
    points ``W`` (K, S, 3) over the target samples ``P`` (M, S, 3) at ``t`` (M, S), half
    kerfs ``half`` (M, S); the face behind and ahead of each (:func:`_faces`; ``hit`` (M,)
    the rulings in the stock)."""
    back, ahead = _faces(frames, t[:, [0, -1]], t, half[:, [0, -1]], sign, closed, hit)
    full = np.array(P)
    full[at] = W
    return corner_error(full, P, back, ahead, half, closed)[at]


def kept_surface_error(
    surface_frames: FloatArray,
    wire_frames: FloatArray,
    stock: Box,
    kerf: float,
    keep: str | FloatArray,
    closed: bool = False,
) -> FloatArray:
    """Return per ruling the largest error [m] of the kept surface left by a wire.

    Per ruling (M,), for a wire on ``wire_frames`` (parallel, offset rulings) against the
    target ``surface_frames``: ``|distance from the wire to each tangent plane along the
    chord - kerf / 2|``, with the wire required on the waste side (a wire on the part side
    counts its full distance plus half the kerf).
    """
    sign = waste_sign(surface_frames, stock, keep, closed)
    t, hit = _chord_samples(surface_frames, stock)
    n = sign * ruling_normals(surface_frames, t, closed)
    d = wire_frames[:, :3, 3] - surface_frames[:, :3, 3]
    dist = np.einsum("mi,mki->mk", d, n)
    return np.where(hit, np.abs(dist - 0.5 * kerf).max(axis=1), 0.0)


def _rotation_between(a: FloatArray, b: FloatArray) -> FloatArray:
    """(M, 3, 3) the smallest rotations taking unit vectors ``a`` (M, 3) to ``b`` (M, 3)
    (Rodrigues: ``I + [v]x + [v]x^2 / (1 + c)``, ``v = a x b``, ``c = a . b``)."""
    v = np.cross(a, b)
    c = np.einsum("mi,mi->m", a, b)
    V = np.zeros((len(a), 3, 3))
    V[:, 0, 1], V[:, 0, 2], V[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    V -= np.swapaxes(V, 1, 2)
    return np.eye(3) + V + (V @ V) / (1.0 + c)[:, None, None]


def _nearest_hit(hit: np.ndarray) -> np.ndarray:
    """(M,) for every ruling the index of the nearest ruling that crosses the stock."""
    M = hit.size
    idx = np.flatnonzero(hit)
    after = idx[np.clip(np.searchsorted(idx, np.arange(M)), 0, idx.size - 1)]
    before = idx[np.clip(np.searchsorted(idx, np.arange(M)) - 1, 0, idx.size - 1)]
    return np.where(np.abs(before - np.arange(M)) < np.abs(after - np.arange(M)), before, after)


def point_kerf_offsets(
    frames: FloatArray, stock: Box, cut: CutSpec, heat: HeatSpec | None, material: Material,
    closed: bool = False, rounds: int = ROUNDS,
) -> KerfOffsets:
    """Return the per-point compensation (module doc) of the target rulings ``frames``.

    ``frames`` (M, 4, 4): each chord end is moved by half the kerf predicted there
    (:func:`.heat_power.held_kerf`) into the waste, ``rounds`` times with the speed ratios
    of the moved wire.  Rulings that miss the stock, or whose chord is shorter than
    :data:`SHORT_CHORD`, get the offset and turn of the nearest ruling with a longer chord.
    """
    M = frames.shape[0]
    sign = waste_sign(frames, stock, cut.keep, closed)
    c0, c1, hit = chords(frames, stock)
    c = np.stack([np.where(hit, c0, 0.0), np.where(hit, c1, 0.0)], axis=1)  # (M, 2)
    u = np.linspace(0.0, 1.0, SAMPLES)
    t = c[:, :1] + (c[:, 1:] - c[:, :1]) * u[None, :]  # (M, K) along the target rulings
    n = sign * ruling_normals(frames, t, closed)  # (M, K, 3) into the waste
    o, z = frames[:, :3, 3], frames[:, :3, 2]
    P = o[:, None, :] + t[..., None] * z[:, None, :]  # (M, K, 3) target chord samples
    x = np.arange(M, dtype=np.float64)
    span = np.where(hit, c[:, 1] - c[:, 0], 0.0)
    near = _nearest_hit(span >= SHORT_CHORD)
    wo, wz = o, z
    for _ in range(max(int(rounds), 1)):
        # the (moved) wire's chord, its points' speeds across it per ruling, their ratios
        a0, a1, on = stock.clip_lines(wo, wz)
        a0, a1 = np.where(on, a0, c[:, 0]), np.where(on, a1, c[:, 1])
        lam = (a0[:, None] + (a1 - a0)[:, None] * u[None, :] + _REACH) / (2.0 * _REACH)
        line = np.stack([wo - _REACH * wz, wo + _REACH * wz], axis=1)
        v = across_speeds(x, line, lam)  # (M, K) per ruling
        ref = np.max(v, axis=1, keepdims=True)
        ratio = np.where(ref > 0.0, v / np.where(ref > 0.0, ref, 1.0), 1.0)
        w = held_kerf(ratio, cut, heat, material)  # (M, K)
        ends, at = offset_ends(frames, t[:, [0, -1]], 0.5 * w[:, [0, -1]], sign, closed, hit)
        wo, wz = _line_through(ends, c[:, 0], z)
        # rulings that miss the stock move as the nearest that crosses it (their speeds
        # are differences with their neighbours: an unmoved neighbour would add a jump)
        turn = _rotation_between(z, wz)[near]
        offset = (wo - o)[near]
        wo, wz = o + offset, np.einsum("mij,mj->mi", turn, z)
    # the kept surface: the moved line against each target tangent plane, half a kerf off
    W = ends[:, :1] + u[None, :, None] * (ends[:, 1:] - ends[:, :1])
    err = np.abs(np.einsum("mki,mki->mk", W - P, n) - 0.5 * w).max(axis=1)
    if at.any():
        err[at] = _corner_error(frames, t, W[at], P, 0.5 * w, sign, closed, at, hit)
    end = np.where(hit[:, None], w[:, [0, -1]], np.nan)
    return KerfOffsets(offset, np.where(hit, err, 0.0), True, turn, end)


def cut_offsets(
    frames: FloatArray, stock: Box, cut: CutSpec, heat: HeatSpec | None,
    material: Material | None, closed: bool,
) -> KerfOffsets:
    """Return a cut's kerf compensation.

    Per point (:func:`point_kerf_offsets`) with a ``material``, else today's constant kerf
    (:func:`kerf_offsets`); none without ``keep``.
    """
    if material is None or cut.keep is None or cut.kerf <= 0.0:
        return kerf_offsets(frames, stock, cut.kerf, cut.keep, closed)
    return point_kerf_offsets(frames, stock, cut, heat, material, closed)


def face_rulings(
    target: FloatArray, wire: FloatArray, stock: Box, keep: str | FloatArray, closed: bool = False,
    own: np.ndarray | None = None,
) -> dict[str, FloatArray]:
    """The part's surface along a pass (``face_error``'s target, :class:`FaceTarget`'s fields).

    Of the target rulings ``target`` (M, 4, 4) that cross the stock (K of them): their
    lines (``origins``, ``directions`` (K, 3)), the normal field along each into the waste,
    ``z x (o' + t z') = normal_a + t normal_b`` (:func:`ruling_normals`, unnormalised), and
    the chord in the block (``chord`` (K, 2) m along ``z``).  Each ruling's normals point
    the way its wire (``wire`` (M, 4, 4), the compensated rulings) is moved off it at the
    chord's middle -- a pass that goes out and back along a loop turns its normals round
    halfway -- and by ``keep`` (:func:`waste_sign`) where the wire is not moved.  ``own``
    (M,) bool: the rulings that are the surface (not a lead-in/out or slit; None: all)."""
    c0, c1, hit = chords(target, stock)
    if own is not None:
        hit = hit & own
    o, z = target[:, :3, 3], target[:, :3, 2]
    a = np.cross(z, _derivative(o, closed))
    b = np.cross(z, _derivative(z, closed))
    mid = 0.5 * (np.nan_to_num(c0) + np.nan_to_num(c1))
    n_mid = a + mid[:, None] * b
    off = np.einsum("ki,ki->k", wire[:, :3, 3] - o, n_mid)
    moved = np.abs(off) > 1e-12 * np.maximum(np.linalg.norm(n_mid, axis=1), 1e-300)
    sign = np.sign(off)
    if not moved[hit].all():
        sign = np.where(moved, sign, waste_sign(target, stock, keep, closed))
    return {"origins": o[hit], "directions": z[hit], "normal_a": (sign[:, None] * a)[hit],
            "normal_b": (sign[:, None] * b)[hit],
            "chord": np.stack([c0[hit], c1[hit]], axis=1)}  # fmt: skip
