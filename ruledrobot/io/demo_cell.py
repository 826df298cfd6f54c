"""The demos' cell as tables of a job file: the 200 x 200 x 150 mm foam block in front of a
UR5e with the 0.4 m hot-wire bow.  The part demo's job (:mod:`ruledrobot.wirecut.job.demo`)
and the carve demo's cell file (:mod:`ruledrobot.carve.demo`) cut the same block with the
same arm and bow, so both are written with this text; it lives here, below both."""

from __future__ import annotations

__all__ = ["DEMO_CELL"]

#: The ``[stock]``, ``[robot]`` and ``[tool]`` tables (m), ending in the ``[tool]`` table
#: so that a file may add keys of the bow after it (``mass``, ``heat``).  No braces:
#: the carve demo formats its cell file with :meth:`str.format`.
DEMO_CELL = """\
[stock]
centre = [0.5, 0.0, 0.3]
size = [0.2, 0.2, 0.15]

[robot]
model = "ur5e"

[tool]
wire_start = [-0.2, 0.0, 0.25]
wire_end = [0.2, 0.0, 0.25]
clearance = 0.02
"""
