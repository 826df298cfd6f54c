"""The reachability map as files: ``reach.json`` (every cell) and ``reach.png`` (one panel
per cut: rulings along the cut against the roll of the wire about the ruling, coloured
by the margin where the arm reaches and by the reason where it does not, with the
path the planner chose drawn on it), and its summary in words."""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ...io.atomic import atomic_write_bytes, atomic_write_json
from ...io.words import index_ranges
from ..job.spec import Job
from .map import PassMap, ReachMap
from .margins import REASON_TEXT, Reason, limit_levers

__all__ = [
    "REACH_FORMAT",
    "REASON_COLOURS",
    "pass_summary",
    "plot_reach",
    "ruling_ranges",
    "summary_lines",
    "write_reach",
    "write_reach_json",
]

REACH_FORMAT = "ruledrobot.reach-map/1"

#: the colour of each reason on the map (reachable cells are green by margin)
REASON_COLOURS = {
    Reason.OUT_OF_REACH: "#d62728", Reason.JOINT_LIMIT: "#ff7f0e",
    Reason.SINGULARITY: "#f0c419", Reason.BOW_STOCK: "#8c564b", Reason.ARM_STOCK: "#9467bd",
    Reason.BOW_ARM: "#e377c2", Reason.BOW_TABLE: "#7f7f7f", Reason.ARM_TABLE: "#17becf",
    Reason.CHORD: "#000000", Reason.CLEARANCE: "#bcbd22",
}  # fmt: skip


def ruling_ranges(pm: PassMap, mask: np.ndarray) -> str:
    """Return the sampled rulings where ``mask`` holds, as ranges of ruling numbers.

    Runs of consecutive samples are joined.
    """
    return index_ranges(mask, pm.idx)


def pass_summary(pm: PassMap) -> dict:
    """Figures of one pass's map.

    Reachable share, cells per reason, the planner's path (its worst margin and where) or the
    best constant roll of the map."""
    d = pm.shown
    cells = pm.reason[d]
    counts = {REASON_TEXT[Reason(r)]: int((cells == r).sum()) for r in np.unique(cells)}
    per_ruling = pm.margin[d].max(axis=0)  # the best roll of each ruling
    out = {
        "direction": "reversed" if d else "along the ruling",
        "reachable_fraction": float((pm.margin[d] >= 0).mean()),
        "cells": counts,
        "rulings_without_any_roll": ruling_ranges(pm, per_ruling < 0),
    }
    out_all = (cells == Reason.OUT_OF_REACH).all(axis=0)
    if out_all.any():
        out["rulings_out_of_reach_at_every_roll"] = ruling_ranges(pm, out_all)
        out["out_of_reach_by_up_to_mm"] = float(-per_ruling[out_all].min() * 1e3)
    if pm.chosen_roll is not None and pm.path_margin is not None:
        w = int(np.argmin(pm.path_margin))
        out["planned"] = {
            "roll_deg": [float(np.degrees(pm.chosen_roll.min())),
                         float(np.degrees(pm.chosen_roll.max()))],
            "worst_margin_mm": float(pm.path_margin[w] * 1e3),
            "worst_at_ruling": int(pm.idx[w]),
            "rulings_failing_on_the_map": ruling_ranges(pm, pm.path_margin < 0),
        }
    c = pm.constant
    if c is not None:  # the one model's best constant roll (docs/place.md, "One model")
        out["best_constant_roll"] = {
            "roll_deg": float(c.roll_deg),
            "reversed": c.reverse,
            "ik_branch": c.branch,
            "worst_margin_mm": float(c.worst * 1e3),
            "reachable_fraction": c.share,
            "sampled_rulings": int(c.idx.size),
            "words": pm.constant_words or c.words(),
        }
    return out


