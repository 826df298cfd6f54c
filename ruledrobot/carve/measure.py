"""Every cut measured against the part, on its rulings' chords in the block.

Each ruling's chord in the block is sampled every :data:`STEP`; each sample's signed
distance to the part (negative inside, :class:`.meshquery.MeshQuery`) gives

* ``gouge``: how far the deepest sample lies inside the part beyond ``tolerance`` (an
  exact cut's rulings lie on the part's face, within the mesh's own chord error);
* ``closest``: the nearest approach of any sample (negative: inside);
* ``farthest``: the largest of the rulings' nearest approaches (how far the loosest
  ruling of a roughing loop stands off the part);
* ``deviation`` (exact cuts): the largest distance from the vertices of the face the cut
  makes to the cut's surface (the nearest ruling, and across to its neighbour: the
  surface's local plane), so that the face is reproduced within it.
"""

from __future__ import annotations

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..geometry.lines import Lines
from .meshquery import MeshQuery
from .model import CarveCut, CutMeasure
from .segment import Region

__all__ = ["STEP", "chord_samples", "measure_cut", "surface_distance"]

STEP = 0.002


def chord_samples(lines: Lines, stock: Box, step: float = STEP) -> tuple[FloatArray, np.ndarray]:
    """Return points (P, 3) along the rulings' chords in the block and the ruling of each.

    Points every ``step`` [m], and the ruling (P,) each belongs to.
    """
    p, d = lines.point, lines.direction
    t0, t1, hit = stock.clip_lines(p, d)
    pts, owner = [], []
    for i in np.flatnonzero(hit):
        n = max(2, int(np.ceil((t1[i] - t0[i]) / step)) + 1)
        t = np.linspace(t0[i], t1[i], n)
        pts.append(p[i] + t[:, None] * d[i])
        owner.append(np.full(n, i))
    if not pts:
        return np.zeros((0, 3)), np.zeros(0, dtype=int)
    return np.concatenate(pts), np.concatenate(owner)


def surface_distance(points: FloatArray, lines: Lines, closed: bool) -> FloatArray:
    """(N,) distance [m] from ``points`` (N, 3) to the ruled surface of ``lines``.

    To the plane through the nearest ruling and the foot on its nearer neighbour."""
    p, d = lines.point, lines.direction
    rel = points[:, None, :] - p[None]
    along = np.einsum("nki,ki->nk", rel, d)
    perp = rel - along[..., None] * d[None]
    dist = np.linalg.norm(perp, axis=2)
    i = np.argmin(dist, axis=1)
    n = len(lines)
    nb = np.stack([(i - 1) % n, (i + 1) % n], axis=1)
    if not closed:
        nb = np.clip(nb, 0, n - 1)
    j = np.where(dist[np.arange(len(points)), nb[:, 0]] < dist[np.arange(len(points)), nb[:, 1]],
                 nb[:, 0], nb[:, 1])  # fmt: skip
    j = np.where(j == i, np.where(i > 0, i - 1, i + 1), j)
    foot_i = p[i] + along[np.arange(len(points)), i][:, None] * d[i]
    foot_j = p[j] + along[np.arange(len(points)), j][:, None] * d[j]
    normal = np.cross(d[i], foot_j - foot_i)
    nn = np.linalg.norm(normal, axis=1)
    ok = nn > 1e-12
    out = dist[np.arange(len(points)), i].copy()
    out[ok] = np.abs(np.einsum("ij,ij->i", points[ok] - foot_i[ok], normal[ok] / nn[ok, None]))
    return out


def measure_cut(cut: CarveCut, stock: Box, query: MeshQuery, tolerance: float,
                region: Region | None = None) -> CutMeasure:  # fmt: skip
    """The measures of one cut (module doc).

    ``ok``: no gouge, and for an exact cut the face within ``tolerance`` of the cut."""
    pts, owner = chord_samples(cut.lines, stock)
    if not len(pts):
        return CutMeasure(0.0, np.inf, np.inf, np.nan, False)
    sd = query.signed(pts)
    gouge = max(0.0, float(-sd.min()) - tolerance)
    per = np.full(len(cut.lines), np.inf)
    np.minimum.at(per, owner, np.abs(sd))
    farthest = float(per[np.isfinite(per)].max())
    deviation = np.nan
    if region is not None:
        deviation = float(surface_distance(region.points, cut.lines, cut.closed).max())
    ok = gouge == 0.0 and (region is None or deviation <= tolerance)
    return CutMeasure(gouge, float(sd.min()), farthest, deviation, ok)
