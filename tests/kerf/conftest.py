"""A job of the demos' cell with the wire's heat on UR's standard analog output 0."""

from __future__ import annotations

import pytest

from ruledrobot.io.demo_cell import DEMO_CELL

JOB = DEMO_CELL + """heat = {{ output = "{output}", preheat = 2.0 }}

[surface]
builtin = "hyperbolic_paraboloid"
params = {{ c = 0.4 }}
u = [-0.12, 0.12]
rulings = 9
pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]

[cut]
feed_speed = 0.004
"""


@pytest.fixture
def job_file(tmp_path):
    """A job file with an analog heat output; ``job_file(output=...)`` another output."""

    def make(output: str = "analog:0", name: str = "job.toml"):
        p = tmp_path / name
        p.write_text(JOB.format(output=output), encoding="utf-8")
        return p

    return make