def write_reach_json(path: str | Path, rm: ReachMap, job_ref: dict | None) -> Path:
    """Write ``reach.json``: every cell of every pass, the rules and the summaries.

    Margins in mm, reasons as codes with their words.
    """
    passes = []
    for pm in rm.passes:
        passes.append({
            "cut": pm.cut, "pass": pm.index, "rulings": pm.rulings,
            "sampled_rulings": pm.idx.tolist(),
            "rolls_deg": np.round(np.degrees(pm.rolls), 3).tolist(),
            "directions": ["along the ruling", "reversed"],
            "margin_mm": np.round(np.maximum(pm.margin, -9999e-3) * 1e3, 1).tolist(),
            "reason": pm.reason.astype(int).tolist(),
            "branch": pm.branch.astype(int).tolist(),
            "in_stock": pm.in_stock.tolist(),
            "slide_m": np.round(pm.slide, 6).tolist(),
            "slides_m": None if pm.slides is None else np.round(pm.slides, 6).tolist(),
            "slide_index": None if pm.slide_index is None else pm.slide_index.astype(
                int).tolist(),
            "planned": None if pm.chosen_roll is None else {
                "roll_deg": np.round(np.degrees(pm.chosen_roll), 3).tolist(),
                "reversed": pm.chosen_reverse,
                "margin_mm": np.round(pm.path_margin * 1e3, 1).tolist(),
                "reason": pm.path_reason.astype(int).tolist(),
            },
            "summary": pass_summary(pm),
        })  # fmt: skip
    r = rm.rules
    doc = {
        "format": REACH_FORMAT,
        "job": job_ref,
        "robot": rm.job.robot.model,
        "rules": {"singularity_min": r.singular_min, "clearance_margin_m": r.margin,
                  "limit_levers_m_per_rad": limit_levers(rm.job.robot_model()).tolist(),
                  "clearance_levels_m": list(r.levels)},
        "reasons": {int(k): v for k, v in REASON_TEXT.items()},
        "margin": "mm: the least of reach, joint-limit, singularity and clearance room "
                  "(docs/place.md); negative where the arm cannot hold the wire",
        "seconds": rm.seconds,
        "passes": passes,
    }  # fmt: skip
    return atomic_write_json(path, doc, compact=True)


#: out-of-reach cells are shaded up to this distance (m)
FAR = 0.2


def _image(pm: PassMap, d: int, top: float) -> np.ndarray:
    """RGB (K, R, 3) of one direction's map: green by margin, red by how far out of
    reach, the other reasons in their colours."""
    from matplotlib import colormaps
    from matplotlib.colors import to_rgb

    m = pm.margin[d]
    rgb = colormaps["Greens"](0.3 + 0.7 * np.clip(m / max(top, 1e-9), 0.0, 1.0))[..., :3]
    for r, colour in REASON_COLOURS.items():
        rgb[pm.reason[d] == r] = to_rgb(colour)
    far = pm.reason[d] == Reason.OUT_OF_REACH
    shade = colormaps["Reds"](0.45 + 0.55 * np.clip(-m / FAR, 0.0, 1.0))[..., :3]
    rgb[far] = shade[far]
    return rgb


def plot_reach(path: str | Path, rm: ReachMap) -> Path:
    """``reach.png``: one panel per cut (its passes side by side), see the module doc."""
    from matplotlib import colormaps
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    cuts = list(dict.fromkeys(pm.cut for pm in rm.passes))
    top = rm.rules.shown
    fig = Figure(figsize=(13, 1.2 + 3.4 * len(cuts)))
    FigureCanvasAgg(fig)
    present: set[int] = set()
    axes = fig.subplots(len(cuts), 1, squeeze=False)[:, 0]
    for ax, name in zip(axes, cuts, strict=True):
        maps = [pm for pm in rm.passes if pm.cut == name]
        x0 = 0.0
        words = []
        for pm in maps:
            d = pm.shown
            present |= set(np.unique(pm.reason[d]).tolist())
            x = pm.idx.astype(float)
            half = np.diff(x).mean() / 2 if x.size > 1 else 0.5
            ext = (x0 + x[0] - half, x0 + x[-1] + half, -180.0, 180.0)
            ax.imshow(_image(pm, d, top), origin="lower", aspect="auto", extent=ext,
                      interpolation="nearest")  # fmt: skip
            ins = np.flatnonzero(pm.in_stock)
            if ins.size:
                ax.plot([x0 + x[ins[0]], x0 + x[ins[-1]]], [183, 183], color="0.2", lw=4,
                        clip_on=False, solid_capstyle="butt")  # fmt: skip
            if pm.chosen_roll is not None:
                deg = np.degrees((pm.chosen_roll + np.pi) % (2 * np.pi) - np.pi)
                y = np.where(np.abs(np.diff(deg, prepend=deg[0])) > 180, np.nan, deg)
                ax.plot(x0 + x, y, color="k", lw=1.6)
                bad = pm.path_margin < 0
                ax.plot(x0 + x[bad], deg[bad], "x", color="red", ms=6)
                w = int(np.argmin(pm.path_margin))
                words.append(f"planned: roll {_roll_text(pm.chosen_roll)}, worst margin "
                             f"{pm.path_margin[w] * 1e3:.0f} mm at ruling {pm.idx[w]}")
            elif pm.constant is not None:
                c = pm.constant
                ax.plot([x0 + x[0], x0 + x[-1]], [c.roll_deg] * 2, color="k",
                        lw=1.0, ls="--")  # fmt: skip
                words.append(f"no path found; dashed: best constant roll {c.roll_deg} deg "
                             f"({c.percent()} % of {c.idx.size} sampled rulings)")
            if pm.chosen_roll is None:
                out = (pm.reason[d] == Reason.OUT_OF_REACH).all(axis=0)
                if out.any():
                    far = float(-pm.margin[d][:, out].max(axis=0).min())
                    words.append(f"rulings {ruling_ranges(pm, out)} out of reach at every "
                                 f"roll, by up to {far * 1e3:.0f} mm")
            if x0 > 0:
                ax.axvline(x0 + x[0] - half, color="w", lw=3)
            x0 += x[-1] + 2 * half
        direction = "wire reversed" if maps[0].shown else "wire along the ruling"
        ax.set_title(f"cut '{name}' ({direction}): " + "; ".join(words), fontsize=9, loc="left")
        ax.set_ylabel("roll about the wire (deg)")
        ax.set_yticks([-180, -90, 0, 90, 180])
        ax.set_xlabel("ruling along the cut (lead-in to lead-out; dark bar: in the block)")
    handles = [Patch(color=REASON_COLOURS[Reason(r)], label=REASON_TEXT[Reason(r)])
               for r in sorted(present) if r]  # fmt: skip
    handles.append(Patch(color="k", label="planned path (x: fails on the map)"))
    fig.legend(handles=handles, loc="lower left", ncol=min(6, len(handles)), fontsize=8,
               frameon=False)  # fmt: skip
    height = 1.2 + 3.4 * len(cuts)
    fig.subplots_adjust(left=0.06, right=0.86, top=1 - 0.35 / height, bottom=1.0 / height,
                        hspace=0.45)  # fmt: skip
    cax = fig.add_axes((0.875, 1.0 / height, 0.012, 1 - 1.35 / height))
    green = colormaps["Greens"]
    cmap = green.from_list("g", green(np.linspace(0.3, 1, 64)))
    sm = ScalarMappable(Normalize(0, top * 1e3), cmap)
    fig.colorbar(sm, cax=cax).set_label("margin where reachable (mm)", fontsize=8)
    cax2 = fig.add_axes((0.935, 1.0 / height, 0.012, 1 - 1.35 / height))
    reds = colormaps["Reds"]
    cmap2 = reds.from_list("r", reds(np.linspace(0.45, 1, 64)))
    sm2 = ScalarMappable(Normalize(0, FAR * 1e3), cmap2)
    fig.colorbar(sm2, cax=cax2).set_label("out of reach by (mm)", fontsize=8)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return atomic_write_bytes(path, buf.getvalue())


