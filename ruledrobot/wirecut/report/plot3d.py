"""The 3-D panel of ``plots.png``: the block, the part and the wire's path, legibly.

Drawn in millimetres in the robot's base frame, equal scales, on a cube about the block
(:func:`~ruledrobot.io.axes3d.cube_axes`):

* the block: its faces barely tinted, its edges drawn;
* the part (``part.stl``, shaded) when a cut names its kept side, else the cut
  surfaces in the block (``surface.stl``);
* the wire's midpoint path through the whole motion, one colour per phase (dashed off
  the block: approach, transits, retract), and the wire itself at a few samples of
  each heated phase (:data:`WIRES_PER_PASS`), clipped to the cube;
* each pass's number and cut name where its cut begins;
* a legend naming the phases, the part and the block, and the title inside the axes.

The drawing order is fixed (block faces, part, block edges, wires, path, labels: the
wire shows in front of the part it cuts) rather than matplotlib's per-collection depth
sort, which hides a whole collection behind another.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...geometry.box import Box
from ...geometry.mesh import Mesh
from ...io.axes3d import cube_axes, draw_box, draw_mesh
from ...robot.motion.trajectory import HEATED_PHASES, PHASE_COLOURS, phases_from_labels
from ...robot.tool import BowTool
from ...robot.wire.in_stock import flange_wire_ends
from ..plan import Plan

__all__ = ["PART_COLOUR", "PHASE_COLOURS", "PHASE_WORDS", "SURFACE_COLOUR", "phase_runs",
           "scene_panel"]

#: the phases in words, for legends
PHASE_WORDS = {
    "approach": "approach", "transit": "transit", "retract": "retract", "move": "move",
    "preheat": "pre-heat", "lead_in": "lead-in", "cut": "cut", "lead_out": "lead-out",
}  # fmt: skip
#: the part (foam) and, when no cut names its kept side, the cut surfaces
PART_COLOUR = "#d8b784"
SURFACE_COLOUR = "#9fb8d6"
#: wires drawn per pass and heated phase, at samples spread evenly over the phase (one:
#: its middle sample), each clipped to the block grown by ``WIRE_REACH`` [m]
WIRES_PER_PASS = {"preheat": 1, "lead_in": 1, "cut": 7, "lead_out": 1}
WIRE_REACH = 0.04
#: points of the midpoint path per run of one phase (the path is smooth; more is time)
PATH_POINTS = 200
#: the cube shown: the block's half-diagonal times this
VIEW_MARGIN = 1.15
#: the cube's size in the panel (matplotlib's box-aspect zoom)
ZOOM = 1.1
#: millimetres per metre (the panel's unit)
MM = 1e3


def _view(stock: Box) -> tuple[np.ndarray, float]:
    """Centre (3,) and half edge [m] of the cube shown about the block."""
    return stock.centre, VIEW_MARGIN * 0.5 * float(np.linalg.norm(stock.size))


def phase_runs(labels: np.ndarray) -> list[tuple[str, int, int]]:
    """The runs ``(phase, start, stop)`` (half-open) of equal labels (M,), in time order.

    By :func:`~ruledrobot.robot.motion.trajectory.phases_from_labels` (one comparison of
    neighbours, no sort of the labels)."""
    return [(p.name, p.start, p.stop) for p in phases_from_labels(labels)]


def _wire_at(plan: Plan, idx: np.ndarray) -> np.ndarray:
    """The wire's ends (K, 2, 3) [m] at motion samples ``idx`` (K,)."""
    bow = plan.bow if plan.bow is not None else BowTool.of(plan.job.tool)
    flange = plan.model.fk(plan.motion.timed.q[idx])
    return flange_wire_ends(flange, bow)


def _clipped(ends: np.ndarray, box: Box) -> np.ndarray:
    """The segments ``ends`` (K, 2, 3) clipped to ``box`` (those missing it left out):
    (K', 2, 3)."""
    a, d = ends[:, 0], ends[:, 1] - ends[:, 0]
    t0, t1, hit = box.clip_lines(a, d)
    t0, t1 = np.clip(t0, 0.0, 1.0), np.clip(t1, 0.0, 1.0)
    keep = hit & (t1 > t0)
    return np.stack([a + t0[:, None] * d, a + t1[:, None] * d], axis=1)[keep]


