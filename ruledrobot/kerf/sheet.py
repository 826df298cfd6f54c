"""The ladder's sheet: what to cut, what to measure and where (``ladder.md``), and the
template of the measurements (``measured.csv``) that ``ruledrobot kerf fit`` reads."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .measured import COLUMNS

__all__ = ["READINGS", "measured_template", "sheet_text"]

#: readings per slot: three along the top, one at mid-height on each end face
READINGS = 5


def measured_template(ladder: Any) -> str:
    """``measured.csv``: a row per test cut, ``kerf_mm`` and ``failed`` left to fill in."""
    rows = ["cut,job," + ",".join(COLUMNS) + ",failed"]
    rows += [f"{c.name},{c.job},{c.speed * 1e3:g},{c.power:g},," for c in ladder.cuts]
    return "\n".join(rows) + "\n"


def sheet_text(ladder: Any, job_file: Path) -> str:
    """``ladder.md``: the cuts, how to run them, and how to measure the slots (module doc)."""
    wa, sa = ladder.wire_axis, ladder.spacing_axis
    length = ladder.size["xyz".index(sa)] * 1e3
    powers = sorted({(c.job, c.power) for c in ladder.cuts})
    out = [
        "# Kerf ladder: cut, measure, fit",
        "",
        f"Written by `ruledrobot kerf ladder {job_file.name}` (docs/kerf.md, \"Calibration\"). "
        f"{len(ladder.cuts)} straight cuts through the block, {ladder.spacing * 1e3:g} mm "
        f"apart along its {sa} axis: the wire lies along the block's {wa} axis and goes "
        "down through it, so each slot is a vertical slit across the whole block. One job "
        f"per power (the job format sets the power per job: {ladder.heat}).",
        "",
        "## 1. Cut",
        "",
        "Use a fresh block of the foam you will cut, placed as the job says. Run the jobs "
        "one after the other, in the same block, without moving it or the slices:",
        "",
    ]
    for job, power in powers:
        out.append(f"- `ruledrobot plan {job}/job.toml --out {job}/plan`, then run it "
                   f"(`ruledrobot run {job}/plan/trajectory.csv ...`): {power:g} W/m")
    out += [
        "",
        "Let the wire cool between jobs only if your supply needs it; the jobs preheat "
        "before each cut. Watch each cut: if the wire bows back visibly, drags or tears the "
        "foam, snaps, or the cut stops, write `yes` in its row's `failed` column (its "
        "speed then bounds `max_speed`).",
        "",
        "## 2. Measure",
        "",
        f"Measure the slots where they stand, before moving a slice. For each slot take "
        f"{READINGS} readings of its width with the inside jaws of a caliper (or feeler "
        "gauges), each across the slot, square to its faces:",
        "",
        "- three on the top face, at a quarter, half and three quarters of the slot's "
        f"length along {wa} (not within 20 mm of the block's edges: the wire's ends, in "
        "the air, run at another temperature than its middle in the foam),",
        "- one at mid-height on each of the two end faces where the slot comes out.",
        "",
        "Write their mean in `kerf_mm` (mm, two decimals). When the readings of a slot "
        "spread by more than 0.1 mm, measure it again; a top-to-end-face difference that "
        "repeats on every slot is the wire's lean or bow, not noise.",
        "",
        "| cut | job | speed mm/s | power W/m | plane from the block's centre mm |",
        "|---|---|---|---|---|",
    ]
    out += [f"| {c.name} | {c.job} | {c.speed * 1e3:g} | {c.power:g} | "
            f"{c.offset * 1e3:+.1f} along {sa} |" for c in ladder.cuts]  # fmt: skip
    out += [
        "",
        f"(The block is {length:g} mm along {sa}; `+` is towards its +{sa} face.)",
        "",
        "## 3. Fit",
        "",
        "Fill in `measured.csv` (its columns `speed_mm_s`, `power_w_m`, `kerf_mm`, `failed`; "
        "the others are for you) and run `ruledrobot kerf fit measured.csv`: it prints "
        "each constant with its standard error, every row's residual and its error when "
        "predicted from the other rows, the verdict, and writes `material.toml`, the "
        "`[material]` table to paste into your jobs, when the fit is good enough.",
        "",
    ]
    return "\n".join(out)
