"""One rule for corners, whatever the file (issue 22, item 3): a foam cutter's profile with
sharp corners (tests/formats/data/profile.ngc: in to the leading edge, round the trailing
edge, out), and the same profile tapered (the tip 0.75 of the root), converted to DXF and
to a lines file plan as the G-code does — refined between its corners, the wire stopping
at them, on the surface within its tolerance, at its feed.  Before, the DXF (default
``dh``) and the lines file were refined over the corners and found no wire motion at all
("no constant or varying roll works")."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from ruledrobot.io.formats.convert import convert
from ruledrobot.robot.wire.cut import feed_measures
from ruledrobot.wirecut.cut.passes import refine_cut
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.motion.corners import corner_nodes
from ruledrobot.wirecut.plan import make_plan

DATA = Path(__file__).parents[2] / "formats" / "data"

#: the profile job of tests/formats/test_gcode_corners.py, kerf compensated (the part inside)
JOB = """\
[surface]
{surface}
pose = [0.4, 0.35, 0.4, 1.5707963267948966, 0.0, 0.0]

[stock]
centre = [0.5, 0.0, 0.44]
size = [0.22, 0.3, 0.06]

[robot]
model = "ur5e"

[tool]
wire_start = [-0.2, 0.0, 0.25]
wire_end = [0.2, 0.0, 0.25]
clearance = 0.02
mass = 1.0

[cut]
feed_speed = 0.008
lead_in = 0.02
lead_out = 0.02
kerf = 0.0008
keep = [0.5, 0.0, 0.44]
"""

SURFACES = {
    "gcode": 'gcode = {{ file = "{name}.ngc", tower_distance = 0.7 }}',
    "dxf": 'dxf = "{name}.dxf"',  # the default algorithm of a DXF: dh
    "lines": 'file = "{name}.json"',
}


def _tapered(text: str) -> str:
    """The program with tower B's moves scaled by 0.75 about (10, 40) mm less 7.5 mm in U:
    a tapered panel (its rulings no longer parallel), the same corners."""

    def move(m: re.Match) -> str:
        x, y = float(m[1]), float(m[2])
        return f"G1 X{x:.3f} Y{y:.3f} U{0.75 * x + 10.0:.3f} V{0.75 * (y - 40.0) + 40.0:.3f}"

    return re.sub(r"G1 X(\S+) Y(\S+) U\S+ V\S+", move, text)


@pytest.fixture(scope="module")
def jobs(tmp_path_factory) -> dict:
    """The job of each profile and format, its files converted from the G-code."""
    folder = tmp_path_factory.mktemp("corners")
    program = (DATA / "profile.ngc").read_text()
    (folder / "profile.ngc").write_text(program)
    (folder / "taper.ngc").write_text(_tapered(program))
    out = {}
    for name in ("profile", "taper"):
        for suffix in ("dxf", "json"):
            convert(folder / f"{name}.ngc", folder / f"{name}.{suffix}",
                    read_options={"tower_distance": 0.7})  # fmt: skip
        for kind, surface in SURFACES.items():
            path = folder / f"{name}_{kind}.toml"
            path.write_text(JOB.format(surface=surface.format(name=name)))
            out[name, kind] = load_job(path)
    return out


def _line_distance(p: np.ndarray, o: np.ndarray, z: np.ndarray) -> np.ndarray:
    d = p - o
    return np.linalg.norm(d - (d * z).sum(axis=1, keepdims=True) * z, axis=1)


@pytest.mark.parametrize("name", ["profile", "taper"])
def test_every_format_is_refined_between_the_same_corners(jobs, name):
    """Independent of the planner's corner rule: the refined rulings of the DXF and the
    lines file are the G-code's within 0.1 mm (their chord ends in the block from the
    G-code's lines), the same count, so the same corners were kept."""
    refined = {k: refine_cut(j.cut, j.stock, k, j.tool.wire_length)
               for (n, k), j in jobs.items() if n == name}  # fmt: skip
    ref = refined["gcode"].frames
    o, z = ref[:, :3, 3], ref[:, :3, 2]
    for kind in ("dxf", "lines"):
        F = refined[kind].frames
        assert F.shape == ref.shape, kind
        c, oF, zF = jobs[name, kind].stock.centre, F[:, :3, 3], F[:, :3, 2]
        foot = oF + ((c - oF) * zF).sum(axis=1, keepdims=True) * zF  # nearest the centre
        for t in (-0.15, 0.15):  # the block's depth along the wire is 0.3 m
            assert _line_distance(foot + t * zF, o, z).max() < 1e-4, kind


def _measures(plan) -> dict:
    mo = plan.motion
    assert mo is not None, plan.reasons
    fm = feed_measures(mo.wire, plan.trajectory.meta.cut)[0]
    stops = mo.surface & (False if mo.corner_stop is None else mo.corner_stop)
    return {
        "corner_stops": int(np.count_nonzero(stops & ~np.r_[False, stops[:-1]])),
        "corners": corner_nodes(mo.passes[0].frames, 0.2),
        "deviation": float(plan.measured.deviation[mo.surface].max()),
        "feed": fm,
    }


@pytest.fixture(scope="module")
def gcode_plans(jobs) -> dict:
    return {name: _measures(make_plan(jobs[name, "gcode"])) for name in ("profile", "taper")}


@pytest.mark.parametrize("name", ["profile", "taper"])
@pytest.mark.parametrize("kind", ["dxf", "lines"])
def test_a_polyline_of_any_format_plans_like_the_gcode(jobs, gcode_plans, name, kind):
    """The wire stops at the G-code's corners (onto the leading edge, round the trailing
    edge at the offset profile's corner point, off the leading edge), within two
    rulings of them; it stays on its ruling within its tolerance, and the feed is held
    within its tolerance between them, as the G-code's to 1 %.  (The count of stops, runs
    of slowed samples, differs where a corner is doubled: the tapered G-code's 3, its
    DXF's 6, with the same dips of the feed.)"""
    ref = gcode_plans[name]
    cut = jobs[name, kind].cut
    got = _measures(make_plan(jobs[name, kind]))
    if name == "profile":
        assert ref["corner_stops"] == 3 and got["corner_stops"] == 3
    assert got["corner_stops"] >= 3 and ref["corner_stops"] >= 3
    gap = np.abs(got["corners"][:, None] - ref["corners"][None, :])
    assert gap.min(axis=0).max() <= 2 and gap.min(axis=1).max() <= 2, got["corners"]
    assert got["deviation"] < cut.wire_tolerance
    assert got["deviation"] < 1e-5 + 2.0 * ref["deviation"]
    fm = got["feed"]
    assert fm.min_ok and fm.max_ok, (fm.lowest, fm.highest)
    assert fm.lowest == pytest.approx(ref["feed"].lowest, rel=0.01)
    assert fm.highest == pytest.approx(ref["feed"].highest, rel=0.01)
