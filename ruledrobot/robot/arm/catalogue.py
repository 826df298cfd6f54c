"""The catalogue of Universal Robots arms: :func:`load` a model by name.

The figures (DH tables, limits, masses, control periods) and their sources are in
:mod:`.ur_tables`.
"""

from __future__ import annotations

import numpy as np

from .calibration import Calibration
from .model import DEFAULT_ACCELERATION, RobotModel
from .ur_tables import DEG, ELBOW_LIMIT, LIMITS, MASSES, MODEL_NAMES, canonical_name, nominal_dh

__all__ = ["MODEL_NAMES", "load"]


def load(name: str, calibration: Calibration | None = None) -> RobotModel:
    """The catalogue model ``name`` (case-insensitive): one of :data:`MODEL_NAMES`.

    ``ur3, ur5, ur10`` (CB3, 125 Hz) and ``ur3e, ur5e, ur10e, ur16e, ur20,
    ur30`` (e-Series, 500 Hz).  No base and no tool are set; use
    :meth:`RobotModel.with_base` / :meth:`RobotModel.with_tool`.

    ``calibration``: the robot's factory calibration (a
    :class:`~ruledrobot.robot.Calibration`; read files with
    :func:`ruledrobot.io.load_calibration`), see :meth:`RobotModel.with_calibration`;
    None gives the nominal arm.
    """
    key = canonical_name(name)
    nom = nominal_dh(key)
    masses, coms = MASSES[key]
    torque, speed_deg, j6_free, period, payload, reach = LIMITS[key]
    limit = np.full(6, 2.0 * np.pi)
    limit[2] = ELBOW_LIMIT
    if j6_free:
        limit[5] = np.inf
    model = RobotModel(
        name=key,
        d=nom.d,
        a=nom.a,
        alpha=nom.alpha,
        theta_offset=nom.theta_offset,
        lower=-limit,
        upper=limit,
        max_velocity=np.array(speed_deg, dtype=float) * DEG,
        max_acceleration=np.full(6, DEFAULT_ACCELERATION),
        max_torque=np.array(torque, dtype=float),
        link_mass=np.array(masses, dtype=float),
        link_com=np.array(coms, dtype=float),
        control_period=period,
        payload=payload,
        reach=reach,
    )
    return model if calibration is None else model.with_calibration(calibration)
