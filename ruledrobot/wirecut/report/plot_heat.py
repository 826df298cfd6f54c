"""The kerf and heat panels of ``plots.png`` (docs/kerf.md, "Pictures").

* :func:`kerf_panel`: the predicted kerf [mm] at both chord ends of the wire on each cut's
  face against time (the wire's start side solid, its end side dashed), the cut's planned
  ``kerf`` as a black line, burns as red crosses.  The arrays are the verdict's own:
  ``plan.measured.faces`` (:class:`~ruledrobot.robot.wire.face.FaceError`, computed once
  with the plan; report.json's ``predicted_kerf_mm`` is their range).
* :func:`heat_panel`: the heat set-point (``Trajectory.heat_power``, W/m) and the wire's
  power after the lag (``plan.measured.wire_power``, what the kerf was predicted with),
  the material's threshold and the output's full scale as lines.

No tolerance band around the planned kerf: with ``[material]`` each chord end is offset
by the kerf predicted there (``wirecut/cut/kerf.py``), so a slower end rightly melts
wider than the cut's ``kerf``; whether the face holds is ``face_error``, in the title.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...geometry.checks import FloatArray
from ...geometry.ranges import runs_of
from ...io.pictures import thinned_series
from ..plan import Plan

__all__ = ["has_heat_schedule", "has_kerf_model", "heat_panel", "kerf_panel", "runs_thinned"]

#: mm: the kerf axis spans at least this (twice the default face tolerance)
MIN_SPAN_MM = 0.2
#: the output's full scale is drawn when the set-points reach this fraction of it (else
#: it is named in the title: a line far above squeezes the schedule)
FULL_SCALE_SHOWN = 0.5
#: line styles of the wire's two chord ends (start side, end side)
END_STYLES = (("-", "wire start side"), ("--", "wire end side"))


def _least_span(ax: Any, span: float) -> None:
    """Widen the y axis about its middle to at least ``span`` (a constant kerf reads as a
    line at its value, not as rounding noise on an offset axis)."""
    lo, hi = ax.get_ylim()
    if hi - lo < span:
        mid = 0.5 * (lo + hi)
        ax.set_ylim(mid - 0.5 * span, mid + 0.5 * span)
    ax.ticklabel_format(axis="y", useOffset=False)


def has_heat_schedule(plan: Plan) -> bool:
    """Whether the plan has a heat model (a ``heat_power`` schedule): the heat panel's rule."""
    return plan.measured is not None and plan.measured.wire_power is not None


def has_kerf_model(plan: Plan) -> bool:
    """Whether the plan predicts the kerf on some cut's face: the kerf panel's rule.

    It needs a ``[material]`` and a heat schedule."""
    me = plan.measured
    return (has_heat_schedule(plan) and plan.job.material is not None
            and any(np.isfinite(fe.worst) or fe.burn for fe in me.faces.values()))  # fmt: skip


def runs_thinned(t: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(t, y)`` kept on the runs where ``y`` (M,) is finite, each run thinned.

    By :func:`~ruledrobot.io.pictures.thinned_series` (every point kept is a sample); the
    runs joined by a NaN (a gap in the line)."""
    ts, ys = [], []
    for a, b in runs_of(np.isfinite(y)):
        tk, yk = thinned_series(t[a:b], y[a:b])
        ts += [tk, [np.nan]]
        ys += [yk, [np.nan]]
    if not ts:
        return np.zeros(0), np.zeros(0)
    return np.concatenate(ts[:-1]), np.concatenate(ys[:-1])


def kerf_panel(ax: Any, plan: Plan) -> None:
    """The predicted kerf [mm] at both wire ends on each cut's face (module doc)."""
    t = plan.motion.timed.t
    faces = plan.measured.faces
    worst = []
    for k, cut in enumerate(plan.job.cuts):
        fe = faces.get(cut.name)
        if fe is None:
            continue
        colour = f"C{k % 10}"
        for j, (style, side) in enumerate(END_STYLES):
            ax.plot(*runs_thinned(t, fe.kerf[:, j] * 1e3), style, color=colour, lw=1.0,
                    label=f"{cut.name}: {side}" if len(plan.job.cuts) > 1 else side)  # fmt: skip
        on = ~np.isnan(fe.kerf).all(axis=1)
        if on.any():
            ax.hlines(cut.kerf * 1e3, t[on].min(), t[on].max(), color="k", lw=0.8,
                      label="the cut's kerf" if k == 0 else None)  # fmt: skip
        burn = np.isinf(fe.kerf).any(axis=1)
        if burn.any():
            ax.plot(t[burn], np.full(burn.sum(), np.nanmax(np.where(
                np.isfinite(fe.kerf), fe.kerf, np.nan)) * 1e3), "x", color="red", ms=4,
                label="burn (a stop with the heat on)")  # fmt: skip
        worst.append(f"{'burn' if fe.burn else f'{fe.worst * 1e3:.3f} mm'}"
                     f"{f' ({cut.name})' if len(plan.job.cuts) > 1 else ''}")
    _least_span(ax, MIN_SPAN_MM)
    ax.set_title("predicted kerf on the part's face at the wire's two ends (mm); face_error "
                 f"{', '.join(worst)} (tolerance {plan.job.cut.tolerance * 1e3:g} mm)",
                 fontsize=9)  # fmt: skip
    ax.legend(fontsize=7, loc="upper right")


def heat_panel(ax: Any, plan: Plan) -> None:
    """The heat set-point and the wire's power after the lag [W/m] (module doc)."""
    t = plan.motion.timed.t
    tr, me = plan.trajectory, plan.measured
    heat = tr.meta.heat
    mode = "on_off" if heat is None else heat.mode
    lag = 0.0 if heat is None else heat.lag
    ax.plot(*thinned_series(t, tr.heat_power), color="tab:red", lw=1.0, label="set-point")
    ax.plot(*thinned_series(t, me.wire_power), "--", color="k", lw=0.9,
            label=f"the wire (set-point {lag:g} s late)")  # fmt: skip
    if plan.job.material is not None:
        ax.axhline(plan.job.material.power_threshold, color="0.4", lw=0.7, ls=":",
                   label="threshold (melts nothing)")  # fmt: skip
    top = None if heat is None else heat.full_scale
    if top is not None and np.max(tr.heat_power) >= FULL_SCALE_SHOWN * top:
        ax.axhline(top, color="tab:red", lw=0.7, ls=":", label="full scale (clipped above)")
    scale = "" if top is None else f", full scale {top:g} W/m"
    ax.set_title(f"heat (W per metre of wire): mode {mode}, set-points lead by {lag:g} s"
                 f"{scale}", fontsize=9)  # fmt: skip
    ax.legend(fontsize=7, loc="upper right")
