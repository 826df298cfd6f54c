"""The arguments every timing function checks alike (built on :mod:`ruledrobot.geometry.
checks`): the joint limits with the controller period, and a factor in (0, 1]."""

from __future__ import annotations

from numpy.typing import ArrayLike

from ....geometry.checks import as_limits, as_number
from .tolerances import FloatArray

__all__ = ["as_factor", "as_rate_limits"]


def as_rate_limits(
    vel_limits: ArrayLike, acc_limits: ArrayLike, dt: float, joints: int
) -> tuple[FloatArray, FloatArray, float]:
    """The limits a timed path keeps, checked in this order (ValueError names the first bad one).

    Parameters
    ----------
    vel_limits : (J,) joint velocity limits [rad/s], each > 0.
    acc_limits : (J,) joint acceleration limits [rad/s²], each > 0.
    dt : the controller period [s], > 0.
    joints : J, the number of joints.

    Returns
    -------
    ``(vel_limits (J,), acc_limits (J,), dt)`` as float64 arrays and a float.
    """
    vlim = as_limits(vel_limits, "vel_limits", joints)
    alim = as_limits(acc_limits, "acc_limits", joints)
    return vlim, alim, as_number(dt, "dt")


def as_factor(value: float, name: str) -> float:
    """``value`` as a float in (0, 1] (a slow-down or safety factor, no unit).

    ValueError naming ``name`` otherwise."""
    x = as_number(value, name)
    if x > 1.0:
        raise ValueError(f"{name}: expected a factor in (0, 1], got {x}")
    return x
