"""The part of ``ruledrobot demo --carve``, made from its closed form: a hyperboloid column.

``x^2 + z^2 = a^2 (1 + y^2 / c^2)`` for ``|y| <= length / 2`` (the axis along y, across the
arm's reach, as the part demo's plug), capped by flat ends that are faces of the block:
a 200 x 200 x 150 mm foam block in front of a UR5e (the part demo's cell,
:data:`ruledrobot.io.demo_cell.DEMO_CELL`).  :func:`write_demo_cell` writes the
part as a binary STL in millimetres and a cell file naming it; ``ruledrobot carve`` then
finds the column's rulings from the mesh alone and cuts them as one closed loop.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..geometry.checks import FloatArray
from ..io.atomic import atomic_write_text
from ..io.demo_cell import DEMO_CELL
from ..io.mesh import write_stl

__all__ = ["CELL", "column_mesh", "write_demo_cell"]

CELL = (
    """\
# ruledrobot demo --carve: a hyperboloid column (a = {a_mm:g} mm, c = {c_mm:g} mm, {l_mm:g} mm
# long, axis along y) carved from the demo's block.  Units: m, rad, s.
# Carve it:  ruledrobot carve cell.toml --out DIR   then plan DIR/job.toml

[part]
file = "column.stl"
units = "mm"
pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]
tolerance = 0.0005
rough_cuts = 4

"""
    + DEMO_CELL
    + """
[cut]
feed_speed = 0.012
approach_speed = 0.6
"""
)


def column_mesh(a: float = 0.06, c: float = 0.3, length: float = 0.2, around: int = 64,
                along: int = 12) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """The capped column (module doc) as ``(vertices (V, 3) m, faces (F, 3))``.

    Closed, faces turned outwards; ``around`` points per ring, ``along`` rings."""
    u = np.linspace(0.0, 2.0 * np.pi, around, endpoint=False)
    y = np.linspace(-0.5 * length, 0.5 * length, along)
    r = a * np.sqrt(1.0 + y**2 / c**2)
    ring = np.stack([np.cos(u), np.zeros_like(u), np.sin(u)], axis=1)
    V = [(r[:, None, None] * ring[None] + y[:, None, None] * [0.0, 1.0, 0.0]).reshape(-1, 3)]
    idx = np.arange(along * around).reshape(along, around)
    a0, a1 = idx[:-1], np.roll(idx[:-1], -1, axis=1)
    b0, b1 = idx[1:], np.roll(idx[1:], -1, axis=1)
    faces = [np.stack([a0, a1, b1], -1).reshape(-1, 3), np.stack([a0, b1, b0], -1).reshape(-1, 3)]
    for k in (0, along - 1):  # a fan to each end's centre
        centre = len(V[0]) + (0 if k == 0 else 1)
        faces.append(np.stack([np.full(around, centre), idx[k], np.roll(idx[k], -1)], 1))
    V += [np.array([[0.0, y[0], 0.0], [0.0, y[-1], 0.0]])]
    v, f = np.concatenate(V), np.concatenate(faces)
    t = v[f]  # star-shaped about the origin: every face turned away from it
    out = np.einsum("ij,ij->i", np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), t.mean(axis=1))
    return v, np.where((out < 0.0)[:, None], f[:, ::-1], f)


def write_demo_cell(folder: str | Path, a: float = 0.06, c: float = 0.3, length: float = 0.2,
                    around: int = 64, along: int = 12) -> Path:  # fmt: skip
    """Write ``column.stl`` (mm) and ``cell.toml`` into ``folder``; the cell file."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    v, f = column_mesh(a, c, length, around, along)
    write_stl(folder / "column.stl", v * 1e3, f, header="ruledrobot demo --carve: a hyperboloid "
              "column, mm")  # fmt: skip
    text = CELL.format(a_mm=a * 1e3, c_mm=c * 1e3, l_mm=length * 1e3)
    return atomic_write_text(folder / "cell.toml", text)
