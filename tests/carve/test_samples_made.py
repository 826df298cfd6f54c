"""Issue 32's proof parts (``ruledrobot.carve.samples``) carved in the demo cell, and the
roughing loop that failed its plan planned again (scripts/parts_table.py is the whole
table)."""

from __future__ import annotations

import json

import numpy as np

from ruledrobot.carve import carve
from ruledrobot.carve.samples import write_part_cell
from ruledrobot.wirecut import load_job, plan


def test_the_channel_block_gets_no_loop_its_planes_made_needless(tmp_path):
    """Its seven planar faces already take everything outside its hull: four loops before,
    in four setups, three of which failed their plans (the bow in the block, the feed)."""
    res = carve(write_part_cell(tmp_path / "part", "channel_block"), tmp_path / "out")
    whole = res.report["whole"]
    assert res.ok and (whole["exact_cuts"], whole["rough_cuts"], whole["setups"]) == (7, 0, 1)
    assert any(n.startswith("no roughing loop") for n in res.report["notes"])
    # the channel and the hole stay: the excess is their volume, the closed forms'
    channel = 0.18 * 0.08 * 0.04  # the floor's saddle term averages to 0 over the channel
    hole = np.pi * 0.015**2 * 0.18
    assert abs(whole["excess"] * whole["part_volume_l"] * 1e-3 - (channel + hole)) < 2e-5


def test_the_fairings_loops_are_even_and_its_fourth_plans_within_the_feed(tmp_path):
    """The fairing's fourth silhouette failed feed_min before (8.2 mm/s: the rulings
    clustered on the standoff's arcs); on the part's own polygon it plans PASS."""
    res = carve(write_part_cell(tmp_path / "part", "fairing"), tmp_path / "out")
    assert res.ok and res.report["whole"]["rough_cuts"] == 4
    assert not any("not chosen" in n for n in res.report["notes"])  # the robot took them
    job = tmp_path / "out" / "setup4" / "job.toml"
    doc = json.loads((job.parent / "rough4.json").read_text())
    p = np.array([line["point"] for line in doc["lines"]])
    gaps = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    assert doc["closed"] and gaps.max() < 0.0051 and gaps.min() > 0.001
    out = plan(load_job(job), None)  # the verdict alone (MuJoCo's included), no files
    assert out.feasible, out.verdict.summary()
