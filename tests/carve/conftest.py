"""A cell around a part made in the tests: the demo's block in front of a UR5e."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.io.demo_cell import DEMO_CELL

CELL = """\
[part]
file = "{file}"
units = "{units}"
pose = {pose}
tolerance = 0.0005
rough_cuts = {rough}

{cell}
[cut]
feed_speed = 0.012
approach_speed = 0.6
"""

#: the part frame at the block's centre; the column's axis along y (as the part demo's plug)
AT_CENTRE = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]
AXIS_Y = [0.5, 0.0, 0.3, float(np.pi / 2), 0.0, 0.0]


def write_cell(folder, file, pose, units="mm", rough=4, name="cell.toml"):
    path = folder / name
    path.write_text(CELL.format(file=file, units=units, pose=pose, rough=rough, cell=DEMO_CELL))
    return path


def run_carve(cell, out):
    res = CliRunner().invoke(app, ["carve", str(cell), "--out", str(out)])
    report = json.loads((out / "carve.json").read_text()) if (out / "carve.json").exists() else None
    return res, report


def cuts_alone(cell):
    """carve's input stage and cut plan without the robot (no file written): ``(cell,
    part, plan)``; for what the geometry alone decides, where a run of ``carve`` would
    add only the robot's wire-pose search of every cut (seconds each)."""
    from ruledrobot.carve.meshquery import MeshQuery
    from ruledrobot.carve.run import cell_cuts, read_input

    spec, part = read_input(cell)
    return spec, part, cell_cuts(spec, part, MeshQuery(part))


@pytest.fixture
def carve_cli():
    return run_carve
