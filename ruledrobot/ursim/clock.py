"""Timing statistics of the emulator's controller clock (:class:`ClockStats`)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

__all__ = ["RECENT", "ClockStats"]

#: how many recent publishes the lateness and gap records keep
RECENT = 20_000


@dataclass
class ClockStats:
    """Timing of the controller clock.

    ``ticks``: control periods run.  ``missed``: periods the clock ran late, after its
    host woke it late (it runs them, and publishes them with their controller time, to
    catch up: the controller's time never stretches).  ``stall_max``: the longest such
    lateness [s] — the emulator's host, not the robot, was slow.
    ``lateness``: recent publish times minus their scheduled times [s].
    ``tick_errors`` / ``publish_errors``: controller periods / publishes that
    raised (logged, rate-limited; the clock goes on).  ``gaps``: recent
    intervals between consecutive publishes [s] (one period when all is well;
    a stall shows here even when the clock resynchronises after it).
    ``gc_max``: the longest garbage-collector pause [s] (it holds the GIL, so
    it stalls the clock too).
    """

    ticks: int = 0
    missed: int = 0
    resyncs: int = 0
    tick_errors: int = 0
    publish_errors: int = 0
    gc_max: float = 0.0
    stall_max: float = 0.0
    lateness: deque[float] = field(default_factory=lambda: deque(maxlen=RECENT))
    gaps: deque[float] = field(default_factory=lambda: deque(maxlen=RECENT))

    def summary(self) -> dict[str, float]:
        """The statistics as one flat dict of floats, durations in milliseconds.

        Counts (``ticks``, ``missed``, ``tick_errors``, ``resyncs``, ``gaps_over_10ms``: gaps longer
        than 10 ms), ``missed_fraction`` (of the ticks), ``lateness_mean_ms``, ``lateness_p99_ms``,
        ``lateness_max_ms``, ``gap_p99_ms``, ``gap_max_ms``, ``stall_max_ms`` and ``gc_max_ms``; an
        empty record counts as a single 0.
        """
        lat = np.asarray(self.lateness or [0.0])
        gap = np.asarray(self.gaps or [0.0])
        return {
            "ticks": float(self.ticks),
            "missed": float(self.missed),
            "missed_fraction": self.missed / max(1, self.ticks),
            "tick_errors": float(self.tick_errors),
            "lateness_mean_ms": float(lat.mean() * 1e3),
            "lateness_p99_ms": float(np.percentile(lat, 99) * 1e3),
            "lateness_max_ms": float(lat.max() * 1e3),
            "gap_p99_ms": float(np.percentile(gap, 99) * 1e3),
            "gap_max_ms": float(gap.max() * 1e3),
            "gaps_over_10ms": float(np.count_nonzero(gap > 0.010)),
            "resyncs": float(self.resyncs),
            "stall_max_ms": self.stall_max * 1e3,
            "gc_max_ms": self.gc_max * 1e3,
        }
