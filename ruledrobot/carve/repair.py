"""The part's mesh as CAD exports it: what is wrong with it, where, and its repair.

A part must be a closed 2-manifold whose facets agree in orientation.  Exports often
miss by a little: seams whose two sides were tessellated apart leave vertices a micron
from each other (the mesh is open along them), and a few facets come out turned the
other way.  :func:`mesh_defects` finds what is wrong and :func:`defects_message` says
where (facet indices and positions in the file's units) and what would mend it;
:func:`repair_mesh` (``[part] repair = true``) mends what can be mended without
changing the part's shape beyond ``merge`` (a hundredth of the tolerance):

* vertices within ``merge`` of one another are merged (each cluster to its first
  vertex), and the facets that collapse with them dropped;
* facets are turned to agree with their neighbours: across every edge of two facets,
  the two facets' orientations relative to a root facet are found by pointer jumping on
  a breadth-first tree of the facets (vectorised), and in each connected piece the
  facets of the smaller orientation are turned.

Holes (edges of one facet after merging) and edges of three or more facets are not
guessed at: the error lists them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.checks import FloatArray
from ..io.words import counted, index_ranges

__all__ = ["MERGE_FRACTION", "MeshDefects", "defects_message", "facet_orientation",
           "mesh_defects", "near_vertex_labels", "repair_mesh"]  # fmt: skip

#: vertices closer than this fraction of the tolerance are one vertex (repair)
MERGE_FRACTION = 0.01
#: facets named in a message (their index ranges; the positions of the first three)
NAMED = 12


@dataclass(frozen=True)
class MeshDefects:
    """What is wrong with a mesh.

    ``boundary`` (K,) the facets with an edge in no other facet (``boundary_edges`` such
    edges), ``nonmanifold`` the facets with an edge in three or more (``nonmanifold_edges``),
    ``flipped`` the facets turned the other way from their neighbours (the smaller side in
    their piece), ``disagree`` how many edges two facets run the same way, ``near`` how many
    vertices lie within the merge distance of another (counted when the mesh is open),
    ``non_orientable`` whether a piece has no consistent orientation."""

    boundary: np.ndarray = field(repr=False)
    nonmanifold: np.ndarray = field(repr=False)
    flipped: np.ndarray = field(repr=False)
    boundary_edges: int = 0
    nonmanifold_edges: int = 0
    disagree: int = 0
    near: int = 0
    non_orientable: bool = False

    @property
    def ok(self) -> bool:
        """Whether the mesh is a closed, consistently oriented 2-manifold."""
        return not (len(self.boundary) or len(self.nonmanifold) or self.disagree
                    or self.non_orientable)  # fmt: skip


def _edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Directed edges (3F, 2) of ``faces`` (F, 3) (ab, bc, ca of each facet in turn), the
    undirected edge (3F,) each is, and how many facet edges (E,) each undirected edge has."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    _, which, counts = np.unique(np.sort(e, axis=1), axis=0, return_inverse=True,
                                 return_counts=True)  # fmt: skip
    return e, which.reshape(-1), counts


def near_vertex_labels(vertices: FloatArray, distance: float) -> np.ndarray:
    """(V,) for each vertex the first vertex of its cluster.

    Vertices joined when they lie within ``distance`` (file units) of one another (chains
    joined too)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    nv = len(vertices)
    pairs = cKDTree(vertices).query_pairs(distance, output_type="ndarray")
    if len(pairs) == 0:
        return np.arange(nv)
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(nv, nv))
    _, labels = connected_components(g, directed=False)
    first = np.full(labels.max() + 1, nv)
    np.minimum.at(first, labels, np.arange(nv))
    return first[labels]


