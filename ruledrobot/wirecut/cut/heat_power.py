"""The wire's power as the heat schedule sets it, and the kerf it melts on the held feed.

One function gives the power the schedule (:func:`~..motion.heat.heat_schedule`) sets for a
cut at a speed of its reference point (:func:`set_power`, docs/kerf.md "Heat modes"); the
compensation predicts the kerf with the same power (:func:`held_kerf`), so that where the
output clips the power at its ``full_scale`` both see the clipped power.  Units: W/m, m/s, m.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.checks import FloatArray
from ...robot.wire.kerf import Material
from ..job.spec import CutSpec, HeatSpec

__all__ = ["burn_advice", "clipping_note", "full_scale", "held_kerf", "on_power", "set_power"]


def full_scale(heat: HeatSpec | None) -> float:
    """The largest power [W/m] the heat's output sets.

    Its ``full_scale`` on an analog output, else unbounded (a digital output switches a
    supply whose power it cannot set)."""
    if heat is not None and heat.kind == "analog" and heat.full_scale is not None:
        return float(heat.full_scale)
    return float("inf")


def on_power(cut: CutSpec, heat: HeatSpec | None, material: Material | None) -> float:
    """The wire's power [W/m] while on in the modes ``on_off`` and ``constant`` (unclipped).

    ``[tool] heat power`` when given, else the power that melts the cut's
    ``kerf`` at its feed (the supply set up for the nominal kerf; needs ``material``)."""
    if heat is not None and heat.power is not None:
        return float(heat.power)
    return float(material.power_for_kerf(max(cut.kerf, material.kerf_base), cut.feed_speed))


def set_power(
    cut: CutSpec, heat: HeatSpec | None, material: Material | None, speed: ArrayLike
) -> FloatArray:
    """The power set-point [W/m] of ``cut`` with the heat on, by mode.

    (``speed``'s shape) with its reference point (the chord's fastest point) moving at
    ``speed`` [m/s], by ``[tool] heat mode``: ``constant_kerf``
    ``material.power_for_kerf(kerf, speed)``, ``constant`` ``power``, ``on_off``
    :func:`on_power`; clipped to ``[0, full_scale]`` (:func:`full_scale`)."""
    v = np.asarray(speed, dtype=np.float64)
    mode = "on_off" if heat is None else heat.mode
    if mode == "constant_kerf":
        p = material.power_for_kerf(cut.kerf, v)
    else:
        p = np.full(v.shape, heat.power if mode == "constant" else on_power(cut, heat, material))
    return np.clip(p, 0.0, full_scale(heat))


def held_kerf(
    ratio: ArrayLike, cut: CutSpec, heat: HeatSpec | None, material: Material
) -> FloatArray:
    """The kerf [m] on the held feed of chord points moving ``ratio`` times the reference.

    (ratio's shape, ``ratio`` <= 1) The reference point, which the time law holds at the cut's feed:
    ``material.kerf(feed * ratio, p)`` with ``p`` the power the schedule sets at the feed
    (:func:`set_power`).  Unclipped ``constant_kerf``: ``kerf_base + (kerf - kerf_base) /
    ratio``."""
    r = np.asarray(ratio, dtype=np.float64)
    return material.kerf(cut.feed_speed * r, set_power(cut, heat, material, cut.feed_speed))


def clipping_note(cut: CutSpec, heat: HeatSpec | None, material: Material | None) -> str | None:
    """A warning when the output's ``full_scale`` clips the power the cut asks at its feed.

    None when it does not: the kerf on the held feed is then narrower than the cut's
    ``kerf`` (the compensation follows it), and where the wire slows the power falls
    below ``full_scale`` again and the kerf comes back to ``kerf``, wider than compensated
    there (``face_error`` judges)."""
    if material is None or heat is None:
        return None
    mode = heat.mode
    want = (material.power_for_kerf(cut.kerf, cut.feed_speed) if mode == "constant_kerf"
            else heat.power if mode == "constant" else on_power(cut, heat, material))  # fmt: skip
    top = full_scale(heat)
    if not float(want) > top:
        return None
    w = float(material.kerf(cut.feed_speed, top))
    words = (f"cut '{cut.name}': [tool] heat full_scale {top:g} W/m clips the power the cut "
             f"asks at its feed {cut.feed_speed * 1e3:g} mm/s ({float(want):.4g} W/m): the "
             f"kerf there is {w * 1e3:.3f} mm, not {cut.kerf * 1e3:.3f} mm (compensated so)")
    if mode == "constant_kerf":
        v = (top - material.power_threshold) * material.kerf_gain / (cut.kerf - material.kerf_base)
        words += (f"; where the wire is slower than {v * 1e3:.3g} mm/s the power is not "
                  f"clipped and the kerf is {cut.kerf * 1e3:.3f} mm, "
                  f"{(cut.kerf - w) * 5e2:.3f} mm more on each side than compensated "
                  "(face_error judges): raise full_scale, lower the feed or the kerf")
    if top <= material.power_threshold:
        words += (f"; full_scale is at or below the material's power_threshold "
                  f"{material.power_threshold:g} W/m: the wire melts nothing")
    return words


def burn_advice(heat: HeatSpec | None, material: Material | None) -> str:
    """What to change when the wire burns where it stands (``face_error``'s burn).

    In the job's words: a mode that keeps its power while the wire stops (``on_off``,
    ``constant``) burns at every stop in the block, whatever the power above the
    material's threshold; ``constant_kerf`` on an analog output drops it to the threshold
    there."""
    p0 = "" if material is None else f" ({material.power_threshold:g} W/m)"
    mode = "on_off" if heat is None else heat.mode
    if mode == "constant_kerf":
        return ("the power cannot fall to the threshold in time: check [tool] heat lag "
                "(the set-points lead the motion by it) and full_scale")
    return (f'mode = "{mode}" keeps the power while the wire stands: set [tool] heat '
            'mode = "constant_kerf" on an analog output (output = "analog:0" with '
            f"full_scale), which lowers the power to the threshold{p0} where the wire stops; "
            "a lower power helps only at or below that threshold")
