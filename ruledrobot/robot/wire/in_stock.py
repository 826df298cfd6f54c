"""The one model of the wire against the block: where the wire is in the foam and how
fast it cuts, per sample of any motion.

Every consumer reads it — the time law's feed bound, the planner's ``in_stock`` and
phases, every verdict check on the feed and the wire, the sidecar, the verification
of exported programs, the runner (live and on its recording), resume and the
viewer — so that they cannot disagree (docs/verdict.md, "One truth about the cut").

The wire is the straight segment from ``ends[:, 0]`` (the tool's ``wire_start``) to
``ends[:, 1]``; a material point of it is a fraction ``lam`` in [0, 1] of the way.

* **Chord**: the part of the wire inside the block (:class:`~ruledrobot.geometry.box.Box`,
  slab method), ``lo <= lam <= hi``.  The wire is *in the stock* where the chord is at
  least :data:`TOUCH` long: a lead-in ends at the first such sample.
* **Depth**: how far the chord reaches into the block, the largest distance of a
  chord point from the block's surface.  In box coordinates that distance is
  ``min_k (h_k - |p_k(lam)|)``, the lower envelope of six affine functions of
  ``lam``, so its maximum is at a chord end or where two of them cross: evaluated
  exactly at those 17 candidates.
* **Cutting speed (feed)**: the speed *across the wire* of its material points
  inside the block — a point sliding along the wire cuts nothing.  For a rigid wire
  the velocity is affine in ``lam``, its part across the wire too, and the norm of an
  affine function is convex, so the largest value over the chord is at a chord end.
  Velocities are central differences of the *same material points* (one-sided at
  the first and last sample): ``v = (p_{k+1}(lam) - p_{k-1}(lam)) / (x_{k+1} -
  x_{k-1})``, across = ``v - (v . d_k) d_k`` with ``d_k`` the wire's direction.

Units: m, s, m/s.  Frames: the wire and the block in one frame (the robot base frame).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from itertools import combinations

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.box import Box
from ...geometry.ranges import runs_of
from .._checks import FloatArray
from ..tool import BowTool

__all__ = [
    "TOUCH",
    "WireInStock",
    "across_speeds",
    "chord_fractions",
    "feed_chord",
    "flange_wire_ends",
    "largest_line_distance",
    "wire_ends",
    "wire_gap",
    "wire_in_stock",
]

#: m: a chord shorter than this is not in the stock (the wire only touches the block).
TOUCH = 1e-6


def largest_line_distance(
    points: ArrayLike, origins: ArrayLike, directions: ArrayLike
) -> FloatArray:
    """Return the largest distance (K,) [m] of points from lines.

    Points (K, P, 3); the lines through ``origins`` (K, 3) along ``directions`` (K, 3),
    normalised here: ``max_p |(x_p - o) x u|``; NaN points are left out (0 when all are).
    The wire's deviation from a line — its target ruling (the plan), the planned wire (an
    exported program, a run) — with the points the chord's ends.
    """
    x = np.asarray(points, dtype=np.float64)
    o = np.asarray(origins, dtype=np.float64)
    u = np.asarray(directions, dtype=np.float64)
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    d = np.linalg.norm(np.cross(x - o[:, None, :], u[:, None, :]), axis=-1)
    return np.nan_to_num(d, nan=0.0).max(axis=1) if d.size else np.zeros(len(o))


def wire_ends(tcp: ArrayLike, wire_length: float) -> FloatArray:
    """Return the wire ends (M, 2, 3) of TCP poses (M, 4, 4): ``p -+ (L / 2) z``.

    The poses' origin is the wire's midpoint and their z axis runs along the wire from its
    start to its end (the planner's wire frame, the trajectory's TCP).
    """
    T = np.asarray(tcp, dtype=np.float64)
    half = 0.5 * float(wire_length) * T[..., :3, 2]
    p = T[..., :3, 3]
    return np.stack([p - half, p + half], axis=-2)


def flange_wire_ends(flange: ArrayLike, bow: BowTool) -> FloatArray:
    """Wire ends (M, 2, 3) of flange poses (M, 4, 4) that carry ``bow``.

    :func:`wire_ends` of the wire frames ``flange @ W``
    (:meth:`~ruledrobot.robot.tool.BowTool.wire_frame`), i.e. the bow's ``wire_start`` and
    ``wire_end`` carried by each flange pose. The one derivation of the wire from the arm (the
    planner, the playback's contacts and video, the viewer); the ends are in the flange poses'
    frame (base or world)."""
    return wire_ends(np.asarray(flange, dtype=np.float64) @ bow.wire_frame(), bow.wire_length)


def chord_fractions(
    ends: ArrayLike, stock: Box, margin: float = 0.0
) -> tuple[FloatArray, FloatArray]:
    """The chord of each wire in the block grown by ``margin``.

    ``(lo, hi)`` (M,) as fractions of the wire from its start, NaN where the chord is shorter
    than :data:`TOUCH` (the wire misses or only touches the block)."""
    e = np.asarray(ends, dtype=np.float64)
    a, d = e[..., 0, :], e[..., 1, :] - e[..., 0, :]
    length = np.linalg.norm(d, axis=-1)
    t_in, t_out, hit = stock.clip_lines(a, d, margin)
    lo = np.clip(np.where(hit, t_in, 0.0), 0.0, 1.0)
    hi = np.clip(np.where(hit, t_out, 0.0), 0.0, 1.0)
    inside = hit & ((hi - lo) * length >= TOUCH)
    return np.where(inside, lo, np.nan), np.where(inside, hi, np.nan)


def _neighbours(m: int) -> tuple[np.ndarray, np.ndarray]:
    k = np.arange(m)
    return np.minimum(k + 1, m - 1), np.maximum(k - 1, 0)


def across_speeds(x: ArrayLike, ends: ArrayLike, fractions: ArrayLike) -> FloatArray:
    """Return the speed across the wire (M, K) of the material points at ``fractions``.

    Points at ``fractions`` (M, K) of each wire (``ends`` (M, 2, 3)), per unit of ``x`` (M,)
    strictly increasing (time: m/s; a path parameter: m per unit).  Central differences of
    the same material points, one-sided at the ends (module doc); NaN fractions give NaN.
    """
    xa = np.asarray(x, dtype=np.float64)
    e = np.asarray(ends, dtype=np.float64)
    f = np.asarray(fractions, dtype=np.float64)
    m = xa.size
    if m < 2:
        return np.where(np.isnan(f), np.nan, 0.0)
    nxt, prv = _neighbours(m)
    a, d = e[:, 0], e[:, 1] - e[:, 0]

    def points(k: np.ndarray) -> FloatArray:  # material points of sample j at sample k[j]
        return a[k, None, :] + f[:, :, None] * d[k, None, :]

    v = (points(nxt) - points(prv)) / (xa[nxt] - xa[prv])[:, None, None]
    u = d / np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-300)
    v = v - (v * u[:, None, :]).sum(-1, keepdims=True) * u[:, None, :]
    return np.linalg.norm(v, axis=-1)


_PAIRS = np.array(list(combinations(range(6), 2)))


def _depth(ends: FloatArray, lo: FloatArray, hi: FloatArray, stock: Box) -> FloatArray:
    """(M,) the largest distance of a chord point from the block's surface (module doc);
    0 where there is no chord."""
    inside = ~np.isnan(lo)
    out = np.zeros(lo.shape)
    if not inside.any():
        return out
    e = stock.to_box(ends[inside])  # (n, 2, 3)
    p0, dp = e[:, 0], e[:, 1] - e[:, 0]
    h = 0.5 * stock.size
    # g(lam) = c + s lam for the six faces: h - p and h + p
    c = np.concatenate([h - p0, h + p0], axis=1)  # (n, 6)
    s = np.concatenate([-dp, dp], axis=1)
    i, j = _PAIRS[:, 0], _PAIRS[:, 1]
    ds = s[:, i] - s[:, j]
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = (c[:, j] - c[:, i]) / ds
    a, b = lo[inside], hi[inside]
    cand = np.concatenate([a[:, None], b[:, None], np.where(np.isfinite(cross), cross, a[:, None])],
                          axis=1)  # fmt: skip
    cand = np.clip(cand, a[:, None], b[:, None])  # (n, 17)
    g = c[:, None, :] + cand[:, :, None] * s[:, None, :]  # (n, 17, 6)
    out[inside] = np.maximum(g.min(axis=2).max(axis=1), 0.0)
    return out


@dataclass(frozen=True, eq=False)
class WireInStock:
    """The wire against the block along M samples (module doc).

    ``t`` (M,) s; ``ends`` (M, 2, 3) the wire's start and end (m); ``lo``, ``hi``
    (M,) the chord as fractions of the wire from its start (NaN outside); ``inside``
    (M,) the wire is in the stock; ``feed`` (M,) m/s, the cutting speed: the fastest
    speed across the wire of a chord point (NaN outside: the wire cuts nothing there);
    ``stock`` the block; :attr:`depth` (M,) m (0 outside), computed when first read.
    """

    t: FloatArray = field(repr=False)
    ends: FloatArray = field(repr=False)
    lo: FloatArray = field(repr=False)
    hi: FloatArray = field(repr=False)
    inside: np.ndarray = field(repr=False)
    feed: FloatArray = field(repr=False)
    stock: Box = field(repr=False)

    @cached_property
    def depth(self) -> FloatArray:
        """(M,) m: how far the chord reaches into the block (module doc); 0 outside."""
        return _depth(self.ends, self.lo, self.hi, self.stock)

    @property
    def n(self) -> int:
        """The number of samples M."""
        return int(self.t.size)

    @property
    def wire_length(self) -> FloatArray:
        """(M,) m."""
        return np.linalg.norm(self.ends[:, 1] - self.ends[:, 0], axis=-1)

    @property
    def chord_length(self) -> FloatArray:
        """(M,) m, 0 outside."""
        return np.nan_to_num(self.hi - self.lo) * self.wire_length

    def fractions(self) -> FloatArray:
        """(M, 2) the chord ends ``[lo, hi]`` (NaN outside)."""
        return np.stack([self.lo, self.hi], axis=1)

    def chord_points(self) -> FloatArray:
        """(M, 2, 3) the chord's ends in the frame of the wire and block (NaN outside)."""
        a, d = self.ends[:, 0], self.ends[:, 1] - self.ends[:, 0]
        return a[:, None, :] + self.fractions()[:, :, None] * d[:, None, :]

    def runs(self) -> tuple[tuple[int, int], ...]:
        """Half-open sample ranges with the wire in the stock (the sidecar's ``in_stock``)."""
        return runs_of(self.inside)

    def first_last(self, rows: ArrayLike | None = None) -> tuple[int, int] | None:
        """Return the first and last sample with the wire in the stock, or None when it never is.

        Of ``rows``, default all.
        """
        idx = np.arange(self.n) if rows is None else np.asarray(rows)
        k = idx[self.inside[idx]]
        return (int(k[0]), int(k[-1])) if k.size else None

    def feed_extremes(self, mask: ArrayLike) -> tuple[float, float, int, int]:
        """Return the lowest and highest feed over the samples of ``mask`` in the stock, and where.

        ``(lowest, highest, at_lowest, at_highest)`` over the samples of ``mask`` that are
        in the stock (NaN and -1 when there are none).
        """
        k = np.flatnonzero(np.asarray(mask, dtype=bool) & self.inside)
        if not k.size:
            return float("nan"), float("nan"), -1, -1
        f = self.feed[k]
        lo, hi = int(np.argmin(f)), int(np.argmax(f))
        return float(f[lo]), float(f[hi]), int(k[lo]), int(k[hi])


def wire_in_stock(t: ArrayLike, ends: ArrayLike, stock: Box) -> WireInStock:
    """The wire against ``stock`` along a motion.

    ``t`` (M,) s strictly increasing, ``ends`` (M, 2, 3) the wire's start and end in the
    block's frame (module doc)."""
    ta = np.asarray(t, dtype=np.float64)
    e = np.asarray(ends, dtype=np.float64)
    if e.ndim != 3 or e.shape[1:] != (2, 3) or e.shape[0] != ta.size:
        raise ValueError(f"ends: expected ({ta.size}, 2, 3) wire end points, got {e.shape}")
    lo, hi = chord_fractions(e, stock)
    inside = ~np.isnan(lo)
    feed = np.full(ta.size, np.nan)
    if inside.any():
        feed[inside] = across_speeds(ta, e, np.stack([lo, hi], axis=1))[inside].max(axis=1)
    return WireInStock(ta, e, lo, hi, inside, feed, stock)


def _nearest(ends: FloatArray, stock: Box) -> tuple[FloatArray, FloatArray]:
    """The wire's distance (M,) [m] from the block and a fraction (M,) where it is that
    close: golden-section search on the convex distance along the wire, to 1e-9 of it."""
    a = stock.to_box(ends[:, 0])
    d = stock.to_box(ends[:, 1]) - a
    h = 0.5 * stock.size

    def dist(lam: FloatArray) -> FloatArray:
        p = a + lam[:, None] * d
        return np.linalg.norm(np.maximum(np.abs(p) - h, 0.0), axis=1)

    x0, x1 = np.zeros(len(a)), np.ones(len(a))
    g = 0.5 * (np.sqrt(5.0) - 1.0)
    c, dd = x1 - g * (x1 - x0), x0 + g * (x1 - x0)
    fc, fd = dist(c), dist(dd)
    for _ in range(45):
        left = fc <= fd
        x1 = np.where(left, dd, x1)
        x0 = np.where(left, x0, c)
        c, dd = x1 - g * (x1 - x0), x0 + g * (x1 - x0)
        fc, fd = dist(c), dist(dd)
    lam = 0.5 * (x0 + x1)
    return dist(lam), lam


def wire_gap(ends: ArrayLike, stock: Box) -> FloatArray:
    """Return how far (M,) [m] the wire (ends (M, 2, 3)) is from the block.

    0 where it touches or crosses it.
    """
    e = np.asarray(ends, dtype=np.float64).reshape(-1, 2, 3)
    return _nearest(e, stock)[0]


def feed_chord(ends: ArrayLike, stock: Box, near: float) -> FloatArray:
    """The chord ends (M, 2) whose speed the time law bounds.

    The chord where the wire is in the stock; where it is outside but within ``near`` (m) of
    the block, the part of the wire nearest the block — its chord in the block grown by the
    wire's distance from it (a point, or a stretch where the wire runs parallel to a face); NaN
    further away (``near = inf``: nowhere).

    As the wire comes to the block, that part becomes the part where it first touches,
    so the bound meets the chord's without a jump (a bound that appears only once the
    wire is inside leaves the path speed no room to fall to the feed before it is
    needed).  The distance is :func:`wire_gap`'s; the grown box is 1e-9 m bigger.
    """
    e = np.asarray(ends, dtype=np.float64)
    lo, hi = chord_fractions(e, stock)
    out = np.stack([lo, hi], axis=1)
    outside = np.isnan(lo)
    if not outside.any() or near <= 0.0:
        return out
    gap, lam = _nearest(e[outside], stock)
    close = gap <= near
    pick = np.flatnonzero(outside)[close]
    if pick.size:
        t_in, t_out, hit = stock.clip_lines(e[pick, 0], e[pick, 1] - e[pick, 0],
                                            gap[close][:, None] + 1e-9)  # fmt: skip
        lam_c = lam[close]
        out[pick, 0] = np.where(hit, np.clip(np.nan_to_num(t_in), 0.0, 1.0), lam_c)
        out[pick, 1] = np.where(hit, np.clip(np.nan_to_num(t_out), 0.0, 1.0), lam_c)
    return out
