"""The heat schedule: the wire's power set-point per sample of the timed motion
(docs/kerf.md, "Heat modes").

Inside the heat windows (pre-heat, lead-in, cut, lead-out: the samples the wire is hot
in) the desired power of the sample's cut is, by ``[tool] heat mode``:

* ``on_off``: the power while on (:func:`~..cut.heat_power.on_power`: ``power``, else
  the power that melts the cut's kerf at its feed);
* ``constant``: ``power``;
* ``constant_kerf``: ``power_threshold + (kerf - kerf_base) v / kerf_gain``
  (:meth:`~ruledrobot.robot.wire.kerf.Material.power_for_kerf`) with ``v`` the measured
  feed of the timed motion (the one model's fastest chord point, the cut's reference
  point); outside the block (pre-heat, the lead-in's way to it) the cut's feed, so the
  wire enters hot enough; at a stop ``v = 0`` and the power falls to the threshold;

zero outside the windows, clipped to ``[0, full_scale]`` on an analog output: one function,
:func:`~..cut.heat_power.set_power`, which the compensation's kerf uses too.  The
set-points lead the motion by the wire's ``lag``: ``setpoint(t) = desired(t + lag)``
(the last value held), so that :func:`~ruledrobot.robot.wire.kerf.wire_power`, the wire's
power as the model delays it, is the desired power.  Units: W/m, s.
"""

from __future__ import annotations

import numpy as np

from ...geometry.checks import FloatArray
from ...robot.motion.trajectory import HEATED_PHASES
from ..cut.heat_power import set_power
from ..job.spec import Job
from .assemble import Motion

__all__ = ["has_heat_model", "heat_schedule"]


def has_heat_model(job: Job) -> bool:
    """Whether the job's heat has a power to schedule.

    A ``[material]``, or a heat ``mode`` other than ``on_off``, or a ``power``.
    """
    h = job.tool.heat
    return job.material is not None or (h is not None and (h.mode != "on_off"
                                                          or h.power is not None))  # fmt: skip


def heat_schedule(job: Job, motion: Motion) -> FloatArray | None:
    """Return the set-point power (M,) [W/m] of every sample of ``motion`` (module doc).

    None when the job has no heat model (:func:`has_heat_model`).
    """
    if not has_heat_model(job):
        return None
    h = job.tool.heat
    t = motion.timed.t
    on = motion.heat if h is not None else np.isin(motion.labels.astype(str), HEATED_PHASES)
    desired = np.zeros(t.size)
    for k, cp in enumerate(motion.passes):
        rows = np.flatnonzero(on & (motion.pass_of == k))
        if not rows.size:
            continue
        # the reference point's speed: measured in the block, the cut's feed outside it
        v = np.where(motion.wire.inside[rows], motion.wire.feed[rows], cp.cut.feed_speed)
        desired[rows] = set_power(cp.cut, h, job.material, np.nan_to_num(v))
    lag = 0.0 if h is None else h.lag
    return np.interp(t + lag, t, desired) if lag > 0.0 else desired
