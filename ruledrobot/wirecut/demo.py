"""The built-in demo job: a hyperbolic paraboloid cut through a foam block in front of a UR5e."""

from __future__ import annotations

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
