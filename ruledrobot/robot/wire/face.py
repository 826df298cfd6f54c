"""The cut face as the foam sees it: how far the predicted face lies from the part's
surface, per sample of any motion (docs/kerf.md, "face_error").

The wire melts a channel of width ``w`` centred on itself (:mod:`.kerf`), so the face
it leaves at a chord end ``x`` is ``x`` moved half a kerf towards the part.  With the
target surface's point ``s`` and unit normal ``n`` into the waste there, the face's
distance from the surface is::

    e = |(x - s) . n - w / 2|

at both chord ends of every sample where the wire is on the face (the cut phase, its
corner stops included; not the lead-in/out, not a closed cut's slits).  The target is
the cut's rulings as lines (origin ``o``, unit direction ``z``) with the surface's
normal field along each, which is exact on a ruled surface: the unnormalised normal
``z x (o' + t z')`` is affine in the ruling parameter ``t`` (``a + t b``), and the
ruling lies in every tangent plane along it, so ``s`` is the chord end's foot on the
ruling and ``(x - s) . n = (x - o) . n``.  The candidate rulings of a sample are those of
the nearest sampled wire positions (:meth:`FaceTarget.samples`: :data:`SAMPLES` points per
chord half a kerf off the surface, in a k-d tree) to either chord end; the plane nearest
the face decides (at a corner of the path the corner ruling's normal bisects the faces;
a neighbour's plane is the face).  The kerf ``w`` at each
end: the cut's constant ``kerf`` without a material; with one, ``material.kerf(v, p)``
with ``v`` the end's speed across the wire (:func:`.in_stock.across_speeds` in time)
and ``p`` the wire's power (:func:`.kerf.wire_power` of the set-points).  A wire that
melts nothing new (power at or below the threshold) stands in the channel it melted
before: the kerf of the last sample that melted carries on; so does a wire that stands
(slower than :data:`STILL`) -- unless at that speed it melts wider than the channel:
the wider kerf when that moves the face by at most the tolerance, else a burn (a hot
wire that stops), ``e = inf``.

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

#: sampled points per target chord (ends included) that find a chord end's rulings
SAMPLES = 5
#: the nearest sampled points whose rulings are a chord end's candidates: the plane
#: nearest the face decides (module doc)
NEAREST = 12
#: m: the largest spacing of the sampled points along the pass between rulings (at least
#: half the kerf): finer than the distance between two faces the wire could mistake
SPACING = 2e-4
#: at most this many parts per gap between two rulings (a gap across a non-face stretch)
MAX_BETWEEN = 1000
#: m/s: a hot wire slower than this stands still and burns: the melt then grows with the
#: time it stays, which the energy balance does not describe (a sampled stop never reaches
#: exactly 0)
STILL = 1e-3
#: W/m: a power within this of the threshold melts nothing (a schedule that drops to the
#: threshold at a stop, interpolated)
MELT_SLACK = 1e-9


@dataclass(frozen=True, eq=False)
class FaceTarget:
    """The part's surface one cut's pass must leave (module doc).

    ``name``: the cut; per target ruling that crosses the block (K of them): ``origins``
    (K, 3) m and unit ``directions`` (K, 3), the ruling's line; ``normal_a``, ``normal_b``
    (K, 3): the surface's normal into the waste along it, ``a + t b`` unnormalised at ``t``
    m along the direction from the origin; ``chord`` (K, 2) m: the chord's ends in the block
    as such ``t``; ``ranges``: the half-open sample ranges with the wire on the face;
    ``kerf`` m: the cut's constant kerf (used without a material); ``tolerance`` m: how far
    the face may lie from the surface."""

    name: str
    origins: FloatArray = field(repr=False)
    directions: FloatArray = field(repr=False)
    normal_a: FloatArray = field(repr=False)
    normal_b: FloatArray = field(repr=False)
    chord: FloatArray = field(repr=False)
    ranges: tuple[tuple[int, int], ...] = ()
    kerf: float = 0.0
    tolerance: float = 1e-4

    def __post_init__(self) -> None:
        arrays = {k: np.asarray(getattr(self, k), dtype=np.float64)
                  for k in ("origins", "directions", "normal_a", "normal_b", "chord")}  # fmt: skip
        K = len(arrays["origins"])
        for k, a in arrays.items():
            shape = (K, 2) if k == "chord" else (K, 3)
            if a.shape != shape or not np.isfinite(a).all():
                raise ValueError(f"face {self.name!r}: {k} must be a finite {shape} array, got "
                                 f"{a.shape}")  # fmt: skip
        norm = np.linalg.norm(arrays["directions"], axis=1, keepdims=True)
        if np.any(norm <= 0.0):
            raise ValueError(f"face {self.name!r}: a ruling's direction is zero")
        arrays["directions"] = arrays["directions"] / norm
        for k, a in arrays.items():
            object.__setattr__(self, k, a)
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

    def samples(self) -> tuple[FloatArray, np.ndarray]:
        """Where the wire belongs: points (P, 3) m and each one's two rulings (P, 2).

        Per ruling :data:`SAMPLES` points evenly along the chord, its ends included, moved
        half the cut's ``kerf`` into the waste: a wire is nearer its own ruling's than
        another face's where two faces run close (both sides of a thin trailing edge lie
        a kerf apart there).  Between consecutive rulings more such rows, linearly, at
        most :data:`SPACING` (or half a kerf, the larger) apart, owned by both rulings: a
        face whose rulings lie far apart (a straight move between two refined corners)
        has points near its wire wherever it is, so the nearest points never all belong
        to a denser face beside it (the way out of a slit past its refined corner was
        judged against the way in, a kerf off)."""
        u = np.linspace(0.0, 1.0, SAMPLES)
        t = self.chord[:, :1] + u * (self.chord[:, 1:] - self.chord[:, :1])
        k = np.broadcast_to(np.arange(len(t))[:, None], t.shape)
        on = self.origins[:, None, :] + t[..., None] * self.directions[:, None, :]
        rows = on + 0.5 * self.kerf * self.normals(k, t)  # (K, SAMPLES, 3)
        K = len(rows)
        gap = np.linalg.norm(np.diff(rows, axis=0), axis=2).max(axis=1) if K > 1 else []
        n = np.maximum(np.ceil(np.asarray(gap) / max(SPACING, 0.5 * self.kerf)), 1).astype(int)
        n = np.minimum(n, MAX_BETWEEN)  # (K-1,) parts per gap
        i = np.repeat(np.arange(K - 1), n - 1)  # the gap of each added row
        f = (np.arange(i.size) - np.repeat(np.cumsum(n - 1) - (n - 1), n - 1) + 1) / n[i]
        between = rows[i] + f[:, None, None] * (rows[i + 1] - rows[i])
        pts = np.concatenate([rows, between]).reshape(-1, 3)
        owner = np.concatenate([np.stack([np.arange(K)] * 2, axis=1), np.stack([i, i + 1], 1)])
        return pts, np.repeat(owner, SAMPLES, axis=0)

    def normals(self, k: np.ndarray, t: FloatArray) -> FloatArray:
        """Unit normals (..., 3) into the waste on rulings ``k`` (...) at ``t`` (...) m."""
        n = self.normal_a[k] + t[..., None] * self.normal_b[k]
        norm = np.linalg.norm(n, axis=-1, keepdims=True)
        return n / np.where(norm > 0.0, norm, 1.0)

    def shifted(self, start: int, stop: int) -> FaceTarget | None:
        """The target on samples ``start:stop`` renumbered from 0.

        None when no range is left."""
        ranges = shifted_ranges(self.ranges, start, stop)
        if not ranges:
            return None
        return FaceTarget(self.name, self.origins, self.directions, self.normal_a,
                          self.normal_b, self.chord, ranges, self.kerf,
                          self.tolerance)  # fmt: skip


@dataclass(frozen=True)
class FaceError:
    """The :func:`face_error` of one cut: per-sample error and kerf, and the worst error.

    ``error`` (M,) m per sample, the larger of its two chord ends (NaN off the face, inf at
    a burn); ``kerf`` (M, 2) m at the chord ends (NaN off the face); ``worst`` m (NaN when
    the wire was never on the face) at sample ``at`` (-1: none), ``t`` s its time; ``burn``:
    the worst is a burn (a stop with the heat above the threshold).
    """

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
        """Return per chord end the smallest and the largest predicted kerf on the face.

        (2, 2) m: per chord end (wire start side, wire end side) the smallest and the
        largest (NaN when never on it).
        """
        k = self.kerf[~np.isnan(self.kerf).any(axis=1)]
        if not k.size:
            return np.full((2, 2), np.nan)
        return np.stack([k.min(axis=0), k.max(axis=0)], axis=1)


def _carried(w: FloatArray, moves: np.ndarray) -> FloatArray:
    """Per column of ``w`` (R, 2): the value of the last row where ``moves`` (R, 2), the
    first such row's before any (NaN where a column never moves)."""
    out = np.full(w.shape, np.nan)
    for j in range(w.shape[1]):
        m = moves[:, j]
        if not m.any():
            continue
        idx = np.maximum.accumulate(np.where(m, np.arange(len(w)), -1))
        out[:, j] = w[np.where(idx < 0, int(np.flatnonzero(m)[0]), idx), j]
    return out


