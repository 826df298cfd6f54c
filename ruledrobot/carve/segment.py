"""The part's surface in regions: faces joined across smooth edges, split at sharp ones.

Two triangles sharing an edge are in one region when their normals differ by less
than ``sharp`` (radians, default 25 degrees): a column's side is one region, its caps two
more, a saddle-topped block six.  Each region is then fitted on its own
(:mod:`.quadric`), whatever its number of triangles (a box exported as 12 triangles is
six regions of two, six planes); a region no ruled surface fits is split again at the
finer creases of :data:`CREASES` and replaced by its pieces when every piece fits
(:data:`MAX_PIECES` at most).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.checks import FloatArray
from .readers import PartMesh

__all__ = ["CREASES", "MAX_PIECES", "Region", "face_normals", "segment"]

SHARP = np.radians(25.0)
#: the finer crease angles at which a region no surface fits is split again (largest
#: first, :func:`~.plan_cuts.find_cuts`): a faceted part's flat facets meeting at 18
#: degrees (a twisted hexagonal frustum's sides) are one region at ``SHARP``, and no
#: quadric holds two planes at a crease; split, each facet is a plane
CREASES = (np.radians(12.5), np.radians(5.0))
#: most pieces a region is split into (:data:`CREASES`): a finely meshed curved surface
#: split at 5 degrees falls apart into its triangles, each "a plane", not faces to cut
MAX_PIECES = 16


@dataclass(frozen=True)
class Region:
    """One smooth piece of the part's surface.

    ``faces`` (K,) indices into the mesh's faces, ``points`` (P, 3) its vertices [m, base
    frame], ``normals`` (P, 3) their outward unit normals (area-weighted over the region's
    faces), ``area`` [m^2], ``between`` (S, 3) its triangles' edge midpoints and centroids [m]."""

    index: int
    faces: np.ndarray = field(repr=False)
    points: FloatArray = field(repr=False)
    normals: FloatArray = field(repr=False)
    area: float
    #: (S, 3) points on its triangles between the vertices: edge midpoints and centroids
    #: [m] (where a fit through the vertices alone is not pinned, :mod:`.quadric`)
    between: FloatArray = field(default_factory=lambda: np.zeros((0, 3)), repr=False)

    @property
    def centroid(self) -> FloatArray:
        """Mean (3,) of the region's vertices ``points`` [m, base frame] (not area-weighted)."""
        return self.points.mean(axis=0)


def face_normals(mesh: PartMesh) -> tuple[FloatArray, FloatArray]:
    """Unit outward normals (F, 3) and areas (F,) of the mesh's triangles."""
    t = mesh.triangles
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    a = np.linalg.norm(n, axis=1)
    return n / np.maximum(a, 1e-300)[:, None], 0.5 * a


def segment(mesh: PartMesh, sharp: float = SHARP, faces: np.ndarray | None = None,
            first: int = 0) -> list[Region]:  # fmt: skip
    """The regions of ``mesh`` (module doc), largest first.

    ``faces``: only these triangles (indices into the mesh's), joined across their own
    shared edges (a region split again, :data:`CREASES`); ``first``: the first region's
    index."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    f = mesh.faces
    nf = len(f)
    normals, areas = face_normals(mesh)
    sub = np.arange(nf) if faces is None else np.asarray(faces)
    fs = f[sub]
    e = np.concatenate([fs[:, [0, 1]], fs[:, [1, 2]], fs[:, [2, 0]]])
    owner = np.tile(sub, 3)
    key = np.sort(e, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    k, o = key[order], owner[order]
    same = np.all(k[1:] == k[:-1], axis=1)
    a, b = o[:-1][same], o[1:][same]
    smooth = np.einsum("ij,ij->i", normals[a], normals[b]) > np.cos(sharp)
    g = coo_matrix((np.ones(int(smooth.sum())), (a[smooth], b[smooth])), shape=(nf, nf))
    _, labels = connected_components(g, directed=False)
    _, labels = np.unique(labels[sub], return_inverse=True)  # the components of ``sub``
    labels = labels.reshape(-1)
    regions: list[Region] = []
    for lab in np.argsort(-np.bincount(labels, weights=areas[sub])):
        faces = sub[labels == lab]
        verts, inv = np.unique(f[faces].ravel(), return_inverse=True)
        vn = np.zeros((len(verts), 3))
        np.add.at(vn, inv, np.repeat(normals[faces] * areas[faces, None], 3, axis=0))
        vn /= np.maximum(np.linalg.norm(vn, axis=1), 1e-300)[:, None]
        t = mesh.vertices[f[faces]]
        between = np.concatenate([0.5 * (t + np.roll(t, -1, axis=1)).reshape(-1, 3),
                                  t.mean(axis=1)])  # fmt: skip
        regions.append(Region(first + len(regions), faces, mesh.vertices[verts], vn,
                              float(areas[faces].sum()), between))  # fmt: skip
    return regions
