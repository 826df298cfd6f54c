"""Tolerances and limits of the time law (shared by its modules and its users)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ....geometry.checks import FloatArray
from ....robot.motion.rates import RATIO_MAX, RATIO_TOL

__all__ = ["RATIO_MAX", "RATIO_TOL", "FloatArray"]

BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]

#: Allowed relative excess of the sampled feed over ``feed_speed`` (round-off of the
#: controllable sets; the bound itself holds between grid points, see step 3).
FEED_TOL = 1e-6
#: A sample inside the stock whose feed is below ``(1 - FEED_HOLD_TOL)·feed_speed``
#: is reported as feed-limited (the joints, not the feed bound, set the speed there).
FEED_HOLD_TOL = 0.01
#: Largest position mismatch (rad) between the end of a part and the start of the
#: next in :func:`concatenate`.
CONTINUITY_TOL = 1e-9
#: Most samples a timed path may have (1 h 6 min at 500 Hz; ~300 MB of q, qd, qdd).
MAX_SAMPLES = 2_000_000
#: Largest relative change of the wire's speed per unit σ within one solver stage: a
#: stage over which it changes more is split (into ``FEED_SPLIT`` parts at most), so
#: that the feed bounds of neighbouring nodes differ by about this much at most.
FEED_SMOOTH = 0.0025
FEED_SPLIT = 64
#: Fewest solver stages; sparse inputs have their gaps split evenly up to this.
MIN_STAGES = 200
#: Verification rounds of :func:`time_path`: the first ``REFINE_ROUNDS`` split the
#: solver stages around the samples that break a limit, the later ones tighten the
#: limits everywhere.
MAX_TRIES = 6
REFINE_ROUNDS = 3
#: Consecutive samples closer than this (rad, Euclidean over the joints) are merged.
_MERGE_TOL = 1e-10
#: Cap on σ̇ (σ in rad of joint distance) as a multiple of the fastest joint limit:
#: bounds the speed on stretches where neither the joints nor the wire move.
_SD_CAP_FACTOR = 1e3
