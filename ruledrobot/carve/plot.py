"""``carve.png``: the part with its cuts' rulings in the block, and the carved block."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..geometry.box import Box
from ..io.atomic import atomic_open
from ..io.axes3d import cube_axes
from .measure import chord_samples
from .plan_cuts import CutPlan
from .readers import PartMesh

__all__ = ["draw"]

MAX_FACES = 6000


def _mesh(ax, vertices, faces, color, alpha) -> None:
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    f = faces[:: max(1, len(faces) // MAX_FACES)]
    ax.add_collection3d(Poly3DCollection(vertices[f] * 1e3, facecolor=color, edgecolor="none",
                                         alpha=alpha))  # fmt: skip


def _frame(ax, stock: Box, title: str) -> None:
    cube_axes(ax, stock.centre * 1e3, 0.5 * float(np.linalg.norm(stock.size)) * 1e3, "mm")
    ax.set_title(title, fontsize=9)


def draw(path: Path, part: PartMesh, plan: CutPlan, carved, stock: Box,
         report: dict[str, Any]) -> Path:  # fmt: skip
    """Draw the picture (module doc) to ``path`` (PNG, written atomically)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12, 6))
    ax1 = fig.add_subplot(1, 2, 1, projection="3d")
    _mesh(ax1, part.vertices, part.faces, "tab:orange", 0.5)
    colors = plt.get_cmap("tab10")
    for k, cut in enumerate(plan.cuts):
        pts, _ = chord_samples(cut.lines, stock, step=1.0)
        if len(pts) < 2:
            continue
        seg = pts.reshape(-1, 2, 3) * 1e3
        for s in seg[:: max(1, len(seg) // 80)]:
            ax1.plot(*s.T, color=colors(k % 10), lw=0.6)
        ax1.plot([], [], color=colors(k % 10), label=f"{cut.name} ({cut.kind})")
    if plan.cuts:
        ax1.legend(fontsize=7, loc="upper left")
    _frame(ax1, stock, "the part and the cuts' rulings in the block")
    ax2 = fig.add_subplot(1, 2, 2, projection="3d")
    if carved is not None:
        _mesh(ax2, carved.vertices, carved.faces, "tab:blue", 0.7)
    w = report["whole"]
    text = (f"part {w['part_volume_l']:.4g} L, carved {w['carved_volume_l']:.4g} L, "
            f"excess {100 * w['excess']:.2f} %")  # fmt: skip
    if report.get("baseline"):
        text += f"\nvisual hull of as many directions: {100 * report['baseline']['excess']:.2f} %"
    _frame(ax2, stock, "the carved block (carved.stl)\n" + text)
    fig.tight_layout()
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=90)
    plt.close(fig)
    return path