def facet_orientation(faces: np.ndarray) -> tuple[np.ndarray, bool]:
    """Return the facets to turn so that every shared edge is run once each way.

    (F,) bool, and whether some piece has no consistent orientation.  The facets turned are,
    in each connected piece, the smaller of its two orientation classes (of two alike, the
    one without the piece's first facet).  Only edges of exactly two facets join facets.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    nf = len(faces)
    e, which, counts = _edges(faces)
    owner = np.tile(np.arange(nf), 3)
    two = counts[which] == 2
    order = np.argsort(which[two], kind="stable")
    idx = np.flatnonzero(two)[order]  # facet edges, the two of each edge side by side
    a, b = owner[idx[0::2]], owner[idx[1::2]]
    same = np.all(e[idx[0::2]] == e[idx[1::2]], axis=1)  # run the same way: disagree
    # a root joined to the first facet of every piece; a breadth-first tree from it
    _, piece = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(nf, nf)),
                                    directed=False)  # fmt: skip
    firsts = np.unique(piece, return_index=True)[1]
    root = nf
    rows = np.concatenate([a, b, np.full(len(firsts), root), firsts])
    cols = np.concatenate([b, a, firsts, np.full(len(firsts), root)])
    g = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(nf + 1, nf + 1)).tocsr()
    _, pred = breadth_first_order(g, root, directed=False, return_predecessors=True)
    anc = np.where(pred < 0, root, pred)
    # the parity of each tree edge: whether a facet disagrees with its parent
    key = np.minimum(a, b) * (nf + 1) + np.maximum(a, b)
    sort = np.argsort(key)
    child = np.arange(nf)
    parent = anc[:nf]
    q = np.minimum(child, parent) * (nf + 1) + np.maximum(child, parent)
    pos = np.clip(np.searchsorted(key[sort], q), 0, max(len(key) - 1, 0))
    par = np.zeros(nf + 1, dtype=np.int8)
    if len(key):
        tree = (parent != root) & (key[sort][pos] == q)
        par[:nf] = np.where(tree, same[sort][pos], 0)
    # pointer jumping: the parity of the path to the root
    for _ in range(int(np.ceil(np.log2(nf + 2))) + 1):
        par = par ^ par[anc]
        anc = anc[anc]
    par = par[:nf].astype(bool)
    non_orientable = bool(np.any((par[a] ^ par[b]) != same))
    # in each piece, turn the smaller class (of two alike, the one without its first facet)
    ones = np.bincount(piece, weights=par, minlength=len(firsts))
    size = np.bincount(piece, minlength=len(firsts))
    turn_ones = (ones < size - ones) | ((ones == size - ones) & ~par[firsts])
    return par == turn_ones[piece], non_orientable


def mesh_defects(vertices: FloatArray, faces: np.ndarray, merge: float) -> MeshDefects:
    """What is wrong with a mesh (:class:`MeshDefects`).

    ``merge`` the distance (file units) within which two vertices count as near."""
    _, which, counts = _edges(faces)
    per_facet = counts[which].reshape(3, -1)
    boundary = np.flatnonzero(np.any(per_facet == 1, axis=0))
    nonmanifold = np.flatnonzero(np.any(per_facet > 2, axis=0))
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    _, directed = np.unique(e, axis=0, return_counts=True)
    disagree = int(np.sum(directed > 1))
    flipped, non_orientable = (facet_orientation(faces) if disagree
                               else (np.zeros(len(faces), dtype=bool), False))  # fmt: skip
    near = 0
    if len(boundary) and merge > 0:  # what welding would close
        near = int(np.sum(near_vertex_labels(vertices, merge) != np.arange(len(vertices))))
    return MeshDefects(boundary, nonmanifold, np.flatnonzero(flipped), int(np.sum(counts == 1)),
                       int(np.sum(counts > 2)), disagree, near, non_orientable)  # fmt: skip


def _where(idx: np.ndarray, vertices: FloatArray, faces: np.ndarray, units: str) -> str:
    """Facets ``idx`` as ``"facets 3-5, 40 (at (x, y, z) units, ...)"``."""
    shown = idx[:NAMED]
    mask = np.zeros(len(faces), dtype=bool)
    mask[shown] = True
    text = f"facet{'s' if len(idx) > 1 else ''} {index_ranges(mask)}"
    if len(idx) > NAMED:
        text += f" and {len(idx) - NAMED} more"
    at = ", ".join("(" + ", ".join(f"{x:.6g}" for x in c) + ")"
                   for c in vertices[faces[idx[:3]]].mean(axis=1))  # fmt: skip
    return f"{text} (centred at {at}{' ...' if len(idx) > 3 else ''} {units})"


def _vertices(n: int) -> str:
    return f"{n} {'vertex' if n == 1 else 'vertices'}"


def defects_message(defects: MeshDefects, vertices: FloatArray, faces: np.ndarray,
                    units: str, merge: float, repaired: bool = False) -> str:  # fmt: skip
    """Return in words what is wrong with the mesh, where, and what mends it.

    Where: facet indices, centres in the file's ``units``.  What mends it: ``repair = true``
    in ``[part]`` when merging vertices within ``merge`` (file units) or turning facets
    would (``repaired``: the mesh is the repair's, and what is left it cannot mend).
    """
    shape = []
    if len(defects.boundary):
        where = _where(defects.boundary, vertices, faces, units)
        shape.append(f"{counted(defects.boundary_edges, 'boundary edge')} (in one facet "
                     f"only: the mesh is open) on {where}")
    if len(defects.nonmanifold):
        shape.append(f"{counted(defects.nonmanifold_edges, 'non-manifold edge')} (in three "
                     f"or more facets) on {_where(defects.nonmanifold, vertices, faces, units)}")
    parts = [f"not a closed 2-manifold mesh: {' and '.join(shape)}"] if shape else []
    if defects.non_orientable:
        parts.append("facets that no orientation makes agree (a one-sided surface)")
    elif defects.disagree:
        parts.append(f"the triangles' orientations disagree across "
                     f"{counted(defects.disagree, 'edge')}: "
                     f"{counted(len(defects.flipped), 'facet')} turned the other way from "
                     f"their neighbours, {_where(defects.flipped, vertices, faces, units)}")
    text = "; ".join(parts)
    if repaired:
        return (f"{text}; repair (merging vertices within {merge:.3g} {units}, turning "
                "facets) cannot mend this: close the mesh in CAD and export it again")
    fix = []
    if defects.near and shape:
        fix.append(f"{_vertices(defects.near)} lie within {merge:.3g} {units} of another "
                   "(seams not welded): repair = true in [part] merges them")
    if defects.disagree and not defects.non_orientable:
        fix.append("repair = true in [part] turns the facets to agree with their neighbours")
    if not fix:
        fix.append("expected a closed solid, every facet counter-clockwise seen from "
                   "outside (repair it in CAD)")
    return f"{text}; {'; '.join(fix)}"


def repair_mesh(vertices: FloatArray, faces: np.ndarray, merge: float,
                units: str) -> tuple[FloatArray, np.ndarray, list[str]]:  # fmt: skip
    """The mesh repaired (module doc) and what was done, in words (empty: nothing was wrong).

    ``merge`` in file units. Vertices (V', 3) are the clusters' first vertices, faces (F', 3)
    renumbered."""
    notes: list[str] = []
    labels = near_vertex_labels(vertices, merge)
    moved = int(np.sum(labels != np.arange(len(vertices))))
    if moved:
        keep = np.flatnonzero(labels == np.arange(len(vertices)))
        new = np.full(len(vertices), -1)
        new[keep] = np.arange(len(keep))
        f = new[labels][faces]
        good = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])
        notes.append(f"merged {_vertices(moved)} into another within {merge:.3g} {units}"
                     + (f", dropping {counted(int(np.sum(~good)), 'facet')} that collapsed"
                        if not good.all() else ""))  # fmt: skip
        vertices, faces = vertices[keep], f[good]
    directed = np.unique(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]),
                         axis=0, return_counts=True)[1]  # fmt: skip
    if np.any(directed > 1):
        turn, non_orientable = facet_orientation(faces)
        if not non_orientable and turn.any():
            faces = np.where(turn[:, None], faces[:, ::-1], faces)
            mask = turn.copy()
            shown = index_ranges(mask) if mask.sum() <= NAMED else (
                index_ranges(mask & (np.cumsum(mask) <= NAMED)) + " ...")
            notes.append(f"turned {counted(int(turn.sum()), 'facet')} to agree with their "
                         f"neighbours ({shown}{', numbered after merging' if moved else ''})")
    return vertices, faces, notes
