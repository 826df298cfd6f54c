"""The arm an emulator runs: a catalogue model, with a calibration (a file, an object or a
seeded random one), and the KinematicsInfo it serves on the primary interface."""

from __future__ import annotations

import os

import numpy as np

from ...io.calibration import load_calibration
from ...protocol.primary import KinematicsInfo
from ...robot import Calibration, RobotModel, load, random_calibration

__all__ = ["emulated_model", "kinematics_info_of"]


def emulated_model(
    model: str | RobotModel, calibration: Calibration | str | os.PathLike | None = None
) -> RobotModel:
    """The arm an emulator runs.

    ``model`` (a catalogue name or a :class:`RobotModel`) with ``calibration`` (a
    :class:`~ruledrobot.robot.Calibration`, a ``ruledrobot.calibration/1`` file, or
    ``"random:SEED"`` for a seeded realistic one) attached. ValueError (naming both models) for
    a calibration of another model, :class:`~ruledrobot.robot.CalibrationError` for a bad file."""
    arm = load(model) if isinstance(model, str) else model
    if not isinstance(arm, RobotModel):
        raise ValueError(f"model: expected a model name or a RobotModel, got {type(arm).__name__}")
    if calibration is None:
        return arm
    if isinstance(calibration, str) and calibration.startswith("random:"):
        seed_text = calibration[len("random:") :]
        if not seed_text.isdigit():
            raise ValueError(f"random:SEED needs a seed >= 0, got {seed_text!r}")
        calibration = random_calibration(arm.name, int(seed_text))
    if isinstance(calibration, (str, os.PathLike)):
        cal, where = load_calibration(calibration), f"{os.fspath(calibration)}: "
    else:
        cal, where = calibration, ""
    if isinstance(cal, Calibration) and cal.model != arm.name:
        raise ValueError(
            f"{where}a calibration of a {cal.model} (source {cal.source!r}), but the emulator "
            f"is a {arm.name}: refused"
        )
    return arm.with_calibration(cal)  # refuses what is not a Calibration


def kinematics_info_of(model: RobotModel) -> KinematicsInfo:
    """The KinematicsInfo an emulator of ``model`` serves.

    Its calibration's (effective table, checksums, status; checksums 0 and status 2 where the
    calibration has none), or for an uncalibrated model its DH table with checksums 0 and
    status 2 ("linearised": the table is the emulated arm's exact kinematics)."""
    if model.calibration is not None:
        return model.calibration.kinematics_info()
    if model.n_joints != 6:
        raise ValueError(f"model {model.name!r}: KinematicsInfo needs 6 joints")
    return KinematicsInfo(
        checksum=(0,) * 6, theta=np.array(model.theta_offset), a=np.array(model.a),
        d=np.array(model.d), alpha=np.array(model.alpha), calibration_status=2,
    )  # fmt: skip