def _kerf(v: FloatArray, p: FloatArray, material: Material, tolerance: float) -> FloatArray:
    """Return the kerf (R, 2) [m] at the chord ends' speeds ``v`` (R, 2) and power ``p`` (R,).

    Module doc: where the wire moves and melts, the model; where it melts nothing new
    or stands still, the channel it melted last -- unless, standing, it melts wider than
    that at :data:`STILL`: the wider kerf when the face moves by at most ``tolerance``
    [m] for it (a set-point a hair above the threshold while the arm settles), else a
    burn (inf)."""
    melts = (p > material.power_threshold + MELT_SLACK)[:, None]
    still = v < STILL
    w = material.kerf(np.where(still, STILL, v), p[:, None])
    channel = _carried(w, melts & ~still)
    channel = np.where(np.isnan(channel), material.kerf_base, channel)
    wider = melts & still & (w > channel)
    burn = wider & (0.5 * (w - channel) > tolerance)
    return np.where(burn, np.inf, np.where((melts & ~still) | wider, w, channel))


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
        w = _kerf(v, p, material, face.tolerance)
    pts, owner = face.samples()
    near = min(NEAREST, len(pts))
    _, idx = cKDTree(pts).query(np.array(x.reshape(-1, 3)), k=near)  # writable copy
    # the candidates of both chord ends serve both: the wire lies on one ruling
    k = owner[np.asarray(idx).reshape(len(x), 2 * near)].reshape(len(x), 1, 4 * near)
    k = np.broadcast_to(k, (len(x), 2, 4 * near))
    rel = x[:, :, None, :] - face.origins[k]
    t = np.einsum("rjni,rjni->rjn", rel, face.directions[k])
    with np.errstate(invalid="ignore"):
        d = np.einsum("rjni,rjni->rjn", rel, face.normals(k, t))
        e = np.abs(d - 0.5 * w[..., None]).min(axis=2)
    e = np.where(np.isinf(w), np.inf, e)
    error[rows] = e.max(axis=1)
    kerf[rows] = w
    j = int(rows[np.argmax(error[rows])])
    return FaceError(face.name, error, kerf, float(error[j]), j, float(wis.t[j]), face.tolerance)


def face_errors(
    wis: WireInStock, power: ArrayLike | None, material: Material | None,
    faces: tuple[FaceTarget, ...],
) -> dict[str, FaceError]:
    """Return :func:`face_error` per cut name, in the order of ``faces``.

    The passes of one cut joined: the larger error per sample, the kerf where a pass is on
    its face.
    """
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
