"""Calibrating the kerf model (docs/kerf.md, "Calibration"): the ladder of test cuts
(:func:`write_ladder`) and the fit of its measurements (:func:`read_measured`,
:func:`fit_kerf`, :func:`material_text`).  An application package beside ``carve``: it
reads the job through the planner's public face (``wirecut.load_job``) and fits the one
kerf model (:class:`ruledrobot.robot.wire.kerf.Material`)."""

from .fit import Constant, KerfFit, fit_kerf, material_text
from .ladder import Ladder, LadderCut, write_ladder
from .measured import Measured, read_measured

__all__ = ["Constant", "KerfFit", "Ladder", "LadderCut", "Measured", "fit_kerf",
           "material_text", "read_measured", "write_ladder"]
