"""From a part to the ruled cuts that make it (``ruledrobot carve``, docs/carve.md).

A cell file names the part (a closed mesh: STL, OBJ, PLY, or a 3DM model) and the
block, robot, tool and cut defaults of a job.  The part's ruled faces — planes,
cylinders, cones, hyperboloids, hyperbolic paraboloids — are cut exactly along their
own rulings; the rest is roughed by loops of rulings that never enter it, compared with
the visual hull of as many parallel directions.  Out come a job the planner runs as it
is, ``carve.json``, ``carved.stl`` and a picture.

Usage::

    from ruledrobot.carve import carve
    result = carve("cell.toml", "out/carve")
    result.report["whole"]["excess"]

An application package above the planner: it imports the geometry, io, subdivision
and robot layers and the planner's top-level names only (``ruledrobot.wirecut``).
"""

from .cell import Cell, PartSpec, load_cell, parse_cell
from .run import CarveResult, carve

__all__ = ["CarveResult", "Cell", "PartSpec", "carve", "load_cell", "parse_cell"]
