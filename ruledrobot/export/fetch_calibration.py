"""A controller's calibration, read over the network: KinematicsInfo from the primary
interface (port 30001) and the robot model from the dashboard (port 29999).

What ``ruledrobot calibration fetch --host H --out robot.calib.json`` does.
"""

from __future__ import annotations

from ..protocol.primary import PRIMARY_PORT, read_kinematics_info
from ..robot.arm.calibration import Calibration
from .run_checks import query_dashboard

__all__ = ["fetch_calibration"]


def fetch_calibration(
    host: str, model: str | None = None, *, timeout: float = 5.0, port: int = PRIMARY_PORT
) -> Calibration:
    """The calibration of the robot at ``host``.

    ``model``: the catalogue name; by default what the dashboard says (``get robot
    model`` and ``PolyscopeVersion``: UR5 on 5.x is a ur5e).  Raises ConnectionError /
    TimeoutError naming the host, ValueError (a :class:`~ruledrobot.robot.CalibrationError`)
    when the table does not belong to the model or is implausible.
    """
    if model is None:
        info = query_dashboard(host, timeout=timeout)
        model = info.robot
        if model is None:
            raise ValueError(
                f"controller {host}: cannot tell the robot model from the dashboard "
                f"({info.model_reply!r}, {info.version_reply!r}); pass --model"
            )
    kin, version = read_kinematics_info(host, port, timeout=timeout)
    where = f"controller {host}" + (f" (software {version.text})" if version else "")
    return Calibration.from_kinematics_info(kin, model, source=where)
