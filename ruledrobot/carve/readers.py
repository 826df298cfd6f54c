"""Reading the part: a closed triangle mesh from STL, OBJ, PLY or a Rhino ``.3dm`` model.

STL (ASCII or binary), OBJ and PLY are read by trimesh (the ``carve`` extra), equal
vertices merged.  A ``.3dm`` model (rhino3dm, the ``cad`` extra) gives its meshes, and
the render meshes Rhino stored with its breps and extrusions (rhino3dm cannot mesh a
brep itself: save the model with its meshes, or export an STL).  The mesh is scaled
from the file's unit to metres and placed by the part's pose in the robot base frame.

A part must be a closed 2-manifold: every edge in exactly two triangles.  An open mesh
(edges of one triangle: holes, a surface and not a solid) or a non-manifold one (edges
of three or more) is refused, naming the file, how many edges of each kind it has and
on which facets (indices, and where); so is one whose triangles disagree in orientation
(an edge run the same way by both its triangles), naming the facets turned the other
way.  ``[part] repair = true`` merges vertices within a hundredth of the tolerance and
turns those facets first (:mod:`.repair`; what it did is noted).  Faces are turned
outwards when the whole mesh is inside out.

Before any of that the part's size is compared with the block's: a file in metres
declared in millimetres makes a part a thousand times too small, which used to be
refused as "the mesh encloses no volume"; now :func:`check_size` names the sizes and the
unit that fits (``the part is 0.2 mm across in a 200 mm block: did you mean units =
"m"?``), and the converse for a part far larger than the block.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..geometry.mesh import signed_volume
from ..io.units import UNIT_NAMES, unit_scale
from .cell import PartSpec
from .repair import MERGE_FRACTION, defects_message, mesh_defects, repair_mesh

__all__ = ["SIZE_RATIO", "PartMesh", "check_size", "edge_counts", "misoriented_edges",
           "read_part", "read_triangles"]  # fmt: skip

#: a part this many times smaller across than the block, or five times larger, is taken
#: for a units mistake when another unit makes it fit the block
SIZE_RATIO = 20.0


@dataclass(frozen=True)
class PartMesh:
    """The part.

    ``vertices`` (V, 3) [m] in the robot base frame, ``faces`` (F, 3) int64, counter-clockwise
    seen from outside; ``source`` the file read; ``repairs`` what ``[part] repair = true`` did
    to the mesh, in words (empty: nothing)."""

    vertices: FloatArray = field(repr=False)
    faces: np.ndarray = field(repr=False)
    source: Path | None = None
    repairs: tuple[str, ...] = ()

    @property
    def triangles(self) -> FloatArray:
        """(F, 3, 3) corner points [m]."""
        return self.vertices[self.faces]

    @property
    def volume(self) -> float:
        """Enclosed volume [m^3] (divergence theorem)."""
        return signed_volume(self.vertices, self.faces)


def edge_counts(faces: np.ndarray) -> tuple[int, int]:
    """Return how many undirected edges lie in one triangle only, and in three or more.

    ``(boundary, non_manifold)`` of the edges of ``faces`` (F, 3).
    """
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return int(np.sum(counts == 1)), int(np.sum(counts > 2))


def misoriented_edges(faces: np.ndarray) -> int:
    """Return how many edges two triangles run the same way.

    Their orientations disagree; a closed manifold whose faces agree runs every edge once
    each way.
    """
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    _, counts = np.unique(e, axis=0, return_counts=True)
    return int(np.sum(counts > 1))


def _read_3dm(path: Path) -> tuple[FloatArray, np.ndarray, str | None]:
    """Vertices (model units), faces and the model's unit name (None: unset)."""
    from ..io.formats.extras import require

    rhino = require("rhino3dm", "reading Rhino .3dm files")
    model = rhino.File3dm.Read(str(path))
    if model is None:
        raise ValueError(f"{path}: not a readable 3DM file")
    names = {"Millimeters": "mm", "Centimeters": "cm", "Meters": "m", "Inches": "in"}
    us = model.Settings.ModelUnitSystem
    units = names.get(getattr(us, "name", str(us)))
    verts: list[np.ndarray] = []
    faces: list[np.ndarray] = []
    count = 0

    def add(mesh) -> None:
        nonlocal count
        v = np.array([[p.X, p.Y, p.Z] for p in mesh.Vertices], dtype=np.float64)
        f = []
        for k in range(len(mesh.Faces)):
            a, b, c, d = mesh.Faces[k]
            f.append((a, b, c))
            if d != c:  # a quad: two triangles
                f.append((a, c, d))
        verts.append(v)
        faces.append(np.asarray(f, dtype=np.int64).reshape(-1, 3) + count)
        count += len(v)

    for obj in model.Objects:
        geo = obj.Geometry
        if isinstance(geo, rhino.Mesh):
            add(geo)
        elif isinstance(geo, (rhino.Brep, rhino.Extrusion)):
            brep = geo if isinstance(geo, rhino.Brep) else geo.ToBrep(True)
            got = False
            for face in brep.Faces:
                m = face.GetMesh(rhino.MeshType.Any)
                if m is not None and len(m.Faces):
                    add(m)
                    got = True
            if not got:
                raise ValueError(f"{path}: a brep without a stored mesh (rhino3dm cannot mesh "
                                 "breps): save the model with render meshes, or export the "
                                 "part as STL")  # fmt: skip
    if not faces:
        raise ValueError(f"{path}: no mesh, brep or extrusion in the model; expected the part")
    return np.concatenate(verts), np.concatenate(faces), units


