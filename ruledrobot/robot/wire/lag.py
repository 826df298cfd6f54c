"""Wire lag: how far a moving hot wire bows behind its ends, and the dwell it asks for.

A taut string of length ``L`` [m] under tension ``T`` [N], loaded by a drag ``q`` [N/m]
across it on a centred chord of length ``c`` (the part of the wire in the foam), bows
at mid-span by the bending moment of the equivalent simply supported beam over ``T``::

    bow = q * c * (2 L - c) / (8 T)        (= q L^2 / (8 T) when the chord is the wire)

(the research notes, hotwire-physics.md, "Wire lag and corners").  The drag grows
with speed; the model takes it linear, ``q = drag * v`` (``drag`` [N/m per m/s], a
material constant measured like the kerf: a cut stopped mid-way shows the bow).

When the ends stop at a corner the middle still trails by ``bow`` and keeps melting its
way at about the speed it had: the corner asks for a dwell of ``bow / v`` [s] before the
wire turns (peers dwell 0.5-1 s at true corners).  Information: the planner does not
bend its path for it.  Units: m, s, N.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._checks import FloatArray

__all__ = ["corner_dwell", "wire_bow"]


def wire_bow(
    speed: ArrayLike, chord: ArrayLike, length: float, tension: float, drag: float
) -> FloatArray:
    """Return the wire's mid-span bow [m] behind its ends: ``drag v c (2L - c) / (8T)``.

    In the broadcast shape, at ``speed`` [m/s] across itself with ``chord`` [m] of it in the
    foam, a wire of ``length`` [m] under ``tension`` [N] and a foam of ``drag`` [N/m per
    m/s].
    """
    if not (np.isfinite(tension) and tension > 0.0):
        raise ValueError(f"wire_tension: expected newtons > 0, got {tension!r}")
    if not (np.isfinite(drag) and drag >= 0.0):
        raise ValueError(f"material.drag: expected N/m per m/s >= 0, got {drag!r}")
    c = np.clip(np.asarray(chord, dtype=np.float64), 0.0, float(length))
    q = float(drag) * np.asarray(speed, dtype=np.float64)
    return q * c * (2.0 * float(length) - c) / (8.0 * float(tension))


def corner_dwell(bow: ArrayLike, speed: ArrayLike) -> FloatArray:
    """Return the dwell [s] a corner asks for: the time the trailing middle takes to catch up.

    ``bow / v`` (0 where the wire does not bow; ``inf`` where it bows and is still).
    """
    b = np.asarray(bow, dtype=np.float64)
    v = np.asarray(speed, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(b > 0.0, b / v, 0.0)
