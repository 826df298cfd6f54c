"""What a trajectory cuts: the block, the wire, the feed each pass must hold — and the
feed and wire checks measured on any motion by the one model (:mod:`.in_stock`).

A trajectory's sidecar carries a :class:`WireCut` (``"cut"``), so that whoever holds
the trajectory alone — an exported program's verification, the runner on its
recording, resume, the viewer — measures the wire against the same block and judges
the feed by the same rule as the planner:

* ``feed_max``: over every sample of a pass's window with the wire in the stock, the
  cutting speed at most ``speed · (1 + tolerance)``;
* ``feed_min``: over the samples of the window's ``held`` ranges (the pass's cut phase
  less the corners where the wire stops and the slits of a closed cut) with the wire
  in the stock, at least ``speed · (1 - tolerance)``.

Units: m, m/s; the block in the robot base frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.box import Box
from ...geometry.ranges import checked_ranges, ranges_mask, runs_of, shifted_ranges
from ..verdict import Check
from .face import FaceTarget
from .in_stock import WireInStock, wire_ends, wire_in_stock
from .kerf import Material

__all__ = ["DWELL_FRACTION", "DWELL_SLACK", "WIRE_TOLERANCE", "FeedMeasure", "FeedWindow",
           "HotDwell", "WireCut", "feed_checks", "feed_measures", "hot_dwell"]

#: m: how far the wire may stray from its target in the stock, by default (a job's
#: ``wire_tolerance``; a trajectory whose sidecar names none)
WIRE_TOLERANCE = 0.0005
#: a hot wire in the block cutting slower than this fraction of the slowest set feed
#: dwells: the melt widens the kerf there, and a wire that stops burns a hole
DWELL_FRACTION = 0.5
#: s: how much longer than its plan's a run's longest hot dwell may be
DWELL_SLACK = 0.1


@dataclass(frozen=True)
class FeedWindow:
    """One pass's feed: its samples, the cut's set speed and tolerances, where it is held.

    Samples ``[start, stop)`` of the pass (lead-in to lead-out), the cut's name, its set
    ``speed`` (m/s) and relative ``tolerance``, the ``held`` ranges where the lowest feed is
    checked (module doc), and the cut's ``wire_tolerance`` (m): how far the wire may stray
    from its target in the stock.
    """

    name: str
    start: int
    stop: int
    speed: float
    tolerance: float
    held: tuple[tuple[int, int], ...] = ()
    wire_tolerance: float = WIRE_TOLERANCE

    def __post_init__(self) -> None:
        if not 0 <= int(self.start) < int(self.stop):
            raise ValueError(f"feed window {self.name!r}: expected 0 <= start < stop, got "
                             f"[{self.start}, {self.stop}]")  # fmt: skip
        if not (np.isfinite(self.speed) and self.speed > 0):
            raise ValueError(f"feed window {self.name!r}: speed must be > 0 m/s, got {self.speed}")
        if not 0 <= self.tolerance < 1:
            raise ValueError(f"feed window {self.name!r}: tolerance must be in [0, 1), got "
                             f"{self.tolerance}")  # fmt: skip
        object.__setattr__(self, "start", int(self.start))
        object.__setattr__(self, "stop", int(self.stop))
        held = checked_ranges(self.held, f"feed window {self.name!r} held")
        object.__setattr__(self, "held", held)
        if not (np.isfinite(self.wire_tolerance) and self.wire_tolerance > 0):
            raise ValueError(f"feed window {self.name!r}: wire_tolerance must be > 0 m, got "
                             f"{self.wire_tolerance}")  # fmt: skip

    def mask(self, n: int) -> np.ndarray:
        """(n,) bool: sample k is in the window ``[start, stop)``."""
        m = np.zeros(n, dtype=bool)
        m[self.start : self.stop] = True
        return m

    def held_mask(self, n: int) -> np.ndarray:
        """(n,) bool: sample k is in one of the ``held`` ranges."""
        return ranges_mask(self.held, n)

    def shifted(self, start: int, stop: int) -> FeedWindow | None:
        """The window on samples ``start:stop`` renumbered from 0 (None when outside)."""
        a, b = max(self.start, start) - start, min(self.stop, stop) - start
        if a >= b:
            return None
        held = shifted_ranges(self.held, start, stop)
        return FeedWindow(self.name, a, b, self.speed, self.tolerance, held, self.wire_tolerance)


@dataclass(frozen=True, eq=False)
class WireCut:
    """What a trajectory cuts: the block, the wire's length and the passes' feeds.

    The block (robot base frame), the wire's length (m) and the passes' feeds, so that any
    motion of the trajectory can be measured (module doc).  The trajectory's TCP is the
    wire's midpoint with z along the wire.  ``faces``: the part's surface each pass leaves
    (:mod:`.face`: ``face_error``); ``material``: the foam's kerf model (None: every cut's
    constant kerf).
    """

    stock: Box
    wire_length: float
    feeds: tuple[FeedWindow, ...] = field(default=())
    faces: tuple[FaceTarget, ...] = field(default=())
    material: Material | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.wire_length) and self.wire_length > 0):
            raise ValueError(f"cut.wire_length: expected a length > 0 m, got {self.wire_length}")
        object.__setattr__(self, "wire_length", float(self.wire_length))
        object.__setattr__(self, "feeds", tuple(self.feeds))
        object.__setattr__(self, "faces", tuple(self.faces))

    @property
    def wire_tolerance(self) -> float:
        """m: the strictest of the passes' wire tolerances (0.5 mm without passes)."""
        return min((w.wire_tolerance for w in self.feeds), default=WIRE_TOLERANCE)

    def measure(self, t: ArrayLike, tcp: ArrayLike) -> WireInStock:
        """The wire against the block along TCP poses ``tcp`` (M, 4, 4) at times ``t`` (M,)."""
        return wire_in_stock(t, wire_ends(tcp, self.wire_length), self.stock)

    def sliced(self, start: int, stop: int) -> WireCut:
        """The same cut for samples ``start:stop`` numbered from 0."""
        feeds = tuple(w for f in self.feeds if (w := f.shifted(start, stop)) is not None)
        faces = tuple(w for f in self.faces if (w := f.shifted(start, stop)) is not None)
        return WireCut(self.stock, self.wire_length, feeds, faces, self.material)


