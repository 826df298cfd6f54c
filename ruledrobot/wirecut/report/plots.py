"""``plots.png`` of a plan: the cut surfaces in the stock with the planned wire positions
(and, kerf compensated, the offset wire path), the joints against their limits, the
feed of every cut against its set feed, the phases on the time axis."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ...geometry.checks import FloatArray
from ...io.atomic import atomic_write_bytes
from ...io.pictures import thinned_series
from ...robot.tool import BowTool
from ...robot.wire.in_stock import flange_wire_ends
from ..plan import Plan

__all__ = ["PHASE_COLOURS", "plot_plan"]

#: colours of the phases in every picture of a plan
PHASE_COLOURS = {
    "approach": "0.75", "preheat": "tab:red", "lead_in": "tab:olive", "cut": "tab:green",
    "lead_out": "tab:cyan", "transit": "tab:purple", "retract": "0.55", "move": "0.9",
}  # fmt: skip


def _phase_bands(ax, t: FloatArray, labels: np.ndarray) -> None:
    lab = labels.astype(str)
    cut = np.flatnonzero(lab[1:] != lab[:-1]) + 1
    for a, b in zip(np.r_[0, cut], np.r_[cut, lab.size] - 1, strict=True):
        ax.axvspan(t[a], t[b], color=PHASE_COLOURS.get(lab[a], "0.9"), alpha=0.15, lw=0)


def plot_plan(path: str | Path, plan: Plan, part=None) -> Path:
    """Write the plan's picture (one PNG) to ``path`` atomically; ``part``: the kept part's
    mesh (:func:`~.part_mesh.part_mesh`), drawn see-through in the stock."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    job, mo, me = plan.job, plan.motion, plan.measured
    fig = Figure(figsize=(14, 9))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(2, 2, (1, 3), projection="3d")
    bow = BowTool.of(job.tool if plan.bow is None else plan.bow)
    colours = ["tab:blue", "tab:green", "tab:brown", "tab:pink", "tab:olive", "tab:cyan"]
    # the many short segments of each kind as one collection each (an artist per
    # segment made the 3-D panel the slowest part of the picture)
    for cp in plan.passes:
        m, h = cp.motion, cp.motion.hit
        c0, c1 = m.chord[:, 0], m.chord[:, 1]
        S = cp.target_frames
        stride = max(1, int(h.sum()) // 60)
        a = S[h, :3, 3] + c0[h, None] * S[h, :3, 2]
        b = S[h, :3, 3] + c1[h, None] * S[h, :3, 2]
        k = next(i for i, c in enumerate(job.cuts) if c is cp.cut)
        ax.add_collection3d(Line3DCollection(np.stack([a[::stride], b[::stride]], axis=1),
                                             colors=colours[k % len(colours)],
                                             linewidths=0.6))  # fmt: skip
        if cp.compensated:
            F = cp.frames
            mid = F[h, :3, 3] + (0.5 * (c0 + c1))[h, None] * F[h, :3, 2]
            ax.plot(*mid.T, color="tab:red", lw=1.0)
        ends = flange_wire_ends(m.flange, bow)
        ax.add_collection3d(Line3DCollection(ends[:: max(1, len(ends) // 10)],
                                             colors="tab:orange", linewidths=1.2))  # fmt: skip
    ax.add_collection3d(Line3DCollection(job.stock.edges, colors="0.4", linewidths=0.8))
    if part is not None:
        tri = part.vertices[part.faces]
        step = max(1, len(tri) // 15000)  # a few thousand facets draw in a second
        ax.add_collection3d(Poly3DCollection(tri[::step], facecolor="tab:green", alpha=0.35,
                                             edgecolor="none"))  # fmt: skip
    names = ", ".join(c.name for c in job.cuts) if len(job.cuts) > 1 else "cut surface"
    comp = "; red: wire path offset by half the kerf" if any(
        cp.compensated for cp in plan.passes) else ""  # fmt: skip
    kept = "; green: the part" if part is not None else ""
    ax.set_title(f"{names} in the stock; orange: planned wire{comp}{kept}", fontsize=9)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    t = mo.timed.t
    ax2 = fig.add_subplot(2, 2, 2)
    _phase_bands(ax2, t, mo.labels)
    for j in range(6):
        ax2.plot(*thinned_series(t, mo.timed.q[:, j]), label=f"q{j + 1}")
    model = plan.model
    lim = ", ".join(f"{hi:.3g}" if np.isfinite(hi) else "inf" for hi in model.upper)
    ax2.set_title(f"joint positions (rad); limits ± [{lim}]", fontsize=9)
    ax2.set_xlabel("t (s)")
    ax2.legend(ncol=6, fontsize=7, loc="upper right")
    ax3 = fig.add_subplot(2, 2, 4)
    _phase_bands(ax3, t, mo.labels)
    for cut in job.cuts:
        ks = [k for k, cp in enumerate(plan.passes) if cp.cut is cut]
        rows = np.isin(mo.pass_of, ks) & mo.surface
        ax3.plot(t[rows], me.feed[rows] * 1e3, ".", ms=1,
                 label=f"{cut.name} (set {cut.feed_speed * 1e3:g})")  # fmt: skip
        ax3.hlines(cut.feed_speed * 1e3, t[rows].min() if rows.any() else 0,
                   t[rows].max() if rows.any() else 0, color="k", lw=0.8)  # fmt: skip
    ax3.set_title("feed of the wire inside the stock (mm/s), measured on the samples",
                  fontsize=9)  # fmt: skip
    ax3.set_xlabel("t (s)")
    present = set(np.unique(mo.labels).astype(str))  # once, not once per phase colour
    handles = [Patch(color=c, alpha=0.3, label=n) for n, c in PHASE_COLOURS.items()
               if n in present]  # fmt: skip
    leg = ax3.legend(fontsize=7, loc="lower right")
    ax3.add_artist(leg)
    ax3.legend(handles=handles, fontsize=7, loc="upper right", title="phase")
    # fixed margins (where tight_layout put the panels): measuring every label first
    # took a fifth of the picture's time
    fig.subplots_adjust(left=0.011, right=0.989, bottom=0.065, top=0.962, wspace=0.14,
                        hspace=0.213)  # fmt: skip
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return atomic_write_bytes(path, buf.getvalue())
