"""``margin.png`` of a placement search: a top view of the cell (the robot's base and
reach, the region, the block where the job put it and where the search puts it, the
best margin over the yaws at every place searched) and the margin against the yaw at
the best place."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_bytes
from ..io.words import mm
from .search import Candidate, PlaceResult

__all__ = ["plot_place"]


def _outline(job, cand: Candidate | None) -> np.ndarray:
    """The block's footprint (5, 2) [m] (closed) after ``cand``'s placement (None: as is)."""
    j = job if cand is None else cand.placement.job(job)
    return j.stock.corners[[0, 4, 6, 2, 0], :2]  # the bottom face, round (Box.corners)


def plot_place(path: str | Path, res: PlaceResult, extra: list[Candidate] | None = None,
               sweep: tuple[np.ndarray, np.ndarray] | None = None) -> Path:  # fmt: skip
    """Write the search's picture (module doc) to ``path`` atomically.

    ``extra``: more placements to outline (setups), numbered; ``sweep``: yaws (rad) and margins
    (m) at the best place (else the samples nearest it are drawn)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle, Rectangle

    job, reg = res.job, res.region
    fig = Figure(figsize=(13, 6))
    FigureCanvasAgg(fig)
    ax, ax2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.3, 1]})
    X, M = res.samples, res.margins * 1e3
    # best over yaw at each place (rounded to the sampling)
    xy = X[:, :2].round(6)
    keys, inv = np.unique(xy, axis=0, return_inverse=True)
    best = np.full(len(keys), -np.inf)
    np.maximum.at(best, inv.ravel(), M)
    lim = max(5.0, float(np.nanmax(np.abs(np.clip(best, -200, 200)))))
    norm = TwoSlopeNorm(0.0, -lim, lim)
    if reg.move == "stock":
        sc = ax.scatter(keys[:, 0], keys[:, 1], c=np.clip(best, -lim, lim), cmap="RdYlGn",
                        norm=norm, s=28, marker="s", zorder=1)  # fmt: skip
        ax.add_patch(Rectangle((reg.x[0], reg.y[0]), reg.x[1] - reg.x[0], reg.y[1] - reg.y[0],
                               fill=False, ls="--", color="0.3", lw=1))  # fmt: skip
        ax.plot(*_outline(job, None).T, color="0.3", lw=1.5, label="block as in the job")
        ax.plot(*_outline(job, res.best).T, color="tab:blue", lw=2.2,
                label=f"best: margin {res.best.margin * 1e3:.0f} mm")  # fmt: skip
        for k, cand in enumerate(extra or [], start=1):
            o = _outline(job, cand)
            ax.plot(*o.T, lw=1.8, label=f"setup {k}: margin {cand.margin * 1e3:.0f} mm")
        model = job.robot_model()
        reach = float(model.reach or 0.0)
        base = model.base[:2, 3]
        ax.add_patch(Circle(base, 0.08, color="0.2"))
        if reach:
            ax.add_patch(Circle(base, reach, fill=False, color="0.5", ls=":", lw=1))
            ax.text(base[0], base[1] + reach, f"{model.name} reach {reach:.2f} m", ha="center",
                    va="bottom", fontsize=8, color="0.4")  # fmt: skip
        ax.set_xlabel("x (m, robot base frame)")
        ax.set_ylabel("y (m)")
        ax.set_title("top view: best margin over the yaws at each block centre searched",
                     fontsize=9)  # fmt: skip
    else:
        sc = ax.scatter(keys[:, 0], keys[:, 1], c=np.clip(best, -lim, lim), cmap="RdYlGn",
                        norm=norm, s=28, marker="s")  # fmt: skip
        ax.plot([res.best.placement.x], [res.best.placement.y], "*", ms=14, color="tab:blue",
                label=f"best: margin {res.best.margin * 1e3:.0f} mm")  # fmt: skip
        ax.plot([0], [0], "o", color="0.2", label="robot base now")
        ax.set_xlabel("robot base moved by x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title("best margin over the turns of the base at each move searched", fontsize=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8, loc="best")
    fig.colorbar(sc, ax=ax, fraction=0.04, pad=0.02).set_label("worst margin (mm)")
    # margin against yaw near the best place
    b = res.best.placement
    if sweep is not None:
        ax2.plot(np.degrees(sweep[0]), sweep[1] * 1e3, "o-", ms=3, color="tab:blue")
    else:
        near = np.hypot(X[:, 0] - b.x, X[:, 1] - b.y)
        sel = near <= near.min() + 1e-9
        order = np.argsort(X[sel, 2])
        ax2.plot(np.degrees(X[sel, 2][order]), M[sel][order], "o-", ms=3, color="tab:blue")
    ax2.axhline(0.0, color="0.3", lw=0.8)
    ax2.axvline(np.degrees(b.yaw), color="tab:blue", ls=":", lw=1)
    ax2.set_xlabel("yaw of the block (deg)" if reg.move == "stock" else "turn of the base (deg)")
    ax2.set_ylabel("worst margin (mm)")
    ax2.set_title(f"at x = {mm(b.x)} mm, y = {mm(b.y)} mm; {len(X)} placements, "
                  f"{res.rulings} rulings x {res.rolls} rolls each", fontsize=9)  # fmt: skip
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return atomic_write_bytes(path, buf.getvalue())
