"""Roughing a part by closed loops of rulings that never enter it, and the foam cutter's baseline.

A plane ``n . x = h(n) + standoff`` with ``h`` the support function of the part's
convex hull never cuts the part.  A closed curve ``gamma`` of normals on the unit
sphere gives a closed sequence of such planes, and consecutive planes meet in a line:
the loop of those lines is a developable that wraps the part, touching its hull along
a curve, and keeps ``K(gamma)``, the points on the inner side of every plane.  Its
rulings lie in supporting planes, so no ruling enters the part (each is still measured,
:mod:`.measure`).

* ``gamma`` a great circle (normals normal to an axis ``a``): the rulings are all
  parallel to ``a`` and the loop is the part's silhouette seen along ``a`` extruded —
  what a foam cutter's parallel wire cuts (with a turntable, along several directions:
  the visual hull).
* ``gamma`` a seam ``normalise(cos s e1 + sin s e2 + A sin(k s + phase) a)``: normals
  that rise and fall round the loop, so that one loop bounds the part from above and
  below too; its rulings are not parallel (they tilt with the seam).  A foam cutter's
  wire cannot follow it; the robot's can.

The loops are chosen greedily (:func:`choose_loops`): each removes the most of what is
still kept of the block, counted on a voxel grid (only voxels outside the part's hull
count: the others are kept by every loop).  The baseline is the same greedy choice
among great circles only, over the same axes: the visual hull of as many directions.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..geometry.lines import Lines

__all__ = ["LOOP_STEP", "Loop", "choose_loops", "fibonacci_axes", "loop_lines",
           "ruling_elevation", "ruling_tilt", "seam_normals", "silhouette"]

SAMPLES = 96
#: largest gap [m] between a great-circle loop's rulings along its polygon
LOOP_STEP = 0.005
#: shortest edge [m] of a great-circle loop's polygon (shorter ones are merged)
MIN_EDGE = 0.001
AMPLITUDES = (0.0, 0.3, 0.6, 0.9)
WAVES = (2, 3)
PHASES = (0.0, 0.5)  # fractions of a half wave
#: voxels on the block for the choice (the grid step follows)
VOXELS = 30_000
#: largest angle [deg] between a loop's rulings and the horizontal: a wire more nearly
#: upright puts the bow's lower arm into the table (a loop about (-0.29, 0.19, 0.94) on
#: the ellipsoid: 2.8 mm deep on the approach; one about (0.58, -0.26, 0.77) planned PASS)
MAX_ELEVATION = 55.0
#: whether carve's own loops include seams: off, since a seam's rulings pivot about
#: points in the block (consecutive supporting planes meet near the part), and the
#: planner's feed checks failed on every seam loop planned (the ellipsoid's: 3-16 mm/s
#: against 12 +- 5 %) while its great circles across the reach passed
SEAMS = False
#: largest angle [deg] between a loop's rulings and the vertical plane across the arm's
#: reach (normal to the horizontal direction from the robot's base to the block)
MAX_TILT = 40.0


@dataclass(frozen=True)
class Loop:
    """A roughing loop's curve of normals and its planes' offsets.

    ``axis`` (3,), ``amplitude`` (0: a great circle), ``waves`` round the loop, ``phase``
    (fraction of a half wave); ``normals`` (K, 3) and ``support`` (K,) [m] the planes'
    offsets (standoff added)."""

    axis: FloatArray = field(repr=False)
    amplitude: float
    waves: int
    phase: float
    normals: FloatArray = field(repr=False)
    support: FloatArray = field(repr=False)

    @property
    def parallel(self) -> bool:
        """Whether the loop is a great circle (``amplitude`` 0): its rulings parallel ``axis``."""
        return self.amplitude == 0.0

    def describe(self) -> str:
        """Return the loop in words.

        ``"silhouette along (+0.00, +0.00, +1.00)"`` for a great circle,
        ``"seam about (...), amplitude 0.3, 2 waves"`` for a seam."""
        a = ", ".join(f"{x:+.2f}" for x in self.axis)
        if self.parallel:
            return f"silhouette along ({a})"
        return f"seam about ({a}), amplitude {self.amplitude:g}, {self.waves} waves"


def fibonacci_axes(n: int) -> FloatArray:
    """``n`` (n, 3) unit vectors spread evenly over the upper half sphere (z >= 0)."""
    k = np.arange(n) + 0.5
    z = k / n
    phi = np.pi * (1 + 5**0.5) * k
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _across(axis: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(a, e1, e2)``: the unit ``axis`` and two unit vectors completing a right-handed
    orthonormal frame."""
    a = axis / np.linalg.norm(axis)
    e1 = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    return a, e1, np.cross(a, e1)


