"""The motion settings an exported program and a run share by default, in one place so
that ``ruledrobot run`` streams or sends exactly the program ``ruledrobot export``
writes for the same samples (``run_program``'s promise) — and the controller's ranges
they are checked against live beside them in :mod:`.urscript`."""

from __future__ import annotations

#: servoj's lookahead time [s] and gain: the servo's tracking law's home
from ..robot.motion.servo import SERVO_GAIN, SERVO_LOOKAHEAD

__all__ = [
    "APPROACH_ACCELERATION",
    "APPROACH_SPEED",
    "FORWARD_BUFFER",
    "FORWARD_STOP_TIME",
    "PATH_ACCELERATION",
    "PATH_BLEND",
    "SERVO_GAIN",
    "SERVO_LOOKAHEAD",
]

#: rad/s and rad/s²: the joint move (``movej``) to the first sample
APPROACH_SPEED = 0.25
APPROACH_ACCELERATION = 0.5
#: m: the blend radius of a movel/movep path program's moves
PATH_BLEND = 0.002
#: m/s²: the tool acceleration of a movel/movep path program's moves
PATH_ACCELERATION = 1.0
#: s: a forwarded run's buffer: the longest stall of the PC the motion rides through
FORWARD_BUFFER = 0.5
#: s: a forwarded run's controlled stop (the path rate falls from 1 to 0 over it)
FORWARD_STOP_TIME = 0.2
