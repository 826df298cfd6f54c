"""One picture per example (matplotlib Agg canvas, no pyplot state)."""

from __future__ import annotations

import io
from typing import Any

import numpy as np

from ..io.axes3d import cube_axes
from .scene import _Scene

# --------------------------------------------------------------------------
# pictures
# --------------------------------------------------------------------------


def _render(scene: _Scene, checks: list[dict[str, Any]]) -> bytes:
    """PNG bytes of one example (Agg canvas, no pyplot state; 3-D, equal aspect)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    fig = Figure(figsize=(6.4, 6.4), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    bounds = [scene.input_segments.reshape(-1, 3)]
    if scene.mesh is not None:
        v, f = scene.mesh
        ax.add_collection3d(
            Poly3DCollection(v[f], facecolor="tab:blue", edgecolor="none", alpha=0.28)
        )
        bounds.append(v)
    if scene.rulings is not None:
        ax.add_collection3d(
            Line3DCollection(scene.rulings, colors="tab:blue", linewidths=0.5, alpha=0.7)
        )
    for pts, colour, label in scene.curves:
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], color=colour, linewidth=1.2, label=label)
    for pts, colour, label in scene.points:
        ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], color=colour, s=4, label=label)
    ax.add_collection3d(Line3DCollection(scene.input_segments, colors="tab:orange", linewidths=3.5))
    ax.plot([], [], color="tab:orange", linewidth=3.5, label="initial lines")
    allpts = np.concatenate(bounds)
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    mid, half = 0.5 * (lo + hi), 0.5 * float((hi - lo).max()) or 1.0
    cube_axes(ax, mid, half, "(m)")
    ax.legend(loc="upper left", fontsize=7)
    ok = all(c["passed"] for c in checks)
    fig.suptitle(scene.title, fontsize=9)
    fig.text(
        0.5,
        0.02,
        f"{len(checks)} checks {'passed' if ok else 'FAILED'}",
        ha="center",
        fontsize=8,
        color="darkgreen" if ok else "red",
    )
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