def _wires(ax: Any, plan: Plan, runs: list[tuple[str, int, int]]) -> None:
    """The wire at a few samples of each heated phase of each pass, one colour a phase,
    where it runs within ``WIRE_REACH`` of the block."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    stock = plan.job.stock
    reach = stock.grown(WIRE_REACH)
    picks: dict[str, list[np.ndarray]] = {}
    for phase, a, b in runs:
        n = WIRES_PER_PASS.get(phase, 0)
        if n and b > a:
            at = np.linspace(a, b - 1, n) if n > 1 else np.array([0.5 * (a + b - 1)])
            picks.setdefault(phase, []).append(np.unique(at.round()))
    for phase, chunks in picks.items():
        seg = _clipped(_wire_at(plan, np.concatenate(chunks).astype(np.intp)), reach)
        if not len(seg):  # (matplotlib refuses an empty 3-D collection)
            continue
        ax.add_collection3d(Line3DCollection(seg * MM, colors=PHASE_COLOURS[phase],
                                             linewidths=1.0, alpha=0.8, zorder=4))  # fmt: skip


def _path(ax: Any, plan: Plan, runs: list[tuple[str, int, int]]) -> None:
    """The wire's midpoint through the whole motion, a line per run of a phase (joined
    to the next run's first sample), solid while the wire is hot, dashed off it."""
    m = len(plan.motion.labels)
    idx = [np.unique(np.r_[np.linspace(a, b - 1, min(b - a, PATH_POINTS)).round(), min(b, m - 1)])
           for _, a, b in runs]  # fmt: skip
    ends = _wire_at(plan, np.concatenate(idx).astype(np.intp))
    mid = 0.5 * (ends[:, 0] + ends[:, 1]) * MM
    start = 0
    for (phase, _, _), k in zip(runs, idx, strict=True):
        p = mid[start : start + len(k)]
        start += len(k)
        ax.plot(*p.T, color=PHASE_COLOURS.get(phase, "0.5"), lw=1.6 if phase == "cut" else 1.2,
                ls="-" if phase in HEATED_PHASES else "--", zorder=5, axlim_clip=True)


def _labels(ax: Any, plan: Plan) -> None:
    """Each pass's number and cut name at the wire's midpoint where its cut begins."""
    mo = plan.motion
    cut = mo.labels == "cut"
    for k, cp in enumerate(plan.passes):
        first = np.flatnonzero(cut & (mo.pass_of == k))
        if not first.size:
            continue
        e = _wire_at(plan, first[:1])[0]
        p = 0.5 * (e[0] + e[1]) * MM
        ax.text(*p, f" {k + 1} {cp.name}", fontsize=9, weight="bold", zorder=6,
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.7})


def _legend(ax: Any, runs: list[tuple[str, int, int]], solid: str) -> None:
    """Legend: the phases present in ``runs`` (one entry a colour), the part or surfaces,
    the block."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    seen = {phase for phase, _, _ in runs}
    present = [p for p in PHASE_COLOURS if p in seen]
    by_colour: dict[str, list[str]] = {}
    for p in present:
        by_colour.setdefault(PHASE_COLOURS[p], []).append(PHASE_WORDS[p])
    hot = {PHASE_COLOURS[p] for p in HEATED_PHASES}
    handles = [Line2D([], [], color=c, lw=1.6, ls="-" if c in hot else "--",
                      label=" / ".join(words)) for c, words in by_colour.items()]  # fmt: skip
    colour = PART_COLOUR if solid == "part" else SURFACE_COLOUR
    handles += [Patch(color=colour, label=solid), Patch(fc="0.35", alpha=0.2, label="block")]
    ax.legend(handles=handles, loc="upper left", fontsize=8, title="wire (midpoint path)",
              title_fontsize=8, framealpha=0.8)  # fmt: skip


def scene_panel(ax: Any, plan: Plan, part: Mesh | None = None,
                surface: Mesh | None = None,
                runs: list[tuple[str, int, int]] | None = None) -> None:  # fmt: skip
    """Draw the 3-D panel (module doc) on the 3-D axes ``ax``.

    Parameters
    ----------
    plan : Plan
        With a motion (``plan.motion`` not None).
    part : Mesh or None
        The part (:func:`~.part_mesh.part_mesh`) [m, base frame], drawn shaded.
    surface : Mesh or None
        The cut surfaces in the block (``surface.stl``), drawn when there is no part.
    runs : list of (str, int, int) or None
        The motion's :func:`phase_runs` when the caller has them (else found here).
    """
    job = plan.job
    ax.computed_zorder = False
    draw_box(ax, job.stock, MM, zorder=0)
    solid = "part" if part is not None else "cut surfaces"
    mesh = part if part is not None else surface
    if mesh is not None and len(mesh.faces):
        draw_mesh(ax, mesh.vertices, mesh.faces, PART_COLOUR if part is not None
                  else SURFACE_COLOUR, MM, alpha=0.95 if part is not None else 0.8,
                  zorder=1)  # fmt: skip
    centre, half = _view(job.stock)
    runs = phase_runs(plan.motion.labels) if runs is None else runs
    _wires(ax, plan, runs)
    _path(ax, plan, runs)
    _labels(ax, plan)
    _legend(ax, runs, solid)
    cube_axes(ax, centre * MM, half * MM, "mm", zoom=ZOOM)
    names = ", ".join(dict.fromkeys(cp.name for cp in plan.passes))
    comp = "; wire kerf compensated" if any(cp.compensated for cp in plan.passes) else ""
    n = len(plan.passes)
    ax.set_title(f"{n} pass{'es' if n > 1 else ''} ({names}) in the block{comp}", fontsize=10)
