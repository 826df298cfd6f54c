"""Rhino ``.3dm`` models out: rulings (line curves, the two end curves and the ruled
surface between them) and triangle meshes (rhino3dm, the ``cad`` extra).

Layers: ``rulings`` (one line curve per ruling), ``end_a`` and ``end_b`` (the
polylines through the ends), ``surface`` (the ruled surface of the two end
polylines: degree 1 both ways, so it holds every drawn ruling exactly), ``mesh``.
The model's unit system is ``units`` (default mm); files are written in the 3DM
version 7 format (read by Rhino 7 and later) to a temporary file, then moved
into place.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.mesh import validate_mesh
from ..atomic import atomic_write_bytes
from ..units import unit_scale
from .cad_common import CadWriteOptions, segments
from .extras import require
from .rulings import Rulings

if TYPE_CHECKING:
    import rhino3dm

__all__ = ["write_mesh_3dm", "write_rhino"]

_SYSTEMS = {"mm": "Millimeters", "cm": "Centimeters", "m": "Meters", "in": "Inches"}


def _model(rhino, units: str):
    model = rhino.File3dm()
    model.Settings.ModelUnitSystem = getattr(rhino.UnitSystem, _SYSTEMS[units])
    return model


def _layer(rhino, model: rhino3dm.File3dm, name: str, color: tuple[int, int, int]):
    attrs = rhino.ObjectAttributes()
    attrs.LayerIndex = model.Layers.AddLayer(name, (*color, 255))
    return attrs


def _save(model: rhino3dm.File3dm, path: str | os.PathLike[str]) -> Path:
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp) / "model.3dm"
        if not model.Write(str(scratch), 7):
            raise ValueError(f"{path}: rhino3dm could not write the model")
        return atomic_write_bytes(path, scratch.read_bytes())


def write_rhino(path: str | os.PathLike[str], rulings: Rulings,
                opts: CadWriteOptions | None = None) -> Path:  # fmt: skip
    """Write rulings as a 3DM model (see the module doc); returns the path."""
    opts = opts or CadWriteOptions()
    rhino = require("rhino3dm", "writing Rhino .3dm files")
    ends = segments(rulings, opts, str(path)) / unit_scale(opts.units, str(path))
    model = _model(rhino, opts.units)
    at_rulings = _layer(rhino, model, "rulings", (90, 90, 90))
    for a, b in ends.tolist():
        model.Objects.AddCurve(rhino.LineCurve(rhino.Point3d(*a), rhino.Point3d(*b)), at_rulings)
    polys = []
    for k, (name, color) in enumerate((("end_a", (200, 30, 30)), ("end_b", (30, 30, 200)))):
        pts = ends[:, k].tolist()
        if rulings.closed:
            pts.append(pts[0])
        poly = rhino.PolylineCurve([rhino.Point3d(*q) for q in pts])
        model.Objects.AddCurve(poly, _layer(rhino, model, name, color))
        polys.append(poly)
    if opts.surface:
        srf = rhino.NurbsSurface.CreateRuledSurface(polys[0], polys[1])
        if srf is not None:
            model.Objects.AddSurface(srf, _layer(rhino, model, "surface", (120, 160, 120)))
    return _save(model, path)


def write_mesh_3dm(path: str | os.PathLike[str], vertices: ArrayLike, faces: ArrayLike,
                   units: str = "mm") -> Path:  # fmt: skip
    """Write a triangle mesh (``vertices`` (V, 3) m, ``faces`` (F, 3)) as a 3DM model in ``units``.

    Returns the path."""
    rhino = require("rhino3dm", "writing Rhino .3dm files")
    v, f = validate_mesh(vertices, faces)
    v = np.asarray(v, dtype=np.float64) / unit_scale(units, str(path))
    mesh = rhino.Mesh()
    for x, y, z in v.tolist():  # rhino3dm 8 has no bulk vertex setter
        mesh.Vertices.Add(x, y, z)
    for a, b, c in np.asarray(f).tolist():
        mesh.Faces.AddFace(a, b, c)
    model = _model(rhino, units)
    model.Objects.AddMesh(mesh, _layer(rhino, model, "mesh", (150, 150, 150)))
    return _save(model, path)