@dataclass(frozen=True)
class FeedMeasure:
    """The feed of one cut (all its windows) on a measured motion.

    The highest feed in the stock and the lowest where it is held (m/s, NaN when never in
    the stock there), the samples where they are, and the set speed and tolerance.
    """

    name: str
    speed: float
    tolerance: float
    highest: float
    lowest: float
    at_highest: int
    at_lowest: int

    @property
    def max_ok(self) -> bool:
        """Whether the highest feed is at most ``speed · (1 + tolerance)``.

        False when the wire never entered the stock in the cut's window
        (:func:`feed_checks`).
        """
        return self.checks()[0].ok

    @property
    def min_ok(self) -> bool:
        """Whether the lowest feed where it is held is at least ``speed · (1 - tolerance)``.

        False when the wire was never in the stock there (:func:`feed_checks`).
        """
        return self.checks()[1].ok

    def checks(
        self,
        key: str = "",
        labels: tuple[str, str] = ("highest feed", "lowest feed"),
        details: tuple[str, str] = ("", ""),
    ) -> tuple[Check, Check]:
        """This cut's ``feed_max`` and ``feed_min`` checks (:func:`feed_checks`)."""
        return feed_checks(key, _mm(self.highest), _mm(self.lowest), self.speed * 1e3,
                           self.tolerance, labels, details)  # fmt: skip


def _mm(x: float) -> float | None:
    """m (/s) -> mm (/s); None for NaN (not measured)."""
    return None if np.isnan(x) else float(x) * 1e3


def feed_checks(
    key: str,
    highest_mm_s: float | None,
    lowest_mm_s: float | None,
    speed_mm_s: float,
    tolerance: float,
    labels: tuple[str, str] = ("highest feed", "lowest feed"),
    details: tuple[str, str] = ("", ""),
) -> tuple[Check, Check]:
    """Return the one feed rule of a cut: its two checks, in mm/s.

    For the plan's verdict, an exported program's and a run's: ``feed_max<key>``: the
    highest feed in the stock at most ``speed · (1 + tolerance)``; ``feed_min<key>``: the
    lowest where it is held at least ``speed · (1 - tolerance)``.  Values in mm/s; None (the
    wire never in the stock there: the cut was not made) fails.  ``labels`` and ``details``
    word the two checks for their report.
    """
    return (
        Check.at_most("feed_max" + key, labels[0], highest_mm_s, speed_mm_s * (1 + tolerance),
                      "mm/s", details[0]),
        Check.at_least("feed_min" + key, labels[1], lowest_mm_s, speed_mm_s * (1 - tolerance),
                       "mm/s", details[1]),
    )  # fmt: skip


def feed_measures(wis: WireInStock, cut: WireCut) -> tuple[FeedMeasure, ...]:
    """Return per cut name the feed checks' figures of the measured motion ``wis``.

    The figures of the module doc, in the order of ``cut.feeds``.
    """
    n = wis.n
    names: list[str] = []
    for w in cut.feeds:
        if w.name not in names:
            names.append(w.name)
    out = []
    for name in names:
        ws = [w for w in cut.feeds if w.name == name]
        inwin = np.zeros(n, dtype=bool)
        held = np.zeros(n, dtype=bool)
        for w in ws:
            inwin |= w.mask(n)
            held |= w.held_mask(n)
        _, hi, _, k_hi = wis.feed_extremes(inwin)
        lo, _, k_lo, _ = wis.feed_extremes(held)
        out.append(FeedMeasure(name, ws[0].speed, ws[0].tolerance, hi, lo, k_hi, k_lo))
    return tuple(out)


@dataclass(frozen=True)
class HotDwell:
    """The longest time the hot wire stayed in the block cutting too slowly.

    Slower than :data:`DWELL_FRACTION` of the slowest set feed: ``seconds``, from sample
    ``start`` to ``stop`` (half-open; ``start = -1`` and 0 s when it never did).
    """

    seconds: float
    start: int = -1
    stop: int = -1


def hot_dwell(wis: WireInStock, hot: ArrayLike, speed: float) -> HotDwell:
    """Return the :class:`HotDwell` of a motion.

    ``wis`` the wire against the block (M samples), ``hot`` (M,) the heat on, ``speed``
    (m/s) the slowest set feed.  A dwell lasts from its first sample to the first sample
    after it (the time the wire spent there).
    """
    h = np.asarray(hot, dtype=bool)
    slow = wis.inside & h & ~(np.nan_to_num(wis.feed, nan=0.0) >= DWELL_FRACTION * speed)
    best = HotDwell(0.0)
    t, n = wis.t, wis.n
    for a, b in runs_of(slow):
        secs = float(t[min(b, n - 1)] - t[a])
        if secs > best.seconds:
            best = HotDwell(secs, a, b)
    return best
