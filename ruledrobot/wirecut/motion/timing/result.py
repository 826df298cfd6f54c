"""The result of the time law: :class:`TimedPath`, a trajectory sampled at the controller period."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ....geometry.ranges import runs_of
from .tolerances import RATIO_MAX, BoolArray, FloatArray, IntArray

# --------------------------------------------------------------------------- result


@dataclass(frozen=True, eq=False)
class TimedPath:
    """A joint trajectory sampled every controller period.

    Arrays are read-only. ``M`` samples, ``J`` joints.

    Attributes:
        t: (M,) time from the start [s], ``t[k] = k·dt``; the last sample is the end.
        q: (M, J) joint positions [rad].
        qd: (M, J) joint velocities [rad/s] of the time law (analytic, not differenced).
        qdd: (M, J) joint accelerations [rad/s²] of the time law.
        s_of_t: (M,) path parameter at each sample, in the caller's units of ``s``
            (:func:`joint_move`: the fraction of the move, 0…1; :func:`concatenate`:
            each part's parameter offset so that the whole is continuous).
        feed: (M,) wire feed [m/s]: central differences of the wire distance
            ``∫ speed_factor ds`` at the sampled ``s_of_t`` (0 out of the stock).
        feed_limited: (M,) True inside the stock where ``feed`` is below
            ``(1 − FEED_HOLD_TOL)·feed_speed``: joint speed/acceleration (including
            the start and stop ramps) and not the feed bound set the pace there.
            "Inside" = the sample and its two neighbours lie in gaps of the caller's
            samples whose both ends have a speed factor > 0 (so the partial gaps at
            stock entry and exit, where the speed factor is interpolated, are not
            reported).
        segment: (M,) index of the part a sample comes from (0 unless concatenated).
        dt: controller period [s].
        vel_limits: (J,) joint velocity limits [rad/s] the ratios refer to.
        acc_limits: (J,) joint acceleration limits [rad/s²] the ratios refer to.
        feed_speed: feed bound [m/s], or None for a motion without a cut.
        max_speed_ratio: max over samples and joints of |Δq/Δt| / vel_limits.
        max_acc_ratio: max of |second difference / Δt²| / acc_limits.
        max_feed_ratio: max over sample intervals of the wire distance travelled in
            the interval / (interval · feed_speed) (0 when there is no feed).
        method: how the time law was computed (``"toppra"``, ``"reachability"``
            fallback with the reason, ``"joint_move"``, ``"concatenate"``).
    """

    t: FloatArray = field(repr=False)
    q: FloatArray = field(repr=False)
    qd: FloatArray = field(repr=False)
    qdd: FloatArray = field(repr=False)
    s_of_t: FloatArray = field(repr=False)
    feed: FloatArray = field(repr=False)
    feed_limited: BoolArray = field(repr=False)
    segment: IntArray = field(repr=False)
    dt: float
    vel_limits: FloatArray = field(repr=False)
    acc_limits: FloatArray = field(repr=False)
    feed_speed: float | None
    max_speed_ratio: float
    max_acc_ratio: float
    max_feed_ratio: float
    method: str

    def __post_init__(self) -> None:
        for name in ("t", "q", "qd", "qdd", "s_of_t", "feed", "feed_limited", "segment",
                     "vel_limits", "acc_limits"):  # fmt: skip
            arr = getattr(self, name)
            if isinstance(arr, np.ndarray):
                arr.flags.writeable = False

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self.t[-1])

    @property
    def n_samples(self) -> int:
        """Number of samples M."""
        return int(self.t.shape[0])

    @property
    def within_limits(self) -> bool:
        """Whether the sampled joint speeds and accelerations are within the limits."""
        return self.max_speed_ratio <= RATIO_MAX and self.max_acc_ratio <= RATIO_MAX

    @property
    def feed_limited_intervals(self) -> FloatArray:
        """(K, 2) ``[t_start, t_end]`` [s] of the runs of feed-limited samples."""
        return _runs(self.feed_limited, self.t)

    def feed_limited_s_intervals(self) -> FloatArray:
        """(K, 2) ``[s_start, s_end]`` of the runs of feed-limited samples."""
        return _runs(self.feed_limited, self.s_of_t)


def _runs(mask: BoolArray, values: FloatArray) -> FloatArray:
    """(K, 2) ``values`` at the first and the last sample of each True run of ``mask``."""
    r = np.asarray(runs_of(mask), dtype=np.int64).reshape(-1, 2)
    return np.stack([values[r[:, 0]], values[r[:, 1] - 1]], axis=1)
