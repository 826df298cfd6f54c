"""Nominal data of the Universal Robots arms: DH tables, limits, masses, control periods.

Pure data (numpy only), below every type of the robot layer: the catalogue
(:func:`~ruledrobot.robot.load`) builds :class:`~ruledrobot.robot.RobotModel` s
from it and calibrations (:mod:`.calibration`) measure their corrections against
its DH tables.
Catalogue of Universal Robots arms: DH tables, limits, masses, control periods.

Sources (collected in the project's research notes, ``mujoco.md`` section 1):

* DH tables: Universal Robots, "DH Parameters for calculations of kinematics
  and dynamics" (e-Series, CB3), cross-checked against
  ``UniversalRobots/Universal_Robots_ROS2_Description`` ``config/<model>/
  default_kinematics.yaml`` (identical).  Standard DH, all theta offsets 0,
  ``alpha = [pi/2, 0, 0, pi/2, -pi/2, 0]``, ``a1 = a4 = a5 = a6 = 0``,
  ``d2 = d3 = 0``.
* Link masses and centres of mass (in DH frame i): the same UR article
  (UR3e/UR5e/UR10e/UR20/UR30) and the ROS2 description's
  ``physical_parameters.yaml`` converted to DH frames.  UR20 link 6 uses the
  ROS value 0.926 kg (UR's article gives 0.846 kg @ [0, -0.0003, -0.0318]).
* Speed and torque limits: ROS2 description ``config/<model>/
  joint_limits.yaml`` (citing the UR manuals and UR's "Max. joint torques"
  article), snapshot of 2024-10-14, tag 2.4.5, commit ``2221ec0f``; every
  figure in ``LIMITS`` equals it.  The torques are those of its PR #195
  ("Update dynamic properties", 2024-09-20), which lowered the UR3e to
  54/54/28/9/9/9 and the UR10e/UR16e wrists to 54 and raised the UR20/UR30
  to 738/738/433/107 N m; versions before that PR read 56/56/28/12/12/12,
  56 and 730/430/100 instead.
* Position limits: +-2 pi on every joint except the elbow (joint 3), which
  is +-pi: the shoulder lift gets in the way beyond about +-pi (the same
  ``joint_limits.yaml`` files, ros-industrial/universal_robot issue 265, and
  MuJoCo Menagerie's ``universal_robots_ur5e``/``ur10e`` class
  ``size3_limited``, +-3.1415).  Wrist 3 of UR3 and UR3e is unlimited
  ("infinite" in the manuals; ``has_position_limits: false`` in the ROS
  description since its PR #196) and is stored as +-inf.
* Acceleration limits are not published by UR: the default is the URScript
  ``movej`` default, 1.4 rad/s^2, on every joint (see ``docs/robot.md``).
* Control period: 2 ms (500 Hz) on e-Series, 8 ms (125 Hz) on CB3.
* Payload and reach: nominal datasheet values (UR10e: the original 10 kg
  rating; later controllers allow 12.5 kg).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._checks import FloatArray

__all__ = ["MODEL_NAMES", "NominalDH", "canonical_name", "nominal_dh"]

DEG = np.pi / 180.0
# Elbow (joint 3) position limit [rad] of every catalogue model: the arm
# collides with itself beyond about +-pi (see the module docstring).
ELBOW_LIMIT = np.pi
ALPHA = (np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0)

# name: (d1, a2, a3, d4, d5, d6)  [m]
DH: dict[str, tuple[float, float, float, float, float, float]] = {
    "ur3": (0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819),
    "ur5": (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
    "ur10": (0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922),
    "ur3e": (0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921),
    "ur5e": (0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
    "ur10e": (0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
    "ur16e": (0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655),
    "ur20": (0.2363, -0.862, -0.7287, 0.201, 0.1593, 0.1543),
    "ur30": (0.2363, -0.637, -0.5037, 0.201, 0.1593, 0.1543),
}

# name: link masses [kg], centres of mass in DH frame i [m]
MASSES: dict[str, tuple[tuple[float, ...], tuple[tuple[float, float, float], ...]]] = {
    "ur3": (
        (2.0, 3.42, 1.26, 0.8, 0.8, 0.35),
        ((0, -0.02, 0), (0.13, 0, 0.1157), (0.05, 0, 0.0238),
         (0, 0, 0.01), (0, 0, 0.01), (0, 0, -0.02)),
    ),
    "ur5": (
        (3.7, 8.393, 2.33, 1.219, 1.219, 0.1879),
        ((0, -0.02561, 0.00193), (0.2125, 0, 0.11336), (0.15, 0, 0.0265),
         (0, -0.0018, 0.01634), (0, 0.0018, 0.01634), (0, 0, -0.00116)),
    ),
    "ur10": (
        (7.1, 12.7, 4.27, 2.0, 2.0, 0.365),
        ((0.021, 0, 0.027), (0.38, 0, 0.158), (0.24, 0, 0.068),
         (0, 0.007, 0.018), (0, 0.007, 0.018), (0, 0, -0.026)),
    ),
    "ur3e": (
        (1.98, 3.4445, 1.437, 0.871, 0.805, 0.261),
        ((0, -0.02, 0), (0.13, 0, 0.1157), (0.05, 0, 0.0238),
         (0, 0, 0.01), (0, 0, 0.01), (0, 0, -0.02)),
    ),
    "ur5e": (
        (3.761, 8.058, 2.846, 1.37, 1.3, 0.365),
        ((0, -0.02561, 0.00193), (0.2125, 0, 0.11336), (0.15, 0, 0.0265),
         (0, -0.0018, 0.01634), (0, 0.0018, 0.01634), (0, 0, -0.001159)),
    ),
    "ur10e": (
        (7.369, 13.051, 3.989, 2.1, 1.98, 0.615),
        ((0.021, 0, 0.027), (0.38, 0, 0.158), (0.24, 0, 0.068),
         (0, 0.007, 0.018), (0, 0.007, 0.018), (0, 0, -0.026)),
    ),
    "ur16e": (
        (7.369, 10.45, 4.321, 2.18, 2.033, 0.907),
        ((0, -0.016, 0.03), (0.302, 0, 0.16), (0.194, 0, 0.065),
         (0, -0.009, 0.011), (0, 0.018, 0.012), (0, 0, -0.044)),
    ),
    "ur20": (
        (16.343, 29.632, 7.879, 3.054, 3.126, 0.926),
        ((0, -0.061, 0.0062), (0.5226, 0, 0.2098), (0.3234, 0, 0.0604),
         (0, -0.0026, 0.0393), (0, 0.0024, 0.0379), (0, 0, -0.0293)),
    ),
    "ur30": (
        (16.343, 28.542, 7.156, 3.054, 3.126, 0.926),
        ((-0.0001, -0.06, 0.0069), (0.3894, 0, 0.2103), (0.2257, 0, 0.0629),
         (0, -0.0048, 0.0353), (0, 0.0046, 0.0341), (0, 0, -0.0293)),
    ),
}  # fmt: skip

# name: (torque [N m], speed [deg/s], J6 unlimited, control period [s], payload [kg], reach [m])
LIMITS: dict[str, tuple[tuple[float, ...], tuple[float, ...], bool, float, float, float]] = {
    "ur3": ((56, 56, 28, 12, 12, 12), (180, 180, 180, 360, 360, 360), True, 0.008, 3.0, 0.5),
    "ur5": ((150, 150, 150, 28, 28, 28), (180,) * 6, False, 0.008, 5.0, 0.85),
    "ur10": ((330, 330, 150, 56, 56, 56), (120, 120, 180, 180, 180, 180), False, 0.008, 10.0, 1.3),
    "ur3e": ((54, 54, 28, 9, 9, 9), (180, 180, 180, 360, 360, 360), True, 0.002, 3.0, 0.5),
    "ur5e": ((150, 150, 150, 28, 28, 28), (180,) * 6, False, 0.002, 5.0, 0.85),
    "ur10e": ((330, 330, 150, 54, 54, 54), (120, 120, 180, 180, 180, 180), False, 0.002, 10.0, 1.3),
    "ur16e": ((330, 330, 150, 54, 54, 54), (120, 120, 180, 180, 180, 180), False, 0.002, 16.0, 0.9),
    "ur20": ((738, 738, 433, 107, 107, 107), (120, 120, 150, 210, 210, 210), False, 0.002, 20.0,
             1.75),
    "ur30": ((738, 738, 433, 107, 107, 107), (120, 120, 150, 210, 210, 210), False, 0.002, 30.0,
             1.3),
}  # fmt: skip

#: Names accepted by :func:`load`, CB3 first, then e-Series.
MODEL_NAMES: tuple[str, ...] = tuple(DH)




class NominalDH(NamedTuple):
    """The nominal standard-DH table of a catalogue model, (6,) each [rad, m, m, rad]."""

    name: str
    theta_offset: FloatArray
    a: FloatArray
    d: FloatArray
    alpha: FloatArray


def canonical_name(name: object) -> str:
    """``name`` as a catalogue key (stripped, lower case); ValueError listing the names."""
    key = name.strip().lower() if isinstance(name, str) else None
    if key not in DH:
        raise ValueError(f"robot model {name!r} is unknown; valid names: {', '.join(MODEL_NAMES)}")
    return key


def nominal_dh(name: str) -> NominalDH:
    """The nominal DH table of model ``name`` (all theta offsets 0, ``d2 = d3 = 0``)."""
    key = canonical_name(name)
    d1, a2, a3, d4, d5, d6 = DH[key]
    return NominalDH(key, np.zeros(6), np.array([0.0, a2, a3, 0.0, 0.0, 0.0]),
                     np.array([d1, 0.0, 0.0, d4, d5, d6]), np.array(ALPHA))  # fmt: skip
