"""Cut job files: a full example parses; every field is validated with file/section/field."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.wirecut.job.load import load_job

EXAMPLE = """
[surface]
builtin = "hyperbolic_paraboloid"
params = { c = 0.4 }
u = [-0.12, 0.12]
rulings = 9
pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]
algorithm = "dh"
scheme = "four_point"
steps = 4

[stock]
centre = [0.5, 0.0, 0.3]
size = [0.2, 0.2, 0.15]
rotvec = [0.0, 0.0, 0.1]

[robot]
model = "ur5e"
base = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
speed_scale = 0.8
acceleration = [1, 1, 1, 2, 2, 2]

[tool]
wire_start = [-0.2, 0.0, 0.25]
wire_end = [0.2, 0.0, 0.25]
clearance = 0.02
mass = 1.2

[cut]
feed_speed = 0.01
lead_in = 0.02
lead_out = 0.03
approach_speed = 0.3
kerf = 0.0008
"""


def write(tmp_path, text):
    p = tmp_path / "job.toml"
    p.write_text(text)
    return p


def test_full_example_parses(tmp_path):
    job = load_job(write(tmp_path, EXAMPLE))
    assert job.surface.builtin == "hyperbolic_paraboloid" and job.surface.u == (-0.12, 0.12)
    np.testing.assert_allclose(job.surface.pose[:3, 3], [0.5, 0.0, 0.3])
    np.testing.assert_allclose(job.stock.size, [0.2, 0.2, 0.15])
    assert job.robot.speed_scale == 0.8 and job.robot.acceleration.tolist() == [1, 1, 1, 2, 2, 2]
    assert job.tool.wire_length == pytest.approx(0.4)
    assert job.cut.lead_out == 0.03
    lines = job.input_lines()
    assert len(lines) == 9
    # the surface pose moved the rulings into the base frame: they pass near the stock centre
    assert np.abs(lines.point[4] - [0.5, 0.0, 0.3]).max() < 0.05


def test_lines_file_surface(tmp_path):
    import ruledrobot as rr

    lines = rr.Lines.from_point_direction(
        np.c_[np.linspace(0, 1, 5), np.zeros((5, 2))], np.tile([0.0, 0.0, 1.0], (5, 1))
    )
    rr.save_lines(tmp_path / "r.json", lines)
    text = EXAMPLE.replace(
        'builtin = "hyperbolic_paraboloid"\nparams = { c = 0.4 }\nu = [-0.12, 0.12]\n',
        'file = "r.json"\n',
    )
    job = load_job(write(tmp_path, text))
    assert len(job.input_lines()) == 5


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("feed_speed = 0.01", "feed_speed = -1", r"\[cut\] feed_speed: expected a number > 0"),
        ("feed_speed = 0.01", "feed_speed = 0.01\nfeedspeed = 2", r"\[cut\] unknown field"),
        ('model = "ur5e"', 'model = "ur99"', r"\[robot\] model: unknown robot 'ur99'"),
        ("size = [0.2, 0.2, 0.15]", "size = [0.2, 0.0, 0.15]", r"\[stock\] size: edge 1"),
        ("centre = [0.5, 0.0, 0.3]", "centre = [0.5, 0.0]", r"\[stock\] centre: expected a list"),
        ('builtin = "hyperbolic_paraboloid"', 'builtin = "torus"', r"unknown surface 'torus'"),
        ("params = { c = 0.4 }", "params = { c = 0.4, q = 1 }", r"\[surface\] params"),
        ("steps = 4", "steps = 4\nspacing = 0.01", r"give steps or spacing, not both"),
        ("u = [-0.12, 0.12]", "u = [0.12, -0.12]", r"\[surface\] u: expected \[start, stop\]"),
        ("clearance = 0.02", "clearance = 0.3", r"\[tool\] clearance: 2 x clearance"),
        ('scheme = "four_point"', 'scheme = "five_point"', r"\[surface\] scheme: expected one"),
        ("[cut]", "[cutting]", r"unknown section\(s\) cutting"),
        ("speed_scale = 0.8", "speed_scale = 1.5", r"speed_scale: expected a number <= 1"),
        ("rulings = 9", "rulings = 2", r"rulings: expected an integer 4 <= rulings"),
    ],
)
def test_bad_fields_name_file_section_and_field(tmp_path, old, new, message):
    assert old in EXAMPLE
    p = write(tmp_path, EXAMPLE.replace(old, new, 1))
    with pytest.raises(ValueError, match=message) as err:
        load_job(p)
    assert str(p) in str(err.value)


def test_unreadable_files(tmp_path):
    with pytest.raises(ValueError, match="no such job file"):
        load_job(tmp_path / "none.toml")
    with pytest.raises(ValueError, match="not valid TOML"):
        load_job(write(tmp_path, "[surface\n"))
    with pytest.raises(ValueError, match="missing section \\[stock\\]"):
        load_job(write(tmp_path, EXAMPLE.split("[stock]")[0]))
