"""UR export: trajectory files, URScript programs, RTDE streaming, and a controller emulator.

* :func:`export_trajectory` — CSV / JSON / NPZ / URScript files (atomic).
* :func:`urscript_program` — a standalone URScript program (servoj or movep/movel).
* :func:`run_trajectory` — play a trajectory on a controller through ur_rtde,
  monitored, with safe stops and a recording of the actual motion.
* :class:`Emulator` / :func:`serve` — a UR controller emulator (RTDE,
  dashboard, script port) that the real ur_rtde client drives
  (``ruledrobot.export.emulator``).

See ``docs/rtde.md``.  ``ur_rtde`` itself is imported only when a run starts.
"""

from __future__ import annotations

from .emulator import Emulator, serve
from .limits import check_trajectory
from .run_plan import recording_path_for
from .runner import ControllerError, RunMode, RunPlan, RunResult, run_trajectory
from .urscript import EXPORT_FORMATS, export_trajectory, urscript_program

__all__ = [
    "EXPORT_FORMATS",
    "ControllerError",
    "Emulator",
    "RunMode",
    "RunPlan",
    "RunResult",
    "check_trajectory",
    "export_trajectory",
    "recording_path_for",
    "run_trajectory",
    "serve",
    "urscript_program",
]
