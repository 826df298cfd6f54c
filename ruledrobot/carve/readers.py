"""Reading the part: a closed triangle mesh from STL, OBJ, PLY or a Rhino ``.3dm`` model.

STL (ASCII or binary), OBJ and PLY are read by trimesh (the ``carve`` extra), equal
vertices merged.  A ``.3dm`` model (rhino3dm, the ``cad`` extra) gives its meshes, and
the render meshes Rhino stored with its breps and extrusions (rhino3dm cannot mesh a
brep itself: save the model with its meshes, or export an STL).  The mesh is scaled
from the file's unit to metres and placed by the part's pose in the robot base frame.

A part must be a closed 2-manifold: every edge in exactly two triangles.  An open mesh
(edges of one triangle: holes, a surface and not a solid) or a non-manifold one (edges
of three or more) is refused, naming the file and how many edges of each kind it has;
so is one whose triangles disagree in orientation (an edge run the same way by both
its triangles).  Faces are turned outwards when the whole mesh is inside out.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..geometry.checks import FloatArray
from ..geometry.mesh import signed_volume
from .cell import PartSpec

__all__ = ["PartMesh", "edge_counts", "misoriented_edges", "read_part", "read_triangles"]


@dataclass(frozen=True)
class PartMesh:
    """The part: ``vertices`` (V, 3) [m] in the robot base frame, ``faces`` (F, 3) int64,
    counter-clockwise seen from outside; ``source`` the file read."""

    vertices: FloatArray = field(repr=False)
    faces: np.ndarray = field(repr=False)
    source: Path | None = None

    @property
    def triangles(self) -> FloatArray:
        """(F, 3, 3) corner points [m]."""
        return self.vertices[self.faces]

    @property
    def volume(self) -> float:
        """Enclosed volume [m^3] (divergence theorem)."""
        return signed_volume(self.vertices, self.faces)


def edge_counts(faces: np.ndarray) -> tuple[int, int]:
    """``(boundary, non_manifold)``: how many undirected edges of ``faces`` (F, 3) lie in
    one triangle only, and in three or more."""
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return int(np.sum(counts == 1)), int(np.sum(counts > 2))


def misoriented_edges(faces: np.ndarray) -> int:
    """How many edges two triangles run the same way (their orientations disagree; a
    closed manifold whose faces agree runs every edge once each way)."""
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
    """Vertices (file units), faces (equal vertices merged) and the unit the file states
    (3DM only; None otherwise)."""
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


def read_part(spec: PartSpec) -> PartMesh:
    """The part of a cell (:class:`.cell.PartSpec`): read, checked closed and manifold,
    in metres and in the robot base frame; ValueError naming the file otherwise."""
    path = spec.file
    v, f, stated = read_triangles(path)
    units = spec.units
    if stated is not None and stated != units:
        raise ValueError(f"{path}: the model's unit system is {stated}, but [part] units = "
                         f"{units!r} (unit mismatch)")  # fmt: skip
    boundary, nonmanifold = edge_counts(f)
    if boundary or nonmanifold:
        what = []
        if boundary:
            what.append(f"{boundary} boundary edge(s) (in one triangle only: the mesh is open)")
        if nonmanifold:
            what.append(f"{nonmanifold} non-manifold edge(s) (in three or more triangles)")
        raise ValueError(f"{path}: not a closed 2-manifold mesh: {' and '.join(what)}; "
                         "expected a closed solid (repair it in CAD: close its "
                         "holes)")  # fmt: skip
    wrong = misoriented_edges(f)
    if wrong:
        raise ValueError(f"{path}: the triangles' orientations disagree across {wrong} edge(s) "
                         "(some faces turned inside out); expected every face counter-"
                         "clockwise seen from outside (repair the normals in CAD)")  # fmt: skip
    v = v * spec.scale
    v = v @ spec.pose[:3, :3].T + spec.pose[:3, 3]
    part = PartMesh(v, f, path)
    vol = part.volume
    if abs(vol) < 1e-12:
        raise ValueError(f"{path}: the mesh encloses no volume")
    if vol < 0.0:
        part = PartMesh(v, f[:, ::-1].copy(), path)
    return part
