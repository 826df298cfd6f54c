"""Jobs of the placement tests (issue 13), as job-file text."""

from __future__ import annotations

from ruledrobot.wirecut.job.demo import DEMO_JOB


def demo_at(x: float, steps: int = 3, robot: str = "ur5e") -> str:
    """The demo job (hyperbolic paraboloid through a 0.2 m block) with the block and the
    surface at ``x`` (m) in front of the robot."""
    return (DEMO_JOB.replace("pose = [0.5, 0.0, 0.3,", f"pose = [{x}, 0.0, 0.3,")
            .replace("centre = [0.5, 0.0, 0.3]", f"centre = [{x}, 0.0, 0.3]")
            .replace("steps = 4", f"steps = {steps}")
            .replace('model = "ur5e"', f'model = "{robot}"'))  # fmt: skip


#: rulings vertical, the wire sweeping across the block's width: surface x -> world y,
#: surface y (the rulings) -> world z, surface z -> world x (120 deg about (1, 1, 1))
_VERTICAL = "1.2091996, 1.2091996, 1.2091996"

#: a 0.9 m block whose two ends are trimmed by curved cuts: from where a UR5e stands, no
#: place near x = 0.75 reaches both ends; turned half a turn between them, both are cut
LONG_JOB = f"""\
# a long block, both ends trimmed (vertical rulings, the wire sweeping across it)
[stock]
centre = [0.75, 0.0, 0.3]
size = [0.9, 0.2, 0.15]

[robot]
model = "ur5e"

[tool]
wire_start = [-0.2, 0.0, 0.25]
wire_end = [0.2, 0.0, 0.25]

[[cut]]
name = "near end"      # the end towards the robot
keep = [0.75, 0.0, 0.3]
[cut.surface]
builtin = "hyperbolic_paraboloid"
params = {{ c = 0.4 }}
u = [-0.14, 0.14]
pose = [0.4, 0.0, 0.3, {_VERTICAL}]
steps = 3

[[cut]]
name = "far end"
keep = [0.75, 0.0, 0.3]
[cut.surface]
builtin = "hyperbolic_paraboloid"
params = {{ c = 0.4 }}
u = [-0.14, 0.14]
pose = [1.1, 0.0, 0.3, {_VERTICAL}]
steps = 3
"""
