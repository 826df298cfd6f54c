"""A foam cutter's program with sharp corners planned as a UR job (a NACA 0015 cut from
the front: in to the leading edge, along the upper surface, round the trailing edge,
back along the lower one, out): the refined path keeps the file's straight moves, the
wire stops at the corners, the kerf goes to the waste side."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.io.formats.gcode import GcodeReadOptions, read_gcode
from ruledrobot.wirecut.cut.passes import refine_cut
from ruledrobot.wirecut.job.load import load_job

DATA = Path(__file__).parent / "data"
runner = CliRunner()

#: the cutter frame in the robot base frame: the wire (cutter z) along -y, the towers'
#: vertical (cutter y) up; the profile lies in a 220 x 60 mm block 0.44 m high
PROFILE_JOB = """\
[surface]
gcode = { file = "profile.ngc", tower_distance = 0.7 }
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
"""


def _polygon_distance(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Distance (N,) of points (N, 2) from the polygon's segments (K, 2)."""
    a, b = polygon[:-1], polygon[1:]
    ab = b - a
    t = ((points[:, None] - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-30)
    foot = a + np.clip(t, 0.0, 1.0)[..., None] * ab
    return np.linalg.norm(points[:, None] - foot, axis=-1).min(axis=1)


def _job(tmp_path: Path) -> Path:
    shutil.copy(DATA / "profile.ngc", tmp_path / "profile.ngc")
    (tmp_path / "job.toml").write_text(PROFILE_JOB)
    return tmp_path / "job.toml"


def test_the_refined_path_keeps_the_files_straight_moves_and_corners(tmp_path):
    """Independent of the planner: intersect the refined rulings with the two tower
    planes and measure them against the file's own moves (the reader's tower points).
    A smoothing scheme over the corners would swing the wire centimetres off them (44 mm
    with four_point over the whole file, 72 mm with the dh algorithm)."""
    job = load_job(_job(tmp_path))
    assert job.cut.surface.algorithm == "projection"  # the G-code default (docs/formats.md)
    rc = refine_cut(job.cut, job.stock, "job", job.tool.wire_length)
    ends = read_gcode(tmp_path / "profile.ngc", GcodeReadOptions(0.7)).ends  # (N, 2, 3) m
    to_cutter = np.linalg.inv(job.cut.surface.pose)
    o = rc.frames[:, :3, 3] @ to_cutter[:3, :3].T + to_cutter[:3, 3]
    z = rc.frames[:, :3, 2] @ to_cutter[:3, :3].T
    for k, tower_z in enumerate((0.0, 0.7)):
        t = (tower_z - o[:, 2]) / z[:, 2]
        at_tower = (o + t[:, None] * z)[:, :2]
        gap = _polygon_distance(at_tower, ends[:, k, :2])
        assert gap.max() < 1e-4, f"tower {k}: {gap.max() * 1e3:.3f} mm off the file's moves"


def test_a_profile_with_sharp_corners_plans_and_the_wire_stops_at_them(tmp_path):
    """Kerf compensated, the part inside the profile."""
    job = _job(tmp_path)
    job.write_text(PROFILE_JOB.replace("kerf = 0.0008", "kerf = 0.0008\nkeep = [0.5, 0.0, 0.44]"))
    out = tmp_path / "out"
    res = runner.invoke(app, ["plan", str(job), "--out", str(out)])
    assert res.exit_code == 0, res.output
    report = json.loads((out / "report.json").read_text())
    assert report["verdict"]["ok"] is True
    # onto the leading edge, round the trailing edge, off the leading edge; the trailing
    # edge's turn of 160-170 degrees stays one corner, at the offset profile's corner point
    # beyond it (docs/kerf.md, "Sharp corners"; the bisector's offset made two of ~90)
    assert report["cuts"][0]["corner_stops"] == 3
    assert report["cuts"][0]["kerf_compensated"] is True
    assert report["max_wire_deviation_mm"] < 0.1
    assert 7.6 <= report["min_feed_speed_mm_s"] and report["max_feed_speed_mm_s"] <= 8.4
    info = {c["name"]: c for c in report["verdict"]["checks"]}["corner_stops"]
    assert info["gating"] is False and info["value"] == 3


def test_a_keep_point_on_the_surface_is_refused_naming_the_field(tmp_path):
    """(0, 40) mm of the file is on the lead-in move: which side is the part?"""
    job = _job(tmp_path)
    job.write_text(PROFILE_JOB.replace("kerf = 0.0008", "kerf = 0.0008\nkeep = [0.4, 0.0, 0.44]"))
    res = runner.invoke(app, ["plan", str(job), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2
    assert "job.toml: [cut] keep: the point lies on the surface" in " ".join(res.output.split())
    assert not (tmp_path / "out").exists()