def read_triangles(path: Path) -> tuple[FloatArray, np.ndarray, str | None]:
    """Read the vertices, faces and stated unit of a mesh file.

    Vertices (file units), faces (equal vertices merged) and the unit the file states (3DM
    only; None otherwise).
    """
    suffix = path.suffix.lower()
    if suffix == ".3dm":
        v, f, units = _read_3dm(path)
    else:
        try:
            import trimesh
        except ImportError:
            raise ValueError(f"{path}: reading STL, OBJ and PLY needs the Python package "
                             "trimesh; install the carve extra: pip install "
                             "'ruledrobot[carve]'") from None  # fmt: skip
        try:
            m = trimesh.load(str(path), force="mesh", process=False)
        except Exception as exc:  # trimesh raises many kinds on a broken file
            raise ValueError(f"{path}: cannot read the mesh "
                             f"({type(exc).__name__}: {exc})") from None  # fmt: skip
        if not hasattr(m, "faces") or len(m.faces) == 0:
            raise ValueError(f"{path}: no triangles in the file")
        v, f, units = np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64), None
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{path}: vertex coordinates that are not finite numbers")
    # merge equal vertices (STL repeats every corner; 3DM faces are per brep face)
    key = np.round(v, 9)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    f = inverse.reshape(-1)[f]
    v = v[first]
    good = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])
    return v, f[good], units


def check_size(vertices: FloatArray, spec: PartSpec, stock: Box, where: str) -> None:
    """Raise ValueError when the part's size against the block points to another unit.

    Naming the sizes and the unit that fits, when the part, ``vertices`` (V, 3) in the
    file's units read as ``spec.units``, is :data:`SIZE_RATIO` times smaller across than the
    block ``stock``, or five times larger, and another unit makes it fit the block (its
    sides against the block's, largest to largest).
    """
    ext = np.sort(np.ptp(vertices, axis=0))[::-1]  # file units, largest first
    block = np.sort(stock.size)[::-1]  # m
    across, size = float(ext[0]) * spec.scale, float(block[0])
    if size / SIZE_RATIO <= across <= 5.0 * size:
        return
    fits = [u for u in UNIT_NAMES if np.all(ext * unit_scale(u, "units") <= block * (1 + 1e-9))]
    best = max(fits, key=lambda u: unit_scale(u, "units"), default=None)
    if best is None or best == spec.units:
        return
    if across < size / SIZE_RATIO and ext[0] * unit_scale(best, "units") < size / SIZE_RATIO:
        return  # small in every unit that fits: a small part, not a mistake
    def mm(x: float) -> str:
        return f"{x * 1e3:,.0f}" if x >= 0.1 else f"{x * 1e3:.3g}"

    raise ValueError(f"{where}: [part] units = {spec.units!r}: the part ({spec.file.name}) is "
                     f"{mm(across)} mm across in a {mm(size)} mm block: did you mean units = "
                     f"\"{best}\"?")  # fmt: skip


def read_part(spec: PartSpec, stock: Box | None = None, where: str = "cell") -> PartMesh:
    """The part of a cell (:class:`.cell.PartSpec`).

    Read, its size checked against the block's (``stock``, when given: :func:`check_size`;
    ``where`` names the cell file), repaired when ``spec.repair`` (:mod:`.repair`), checked
    closed, manifold and consistently oriented, in metres and in the robot base frame;
    ValueError naming the file and where its mesh fails otherwise."""
    path = spec.file
    v, f, stated = read_triangles(path)
    units = spec.units
    if stated is not None and stated != units:
        raise ValueError(f"{path}: the model's unit system is {stated}, but [part] units = "
                         f"{units!r} (unit mismatch)")  # fmt: skip
    if stock is not None:
        check_size(v, spec, stock, where)
    merge = spec.tolerance * MERGE_FRACTION / spec.scale  # file units
    repairs: list[str] = []
    if spec.repair:
        v, f, repairs = repair_mesh(v, f, merge, units)
    defects = mesh_defects(v, f, merge)
    if not defects.ok:
        raise ValueError(f"{path}: {defects_message(defects, v, f, units, merge, spec.repair)}")
    v = v * spec.scale
    v = v @ spec.pose[:3, :3].T + spec.pose[:3, 3]
    part = PartMesh(v, f, path, tuple(repairs))
    vol = part.volume
    if abs(vol) < 1e-12:
        raise ValueError(f"{path}: the mesh encloses no volume ({vol * 1e9:.3g} mm^3 in "
                         f"[part] units = {units!r})")  # fmt: skip
    if vol < 0.0:
        part = PartMesh(v, f[:, ::-1].copy(), path, tuple(repairs))
    return part
