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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from .wire_geometry import chords

__all__ = ["KerfOffsets", "kept_surface_error", "kerf_offsets", "ruling_normals", "waste_sign"]

#: points per chord at which the normals are sampled
SAMPLES = 9
#: a ``keep`` point nearer the surface than this [m] does not say which side is the part
KEEP_CLEARANCE = 1e-4


@dataclass(frozen=True)
class KerfOffsets:
    """Per ruling (M,) the wire's offset vector (M, 3) [m] and the predicted error of the
    kept surface (M,) [m] (the largest over the chord, >= 0); zeros when not compensated."""

    offset: FloatArray
    error: FloatArray
    compensated: bool


def _derivative(x: FloatArray, closed: bool) -> FloatArray:
    """d/di of samples x (M, 3): central differences, periodic when ``closed``."""
    if closed:
        return 0.5 * (np.roll(x, -1, axis=0) - np.roll(x, 1, axis=0))
    return np.gradient(x, axis=0)


def ruling_normals(frames: FloatArray, t: FloatArray, closed: bool = False) -> FloatArray:
    """Unit normals (M, K, 3) of the surface swept by the frames' z axes at wire
    parameters ``t`` (M, K) [m along z from the origin], ``z x (o' + t z')``."""
    o, z = frames[:, :3, 3], frames[:, :3, 2]
    do, dz = _derivative(o, closed), _derivative(z, closed)
    tangent = do[:, None, :] + t[..., None] * dz[:, None, :]
    n = np.cross(np.broadcast_to(z[:, None, :], tangent.shape), tangent)
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
    """The minimax offsets (module doc) of every ruling towards the waste by ``kerf / 2``;
    zero offsets when ``keep`` is None or ``kerf`` is 0.  Rulings that miss the stock get
    the offset of the nearest ruling that crosses it (the lead-in/out keeps its side)."""
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
    length = 2.0 * r / (1.0 + np.cos(half))
    offset = length[:, None] * bis
    idx = np.flatnonzero(hit)
    nearest = idx[np.clip(np.searchsorted(idx, np.arange(M)), 0, idx.size - 1)]
    left = idx[np.clip(np.searchsorted(idx, np.arange(M)) - 1, 0, idx.size - 1)]
    nearest = np.where(np.abs(left - np.arange(M)) < np.abs(nearest - np.arange(M)), left, nearest)
    offset = np.where(hit[:, None], offset, offset[nearest])
    err = np.abs(np.einsum("mi,mki->mk", offset, n) - r).max(axis=1)
    return KerfOffsets(offset, np.where(hit, err, 0.0), True)


def kept_surface_error(
    surface_frames: FloatArray,
    wire_frames: FloatArray,
    stock: Box,
    kerf: float,
    keep: str | FloatArray,
    closed: bool = False,
) -> FloatArray:
    """Per ruling (M,) the largest error [m] of the kept surface left by a wire on
    ``wire_frames`` (parallel, offset rulings) against the target ``surface_frames``:
    ``|distance from the wire to each tangent plane along the chord - kerf / 2|``, with
    the wire required on the waste side (a wire on the part side counts its full
    distance plus half the kerf)."""
    sign = waste_sign(surface_frames, stock, keep, closed)
    t, hit = _chord_samples(surface_frames, stock)
    n = sign * ruling_normals(surface_frames, t, closed)
    d = wire_frames[:, :3, 3] - surface_frames[:, :3, 3]
    dist = np.einsum("mi,mki->mk", d, n)
    return np.where(hit, np.abs(dist - 0.5 * kerf).max(axis=1), 0.0)
