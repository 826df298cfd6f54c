"""``plots.png`` of a plan: on the left the cut in 3-D (the block, the part, the wire's path
by phase: :mod:`.plot3d`), on the right the time panels, one under the other on a shared
time axis with the phases as bands: the joints against their limits and the feed of
every cut against its set feed; when the plan has a heat model, the predicted kerf at both
wire ends and the heat schedule (:mod:`.plot_heat`).

Each time panel is one function ``panel(ax, plan)`` (:data:`TIME_PANELS`); a panel
added to the tuple (or handed to :func:`plot_plan`) gets its own row; a
:class:`ShownWhen` panel only when its rule holds for the plan.  The layout has fixed
margins (:data:`MARGINS`, in inches, so that they hold for any number of rows).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...geometry.checks import FloatArray
from ...geometry.mesh import Mesh
from ...io.pictures import thinned_series, write_png
from ..plan import Plan
from .plot3d import PHASE_COLOURS, PHASE_WORDS, phase_runs, scene_panel
from .plot_heat import has_heat_schedule, has_kerf_model, heat_panel, kerf_panel

__all__ = ["PHASE_COLOURS", "TIME_PANELS", "ShownWhen", "feed_panel", "joints_panel",
           "plot_plan"]

#: a time panel: draws on its axes (time [s] along x, shared) from the plan
TimePanel = Callable[[Any, Plan], None]
#: the picture's size [in] (its height grows by ``ROW_HEIGHT`` for every time panel past
#: two) and resolution
SIZE, ROW_HEIGHT, DPI = (15.0, 9.0), 4.0, 90
#: the margins [in] round the panels, the gap [in] between two time panels (a title above,
#: "t (s)" below) and the space between the 3-D and the time columns (a fraction of a
#: column's width: the time panels' tick labels)
MARGINS = {"left": 0.15, "right": 0.15, "top": 0.35, "bottom": 0.55, "gap": 0.75,
           "wspace": 0.1}


def _phase_bands(ax: Any, t: FloatArray, runs: list[tuple[str, int, int]]) -> None:
    """The phases (:func:`.plot3d.phase_runs`) as bands of their colour behind a time panel.

    One collection of full-height rectangles (x in time, y in axes units), as
    ``ax.axvspan`` draws them one patch each; their times join the x data limits."""
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import to_rgba_array

    if not runs:
        return
    a = np.array([r[1] for r in runs])
    x0, x1 = t[a], t[np.array([r[2] for r in runs]) - 1]
    verts = np.stack([np.c_[x0, np.zeros_like(x0)], np.c_[x0, np.ones_like(x0)],
                      np.c_[x1, np.ones_like(x1)], np.c_[x1, np.zeros_like(x1)]], axis=1)
    colours = to_rgba_array([PHASE_COLOURS.get(r[0], "0.9") for r in runs], alpha=0.12)
    ax.add_collection(PolyCollection(verts, facecolors=colours, edgecolors=colours,
                                     linewidths=0, transform=ax.get_xaxis_transform()),
                      autolim=False)  # fmt: skip
    ax.update_datalim(np.c_[np.r_[x0, x1], np.zeros(2 * len(a))], updatey=False)
    ax.autoscale_view(scaley=False)


def joints_panel(ax: Any, plan: Plan) -> None:
    """The six joint positions [rad] against time, their limits in the title."""
    mo = plan.motion
    t = mo.timed.t
    for j in range(mo.timed.q.shape[1]):
        ax.plot(*thinned_series(t, mo.timed.q[:, j]), label=f"q{j + 1}")
    lim = ", ".join(f"{hi:.3g}" if np.isfinite(hi) else "inf" for hi in plan.model.upper)
    ax.set_title(f"joint positions (rad); limits ± [{lim}]", fontsize=9)
    ax.legend(ncol=6, fontsize=7, loc="upper right")


def feed_panel(ax: Any, plan: Plan) -> None:
    """Draw the feed [mm/s] of the wire on the target surface into ``ax``.

    Measured on the samples, each cut against its set feed (a black line), and the phases'
    legend.
    """
    from matplotlib.patches import Patch

    job, mo, me = plan.job, plan.motion, plan.measured
    t = mo.timed.t
    for cut in job.cuts:
        ks = [k for k, cp in enumerate(plan.passes) if cp.cut is cut]
        rows = np.isin(mo.pass_of, ks) & mo.surface
        ax.plot(t[rows], me.feed[rows] * 1e3, ".", ms=1,
                label=f"{cut.name} (set {cut.feed_speed * 1e3:g})")  # fmt: skip
        if rows.any():
            ax.hlines(cut.feed_speed * 1e3, t[rows].min(), t[rows].max(), color="k", lw=0.8)
    ax.set_title("feed of the wire inside the stock (mm/s), measured on the samples",
                 fontsize=9)  # fmt: skip
    present = {phase for phase, _, _ in phase_runs(mo.labels)}
    words: dict[str, list[str]] = {}
    for p, c in PHASE_COLOURS.items():
        if p in present:
            words.setdefault(c, []).append(PHASE_WORDS[p])
    leg = ax.legend(fontsize=7, loc="lower right", markerscale=6)
    ax.add_artist(leg)
    ax.legend(handles=[Patch(color=c, alpha=0.3, label=" / ".join(w)) for c, w in words.items()],
              fontsize=7, loc="upper right", title="phase")  # fmt: skip


@dataclass(frozen=True)
class ShownWhen:
    """A time panel (``panel(ax, plan)``) drawn only for plans where ``rule(plan)`` holds."""

    panel: TimePanel
    rule: Callable[[Plan], bool]

    def __call__(self, ax: Any, plan: Plan) -> None:
        self.panel(ax, plan)


def _shown(panel: TimePanel, plan: Plan) -> bool:
    return not isinstance(panel, ShownWhen) or panel.rule(plan)


#: the time panels, top to bottom (the kerf and the heat only with a heat model)
TIME_PANELS: tuple[TimePanel, ...] = (
    joints_panel, feed_panel, ShownWhen(kerf_panel, has_kerf_model),
    ShownWhen(heat_panel, has_heat_schedule),
)  # fmt: skip


def plan_figure(plan: Plan, part: Mesh | None = None, surface: Mesh | None = None,
                panels: Sequence[TimePanel] = TIME_PANELS) -> Any:  # fmt: skip
    """The picture (module doc) as a matplotlib Figure on an Agg canvas (no pyplot state).

    Parameters
    ----------
    plan : Plan
        With a motion.
    part, surface : Mesh or None
        The part and the cut surfaces [m, base frame] (:func:`.plot3d.scene_panel`).
    panels : sequence of callables
        The time panels, top to bottom (:data:`TIME_PANELS`; a :class:`ShownWhen` panel
        only where its rule holds).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    panels = [p for p in panels if _shown(p, plan)]
    rows = max(1, len(panels))
    height = SIZE[1] + ROW_HEIGHT * max(0, rows - 2)
    fig = Figure(figsize=(SIZE[0], height), dpi=DPI)
    FigureCanvasAgg(fig)
    # fixed margins in inches (room for the panels' titles, tick labels and "t (s)"): a
    # layout engine measures every text first, a third of the picture's drawing time
    top, bottom, gap = MARGINS["top"], MARGINS["bottom"], MARGINS["gap"]
    axis_h = (height - top - bottom - gap * (rows - 1)) / rows
    grid = fig.add_gridspec(rows, 2, width_ratios=(1.0, 1.0), left=MARGINS["left"] / SIZE[0],
                            right=1.0 - MARGINS["right"] / SIZE[0], top=1.0 - top / height,
                            bottom=bottom / height, wspace=MARGINS["wspace"],
                            hspace=gap / axis_h)  # fmt: skip
    runs = phase_runs(plan.motion.labels)
    scene_panel(fig.add_subplot(grid[:, 0], projection="3d"), plan, part, surface, runs)
    t = plan.motion.timed.t
    first = None
    for k, panel in enumerate(panels):
        ax = fig.add_subplot(grid[k, 1], sharex=first)
        first = first or ax
        _phase_bands(ax, t, runs)
        panel(ax, plan)
        ax.set_xlabel("t (s)")
    return fig


def plot_plan(path: str | Path, plan: Plan, part: Mesh | None = None,
              surface: Mesh | None = None, panels: Sequence[TimePanel] = TIME_PANELS
              ) -> Path:  # fmt: skip
    """Write the plan's picture (:func:`plan_figure`) to ``path`` (PNG) atomically."""
    return write_png(plan_figure(plan, part, surface, panels), path)