def _roll_text(roll: np.ndarray) -> str:
    lo, hi = np.degrees(roll.min()), np.degrees(roll.max())
    return f"{lo:.0f} deg" if abs(hi - lo) < 0.5 else f"{lo:.0f} to {hi:.0f} deg"


def write_reach(
    job: Job,
    out: str | Path,
    rulings: int = 240,
    rolls: int = 72,
    progress: Callable[[str], None] | None = None,
    slides: int = 1,
) -> tuple[ReachMap, dict[str, Path]]:
    """Map ``job`` (:func:`~.map.reach_map`) and write ``reach.png`` and ``reach.json``.

    Into the folder ``out`` (written whole, swapped in at the end).
    """
    from ...io.outdir import StagedFolder
    from ..plan import job_reference
    from .map import reach_map

    with StagedFolder(out) as stage:
        rm = reach_map(job, rulings=rulings, rolls=rolls, progress=progress, slides=slides)
        write_reach_json(stage.path / "reach.json", rm, job_reference(job))
        plot_reach(stage.path / "reach.png", rm)
        ok = all(pm.feasible for pm in rm.passes)
        target = stage.commit({"kind": "reach", "feasible": ok})
    return rm, {"map": target / "reach.png", "json": target / "reach.json"}


def summary_lines(rm: ReachMap) -> list[str]:
    """The map of each pass in a sentence or two (for the command line)."""
    lines = []
    for pm in rm.passes:
        s = pass_summary(pm)
        head = f"{pm.cut}" + (f" (pass {pm.index + 1})" if len(rm.passes) > len(
            {p.cut for p in rm.passes}) else "")  # fmt: skip
        share = 100 * s["reachable_fraction"]
        text = f"{head}: {share:.0f} % of (ruling, roll) cells reachable ({s['direction']})"
        if "planned" in s:
            p = s["planned"]
            text += (f"; planned path: worst margin {p['worst_margin_mm']:.0f} mm at ruling "
                     f"{p['worst_at_ruling']}")
        elif pm.constant is not None:
            text += f"; no feasible path: {pm.constant_words or pm.constant.words()}"
        else:
            text += "; no feasible path"
        if s["rulings_without_any_roll"]:
            text += f"; no roll works at rulings {s['rulings_without_any_roll']}"
        if "out_of_reach_by_up_to_mm" in s:
            text += (f" (out of reach at every roll: rulings "
                     f"{s['rulings_out_of_reach_at_every_roll']}, by up to "
                     f"{s['out_of_reach_by_up_to_mm']:.0f} mm)")
        lines.append(text)
    return lines