def seam_normals(axis: FloatArray, amplitude: float, waves: int, phase: float,
                 samples: int = SAMPLES) -> FloatArray:  # fmt: skip
    """(samples, 3) unit normals of a seam about ``axis`` (module doc)."""
    a, e1, e2 = _across(axis)
    s = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    g = (np.cos(s)[:, None] * e1 + np.sin(s)[:, None] * e2
         + amplitude * np.sin(waves * s + phase * np.pi / max(waves, 1))[:, None] * a)  # fmt: skip
    return g / np.linalg.norm(g, axis=1)[:, None]


def _corners(n: FloatArray, h: FloatArray) -> FloatArray:
    """(K, 2) the corners of the convex polygon ``n_i . x <= h_i`` (normals (K, 2) in
    order round it): corner ``i`` where lines ``i`` and ``i + 1`` meet."""
    M = np.stack([n, np.roll(n, -1, axis=0)], axis=1)
    return np.linalg.solve(M, np.stack([h, np.roll(h, -1)], axis=1)[..., None])[..., 0]


def silhouette(axis: FloatArray, hull: FloatArray, standoff: float,
               min_edge: float = MIN_EDGE) -> Loop:  # fmt: skip
    """The great-circle loop along ``axis`` on the part's own silhouette.

    Its planes are the edges of the convex polygon of the hull vertices ``hull`` (H, 3)
    seen along the axis, each moved out by ``standoff`` [m], so that the loop's corners
    are the polygon's (mitred), not clusters of rulings on a tiny arc round each vertex
    (a sampled circle of normals puts many of them within ``standoff`` of a vertex and
    none along a long edge: the planner's refinement of so uneven a loop wiggles, and the
    arm cannot hold the feed through it).  Edges shorter than ``min_edge`` go (the lines
    beside them extended where they turn by less than 120 degrees together): the polygon
    only grows."""
    from scipy.spatial import ConvexHull

    a, e1, e2 = _across(np.asarray(axis, dtype=float))
    P = hull @ np.stack([e1, e2], axis=1)
    v = P[ConvexHull(P).vertices]  # counter-clockwise
    e = np.roll(v, -1, axis=0) - v
    n = np.stack([e[:, 1], -e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
    h = np.einsum("ij,ij->i", n, v) + standoff
    keep = np.ones(len(n), bool)
    while keep.sum() > 3:
        idx = np.flatnonzero(keep)
        c = _corners(n[idx], h[idx])
        length = np.linalg.norm(c - np.roll(c, 1, axis=0), axis=1)  # edge i: c[i-1] to c[i]
        beside = np.einsum("ij,ij->i", np.roll(n[idx], 1, axis=0), np.roll(n[idx], -1, axis=0))
        short = np.flatnonzero((length < min_edge) & (beside > -0.5))
        if not short.size:
            break
        keep[idx[short[np.argmin(length[short])]]] = False
    n, h = n[keep], h[keep]
    return Loop(a, 0.0, 2, 0.0, n[:, :1] * e1 + n[:, 1:] * e2, h)


def loop_lines(loop: Loop, centre: FloatArray, step: float = LOOP_STEP) -> Lines:
    """Return the loop's rulings: consecutive planes' lines of intersection, oriented alike.

    Each line by its point nearest ``centre``; a great circle's also along its polygon's
    edges, evenly, at most ``step`` [m] apart (its corners kept)."""
    n0, n1 = loop.normals, np.roll(loop.normals, -1, axis=0)
    h0, h1 = loop.support, np.roll(loop.support, -1)
    d = np.cross(n0, n1)
    d /= np.linalg.norm(d, axis=1)[:, None]
    M = np.stack([n0, n1, d], axis=1)  # (K, 3, 3)
    rhs = np.stack([h0, h1, d @ centre], axis=1)
    p = np.linalg.solve(M, rhs[..., None])[..., 0]
    if np.mean(d @ loop.axis) < 0.0:
        d = -d
    if loop.parallel:
        d = np.broadcast_to(loop.axis / np.linalg.norm(loop.axis), p.shape)
        p -= np.outer((p - centre) @ d[0], d[0])  # the corners in the plane through centre
        edge = np.roll(p, -1, axis=0) - p
        parts = np.maximum(1, np.ceil(np.linalg.norm(edge, axis=1) / step)).astype(int)
        k = np.repeat(np.arange(len(p)), parts)
        t = np.arange(len(k)) - np.repeat(np.cumsum(parts) - parts, parts)
        p = p[k] + (t / parts[k])[:, None] * edge[k]
        d = np.broadcast_to(d[0], p.shape)
    return Lines.from_point_direction(p, d)


def ruling_tilt(normals: FloatArray, radial: FloatArray) -> float:
    """Return the largest tilt [deg] of a loop's rulings from the plane normal to ``radial``.

    The largest angle [deg] between a loop's rulings (consecutive planes of ``normals``
    (K, 3) meet in them) and the plane normal to ``radial`` (3,)."""
    d = np.cross(normals, np.roll(normals, -1, axis=0))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return float(np.degrees(np.arcsin(np.clip(np.abs(d @ radial).max(), 0.0, 1.0))))


def ruling_elevation(normals: FloatArray) -> float:
    """The largest angle [deg] between a loop's rulings and the horizontal plane."""
    return ruling_tilt(normals, np.array([0.0, 0.0, 1.0]))


def _candidates(hull: FloatArray, standoff: float, axes: FloatArray, seams: bool,
                radial: FloatArray | None = None, max_tilt: float = MAX_TILT
                ) -> list[Loop]:  # fmt: skip
    out = []
    for a in axes:
        shapes = [(0.0, 2, 0.0)]
        if seams:
            shapes += [(A, k, ph) for A in AMPLITUDES[1:] for k in WAVES for ph in PHASES]
        for A, k, ph in shapes:
            n = seam_normals(a, A, k, ph)
            if radial is not None and (ruling_tilt(n, radial) > max_tilt
                                       or ruling_elevation(n) > MAX_ELEVATION):
                continue
            if A == 0.0:
                out.append(silhouette(a, hull, standoff))
                continue
            h = (hull @ n.T).max(axis=0) + standoff
            out.append(Loop(a, A, k, ph, n, h))
    return out


def _voxels(stock: Box, count: int) -> tuple[FloatArray, float, tuple[int, int, int]]:
    """The centres (N, 3) [m, base frame] of about ``count`` voxels of the block, their
    step [m] and the grid's shape."""
    h = float((np.prod(stock.size) / count) ** (1 / 3))
    axes = [np.arange(0.5 * h, s, h) - 0.5 * s for s in stock.size]
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    local = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
    return local @ stock.rotation.T + stock.centre, h, X.shape


def _all_below(points: np.ndarray, normals_t: np.ndarray, offsets: np.ndarray,
               cells: int = 2**16) -> np.ndarray:
    """Whether each point (N, 3) satisfies every ``p . n_j <= offset_j`` (normals (3, K)).

    In the dtype given, in chunks of about ``cells`` products (in cache and below
    OpenBLAS's threading: the fastest measured on the 2-core machine); the (N, K) matrix
    of a convex hull's thousands of facets at once took a gigabyte and seconds of page
    faults (the ellipsoid's hull, 30,000 voxels against 3,840 facets: 4 s, now 0.1 s)."""
    out = np.empty(len(points), dtype=bool)
    step = max(1, cells // max(1, normals_t.shape[1]))
    for s in range(0, len(points), step):
        out[s:s + step] = np.all(points[s:s + step] @ normals_t <= offsets, axis=1)
    return out


def choose_loops(hull: FloatArray, stock: Box, count: int, standoff: float,
                 seams: bool = True, axes: FloatArray | None = None,
                 radial: FloatArray | None = None, max_tilt: float = MAX_TILT,
                 accept: Callable[[Loop], bool] | None = None,
                 gone: Callable[[FloatArray, tuple[int, int, int]], np.ndarray] | None = None,
                 ) -> tuple[list[Loop], list[float]]:  # fmt: skip
    """Choose ``count`` roughing loops about the part's hull, greedily (module doc).

    Loops about the part's hull vertices ``hull`` (H, 3) [m]; with ``seams=False`` great
    circles only (the baseline).  Also the block's kept volume [m^3] on the voxel grid after
    each loop.  ``accept(loop)``: whether the robot can cut a loop (asked of the best loop
    of a round, then of the next best while it says no; each loop asked once): a loop it
    refuses is never chosen.  ``gone(points, shape)``: which voxels of the grid (N, 3),
    ``shape``, the exact cuts take away already (they count for no loop: a part whose exact
    cuts leave nothing outside its hull gets no loop).  Which voxels each candidate takes
    is counted once; a round counts those still left."""
    from scipy.spatial import ConvexHull

    axes = fibonacci_axes(24) if axes is None else axes
    pts, h, shape = _voxels(stock, VOXELS)
    eq = ConvexHull(hull).equations
    in_hull = _all_below(pts, eq[:, :3].T, -eq[:, 3])
    left = ~in_hull if gone is None else ~in_hull & ~gone(pts, shape)
    alive = (pts[left] - stock.centre).astype(np.float32)
    cands = _candidates(hull, standoff, axes, seams, radial, max_tilt)
    takes = np.array([~_all_below(alive, c.normals.T.astype(np.float32),
                                  (c.support - c.normals @ stock.centre).astype(np.float32))
                      for c in cands]).reshape(len(cands), len(alive))  # fmt: skip
    still = np.ones(len(alive), dtype=bool)
    chosen, kept = [], []
    verdict: dict[int, bool] = {}
    for _ in range(count):
        gains = np.count_nonzero(takes & still, axis=1)
        best = None
        for i in np.argsort(-gains, kind="stable"):
            if gains[i] <= 0:
                break
            if accept is not None and i not in verdict:
                verdict[i] = bool(accept(cands[i]))
            if accept is None or verdict[i]:
                best = i
                break
        if best is None:
            break
        chosen.append(cands[best])
        still &= ~takes[best]
        kept.append(float((np.count_nonzero(still) + in_hull.sum()) * h**3))
    return chosen, kept
