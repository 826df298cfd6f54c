"""The built-in demo jobs: one cut (a hyperbolic paraboloid through a foam block in front of a
UR5e) and a part (three cuts, the last one all the way round, kerf compensated, heat switched)
in the cell the carve demo shares (:data:`ruledrobot.io.demo_cell.DEMO_CELL`)."""

from __future__ import annotations

from ...io.demo_cell import DEMO_CELL

DEMO_JOB = """\
# ruledrobot demo job: a hyperbolic paraboloid (z = x y / c) cut through a foam
# block in front of a UR5e with a 0.4 m hot-wire bow.  Units: m, rad, s.
# Copy this file, edit it, and run:  ruledrobot plan my_job.toml --out my_cut

[surface]
builtin = "hyperbolic_paraboloid"
params = { c = 0.4 }
u = [-0.12, 0.12]          # rulings at x = u (m) in the surface frame
rulings = 9                # input rulings, refined below
pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]   # surface frame in the robot base frame
algorithm = "dh"
scheme = "four_point"
steps = 4

[stock]                    # the foam block
centre = [0.5, 0.0, 0.3]
size = [0.2, 0.2, 0.15]
rotvec = [0.0, 0.0, 0.0]

[robot]
model = "ur5e"
base = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
speed_scale = 1.0

[tool]                     # the bow, wire end points in the flange frame
wire_start = [-0.2, 0.0, 0.25]
wire_end = [0.2, 0.0, 0.25]
clearance = 0.02
mass = 1.0

[cut]
feed_speed = 0.01          # m/s
lead_in = 0.02
lead_out = 0.02
approach_speed = 0.3
kerf = 0.0008
"""

PART_JOB = (
    """\
# ruledrobot part demo: a foam block trimmed on top by a saddle and on one side by a
# twisted face, then a plug cut all the way round a horizontal axis -- the part is the
# plug, a hyperboloid band with a saddle top and a flat side.  Every cut keeps the
# part's side (kerf compensated); the robot switches the wire's heat on standard
# digital output 0, with a one-second pre-heat before each cut.  Units: m, rad, s.
# Copy this file, edit it, and run:  ruledrobot plan my_part.toml --out my_part

"""
    + DEMO_CELL
    + """\
mass = 1.0
heat = { output = "standard:0", preheat = 1.0 }

[[cut]]
name = "top"
keep = [0.5, 0.0, 0.3]          # a point of the part
feed_speed = 0.012
approach_speed = 0.6
[cut.surface]
builtin = "hyperbolic_paraboloid"
params = { c = 0.4 }
u = [-0.12, 0.12]
rulings = 9
pose = [0.5, 0.0, 0.335, 0.0, 0.0, 0.0]
steps = 4

[[cut]]
name = "side"
keep = [0.5, 0.0, 0.3]
feed_speed = 0.012
approach_speed = 0.6
[cut.surface]
builtin = "hyperbolic_paraboloid"
params = { c = 1.0 }
u = [-0.1, 0.1]
rulings = 9
pose = [0.545, 0.0, 0.3, 0.0, 1.5707963267948966, 0.0]   # turned upright, 4.5 cm from the centre
steps = 4

[[cut]]
name = "plug"                     # closed: the band all the way round (no u range)
keep = "inside"
feed_speed = 0.012
approach_speed = 0.6
[cut.surface]
builtin = "hyperboloid"
params = { a = 0.06, c = 0.3 }
rulings = 16
pose = [0.5, 0.0, 0.3, 1.5707963267948966, 0.0, 0.0]     # axis along y
steps = 5
"""
)
