"""``carve.png``: the part with its faces coloured by the cut that makes them, and the
carved block (``carved.stl``) as a shaded surface coloured the same way.

Left, the part (shaded, millimetres) in the block: a face cut exactly takes its cut's
colour, a face of the block is grey, a face left to the roughing loops is dark grey;
a few of each cut's rulings (where the wire runs) are drawn in the block, and a legend
names the cuts in the order they are made.  Right, the carved block: each of its faces
takes the colour of the cut whose surface it lies on (within :data:`ON_CUT`), a face on
the block's own faces is grey; the title gives the volumes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..io.atomic import atomic_open
from ..io.axes3d import coarse_mesh, cube_axes, draw_box, draw_mesh
from .measure import surface_distance
from .plan_cuts import CutPlan
from .readers import PartMesh

__all__ = ["BLOCK_FACE", "ON_CUT", "ROUGHED", "carve_figure", "cut_colours", "draw"]

#: colours of the faces no cut makes: the block's own, and the part's left to roughing
BLOCK_FACE, ROUGHED = "0.85", "0.6"
#: a face of the carved block lies on a cut's surface within this [m] (the carved
#: mesh as drawn is coarsened by some millimetres: :func:`~ruledrobot.io.axes3d.coarse_mesh`)
ON_CUT = 0.004
#: rulings drawn per cut in the left panel
RULINGS = 12
#: millimetres per metre (the picture's unit)
MM = 1e3


def cut_colours(n: int) -> FloatArray:
    """RGBA (n, 4) of ``n`` cuts in the order they are made (tab10, then tab20)."""
    from matplotlib import colormaps

    cmap = colormaps["tab10" if n <= 10 else "tab20"]
    return np.array([cmap(k % cmap.N) for k in range(n)])


def _part_colours(part: PartMesh, plan: CutPlan, colours: FloatArray) -> FloatArray:
    """RGBA (F, 4) of the part's faces: its cut's colour (a face cut exactly), grey (a
    face of the block) or dark grey (left to the roughing loops)."""
    from matplotlib.colors import to_rgba

    out = np.tile(to_rgba(ROUGHED), (len(part.faces), 1))
    of_region = {c.region: k for k, c in enumerate(plan.cuts) if c.region is not None}
    for r in plan.regions:
        if plan.faces.get(r.index) == "block face":
            out[r.faces] = to_rgba(BLOCK_FACE)
        elif r.index in of_region:
            out[r.faces] = colours[of_region[r.index]]
    return out


def _carved_colours(tri: FloatArray, plan: CutPlan, colours: FloatArray
                    ) -> FloatArray:  # fmt: skip
    """RGBA (F, 4) of triangles ``tri`` (F, 3, 3) of the carved block: the colour of the
    cut whose surface is nearest their centroid within :data:`ON_CUT`, else grey."""
    from matplotlib.colors import to_rgba

    c = tri.mean(axis=1)
    best = np.full(len(c), ON_CUT)
    out = np.tile(to_rgba(BLOCK_FACE), (len(c), 1))
    for k, cut in enumerate(plan.cuts):
        d = np.concatenate([surface_distance(part, cut.lines, cut.closed)
                            for part in np.array_split(c, max(1, len(c) // 2000))])  # fmt: skip
        near = d < best
        best = np.where(near, d, best)
        out[near] = colours[k]
    return out


def _rulings(ax: Any, plan: CutPlan, stock: Box, colours: FloatArray, centre: FloatArray
             ) -> None:  # fmt: skip
    """A few of each cut's rulings, clipped to the block, in a darker shade of its colour:
    those on the viewer's side of the part's ``centre`` (3,) [m] drawn over the part,
    the others before it (the part hides them where it lies in front)."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    e, a = np.radians(ax.elev), np.radians(ax.azim)
    view = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    for k, cut in enumerate(plan.cuts):
        lines = cut.lines[np.unique(np.linspace(0, len(cut.lines) - 1, RULINGS).round()
                                    .astype(int))]  # fmt: skip
        t0, t1, hit = stock.clip_lines(lines.point, lines.direction)
        p, d = lines.point[hit], lines.direction[hit]
        seg = np.stack([p + t0[hit, None] * d, p + t1[hit, None] * d], axis=1)
        front = (seg.mean(axis=1) - centre) @ view > 0.0
        shade = colours[k] * [0.6, 0.6, 0.6, 1.0]
        for mask, z in ((front, 3.0), (~front, 0.5)):
            if mask.any():  # (matplotlib refuses an empty 3-D collection)
                    ax.add_collection3d(Line3DCollection(seg[mask] * MM, colors=[shade],
                                                     linewidths=0.8, zorder=z))  # fmt: skip


