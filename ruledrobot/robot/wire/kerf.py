"""The kerf a hot wire melts: the one model of its width from speed and heat.

An energy balance per metre of wire (docs/kerf.md; the research notes, hotwire-physics.md):
the heat put into the wire above what it loses without cutting, ``p - p0`` [W/m], melts
a channel of width ``w`` while the wire moves across itself at ``v`` [m/s]::

    w(v, p) = kerf_base + kerf_gain * max(p - power_threshold, 0) / v

``kerf_base`` [m] is the wire's own width and the melt floor; ``kerf_gain`` [m^2/s per
W/m] the inverse of the energy per volume of foam melted; ``power_threshold`` [W/m]
the losses.  A wire hotter than its threshold that stops (``v = 0``) melts without
bound: ``w = inf`` (a burn).  Above ``max_speed * (p - power_threshold)`` [m/s] the
wire cannot melt its way and drags (bows, snaps).

Holding the kerf at ``w`` while the speed changes asks for the power::

    p(v) = power_threshold + (w - kerf_base) * v / kerf_gain

(the physics of Jedicut's two (speed, heat) points and GRBL's laser mode M4).

The wire's temperature lags its set-point; the model treats the lag as a pure delay of
``lag`` seconds (:func:`wire_power`): a schedule whose set-points lead the motion by
``lag`` heats the wire as planned.  Units: m, s, W/m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._checks import FloatArray

__all__ = ["Material", "wire_power"]


def _positive(name: str, value: float, allow_zero: bool = False) -> float:
    x = float(value)
    ok = np.isfinite(x) and (x >= 0.0 if allow_zero else x > 0.0)
    if not ok:
        raise ValueError(f"material.{name}: expected a finite number "
                         f"{'>= 0' if allow_zero else '> 0'}, got {value!r}")  # fmt: skip
    return x


@dataclass(frozen=True)
class Material:
    """A foam's kerf constants (module doc).

    ``kerf_base`` m, ``kerf_gain`` m^2/s per W/m, ``power_threshold`` W/m, ``max_speed``
    (m/s per W/m above the threshold) or None; ``drag`` (N/m per m/s, the foam's drag on
    the moving wire: :mod:`.lag`) or None.
    """

    kerf_base: float
    kerf_gain: float
    power_threshold: float = 0.0
    max_speed: float | None = None
    drag: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "kerf_base", _positive("kerf_base", self.kerf_base, True))
        object.__setattr__(self, "kerf_gain", _positive("kerf_gain", self.kerf_gain))
        object.__setattr__(self, "power_threshold",
                           _positive("power_threshold", self.power_threshold, True))  # fmt: skip
        if self.max_speed is not None:
            object.__setattr__(self, "max_speed", _positive("max_speed", self.max_speed))
        if self.drag is not None:
            object.__setattr__(self, "drag", _positive("drag", self.drag, True))

    def kerf(self, speed: ArrayLike, power: ArrayLike) -> FloatArray:
        """Return the kerf [m] at ``speed`` [m/s] across the wire and wire ``power`` [W/m].

        In the broadcast shape: ``kerf_base + kerf_gain * max(p - p0, 0) / v``; ``inf``
        where the wire is hotter than its threshold and still, ``kerf_base`` where it is not
        hotter.
        """
        v = np.asarray(speed, dtype=np.float64)
        excess = np.maximum(np.asarray(power, dtype=np.float64) - self.power_threshold, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            melt = np.where(excess > 0.0, self.kerf_gain * excess / v, 0.0)
        return self.kerf_base + np.where(np.isnan(melt), np.inf, melt)

    def power_for_kerf(self, kerf: ArrayLike, speed: ArrayLike) -> FloatArray:
        """Return the wire power [W/m] that melts ``kerf`` [m] at ``speed`` [m/s].

        In the broadcast shape: ``p0 + (kerf - kerf_base) * v / kerf_gain``; raises where
        ``kerf`` is below ``kerf_base`` (no power melts less than the wire's own width).
        """
        w = np.asarray(kerf, dtype=np.float64)
        if np.any(w < self.kerf_base):
            raise ValueError(f"kerf {np.min(w) * 1e3:.4g} mm is below the material's "
                             f"kerf_base {self.kerf_base * 1e3:.4g} mm: no heat melts less "
                             "than the wire")  # fmt: skip
        return self.power_threshold + (w - self.kerf_base) * np.asarray(speed) / self.kerf_gain

    def speed_limit(self, power: ArrayLike) -> FloatArray:
        """Return the fastest speed [m/s] the wire melts its way at ``power`` [W/m].

        ``max_speed * max(p - p0, 0)``; ``inf`` when the material gives no ``max_speed``.
        """
        p = np.asarray(power, dtype=np.float64)
        if self.max_speed is None:
            return np.full(p.shape, np.inf)
        return self.max_speed * np.maximum(p - self.power_threshold, 0.0)


def wire_power(t: ArrayLike, setpoint: ArrayLike, lag: float) -> FloatArray:
    """Return the wire's power (N,) [W/m] at times ``t`` (N,) of a set-point schedule.

    Times ``t`` [s, increasing]; ``setpoint`` (N,) [W/m] given at the same times: the
    set-point ``lag`` s earlier (a pure delay, module doc), held at the first set-point
    before it and linearly interpolated between samples.
    """
    ta = np.asarray(t, dtype=np.float64)
    p = np.asarray(setpoint, dtype=np.float64)
    if lag < 0.0 or not np.isfinite(lag):
        raise ValueError(f"heat lag: expected seconds >= 0, got {lag!r}")
    if lag == 0.0 or ta.size == 0:
        return p.copy()
    return np.interp(ta - lag, ta, p)
