"""3-D pictures shown undistorted and legible: a cube of equal aspect, the block as a
translucent box, meshes as shaded surfaces.

The plan's picture (``plots.png``, :mod:`ruledrobot.wirecut.report.plot3d`), the carve
picture (``carve.png``, millimetres) and the gallery's examples (metres) are drawn this
way.  matplotlib is imported inside the functions that draw (``import ruledrobot`` stays
fast); the caller has made the axes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.box import Box
from ..geometry.checks import FloatArray

__all__ = ["MESH_FACES", "coarse_mesh", "cube_axes", "draw_box", "draw_mesh", "lambert"]

#: most triangles a shaded mesh is drawn with: a matplotlib 3-D collection of ~10^4
#: polygons draws in well under a second, and the picture (600 px a side) shows no more
MESH_FACES = 12_000
#: the light of every shaded mesh, as matplotlib's LightSource angles [deg] (azimuth
#: clockwise from +y): from above and behind the viewer of the default view (from the
#: math azimuth -60 deg, elevation 30 deg), so that the faces seen are lit, the top most
LIGHT_AZIMUTH, LIGHT_ALTITUDE = 145.0, 50.0
#: the brightness of a face turned away from the light (the rest is the light's)
AMBIENT = 0.4
#: the block's faces: corner indices (6, 4) of :attr:`Box.corners` (corner 4i + 2j + k)
_BOX_FACES = np.array([[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4],
                       [1, 3, 7, 5]])  # fmt: skip


def cube_axes(ax: Any, centre: ArrayLike, half: float, unit: str, zoom: float = 1.0) -> None:
    """Show the cube ``centre +- half`` on the 3-D axes ``ax``, equal aspect, axes labelled.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        The axes; their limits, box aspect and axis labels are set.
    centre : array-like, shape (3,)
        Centre of the cube in the axes' data frame and unit (the picture's).
    half : float
        Half the cube's edge, in the same unit.
    unit : str
        The unit as the labels give it after the axis name: ``"(m)"`` labels
        ``x (m)``, ``"mm"`` labels ``x mm``.
    zoom : float
        The cube's size in the axes (matplotlib's box-aspect zoom; 1 leaves room for
        the tick labels at any view).
    """
    x, y, z = np.asarray(centre, dtype=np.float64)
    ax.set_xlim(x - half, x + half)
    ax.set_ylim(y - half, y + half)
    ax.set_zlim(z - half, z + half)
    ax.set_box_aspect((1.0, 1.0, 1.0), zoom=zoom)
    ax.set_xlabel(f"x {unit}")
    ax.set_ylabel(f"y {unit}")
    ax.set_zlabel(f"z {unit}")


def _unique_rows(rows: np.ndarray, **kwargs: bool) -> tuple[np.ndarray, ...]:
    """``np.unique(rows, axis=0, **kwargs)`` of integer rows (N, K), by one int64 key a row.

    The keys are ordered as the rows are lexicographically, so the inverse and the first
    indices are the same, without sorting the rows as records (a tenth of the time); the
    rows themselves are sorted when their keys would overflow."""
    lo, hi = (rows.min(axis=0), rows.max(axis=0)) if len(rows) else (0, 0)
    span = np.asarray(hi - lo + 1, dtype=np.int64)
    if not len(rows) or float(np.prod(span.astype(np.float64))) >= 2.0**62:
        return np.unique(rows, axis=0, **kwargs)
    key = np.zeros(len(rows), dtype=np.int64)
    for k in range(rows.shape[1]):  # (a few columns)
        key = key * span[k] + (rows[:, k] - lo[k])
    return np.unique(key, **kwargs)


def coarse_mesh(vertices: FloatArray, faces: np.ndarray, most: int = MESH_FACES
                ) -> tuple[FloatArray, np.ndarray, np.ndarray]:  # fmt: skip
    """Return a mesh of at most about ``most`` triangles that looks like ``(vertices, faces)``.

    By vertex clustering (Rossignac and Borrel, "Multi-resolution 3D approximations for
    rendering complex scenes", 1993).

    The vertices falling in one cell of a grid are merged at their mean; triangles with
    two corners in one cell vanish, and of triangles with the same corners one is kept.
    The cell is ``sqrt(2 A / most)`` for a surface of area ``A`` (a grid of squares of
    that side holds about ``most`` triangles on the surface), halved until the
    triangles left are at least a quarter of ``most`` (a mesh whose vertices crowd
    along its sharp edges, as a boolean's output does, keeps its broad faces).  The
    surface moves by at most a cell's diagonal: a picture's approximation, not a mesh
    to measure on.

    Parameters
    ----------
    vertices : ndarray, shape (V, 3)
    faces : ndarray, shape (F, 3)
        Vertex indices.
    most : int
        The largest number of triangles wanted.

    Returns
    -------
    vertices : ndarray, shape (V', 3)
    faces : ndarray, shape (F', 3)
    kept : ndarray, shape (F',)
        The index in ``faces`` of each triangle kept (for per-face colours).
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(f) <= most:
        return v, f, np.arange(len(f))
    t = v[f]
    area = 0.5 * float(np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]),
                                      axis=1).sum())  # fmt: skip
    cell = np.sqrt(2.0 * area / most)
    while True:
        _, inv = _unique_rows(np.floor(v / cell).astype(np.int64), return_inverse=True)
        inv = inv.reshape(-1)
        n = np.bincount(inv).astype(np.float64)
        merged = np.stack([np.bincount(inv, weights=v[:, k]) for k in range(3)], 1) / n[:, None]
        g = inv[f]
        ok = np.flatnonzero((g[:, 0] != g[:, 1]) & (g[:, 1] != g[:, 2]) & (g[:, 0] != g[:, 2]))
        _, first = _unique_rows(np.sort(g[ok], axis=1), return_index=True)
        kept = ok[np.sort(first)]
        if len(kept) >= most // 4 or cell < 1e-9:
            return merged, g[kept], kept
        cell *= 0.5


def lambert(normals: FloatArray) -> FloatArray:
    """Return the brightness (F,) of faces with ``normals`` (F, 3) under the light.

    Normals of any length; the light is :data:`LIGHT_AZIMUTH`, :data:`LIGHT_ALTITUDE`:
    ``AMBIENT + (1 - AMBIENT) max(n.l, 0)`` (Lambert's cosine law), 1 facing it, ``AMBIENT``
    turned away.
    """
    az, alt = np.radians(90.0 - LIGHT_AZIMUTH), np.radians(LIGHT_ALTITUDE)
    light = np.array([np.cos(az) * np.cos(alt), np.sin(az) * np.cos(alt), np.sin(alt)])
    n = np.asarray(normals, dtype=np.float64)
    cos = n @ light / np.maximum(np.linalg.norm(n, axis=1), 1e-300)
    return AMBIENT + (1.0 - AMBIENT) * np.maximum(cos, 0.0)


def draw_mesh(ax: Any, vertices: FloatArray, faces: np.ndarray, colour: Any,
              scale: float = 1.0, alpha: float = 1.0, zorder: float = 1.0,
              most: int = MESH_FACES) -> Any:  # fmt: skip
    """Draw a triangle mesh on the 3-D axes ``ax`` as a shaded surface (no edges).

    Parameters
    ----------
    vertices : ndarray, shape (V, 3)
        In metres; drawn times ``scale`` (1e3: millimetres).
    faces : ndarray, shape (F, 3)
        Vertex indices, counter-clockwise seen from outside (a face turned away from
        the light is darker: :data:`LIGHT_AZIMUTH`, :data:`LIGHT_ALTITUDE`).
    colour : colour or array, shape (F, 4)
        One colour, or one RGBA per face (carried through :func:`coarse_mesh`).
    alpha : float
        Opacity of every face.
    zorder : float
        Drawing order (the caller sets ``ax.computed_zorder = False`` to fix it).
    most : int
        Meshes of more triangles are drawn coarsened (:func:`coarse_mesh`).

    Returns
    -------
    mpl_toolkits.mplot3d.art3d.Poly3DCollection
        The surface added to ``ax``.
    """
    from matplotlib.colors import to_rgba, to_rgba_array
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    v, f, kept = coarse_mesh(vertices, faces, most)
    per_face = np.ndim(colour) == 2
    rgba = to_rgba_array(colour)[kept] if per_face else np.tile(to_rgba(colour), (len(f), 1))
    tri = v[f]
    rgba[:, :3] *= lambert(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))[:, None]
    rgba[:, 3] = alpha
    # edges of each face's own colour: no light seams where antialiased faces meet
    surface = Poly3DCollection(tri * scale, facecolors=rgba, edgecolors=rgba, linewidths=0.3,
                               zorder=zorder)  # fmt: skip
    ax.add_collection3d(surface)
    return surface


def draw_box(ax: Any, box: Box, scale: float = 1.0, colour: Any = "0.35",
             zorder: float = 0.0) -> tuple[Any, Any]:  # fmt: skip
    """Draw the block ``box`` on the 3-D axes ``ax``: faces barely tinted, edges drawn.

    Parameters
    ----------
    box : Box
        In metres; drawn times ``scale`` (1e3: millimetres).
    colour : colour
        Of the edges (the faces take it at a tenth of its opacity).
    zorder : float
        Drawing order of the faces; the edges one above.

    Returns
    -------
    faces, edges : Poly3DCollection, Line3DCollection
        The artists added to ``ax``.
    """
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    corners = box.corners * scale
    faces = Poly3DCollection(corners[_BOX_FACES], facecolor=colour, alpha=0.07,
                             edgecolor="none", zorder=zorder)  # fmt: skip
    edges = Line3DCollection(box.edges * scale, colors=colour, linewidths=1.0,
                             zorder=zorder + 1)  # fmt: skip
    ax.add_collection3d(faces)
    ax.add_collection3d(edges)
    return faces, edges
