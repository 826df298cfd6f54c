"""The cut face as the foam sees it: how far the predicted face lies from the part's
surface, per sample of any motion (docs/kerf.md, "face_error").

The wire melts a channel of width ``w`` centred on itself (:mod:`.kerf`), so the face
it leaves at a chord end ``x`` is ``x`` moved half a kerf towards the part.  With the
target surface's point ``s`` and unit normal ``n`` into the waste there, the face's
distance from the surface is::

    e = |(x - s) . n - w / 2|

at both chord ends of every sample where the wire is on the face (the cut phase, its
corner stops included; not the lead-in/out, not a closed cut's slits).  ``s`` and ``n``
are those of the nearest chord end of the target rulings (a k-d tree; the tangent plane
there stands for the surface within half a ruling interval).  The kerf ``w`` at each
end: the cut's constant ``kerf`` without a material; with one, ``material.kerf(v, p)``
with ``v`` the end's speed across the wire (:func:`.in_stock.across_speeds` in time)
and ``p`` the wire's power (:func:`.kerf.wire_power` of the set-points).  A wire that
melts nothing new (power at or below the threshold) stands in the channel it melted
before: the kerf of the last sample that melted carries on.  A hot wire that stops is
a burn: ``e = inf``.

Everyone who holds a motion and its heat calls :func:`face_error` with the
:class:`FaceTarget` of the trajectory's sidecar: the plan, an export's verification,
a run's verdict on its recording.  Units: m, s, W/m; one frame (the robot base frame).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.ranges import checked_ranges, ranges_mask, shifted_ranges
from .._checks import FloatArray
from .in_stock import WireInStock, across_speeds
from .kerf import Material

__all__ = ["FaceError", "FaceTarget", "face_error", "face_errors"]

#: W/m: a power within this of the threshold melts nothing (a schedule that drops to the
#: threshold at a stop, interpolated)
MELT_SLACK = 1e-9


@dataclass(frozen=True, eq=False)
class FaceTarget:
    """The part's surface one cut's pass must leave (module doc).

    ``name``: the cut; ``points`` (K, 2, 3) m: the chord ends of its target rulings in the
    block; ``normals`` (K, 2, 3): unit normals of the surface there, into the waste;
    ``ranges``: the half-open sample ranges with the wire on the face; ``kerf`` m: the
    cut's constant kerf (used without a material); ``tolerance`` m: how far the face may
    lie from the surface."""

    name: str
    points: FloatArray = field(repr=False)
    normals: FloatArray = field(repr=False)
    ranges: tuple[tuple[int, int], ...] = ()
    kerf: float = 0.0
    tolerance: float = 1e-4

    def __post_init__(self) -> None:
        p = np.asarray(self.points, dtype=np.float64).reshape(-1, 2, 3)
        n = np.asarray(self.normals, dtype=np.float64).reshape(-1, 2, 3)
        if p.shape != n.shape or not (np.isfinite(p).all() and np.isfinite(n).all()):
            raise ValueError(f"face {self.name!r}: points {p.shape} and normals {n.shape} must "
                             "be finite (K, 2, 3) arrays of one shape")  # fmt: skip
        norm = np.linalg.norm(n, axis=-1, keepdims=True)
        if np.any(norm <= 0.0):
            raise ValueError(f"face {self.name!r}: a normal is zero")
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "normals", n / norm)
        ranges = checked_ranges(self.ranges, f"face {self.name!r} ranges")
        object.__setattr__(self, "ranges", ranges)
        if not (np.isfinite(self.kerf) and self.kerf >= 0.0):
            raise ValueError(f"face {self.name!r}: kerf must be >= 0 m, got {self.kerf}")
        if not (np.isfinite(self.tolerance) and self.tolerance > 0.0):
            raise ValueError(f"face {self.name!r}: tolerance must be > 0 m, got {self.tolerance}")
        object.__setattr__(self, "kerf", float(self.kerf))
        object.__setattr__(self, "tolerance", float(self.tolerance))

    def mask(self, n: int) -> np.ndarray:
        """(n,) bool: sample k is on the face."""
        return ranges_mask(self.ranges, n)

    def shifted(self, start: int, stop: int) -> FaceTarget | None:
        """The target on samples ``start:stop`` renumbered from 0 (None when no range is
        left)."""
        ranges = shifted_ranges(self.ranges, start, stop)
        if not ranges:
            return None
        return FaceTarget(self.name, self.points, self.normals, ranges, self.kerf,
                          self.tolerance)  # fmt: skip


@dataclass(frozen=True)
class FaceError:
    """:func:`face_error` of one cut: ``error`` (M,) m per sample, the larger of its two
    chord ends (NaN off the face, inf at a burn); ``kerf`` (M, 2) m at the chord ends
    (NaN off the face); ``worst`` m (NaN when the wire was never on the face) at sample
    ``at`` (-1: none), ``t`` s its time; ``burn``: the worst is a burn (a stop with the
    heat above the threshold)."""

    name: str
    error: FloatArray = field(repr=False)
    kerf: FloatArray = field(repr=False)
    worst: float
    at: int
    t: float
    tolerance: float

    @property
    def burn(self) -> bool:
        """Whether the worst sample is a burn (``inf``)."""
        return bool(np.isinf(self.worst))

    @property
    def ok(self) -> bool:
        """Whether the worst error is at most the tolerance (False when never on the face)."""
        return bool(np.isfinite(self.worst) and self.worst <= self.tolerance)

    def kerf_range(self) -> FloatArray:
        """(2, 2) m: per chord end (wire start side, wire end side) the smallest and the
        largest predicted kerf on the face (NaN when never on it)."""
        k = self.kerf[~np.isnan(self.kerf).any(axis=1)]
        if not k.size:
            return np.full((2, 2), np.nan)
        return np.stack([k.min(axis=0), k.max(axis=0)], axis=1)


def _carried(w: FloatArray, melts: np.ndarray) -> FloatArray:
    """``w`` (M, 2) with the rows where the wire melts nothing replaced by the last row
    that melted (the first melting row before any)."""
    if melts.all() or not melts.any():
        return w
    idx = np.where(melts, np.arange(len(w)), -1)
    idx = np.maximum.accumulate(idx)
    idx = np.where(idx < 0, int(np.flatnonzero(melts)[0]), idx)
    return w[idx]


def face_error(
    wis: WireInStock, power: ArrayLike | None, material: Material | None, face: FaceTarget
) -> FaceError:
    """The predicted cut face against ``face`` along a motion (module doc).

    ``wis``: the wire against the block (M samples); ``power`` (M,) W/m the wire's power
    (:func:`.kerf.wire_power` of the set-points; None: no heat model, the constant kerf);
    ``material``: the foam (None: ``face.kerf`` everywhere)."""
    from scipy.spatial import cKDTree

    M = wis.n
    rows = np.flatnonzero(face.mask(M) & wis.inside)
    error = np.full(M, np.nan)
    kerf = np.full((M, 2), np.nan)
    if not rows.size:
        return FaceError(face.name, error, kerf, float("nan"), -1, float("nan"), face.tolerance)
    x = wis.chord_points()[rows]  # (R, 2, 3)
    if material is None or power is None:
        w = np.full((rows.size, 2), face.kerf)
    else:
        p = np.asarray(power, dtype=np.float64)[rows]
        v = across_speeds(wis.t, wis.ends, wis.fractions())[rows]  # (R, 2)
        w = material.kerf(v, p[:, None])
        melts = p > material.power_threshold + MELT_SLACK
        w = np.where(melts[:, None] | ~np.isfinite(w), w, np.nan)
        w = np.where(melts[:, None], w, _carried(w, melts))
        w = np.where(np.isnan(w), material.kerf_base, w)
    tree = cKDTree(face.points.reshape(-1, 3))
    _, k = tree.query(x.reshape(-1, 3))
    s = face.points.reshape(-1, 3)[k].reshape(x.shape)
    n = face.normals.reshape(-1, 3)[k].reshape(x.shape)
    with np.errstate(invalid="ignore"):
        e = np.abs(np.einsum("rki,rki->rk", x - s, n) - 0.5 * w)
    e = np.where(np.isinf(w), np.inf, e)
    error[rows] = e.max(axis=1)
    kerf[rows] = w
    j = int(rows[np.argmax(error[rows])])
    return FaceError(face.name, error, kerf, float(error[j]), j, float(wis.t[j]), face.tolerance)


def face_errors(
    wis: WireInStock, power: ArrayLike | None, material: Material | None,
    faces: tuple[FaceTarget, ...],
) -> dict[str, FaceError]:
    """:func:`face_error` per cut name (the passes of one cut joined: the larger error per
    sample, the kerf where a pass is on its face), in the order of ``faces``."""
    out: dict[str, FaceError] = {}
    for f in faces:
        e = face_error(wis, power, material, f)
        if f.name in out:
            a = out[f.name]
            error = np.fmax(a.error, e.error)
            kerf = np.where(np.isnan(e.kerf), a.kerf, e.kerf)
            e = e if not np.isnan(e.worst) and not (e.worst <= a.worst) else a
            e = FaceError(f.name, error, kerf, e.worst, e.at, e.t, e.tolerance)
        out[f.name] = e
    return out