def _legend(ax: Any, plan: CutPlan, colours: FloatArray) -> None:
    """The cuts in the order they are made, then the faces no cut makes."""
    from matplotlib.patches import Patch

    handles = [Patch(color=colours[k], label=f"{k + 1} {c.name} ({c.kind})")
               for k, c in enumerate(plan.cuts)]  # fmt: skip
    status = set(plan.faces.values())
    if "block face" in status:
        handles.append(Patch(color=BLOCK_FACE, label="face of the block"))
    if status - {"block face", "exact"}:
        handles.append(Patch(color=ROUGHED, label="left to the roughing"))
    ax.legend(handles=handles, loc="upper left", fontsize=8, title="cuts, in order",
              title_fontsize=8, framealpha=0.8)  # fmt: skip


def _frame(ax: Any, stock: Box, title: str) -> None:
    ax.computed_zorder = False
    draw_box(ax, stock, MM, zorder=0)
    cube_axes(ax, stock.centre * MM, 0.55 * float(np.linalg.norm(stock.size)) * MM, "mm",
              zoom=1.1)  # fmt: skip
    ax.set_title(title, fontsize=10)


def carve_figure(part: PartMesh, plan: CutPlan, carved, stock: Box,
                 report: dict[str, Any]) -> Any:  # fmt: skip
    """Return the picture (module doc) as a matplotlib Figure on an Agg canvas.

    No pyplot state; ``carved`` the carved block's mesh or None, ``report`` carve's
    (volumes).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(14, 7))
    FigureCanvasAgg(fig)
    # fixed margins (room for the two-line title of the right panel): a layout engine
    # measures every text first, a third of the drawing time
    fig.subplots_adjust(left=0.0, right=0.96, bottom=0.08, top=0.92, wspace=0.08)
    colours = cut_colours(len(plan.cuts))
    ax1 = fig.add_subplot(1, 2, 1, projection="3d")
    _frame(ax1, stock, "the part, each face coloured by the cut that makes it, and the cuts' "
           "rulings")
    draw_mesh(ax1, part.vertices, part.faces, _part_colours(part, plan, colours), MM, zorder=1)
    _rulings(ax1, plan, stock, colours, part.vertices.mean(axis=0))
    _legend(ax1, plan, colours)
    w = report["whole"]
    text = (f"part {w['part_volume_l']:.4g} L, carved {w['carved_volume_l']:.4g} L, "
            f"excess {round(100 * w['excess'], 2) + 0.0:.2f} %")  # fmt: skip
    if report.get("baseline"):
        text += f"\nvisual hull of as many directions: {100 * report['baseline']['excess']:.2f} %"
    ax2 = fig.add_subplot(1, 2, 2, projection="3d")
    _frame(ax2, stock, "the carved block (carved.stl)\n" + text)
    if carved is not None and len(carved.faces):
        v, f, _ = coarse_mesh(carved.vertices, carved.faces)
        draw_mesh(ax2, v, f, _carved_colours(v[f], plan, colours), MM, zorder=1)
    return fig


def draw(path: Path, part: PartMesh, plan: CutPlan, carved, stock: Box,
         report: dict[str, Any]) -> Path:  # fmt: skip
    """Draw the picture (:func:`carve_figure`) to ``path`` (PNG, written atomically)."""
    fig = carve_figure(part, plan, carved, stock, report)
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=90)
    return path
